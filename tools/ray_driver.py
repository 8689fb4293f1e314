#!/usr/bin/env python3
"""gyrolab's Ray driver: runs the chunks of a sweep as Ray tasks on a running cluster.

Started by `gyrolab sweep run STUDY --engine ray --address HOST:PORT --out DIR` (which writes
this file into DIR/ray/ and the chunks of run indices into DIR/ray/tasks.json); not meant to be
run by hand. Each task runs the `gyrolab` binary (`gyrolab sweep exec DIR --runs … --attempt …`)
on one chunk; the binary writes the chunk's rows as one Parquet part into DIR (a folder every
node sees) through an attempt-named `.partial` file, so a retried task never collides with a
dead one, and it exits by itself if its worker dies. A task whose worker is killed is retried
by Ray (`max_retries`); one whose gyrolab exits non-zero is retried too (`retry_exceptions`).

Progress goes to stdout as JSON lines, one per finished task:
  {"event": "done", "task": K, "ran": N, "failed": F, "attempt": "..."}
  {"event": "task_failed", "task": K, "error": "..."}
  {"event": "finished"}

The address is passed explicitly (never "auto": it can pick a stale cluster); authentication
comes from the environment (RAY_AUTH_MODE, RAY_AUTH_TOKEN) as the cluster was started with.
"""
import argparse
import json
import subprocess
import sys
import uuid

import ray


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--address", required=True, help="HOST:PORT of the cluster's GCS")
    ap.add_argument("--out", required=True, help="the sweep folder (seen by every node)")
    ap.add_argument("--gyrolab", required=True, help="the gyrolab binary (same path on every node)")
    ap.add_argument("--tasks", required=True, help="JSON list of chunks of run indices")
    ap.add_argument("--max-retries", type=int, default=3)
    args = ap.parse_args()
    with open(args.tasks) as f:
        chunks = json.load(f)

    ray.init(address=args.address, log_to_driver=False)

    gyrolab, out = args.gyrolab, args.out

    @ray.remote(num_cpus=1, max_retries=args.max_retries, retry_exceptions=True)
    def run_chunk(k, runs):
        attempt = f"ray-{k}-{uuid.uuid4().hex[:12]}"
        cmd = [gyrolab, "sweep", "exec", out, "--runs", ",".join(map(str, runs)),
               "--attempt", attempt]
        p = subprocess.run(cmd, capture_output=True, text=True)
        if p.returncode != 0:
            raise RuntimeError(f"gyrolab exited {p.returncode}: {p.stderr[-2000:]}")
        return json.loads(p.stdout.strip().splitlines()[-1])

    pending = {run_chunk.remote(k, c): k for k, c in enumerate(chunks)}
    while pending:
        done, _ = ray.wait(list(pending), num_returns=1)
        for ref in done:
            k = pending.pop(ref)
            try:
                res = ray.get(ref)
                print(json.dumps({"event": "done", "task": k, **res}), flush=True)
            except Exception as e:  # a task that failed after its retries
                print(json.dumps({"event": "task_failed", "task": k, "error": str(e)[-1000:]}),
                      flush=True)
    print(json.dumps({"event": "finished"}), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
