"""Reads an .rrd through Rerun's own decoder (rerun-sdk) and prints a JSON summary per entity:
static components, and for every temporal component its `sim_time` stamps (ns) and values; and the
components of every blueprint entity."""
import json
import sys

import pyarrow as pa
from rerun.experimental import RrdReader

reader = RrdReader(sys.argv[1])
out = {
    "recordings": len(reader.recordings()),
    "blueprints": len(reader.blueprints()),
    "entities": {},
    "blueprint_entities": {},
}
for store in reader.blueprints():
    for chunk in reader.stream(store=store):
        names = chunk.to_record_batch().schema.names
        components = out["blueprint_entities"].setdefault(chunk.entity_path, [])
        components += [n for n in names if ":" in n]
for chunk in reader.stream():
    batch = chunk.to_record_batch()
    entity = out["entities"].setdefault(chunk.entity_path, {"static": [], "temporal": {}})
    names = batch.schema.names
    components = [n for n in names if ":" in n]
    if chunk.is_static:
        entity["static"] += components
        continue
    if "sim_time" not in names:
        continue
    times = batch.column("sim_time").cast(pa.int64()).to_pylist()
    for name in components:
        d = entity["temporal"].setdefault(name, {"time_ns": [], "values": []})
        d["time_ns"] += times
        d["values"] += batch.column(name).to_pylist()
json.dump(out, sys.stdout)
