#!/usr/bin/env python3
"""Checks the workspace's layer graph (ARCHITECTURE.md) from `cargo metadata`:

- gyro-model (physics) and gyro-mcap (the recording contract) depend on no workspace crate;
- nothing depends on gyrolab (the command line is the top);
- dev-only crates (publish = false and named *-testkit) are only ever dev-dependencies.

Normal and build dependencies are checked; a dev-dependency may point at any crate below.
Exits 1 naming every edge that breaks a rule.
"""
import json
import subprocess
import sys

LEAVES = {"gyro-model", "gyro-mcap"}
TOP = "gyrolab"

meta = json.loads(
    subprocess.run(
        ["cargo", "metadata", "--format-version", "1", "--no-deps", "--offline"],
        check=True,
        capture_output=True,
        text=True,
    ).stdout
)
members = {p["name"]: p for p in meta["packages"]}
testkits = {n for n, p in members.items() if n.endswith("-testkit")}
errors = []
for name, package in sorted(members.items()):
    for dep in package["dependencies"]:
        target = dep["name"]
        if target not in members:
            continue
        kind = dep["kind"] or "normal"
        if target == TOP:
            errors.append(f"{name} depends on {TOP} ({kind}): nothing may depend on the command line")
        if kind == "dev":
            continue
        if name in LEAVES:
            errors.append(f"{name} depends on workspace crate {target} ({kind}): {name} must depend on none")
        if target in testkits:
            errors.append(f"{name} depends on {target} as a {kind} dependency: test kits are dev-only")
for e in errors:
    print(f"layering: {e}", file=sys.stderr)
if errors:
    sys.exit(1)
print(f"layering: {len(members)} workspace crates, rules hold")
