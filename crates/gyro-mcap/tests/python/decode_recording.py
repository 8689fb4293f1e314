"""Decodes every channel of a gyrolab recording with the reference Python MCAP libraries
(mcap + mcap-protobuf-support) and prints what it found for the Rust tests to check.

Usage:
  python decode_recording.py RECORDING.mcap          `key=value` lines (the synthetic sample's test)
  python decode_recording.py RECORDING.mcap --json   one JSON object, for any recording: per topic
      the schema, the message count, and every field of the messages whose index is listed in
      --rows (default 0,1 and the last), floats as the bits of their IEEE double (exact)
"""

import json
import struct
import sys

from mcap.reader import make_reader
from mcap_protobuf.decoder import DecoderFactory


def bits(x):
    return struct.unpack("<Q", struct.pack("<d", x))[0]


def main(path):
    with open(path, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        summary = reader.get_summary()
        print(f"statistics.message_count={summary.statistics.message_count}")
        print(f"statistics.chunk_count={summary.statistics.chunk_count}")
        print(f"chunk_indexes={len(summary.chunk_indexes)}")
        counts = {}
        seen = {}
        for schema, channel, message, decoded in reader.iter_decoded_messages(log_time_order=False):
            topic = channel.topic
            i = counts.get(topic, 0)
            counts[topic] = i + 1
            seen.setdefault(topic, schema.name)
            if topic == "/compass" and i == 10:
                print(f"compass.10.log_time={message.log_time}")
                print(f"compass.10.heading_rad.bits={bits(decoded.heading_rad)}")
                print(f"compass.10.awkward.bits={bits(decoded.awkward)}")
            if topic == "/events" and i == 3:
                print(f"events.3.code={decoded.code}")
                print(f"events.3.label={decoded.label}")
                print(f"events.3.big={decoded.big}")
            if topic == "/solver" and i == 1:
                print(f"solver.1.integrator={decoded.integrator}")
                print(f"solver.1.rhs_calls={decoded.rhs_calls}")
            if topic == "/poses" and i == 5:
                ts = decoded.timestamp
                print(f"poses.5.timestamp_ns={ts.seconds * 1_000_000_000 + ts.nanos}")
                print(f"poses.5.parent={decoded.parent_frame_id}")
                print(f"poses.5.child={decoded.child_frame_id}")
                print(f"poses.5.translation_z.bits={bits(decoded.translation.z)}")
                print(f"poses.5.rotation_w.bits={bits(decoded.rotation.w)}")
        for topic, n in sorted(counts.items()):
            print(f"count.{topic}={n}")
            print(f"schema.{topic}={seen[topic]}")
        for m in reader.iter_metadata():
            print(f"metadata.{m.name}={len(m.metadata)}")
        for a in reader.iter_attachments():
            print(f"attachment.{a.name}={len(a.data)}")


def flatten(msg, prefix=""):
    """Every field of a decoded protobuf message (zeros too: proto3 does not keep presence), nested
    messages as dotted names; doubles as {"bits": u64} so the comparison is exact."""
    out = {}
    for field in msg.DESCRIPTOR.fields:
        value = getattr(msg, field.name)
        name = prefix + field.name
        if field.type == field.TYPE_MESSAGE:
            out.update(flatten(value, name + "."))
        elif field.type in (field.TYPE_DOUBLE, field.TYPE_FLOAT):
            out[name] = {"bits": bits(value)}
        else:
            out[name] = value
    return out


def main_json(path, rows):
    with open(path, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        summary = reader.get_summary()
        topics = {}
        decoded_rows = {}
        for schema, channel, message, decoded in reader.iter_decoded_messages(log_time_order=False):
            t = topics.setdefault(
                channel.topic,
                {"schema": schema.name, "encoding": channel.message_encoding, "count": 0},
            )
            i = t["count"]
            t["count"] = i + 1
            # Keep the first rows asked for and always the latest (the last row is known at the end).
            if i in rows:
                decoded_rows[(channel.topic, i)] = (message.log_time, flatten(decoded))
            t["_last"] = (message.log_time, decoded)
        for topic, t in topics.items():
            log_time, last = t.pop("_last")
            t["rows"] = {
                str(i): {"log_time": lt, "fields": fields}
                for (tp, i), (lt, fields) in decoded_rows.items()
                if tp == topic
            }
            t["rows"]["last"] = {"log_time": log_time, "fields": flatten(last)}
        out = {
            "message_count": summary.statistics.message_count,
            "topics": topics,
            "metadata": {m.name: dict(m.metadata) for m in reader.iter_metadata()},
            "attachments": {a.name: len(a.data) for a in reader.iter_attachments()},
        }
        json.dump(out, sys.stdout, sort_keys=True)


if __name__ == "__main__":
    if "--json" in sys.argv[2:]:
        rows = {0, 1}
        if "--rows" in sys.argv:
            rows = {int(x) for x in sys.argv[sys.argv.index("--rows") + 1].split(",")}
        main_json(sys.argv[1], rows)
    else:
        main(sys.argv[1])
