"""Decodes every channel of a gyrolab recording with the reference Python MCAP libraries
(mcap + mcap-protobuf-support) and prints `key=value` lines for the Rust test to check.

Usage: python decode_recording.py RECORDING.mcap
"""

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


if __name__ == "__main__":
    main(sys.argv[1])
