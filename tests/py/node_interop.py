#!/usr/bin/env python3
"""Interop peer for `drape node` on Eclipse Cyclone DDS (a different DDS implementation than
the node's RustDDS). Run inside the same private network namespace as the node
(tests/node_interop.rs does both).

Publishes /joint_states that swing drape_bot's right arm, and checks that the node
  * publishes ~/mesh (visualization_msgs/Marker, Jazzy layout) and ~/points
    (sensor_msgs/PointCloud2) at the configured rate (within 10 %),
  * moves the cloth as the joints move (vertex positions change),
  * publishes ~/obstacles and /diagnostics,
  * drops a joint state naming an unknown joint, warns on /rosout and counts it,
  * answers ~/reset (std_srvs/Trigger, rmw_cyclonedds request header).
Exit status 0 on success; the failures are printed.
"""

import argparse
import math
import os
import struct
import sys
import time
from dataclasses import dataclass

from cyclonedds.core import Qos, Policy
from cyclonedds.domain import DomainParticipant
from cyclonedds.idl import IdlStruct
from cyclonedds.idl.types import float32, float64, int32, int64, sequence, uint8, uint32, uint64
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.util import duration


@dataclass
class Time(IdlStruct, typename="builtin_interfaces::msg::dds_::Time_"):
    sec: int32
    nanosec: uint32


@dataclass
class Duration(IdlStruct, typename="builtin_interfaces::msg::dds_::Duration_"):
    sec: int32
    nanosec: uint32


@dataclass
class Header(IdlStruct, typename="std_msgs::msg::dds_::Header_"):
    stamp: Time
    frame_id: str


@dataclass
class JointState(IdlStruct, typename="sensor_msgs::msg::dds_::JointState_"):
    header: Header
    name: sequence[str]
    position: sequence[float64]
    velocity: sequence[float64]
    effort: sequence[float64]


@dataclass
class PointField(IdlStruct, typename="sensor_msgs::msg::dds_::PointField_"):
    name: str
    offset: uint32
    datatype: uint8
    count: uint32


@dataclass
class PointCloud2(IdlStruct, typename="sensor_msgs::msg::dds_::PointCloud2_"):
    header: Header
    height: uint32
    width: uint32
    fields: sequence[PointField]
    is_bigendian: bool
    point_step: uint32
    row_step: uint32
    data: sequence[uint8]
    is_dense: bool


@dataclass
class Point(IdlStruct, typename="geometry_msgs::msg::dds_::Point_"):
    x: float64
    y: float64
    z: float64


@dataclass
class Vector3(IdlStruct, typename="geometry_msgs::msg::dds_::Vector3_"):
    x: float64
    y: float64
    z: float64


@dataclass
class Quaternion(IdlStruct, typename="geometry_msgs::msg::dds_::Quaternion_"):
    x: float64
    y: float64
    z: float64
    w: float64


@dataclass
class Pose(IdlStruct, typename="geometry_msgs::msg::dds_::Pose_"):
    position: Point
    orientation: Quaternion


@dataclass
class ColorRGBA(IdlStruct, typename="std_msgs::msg::dds_::ColorRGBA_"):
    r: float32
    g: float32
    b: float32
    a: float32


@dataclass
class CompressedImage(IdlStruct, typename="sensor_msgs::msg::dds_::CompressedImage_"):
    header: Header
    format: str
    data: sequence[uint8]


@dataclass
class UVCoordinate(IdlStruct, typename="visualization_msgs::msg::dds_::UVCoordinate_"):
    u: float32
    v: float32


@dataclass
class MeshFile(IdlStruct, typename="visualization_msgs::msg::dds_::MeshFile_"):
    filename: str
    data: sequence[uint8]


@dataclass
class Marker(IdlStruct, typename="visualization_msgs::msg::dds_::Marker_"):
    """Jazzy layout."""
    header: Header
    ns: str
    id: int32
    type: int32
    action: int32
    pose: Pose
    scale: Vector3
    color: ColorRGBA
    lifetime: Duration
    frame_locked: bool
    points: sequence[Point]
    colors: sequence[ColorRGBA]
    texture_resource: str
    texture: CompressedImage
    uv_coordinates: sequence[UVCoordinate]
    text: str
    mesh_resource: str
    mesh_file: MeshFile
    mesh_use_embedded_materials: bool


@dataclass
class KeyValue(IdlStruct, typename="diagnostic_msgs::msg::dds_::KeyValue_"):
    key: str
    value: str


@dataclass
class DiagnosticStatus(IdlStruct, typename="diagnostic_msgs::msg::dds_::DiagnosticStatus_"):
    level: uint8
    name: str
    message: str
    hardware_id: str
    values: sequence[KeyValue]


