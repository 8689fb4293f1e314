#!/usr/bin/env python3
"""Every file under crates/*/tests/ is compiled: each crate's integration tests are modules of
one binary (tests/main.rs, `autotests = false`), so a file that main.rs does not declare, and
that no [[test]] target names, would silently never build or run. Exits 1 naming such files."""
import pathlib
import re
import sys

missing = []
for tests in sorted(pathlib.Path("crates").glob("*/tests")):
    manifest = (tests.parent / "Cargo.toml").read_text()
    targets = set(re.findall(r'path\s*=\s*"tests/([^"/]+)\.rs"', manifest))
    main = tests / "main.rs"
    declared = set(re.findall(r"^mod (\w+);", main.read_text(), re.M)) if main.exists() else set()
    for f in sorted(tests.glob("*.rs")):
        if f.stem != "main" and f.stem not in declared and f.stem not in targets:
            missing.append(str(f))
for f in missing:
    print(f"test modules: {f} is neither a `mod` of tests/main.rs nor a [[test]] target", file=sys.stderr)
if missing:
    sys.exit(1)
print("test modules: every file under crates/*/tests is compiled")
