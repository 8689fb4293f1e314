#!/usr/bin/env python3
"""Tests and benches find files through gyro-testkit's `manifest_dir!()` / `repo_root!()`, not
`env!("CARGO_MANIFEST_DIR")`: cargo does not rebuild a workspace member whose checkout moved
(a fresh clone reusing a target directory, as .ci/run does), so a compiled-in path can name the
checkout that built the binary, or one that is gone (gyro-testkit's crate doc). `include_str!`
and `include_bytes!` are fine: cargo tracks the file's contents. Exits 1 naming each use."""
import pathlib
import re
import sys

found = []
for kind in ("tests", "benches"):
    for f in sorted(pathlib.Path("crates").glob(f"*/{kind}/**/*.rs")):
        for n, line in enumerate(f.read_text().splitlines(), 1):
            if 'env!("CARGO_MANIFEST_DIR")' in line and not re.search(r"include_(str|bytes)!", line):
                found.append(f"{f}:{n}")
for place in found:
    print(f"test paths: {place} compiles its checkout's path in; use gyro_testkit::manifest_dir!() "
          "or repo_root!()", file=sys.stderr)
if found:
    sys.exit(1)
print("test paths: tests and benches find the repository at run time")