@dataclass
class DiagnosticArray(IdlStruct, typename="diagnostic_msgs::msg::dds_::DiagnosticArray_"):
    header: Header
    status: sequence[DiagnosticStatus]


@dataclass
class Log(IdlStruct, typename="rcl_interfaces::msg::dds_::Log_"):
    stamp: Time
    level: uint8
    name: str
    msg: str
    file: str
    function: str
    line: uint32


@dataclass
class MarkerArray(IdlStruct, typename="visualization_msgs::msg::dds_::MarkerArray_"):
    markers: sequence[Marker]


# rmw_cyclonedds puts a (client guid, sequence number) header in front of request and reply.
@dataclass
class TriggerRequest(IdlStruct, typename="std_srvs::srv::dds_::Trigger_Request_"):
    client_guid: uint64
    seq: int64
    structure_needs_at_least_one_member: uint8


@dataclass
class TriggerResponse(IdlStruct, typename="std_srvs::srv::dds_::Trigger_Response_"):
    client_guid: uint64
    seq: int64
    success: bool
    message: str


def vertices(cloud):
    data = bytes(cloud.data)
    step = cloud.point_step
    return [struct.unpack_from("<fff", data, i * step) for i in range(cloud.width)]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--rate", type=float, default=30.0, help="configured publish rate (Hz)")
    ap.add_argument("--seconds", type=float, default=4.0, help="measurement window (s)")
    ap.add_argument("--node", default="drape")
    ap.add_argument("--timeout", type=float, default=30.0, help="wait for the node (s)")
    args = ap.parse_args()

    dp = DomainParticipant(int(os.environ.get("ROS_DOMAIN_ID", "0") or 0))
    reliable = Qos(Policy.Reliability.Reliable(max_blocking_time=duration(milliseconds=100)),
                   Policy.History.KeepLast(10))
    # Deep enough that a slow Python loop does not lose samples it has not taken yet.
    sensor = Qos(Policy.Reliability.BestEffort, Policy.History.KeepLast(30))
    js_w = DataWriter(dp, Topic(dp, "rt/joint_states", JointState), qos=reliable)
    mesh_r = DataReader(dp, Topic(dp, f"rt/{args.node}/mesh", Marker), qos=sensor)
    pts_r = DataReader(dp, Topic(dp, f"rt/{args.node}/points", PointCloud2), qos=sensor)
    obst_r = DataReader(dp, Topic(dp, f"rt/{args.node}/obstacles", MarkerArray), qos=sensor)
    log_r = DataReader(dp, Topic(dp, "rt/rosout", Log),
                       qos=Qos(Policy.Reliability.BestEffort, Policy.History.KeepLast(100)))
    diag_r = DataReader(dp, Topic(dp, "rt/diagnostics", DiagnosticArray), qos=reliable)
    rq_w = DataWriter(dp, Topic(dp, f"rq/{args.node}/resetRequest", TriggerRequest), qos=reliable)
    rr_r = DataReader(dp, Topic(dp, f"rr/{args.node}/resetReply", TriggerResponse), qos=reliable)

    failures = []
    names = ["right_shoulder_pitch", "right_elbow", "right_wrist"]
    t0 = time.monotonic()

    def publish_joints():
        t = time.monotonic() - t0
        s = -1.5 + 0.5 * math.sin(2.0 * t)
        now = time.time()
        stamp = Time(sec=int(now), nanosec=int((now % 1.0) * 1e9))
        js_w.write(JointState(header=Header(stamp=stamp, frame_id=""), name=names,
                              position=[s, -0.2, 0.3 * math.sin(3.0 * t)], velocity=[], effort=[]))

    # Wait for the node: joint states flow meanwhile so the arm moves from the start.
    first_cloud = None
    while first_cloud is None:
        if time.monotonic() - t0 > args.timeout:
            print(f"FAIL: no ~/points within {args.timeout} s", file=sys.stderr)
            return 1
        publish_joints()
        for s in pts_r.take(N=100):
            if isinstance(s, PointCloud2):
                first_cloud = s
        time.sleep(0.02)
    print(f"node up after {time.monotonic() - t0:.2f} s; frame {first_cloud.header.frame_id}, "
          f"{first_cloud.width} points")
    # Warm up (discovery of every endpoint), then drain.
    warm = time.monotonic() + 1.0
    while time.monotonic() < warm:
        publish_joints()
        mesh_r.take(N=100)
        pts_r.take(N=100)
        time.sleep(0.02)

    n_mesh = n_pts = 0
    obstacles = []
    diags = []
    clouds = []
    mesh_sizes = set()
    start = time.monotonic()
    next_js = start
    while time.monotonic() - start < args.seconds:
        now = time.monotonic()
        if now >= next_js:
            publish_joints()
            next_js += 0.02
        for s in mesh_r.take(N=100):
            if isinstance(s, Marker):
                n_mesh += 1
                mesh_sizes.add(len(s.points))
                if s.type != 11:
                    failures.append(f"mesh Marker type {s.type}, expected TRIANGLE_LIST (11)")
        for s in pts_r.take(N=100):
            if isinstance(s, PointCloud2):
                n_pts += 1
                if len(clouds) < 2 or n_pts % 10 == 0:
                    clouds.append(vertices(s))
        for s in diag_r.take(N=100):
            if isinstance(s, DiagnosticArray):
                diags.append(s)
        for s in obst_r.take(N=100):
            if isinstance(s, MarkerArray):
                obstacles.append(s)
        time.sleep(0.002)
    elapsed = time.monotonic() - start
    mesh_rate, pts_rate = n_mesh / elapsed, n_pts / elapsed
    print(f"~/mesh {mesh_rate:.1f} Hz, ~/points {pts_rate:.1f} Hz over {elapsed:.2f} s "
          f"(configured {args.rate} Hz); mesh sizes {sorted(mesh_sizes)}; {len(diags)} diagnostics")
    for what, r in (("~/mesh", mesh_rate), ("~/points", pts_rate)):
        if abs(r - args.rate) > 0.1 * args.rate:
            failures.append(f"{what} at {r:.1f} Hz, not within 10 % of {args.rate} Hz")

    moved = 0.0
    if len(clouds) >= 2:
        a = clouds[0]
        for b in clouds[1:]:
            moved = max(moved, max(math.dist(p, q) for p, q in zip(a, b)))
    print(f"largest vertex displacement while the arm swings: {moved:.3f} m")
    if moved < 0.05:
        failures.append(f"cloth barely moved ({moved:.3f} m) while the joints moved")

    if not obstacles:
        failures.append("no ~/obstacles")
    else:
        kinds = sorted({m.type for m in obstacles[-1].markers})
        print(f"~/obstacles: {len(obstacles[-1].markers)} markers of types {kinds}")
        if not obstacles[-1].markers:
            failures.append("~/obstacles is empty for a robot scene")

    if not diags:
        failures.append("no /diagnostics")
    else:
        st = diags[-1].status[0]
        kv = {k.key: k.value for k in st.values}
        print(f"diagnostics: {st.name}: {st.message}; rtf {kv.get('real_time_factor')}, "
              f"joint states {kv.get('joint_states')}, dropped {kv.get('dropped_joint_states')}")
        if int(kv.get("joint_states", "0")) == 0:
            failures.append("diagnostics count no joint states: /joint_states did not arrive")

    # A joint the robot does not have: dropped, warned about on /rosout, counted in /diagnostics.
    now = time.time()
    stamp = Time(sec=int(now), nanosec=int((now % 1.0) * 1e9))
    js_w.write(JointState(header=Header(stamp=stamp, frame_id=""), name=["tail_joint"],
                          position=[0.1], velocity=[], effort=[]))
    warned = None
    counted = False
    deadline = time.monotonic() + 4.0
    while (warned is None or not counted) and time.monotonic() < deadline:
        for s in log_r.take(N=100):
            if isinstance(s, Log) and "tail_joint" in s.msg:
                warned = s
        for s in diag_r.take(N=100):
            if isinstance(s, DiagnosticArray):
                kv = {k.key: k.value for k in s.status[0].values}
                counted |= int(kv.get("dropped_unknown_joint", "0")) >= 1
        time.sleep(0.01)
    if warned is None:
        failures.append("no /rosout warning about the unknown joint")
    else:
        print(f"/rosout [{warned.level}] {warned.name}: {warned.msg}")
    if not counted:
        failures.append("/diagnostics did not count the dropped joint state")

    # ~/reset: resend until answered (the reply reader may still be matching).
    answer = None
    deadline = time.monotonic() + 10.0
    seq = 0
    while answer is None and time.monotonic() < deadline:
        seq += 1
        rq_w.write(TriggerRequest(client_guid=0x1234, seq=seq, structure_needs_at_least_one_member=0))
        wait = time.monotonic() + 0.5
        while answer is None and time.monotonic() < wait:
            for s in rr_r.take(N=10):
                if isinstance(s, TriggerResponse) and s.client_guid == 0x1234:
                    answer = s
            time.sleep(0.01)
    if answer is None:
        failures.append("~/reset did not answer")
    else:
        print(f"~/reset: success={answer.success} message={answer.message!r}")
        if not answer.success:
            failures.append(f"~/reset failed: {answer.message}")

    for f in failures:
        print(f"FAIL: {f}", file=sys.stderr)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
