#!/usr/bin/env python3
"""Summarise a rosbag2 MCAP file with the independent `rosbags` reader, as JSON on stdout.

usage: summarize_bag.py BAG

For every topic: type, message count, first and last log time (ns). For the last message of
each sensor_msgs/msg/PointCloud2 topic: width, point_step, field names and the decoded xyz of
every point; for visualization_msgs/msg/Marker: type, number of points, colour, frame id and
the first three points. Exit 2 when rosbags is missing, 1 when the file cannot be read.
"""
import json
import sys
from pathlib import Path

try:
    import numpy as np
    from rosbags.highlevel import AnyReader
except ImportError as exc:
    print(f"rosbags is not importable ({exc}): pip install rosbags", file=sys.stderr)
    sys.exit(2)


def main(path):
    out = {}
    with AnyReader([Path(path)]) as reader:
        for conn in reader.connections:
            out[conn.topic] = {"type": conn.msgtype, "count": 0, "first": None, "last": None}
        for conn, t, raw in reader.messages():
            info = out[conn.topic]
            info["count"] += 1
            info["first"] = t if info["first"] is None else info["first"]
            info["last"] = t
            msg = reader.deserialize(raw, conn.msgtype)
            if conn.msgtype == "sensor_msgs/msg/PointCloud2":
                data = np.frombuffer(bytes(msg.data), dtype="<f4").reshape(-1, msg.point_step // 4)
                info["width"] = int(msg.width)
                info["point_step"] = int(msg.point_step)
                info["fields"] = [f.name for f in msg.fields]
                info["frame_id"] = msg.header.frame_id
                info["stamp"] = int(msg.header.stamp.sec) * 1_000_000_000 + int(msg.header.stamp.nanosec)
                info["xyz"] = data[:, :3].astype(float).tolist()
                info["finite"] = bool(np.isfinite(data).all())
            elif conn.msgtype == "visualization_msgs/msg/Marker":
                info["marker_type"] = int(msg.type)
                info["points"] = len(msg.points)
                info["color"] = [msg.color.r, msg.color.g, msg.color.b, msg.color.a]
                info["frame_id"] = msg.header.frame_id
                info["first_points"] = [[p.x, p.y, p.z] for p in msg.points[:3]]
    json.dump(out, sys.stdout)


if __name__ == "__main__":
    try:
        main(sys.argv[1])
    except Exception as exc:  # report, do not trace back: the Rust test prints this
        print(f"cannot read {sys.argv[1]}: {exc!r}", file=sys.stderr)
        sys.exit(1)
