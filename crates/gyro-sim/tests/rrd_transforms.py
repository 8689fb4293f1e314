"""Reads an .rrd made by `rerun mcap convert` through Rerun's own decoder (rerun-sdk) and prints,
as JSON, every Transform3D it holds, by child frame: the parent frame(s), how many there are, and
the latest one (time on the `message_log_time` timeline in ns, translation, quaternion xyzw).

Usage: python rrd_transforms.py FILE.rrd
"""

import json
import sys

import pyarrow as pa
from rerun.experimental import RrdReader

TIMELINE = "message_log_time"

frames = {}
timelines = set()
for chunk in RrdReader(sys.argv[1]).stream():
    batch = chunk.to_record_batch()
    names = batch.schema.names
    if chunk.is_static or "Transform3D:child_frame" not in names:
        continue
    timelines.update(n for n in names if batch.schema.field(n).metadata
                     and batch.schema.field(n).metadata.get(b"rerun:kind") == b"index")
    times = batch.column(TIMELINE).cast(pa.int64()).to_pylist()
    child = batch.column("Transform3D:child_frame").to_pylist()
    parent = batch.column("Transform3D:parent_frame").to_pylist()
    trans = batch.column("Transform3D:translation").to_pylist()
    quat = batch.column("Transform3D:quaternion").to_pylist()
    for i, t in enumerate(times):
        # One transform per row (each component a list of one).
        for k, c in enumerate(child[i] or []):
            f = frames.setdefault(c, {"parents": set(), "count": 0, "entities": set(), "last": None})
            f["parents"].add(parent[i][k])
            f["entities"].add(chunk.entity_path)
            f["count"] += 1
            if f["last"] is None or t >= f["last"][0]:
                f["last"] = (t, trans[i][k], quat[i][k])

out = {"timelines": sorted(t.decode() if isinstance(t, bytes) else t for t in timelines),
       "transforms": {}}
for c, f in sorted(frames.items()):
    t, tr, q = f["last"]
    out["transforms"][c] = {
        "parent_frame": sorted(f["parents"])[0] if len(f["parents"]) == 1 else sorted(f["parents"]),
        "entities": sorted(f["entities"]),
        "count": f["count"],
        "last_time_ns": t,
        "last_translation": tr,
        "last_quaternion_xyzw": q,
    }
json.dump(out, sys.stdout, sort_keys=True)
