#!/usr/bin/env bash
# The Python peer benchmark: makes its own virtual environment (numpy + SciPy from PyPI), runs
# gyrolab's side (cargo, release) and SciPy's side of the same cases on this machine in one run,
# and prints the wall-time ratios at matched achieved error.
#   bash analysis/bench/run.sh            # from the repository root
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
venv="${PEER_VENV:-$here/.venv}"
if [ ! -x "$venv/bin/python" ]; then
    python3 -m venv "$venv"
    "$venv/bin/pip" install --quiet -r "$here/requirements.txt"
fi
exec "$venv/bin/python" "$here/peer.py" "$@"
