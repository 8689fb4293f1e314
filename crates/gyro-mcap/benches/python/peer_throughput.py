"""The Python peer of benches/throughput.rs: the same load (a 20-double record channel and a
6-frame foxglove.FrameTransform channel at 10 Hz) written with the reference `mcap` +
`mcap-protobuf-support` libraries (zstd chunks, their defaults) and read back decoded, so the two
can be compared on the same machine at the same moment.

Usage: python peer_throughput.py [HOURS]   (default 0.25 h = 63 000 messages)
Needs: pip install mcap==1.6.0 mcap-protobuf-support==0.6.0
"""

import math
import os
import sys
import tempfile
import time

from google.protobuf import descriptor_pb2, descriptor_pool, message_factory
from google.protobuf import timestamp_pb2  # noqa: F401  (registers its descriptor)
from mcap.reader import make_reader
from mcap_protobuf.decoder import DecoderFactory
from mcap_protobuf.writer import Writer


def classes():
    pool = descriptor_pool.Default()
    fd = descriptor_pb2.FileDescriptorProto(name="bench/compass.proto", package="gyrolab", syntax="proto3")
    m = fd.message_type.add(name="CompassState")
    for i in range(20):
        m.field.add(name=f"q{i}", number=i + 1, type=descriptor_pb2.FieldDescriptorProto.TYPE_DOUBLE,
                    label=descriptor_pb2.FieldDescriptorProto.LABEL_OPTIONAL)
    pool.Add(fd)
    fx = descriptor_pb2.FileDescriptorProto(name="foxglove/FrameTransform.proto", package="foxglove",
                                            syntax="proto3", dependency=["google/protobuf/timestamp.proto"])
    D = descriptor_pb2.FieldDescriptorProto
    v = fx.message_type.add(name="Vector3")
    for i, n in enumerate("xyz"):
        v.field.add(name=n, number=i + 1, type=D.TYPE_DOUBLE, label=D.LABEL_OPTIONAL)
    q = fx.message_type.add(name="Quaternion")
    for i, n in enumerate("xyzw"):
        q.field.add(name=n, number=i + 1, type=D.TYPE_DOUBLE, label=D.LABEL_OPTIONAL)
    t = fx.message_type.add(name="FrameTransform")
    t.field.add(name="timestamp", number=1, type=D.TYPE_MESSAGE, type_name=".google.protobuf.Timestamp", label=D.LABEL_OPTIONAL)
    t.field.add(name="parent_frame_id", number=2, type=D.TYPE_STRING, label=D.LABEL_OPTIONAL)
    t.field.add(name="child_frame_id", number=3, type=D.TYPE_STRING, label=D.LABEL_OPTIONAL)
    t.field.add(name="translation", number=4, type=D.TYPE_MESSAGE, type_name=".foxglove.Vector3", label=D.LABEL_OPTIONAL)
    t.field.add(name="rotation", number=5, type=D.TYPE_MESSAGE, type_name=".foxglove.Quaternion", label=D.LABEL_OPTIONAL)
    pool.Add(fx)
    get = message_factory.GetMessageClass
    return get(pool.FindMessageTypeByName("gyrolab.CompassState")), get(pool.FindMessageTypeByName("foxglove.FrameTransform"))


def main():
    hours = float(sys.argv[1]) if len(sys.argv) > 1 else 0.25
    steps = int(hours * 3600 * 10)
    Compass, FrameTransform = classes()
    frames = ["earth", "ship", "gimbal", "spider", "case", "rotor", "spin"]
    path = os.path.join(tempfile.mkdtemp(), "peer.mcap")
    t0, c0 = time.perf_counter(), time.process_time()
    n = 0
    with open(path, "wb") as f, Writer(f) as w:
        for i in range(steps):
            t_ns = i * 100_000_000
            rec = Compass(**{f"q{k}": math.sin(1e-4 * (k + 1) * i) * 1e-2 + k for k in range(20)})
            w.write_message(topic="/compass", message=rec, log_time=t_ns, publish_time=t_ns)
            n += 1
            for k in range(6):
                s = math.sin(1e-4 * (21 + k) * i)
                p = FrameTransform(parent_frame_id=frames[k], child_frame_id=frames[k + 1])
                p.timestamp.seconds, p.timestamp.nanos = divmod(t_ns, 1_000_000_000)
                p.translation.x, p.translation.z = 0.1 * k, 0.05 * s
                p.rotation.z, p.rotation.w = s, math.sqrt(max(0.0, 1 - s * s))
                w.write_message(topic="/poses", message=p, log_time=t_ns, publish_time=t_ns)
                n += 1
    write_s, write_cpu = time.perf_counter() - t0, time.process_time() - c0
    size = os.path.getsize(path)
    t0, c0 = time.perf_counter(), time.process_time()
    m = 0
    with open(path, "rb") as f:
        for _ in make_reader(f, decoder_factories=[DecoderFactory()]).iter_decoded_messages():
            m += 1
    read_s, read_cpu = time.perf_counter() - t0, time.process_time() - c0
    assert m == n
    # The writer alone: the same payloads serialized beforehand, written with the raw writer.
    from mcap.writer import CompressionType
    from mcap.writer import Writer as RawWriter

    payloads = []
    with open(path, "rb") as f:
        for schema, channel, message in make_reader(f).iter_messages():
            payloads.append((channel.topic, message.log_time, message.data))
    raw_path = path + ".raw"
    t0, c0 = time.perf_counter(), time.process_time()
    with open(raw_path, "wb") as f:
        w = RawWriter(f, compression=CompressionType.ZSTD)
        w.start()
        ids = {}
        for topic in ("/compass", "/poses"):
            sid = w.register_schema(name=topic, encoding="protobuf", data=b"")
            ids[topic] = w.register_channel(topic=topic, message_encoding="protobuf", schema_id=sid)
        for topic, t_ns, data in payloads:
            w.add_message(channel_id=ids[topic], log_time=t_ns, data=data, publish_time=t_ns)
        w.finish()
    raw_s, raw_cpu = time.perf_counter() - t0, time.process_time() - c0
    os.remove(raw_path)
    print(f"python mcap: {n} messages, {size / 1e6:.1f} MB")
    print(f"write raw (payloads serialized beforehand): {n / raw_s / 1e3:.0f} k msgs/s "
          f"({n / raw_cpu / 1e3:.0f} k per CPU second)")
    print(f"write (protobuf messages built and serialized): {n / write_s / 1e3:.0f} k msgs/s ({n / write_cpu / 1e3:.0f} k per CPU second)")
    print(f"read (decoded): {n / read_s / 1e3:.0f} k msgs/s ({n / read_cpu / 1e3:.0f} k per CPU second)")
    os.remove(path)


if __name__ == "__main__":
    main()
