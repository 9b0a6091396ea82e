#!/usr/bin/env python3
"""Check a drape-written rosbag2 MCAP file with the independent `rosbags` reader.

usage: check_bag.py BAG EXPECT.json

EXPECT.json:
  {"distro": "humble"|"jazzy",
   "topics": {"/name": {"type": "pkg/msg/Type", "count": N,
                        "durability": 1|2 (optional, rmw enum of the offered QoS),
                        "messages": [{"index": i, "log_time": ns (optional),
                                      "fields": {nested expected values} (optional),
                                      "cloud": [[v per field, ...] per point] (optional)}]}}}

Numbers compare exactly: the writer prints the f64 (or f32 widened to f64) values it
serialised, and Python parses that shortest decimal back to the same double.
Exit 0 when everything matches, 1 with a list of mismatches, 2 when rosbags is missing.
"""
import json
import sys
from pathlib import Path

try:
    import numpy as np
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_typestore
except ImportError as exc:  # pragma: no cover - exercised on machines without rosbags
    print(f"rosbags is not importable ({exc}): pip install rosbags", file=sys.stderr)
    sys.exit(2)

# Fields Iron added to visualization_msgs/Marker; a Humble Marker must not have them.
JAZZY_ONLY_MARKER_FIELDS = {"texture_resource", "texture", "uv_coordinates", "mesh_file"}

errors = []


def fail(msg):
    errors.append(msg)


def compare(actual, expected, path):
    if isinstance(expected, dict):
        for key, value in expected.items():
            if not hasattr(actual, key):
                fail(f"{path}: no field {key!r}")
                continue
            compare(getattr(actual, key), value, f"{path}.{key}")
    elif isinstance(expected, list):
        if len(actual) != len(expected):
            fail(f"{path}: length {len(actual)} != expected {len(expected)}")
            return
        for i, (a, e) in enumerate(zip(actual, expected)):
            compare(a, e, f"{path}[{i}]")
    elif isinstance(expected, bool):
        if bool(actual) != expected:
            fail(f"{path}: {actual!r} != {expected!r}")
    elif isinstance(expected, (int, float)):
        if isinstance(actual, (str, bytes)) or float(actual) != float(expected):
            fail(f"{path}: {actual!r} != {expected!r}")
    elif isinstance(expected, str):
        if actual != expected:
            fail(f"{path}: {actual!r} != {expected!r}")
    else:
        fail(f"{path}: unsupported expectation {expected!r}")


def decode_cloud(msg):
    """Per point, each FLOAT32 field's value, read by offset (independent of drape)."""
    dtype = np.dtype(">f4" if msg.is_bigendian else "<f4")
    raw = np.asarray(msg.data, dtype=np.uint8).tobytes()
    if len(raw) != msg.width * msg.height * msg.point_step:
        fail(f"cloud: {len(raw)} bytes for {msg.width}x{msg.height} points of {msg.point_step}")
        return []
    out = []
    for p in range(msg.width * msg.height):
        base = p * msg.point_step
        out.append([float(np.frombuffer(raw, dtype, 1, base + f.offset)[0]) for f in msg.fields])
    return out


def field_names(store, typename):
    return [name for name, _ in store.fielddefs[typename][1]]


def check_definitions(reader, distro):
    """Every type the bag defines must have the upstream field list."""
    ref = get_typestore(Stores.ROS2_JAZZY)
    for typename, (_, fields) in reader.typestore.fielddefs.items():
        if typename not in ref.fielddefs:
            continue
        got = [(n, repr(t)) for n, t in fields]
        want = [(n, repr(t)) for n, t in ref.fielddefs[typename][1]]
        if typename == "visualization_msgs/msg/Marker" and distro == "humble":
            want = [w for w in want if w[0] not in JAZZY_ONLY_MARKER_FIELDS]
        if got != want:
            fail(f"definition of {typename} ({distro}): {[g[0] for g in got]} != {[w[0] for w in want]}")


def qos_durability(conn):
    profiles = getattr(conn.ext, "offered_qos_profiles", None)
    if isinstance(profiles, str):
        import yaml  # pragma: no cover - older rosbags keep the YAML text

        profiles = yaml.safe_load(profiles)
        return profiles[0]["durability"]
    if not profiles:
        return None
    dur = profiles[0].durability
    return int(getattr(dur, "value", dur))


def main():
    bag, expect_path = Path(sys.argv[1]), Path(sys.argv[2])
    expect = json.loads(expect_path.read_text())
    with AnyReader([bag]) as reader:
        check_definitions(reader, expect["distro"])
        conns = {c.topic: c for c in reader.connections}
        if set(conns) != set(expect["topics"]):
            fail(f"topics {sorted(conns)} != expected {sorted(expect['topics'])}")
        for topic, exp in expect["topics"].items():
            conn = conns.get(topic)
            if conn is None:
                continue
            if conn.msgtype != exp["type"]:
                fail(f"{topic}: type {conn.msgtype} != {exp['type']}")
            if "durability" in exp and qos_durability(conn) != exp["durability"]:
                fail(f"{topic}: offered durability {qos_durability(conn)} != {exp['durability']}")
            msgs = []
            for c, t, raw in reader.messages(connections=[conn]):
                msg = reader.deserialize(raw, c.msgtype)
                # Re-encoding with rosbags must give drape's bytes exactly (layout,
                # padding and encapsulation header included).
                again = bytes(reader.typestore.serialize_cdr(msg, c.msgtype))
                if again != bytes(raw):
                    fail(f"{topic}[{len(msgs)}]: rosbags re-serialises {len(again)} bytes "
                         f"differing from the {len(raw)} drape wrote")
                msgs.append((t, msg))
            if len(msgs) != exp["count"]:
                fail(f"{topic}: {len(msgs)} messages != expected {exp['count']}")
            for m in exp.get("messages", []):
                i = int(m["index"])
                if i >= len(msgs):
                    fail(f"{topic}: no message {i}")
                    continue
                t, msg = msgs[i]
                if "log_time" in m and t != m["log_time"]:
                    fail(f"{topic}[{i}]: log time {t} != {m['log_time']}")
                compare(msg, m.get("fields", {}), f"{topic}[{i}]")
                if "cloud" in m:
                    compare(decode_cloud(msg), m["cloud"], f"{topic}[{i}].cloud")
    if errors:
        print(f"{bag}: {len(errors)} mismatches", file=sys.stderr)
        for e in errors[:50]:
            print("  " + e, file=sys.stderr)
        sys.exit(1)
    print(f"{bag}: OK ({len(expect['topics'])} topics)")


if __name__ == "__main__":
    main()
