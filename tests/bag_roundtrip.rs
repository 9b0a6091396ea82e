//! rosbag2 MCAP round trips: drape writes, the independent `rosbags` Python reader and
//! drape's own reader read back; plus a byte-level CDR check and reader/writer errors.
#![cfg(feature = "ros")]

use drape::ros::msg::{
    Clock, ColorRGBA, DiagnosticArray, DiagnosticStatus, Header, JointState, KeyValue, MarkerArray,
    RosString, TFMessage, Time, Transform, TransformStamped, Vector3,
};
use drape::ros::{
    cdr, mesh_marker, offered_qos_profiles, point_cloud, read_joint_states, read_topic, BagError,
    BagWriter, Distro, Durability, Reliability, RosMessage,
};
use drape::Vec3;
use serde::Serialize;
use std::fmt::Write as _;
use std::path::Path;
use std::process::Command;

// ---------- a minimal JSON writer for the Python expectations ----------

enum J {
    Num(f64),
    Bool(bool),
    Str(String),
    Arr(Vec<J>),
    Obj(Vec<(&'static str, J)>),
}

impl J {
    fn render(&self, out: &mut String) {
        match self {
            // `{:?}` prints the shortest decimal that parses back to the same f64.
            J::Num(v) => write!(out, "{v:?}").unwrap(),
            J::Bool(b) => write!(out, "{b}").unwrap(),
            J::Str(s) => write!(out, "{s:?}").unwrap(),
            J::Arr(items) => {
                out.push('[');
                for (i, item) in items.iter().enumerate() {
                    if i > 0 {
                        out.push(',');
                    }
                    item.render(out);
                }
                out.push(']');
            }
            J::Obj(items) => {
                out.push('{');
                for (i, (k, v)) in items.iter().enumerate() {
                    if i > 0 {
                        out.push(',');
                    }
                    write!(out, "{k:?}:").unwrap();
                    v.render(out);
                }
                out.push('}');
            }
        }
    }
}

fn num(v: impl Into<f64>) -> J {
    J::Num(v.into())
}

fn s(v: &str) -> J {
    J::Str(v.to_string())
}

// ---------- test data ----------

/// A 3x3 grid with irrational-ish coordinates, so f32 rounding shows if it happens.
fn cloth(frame: usize) -> (Vec<Vec3>, Vec<Vec3>, Vec<[u32; 3]>) {
    let n = 3;
    let mut pos = Vec::new();
    let mut nrm = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let x = 0.1 * i as f64 + 0.0137 * frame as f64;
            let y = 0.1 * j as f64 - 1.0 / 3.0;
            let z = (x * 7.0).sin() * 0.05 + 0.7;
            pos.push(Vec3::new(x, y, z));
            nrm.push(Vec3::new(-0.3 * x, 0.2, 1.0).normalize());
        }
    }
    let mut tris = Vec::new();
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            let a = (j * n + i) as u32;
            tris.push([a, a + 1, a + n as u32]);
            tris.push([a + 1, a + n as u32 + 1, a + n as u32]);
        }
    }
    (pos, nrm, tris)
}

fn joint_state(k: usize) -> JointState {
    JointState {
        header: Header::new(Time::from_nanos(k as u64 * 10_000_000), ""),
        name: vec!["panda_joint1".into(), "panda_joint2".into()],
        position: vec![0.1 * k as f64, -0.785 + 1e-3 * k as f64],
        velocity: vec![],
        effort: vec![],
    }
}

const COLOR: ColorRGBA = ColorRGBA {
    r: 0.9,
    g: 0.35,
    b: 0.1,
    a: 1.0,
};

struct Expect {
    topics: Vec<(&'static str, J)>,
}

impl Expect {
    fn topic(&mut self, name: &'static str, ty: &str, count: usize, extra: Vec<(&'static str, J)>) {
        let mut o = vec![("type", s(ty)), ("count", num(count as f64))];
        o.extend(extra);
        self.topics.push((name, J::Obj(o)));
    }
}

/// Writes a bag with every message kind for `distro`; returns the expectations.
fn write_sample_bag(path: &Path, distro: Distro) -> String {
    let mut bag = BagWriter::create(path).unwrap();
    let marker_t = bag
        .add_topic::<drape::ros::msg::Marker>("/cloth/marker", distro, None)
        .unwrap();
    let array_t = bag
        .add_topic::<MarkerArray>("/cloth/markers", distro, None)
        .unwrap();
    let cloud_t = bag
        .add_topic::<drape::ros::msg::PointCloud2>(
            "/cloth/points",
            distro,
            Some(&offered_qos_profiles(
                Reliability::BestEffort,
                Durability::Volatile,
            )),
        )
        .unwrap();
    let joints_t = bag
        .add_topic::<JointState>("/joint_states", distro, None)
        .unwrap();
    let tf_t = bag.add_topic::<TFMessage>("/tf", distro, None).unwrap();
    let latched = offered_qos_profiles(Reliability::Reliable, Durability::TransientLocal);
    let desc_t = bag
        .add_topic::<RosString>("/robot_description", distro, Some(&latched))
        .unwrap();
    let clock_t = bag.add_topic::<Clock>("/clock", distro, None).unwrap();
    let diag_t = bag
        .add_topic::<DiagnosticArray>("/diagnostics", distro, None)
        .unwrap();

    let mut marker_msgs = Vec::new();
    let mut cloud_msgs = Vec::new();
    for frame in 0..2 {
        let t_ns = 1_000_000_000 + frame as u64 * 33_333_333;
        let stamp = Time::from_nanos(t_ns);
        let (pos, nrm, tris) = cloth(frame);
        let marker = mesh_marker(distro, stamp, "world", "cloth", &pos, &tris, COLOR);
        bag.write(marker_t, t_ns, &marker).unwrap();
        bag.write(
            array_t,
            t_ns,
            &MarkerArray {
                markers: vec![marker.clone(), marker],
            },
        )
        .unwrap();
        bag.write(cloud_t, t_ns, &point_cloud(stamp, "world", &pos, &nrm))
            .unwrap();

        let points: Vec<J> = tris
            .iter()
            .flatten()
            .map(|&i| {
                let p = pos[i as usize];
                J::Obj(vec![("x", num(p.x)), ("y", num(p.y)), ("z", num(p.z))])
            })
            .collect();
        marker_msgs.push(J::Obj(vec![
            ("index", num(frame as f64)),
            ("log_time", num(t_ns as f64)),
            (
                "fields",
                J::Obj(vec![
                    (
                        "header",
                        J::Obj(vec![
                            ("frame_id", s("world")),
                            (
                                "stamp",
                                J::Obj(vec![("sec", num(1)), ("nanosec", num(stamp.nanosec))]),
                            ),
                        ]),
                    ),
                    ("ns", s("cloth")),
                    ("type", num(11)),
                    ("action", num(0)),
                    ("frame_locked", J::Bool(false)),
                    (
                        "scale",
                        J::Obj(vec![("x", num(1)), ("y", num(1)), ("z", num(1))]),
                    ),
                    (
                        "pose",
                        J::Obj(vec![(
                            "orientation",
                            J::Obj(vec![("w", num(1)), ("x", num(0))]),
                        )]),
                    ),
                    (
                        "color",
                        J::Obj(vec![
                            ("r", num(COLOR.r)),
                            ("g", num(COLOR.g)),
                            ("b", num(COLOR.b)),
                            ("a", num(COLOR.a)),
                        ]),
                    ),
                    ("points", J::Arr(points)),
                    ("mesh_use_embedded_materials", J::Bool(false)),
                ]),
            ),
        ]));
        let cloud_pts: Vec<J> = pos
            .iter()
            .zip(&nrm)
            .map(|(p, n)| {
                J::Arr(
                    [p.x, p.y, p.z, n.x, n.y, n.z]
                        .iter()
                        .map(|&v| num(v as f32))
                        .collect(),
                )
            })
            .collect();
        let field_names = ["x", "y", "z", "normal_x", "normal_y", "normal_z"];
        cloud_msgs.push(J::Obj(vec![
            ("index", num(frame as f64)),
            (
                "fields",
                J::Obj(vec![
                    ("width", num(9)),
                    ("height", num(1)),
                    ("point_step", num(24)),
                    ("row_step", num(216)),
                    ("is_dense", J::Bool(true)),
                    ("is_bigendian", J::Bool(false)),
                    (
                        "fields",
                        J::Arr(
                            field_names
                                .iter()
                                .enumerate()
                                .map(|(k, n)| {
                                    J::Obj(vec![
                                        ("name", s(n)),
                                        ("offset", num(4 * k as u32)),
                                        ("datatype", num(7)),
                                        ("count", num(1)),
                                    ])
                                })
                                .collect(),
                        ),
                    ),
                ]),
            ),
            ("cloud", J::Arr(cloud_pts)),
        ]));
    }
    for k in 0..3 {
        bag.write(joints_t, 2_000_000_000 + k as u64, &joint_state(k))
            .unwrap();
    }
    let tf = TFMessage {
        transforms: vec![TransformStamped {
            header: Header::new(Time::from_nanos(1_500_000_000), "world"),
            child_frame_id: "panda_link0".into(),
            transform: Transform {
                translation: Vector3 {
                    x: 0.25,
                    y: -0.125,
                    z: 1.0 / 3.0,
                },
                rotation: glam::DQuat::from_rotation_z(0.3).into(),
            },
        }],
    };
    bag.write(tf_t, 1_500_000_000, &tf).unwrap();
    let urdf = "<robot name=\"r\"><link name=\"base\"/></robot>";
    bag.write(desc_t, 1_000_000_000, &RosString { data: urdf.into() })
        .unwrap();
    bag.write(
        clock_t,
        1_000_000_000,
        &Clock {
            clock: Time::from_nanos(1_000_000_000),
        },
    )
    .unwrap();
    let diag = DiagnosticArray {
        header: Header::new(Time::from_nanos(1_000_000_000), ""),
        status: vec![DiagnosticStatus {
            level: DiagnosticStatus::WARN,
            name: "drape: solver".into(),
            message: "slow step".into(),
            hardware_id: "".into(),
            values: vec![KeyValue {
                key: "step_ms".into(),
                value: "41.5".into(),
            }],
        }],
    };
    bag.write(diag_t, 1_000_000_000, &diag).unwrap();
    bag.finish().unwrap();

    let q = glam::DQuat::from_rotation_z(0.3);
    let mut e = Expect { topics: Vec::new() };
    e.topic(
        "/cloth/marker",
        "visualization_msgs/msg/Marker",
        2,
        vec![("messages", J::Arr(marker_msgs))],
    );
    e.topic(
        "/cloth/markers",
        "visualization_msgs/msg/MarkerArray",
        2,
        vec![],
    );
    e.topic(
        "/cloth/points",
        "sensor_msgs/msg/PointCloud2",
        2,
        vec![("durability", num(2)), ("messages", J::Arr(cloud_msgs))],
    );
    let joints: Vec<J> = (0..3)
        .map(|k| {
            let js = joint_state(k);
            J::Obj(vec![
                ("index", num(k as f64)),
                ("log_time", num(2_000_000_000.0 + k as f64)),
                (
                    "fields",
                    J::Obj(vec![
                        ("name", J::Arr(js.name.iter().map(|n| s(n)).collect())),
                        (
                            "position",
                            J::Arr(js.position.iter().map(|&p| num(p)).collect()),
                        ),
                        ("velocity", J::Arr(vec![])),
                    ]),
                ),
            ])
        })
        .collect();
    e.topic(
        "/joint_states",
        "sensor_msgs/msg/JointState",
        3,
        vec![("messages", J::Arr(joints))],
    );
    e.topic(
        "/tf",
        "tf2_msgs/msg/TFMessage",
        1,
        vec![(
            "messages",
            J::Arr(vec![J::Obj(vec![
                ("index", num(0)),
                (
                    "fields",
                    J::Obj(vec![(
                        "transforms",
                        J::Arr(vec![J::Obj(vec![
                            ("child_frame_id", s("panda_link0")),
                            (
                                "transform",
                                J::Obj(vec![
                                    (
                                        "translation",
                                        J::Obj(vec![
                                            ("x", num(0.25)),
                                            ("y", num(-0.125)),
                                            ("z", num(1.0 / 3.0)),
                                        ]),
                                    ),
                                    ("rotation", J::Obj(vec![("z", num(q.z)), ("w", num(q.w))])),
                                ]),
                            ),
                        ])]),
                    )]),
                ),
            ])]),
        )],
    );
    e.topic(
        "/robot_description",
        "std_msgs/msg/String",
        1,
        vec![
            ("durability", num(1)),
            (
                "messages",
                J::Arr(vec![J::Obj(vec![
                    ("index", num(0)),
                    ("fields", J::Obj(vec![("data", s(urdf))])),
                ])]),
            ),
        ],
    );
    e.topic(
        "/clock",
        "rosgraph_msgs/msg/Clock",
        1,
        vec![(
            "messages",
            J::Arr(vec![J::Obj(vec![
                ("index", num(0)),
                (
                    "fields",
                    J::Obj(vec![(
                        "clock",
                        J::Obj(vec![("sec", num(1)), ("nanosec", num(0))]),
                    )]),
                ),
            ])]),
        )],
    );
    e.topic(
        "/diagnostics",
        "diagnostic_msgs/msg/DiagnosticArray",
        1,
        vec![(
            "messages",
            J::Arr(vec![J::Obj(vec![
                ("index", num(0)),
                (
                    "fields",
                    J::Obj(vec![(
                        "status",
                        J::Arr(vec![J::Obj(vec![
                            ("level", num(1)),
                            ("name", s("drape: solver")),
                            (
                                "values",
                                J::Arr(vec![J::Obj(vec![
                                    ("key", s("step_ms")),
                                    ("value", s("41.5")),
                                ])]),
                            ),
                        ])]),
                    )]),
                ),
            ])]),
        )],
    );
    let mut out = String::new();
    J::Obj(vec![
        ("distro", s(distro.name())),
        ("topics", J::Obj(e.topics)),
    ])
    .render(&mut out);
    out
}

fn run_check_bag(bag: &Path, expect_json: &str) {
    let dir = bag.parent().unwrap();
    let expect = dir.join(format!(
        "{}.expect.json",
        bag.file_stem().unwrap().to_string_lossy()
    ));
    std::fs::write(&expect, expect_json).unwrap();
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/py/check_bag.py");
    let out = Command::new("python3")
        .arg(&script)
        .arg(bag)
        .arg(&expect)
        .output()
        .expect(
            "python3 must be installed to run tests/py/check_bag.py (then: pip install rosbags)",
        );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_ne!(
        out.status.code(),
        Some(2),
        "rosbags is missing: pip install rosbags\n{stderr}"
    );
    assert!(
        out.status.success(),
        "check_bag.py rejected {}:\n{}{stderr}",
        bag.display(),
        String::from_utf8_lossy(&out.stdout)
    );
}

#[test]
fn rosbags_reads_humble_and_jazzy_bags() {
    let dir = tempfile::tempdir().unwrap();
    for distro in [Distro::Humble, Distro::Jazzy] {
        let bag = dir.path().join(format!("sample_{distro}.mcap"));
        let expect = write_sample_bag(&bag, distro);
        run_check_bag(&bag, &expect);
    }
}

#[test]
fn check_bag_detects_a_wrong_value() {
    // The Python checker must be able to fail: perturb one expected joint position.
    let dir = tempfile::tempdir().unwrap();
    let bag = dir.path().join("sample.mcap");
    let expect = write_sample_bag(&bag, Distro::Jazzy);
    let bad = expect.replacen("\"position\":[0.0,", "\"position\":[1e-9,", 1);
    assert_ne!(bad, expect, "perturbation did not apply");
    std::fs::write(dir.path().join("bad.json"), &bad).unwrap();
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/py/check_bag.py");
    let out = Command::new("python3")
        .arg(&script)
        .arg(&bag)
        .arg(dir.path().join("bad.json"))
        .output()
        .expect("python3");
    assert_eq!(
        out.status.code(),
        Some(1),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(String::from_utf8_lossy(&out.stderr).contains("/joint_states[0].position[0]"));
}

#[test]
fn joint_states_round_trip_through_drape_reader() {
    let dir = tempfile::tempdir().unwrap();
    let bag = dir.path().join("sample.mcap");
    write_sample_bag(&bag, Distro::Humble);
    let read = read_joint_states(&bag).unwrap();
    assert_eq!(read.len(), 3);
    for (k, (t, js)) in read.iter().enumerate() {
        assert_eq!(*t, 2_000_000_000 + k as u64);
        assert_eq!(*js, joint_state(k));
    }
    let tf = read_topic::<TFMessage>(&bag, "/tf").unwrap();
    assert_eq!(tf.messages.len(), 1);
    assert_eq!(tf.messages[0].1.transforms[0].child_frame_id, "panda_link0");
    assert_eq!(tf.skipped, 0);
    assert!(tf.truncated.is_none());
}

#[test]
fn joint_state_cdr_bytes_match_hand_computed() {
    let js = JointState {
        header: Header::new(Time { sec: 1, nanosec: 2 }, ""),
        name: vec!["a".into(), "bc".into()],
        position: vec![1.5],
        velocity: vec![-2.0],
        effort: vec![],
    };
    #[rustfmt::skip]
    let expected: Vec<u8> = [
        &[0x00, 0x01, 0x00, 0x00][..],     // encapsulation: CDR little-endian
        &[1, 0, 0, 0, 2, 0, 0, 0],         // body 0: stamp.sec, 4: stamp.nanosec
        &[1, 0, 0, 0, 0],                  // 8: frame_id length 1 (just NUL), 12: NUL
        &[0, 0, 0],                        // 13: pad to 4
        &[2, 0, 0, 0],                     // 16: name count
        &[2, 0, 0, 0, b'a', 0],            // 20: "a" (len 2 incl. NUL)
        &[0, 0],                           // 26: pad to 4
        &[3, 0, 0, 0, b'b', b'c', 0],      // 28: "bc"
        &[0],                              // 35: pad to 4
        &[1, 0, 0, 0],                     // 36: position count
        &1.5f64.to_le_bytes(),             // 40: already 8-aligned
        &[1, 0, 0, 0],                     // 48: velocity count
        &[0, 0, 0, 0],                     // 52: pad to 8 (relative to body start)
        &(-2.0f64).to_le_bytes(),          // 56
        &[0, 0, 0, 0],                     // 64: effort count
    ]
    .concat();
    let got = cdr::encode(&js).unwrap();
    assert_eq!(got, expected);
    let back: JointState = cdr::decode(&got).unwrap();
    assert_eq!(back, js);
}

/// Serialises as garbage under the JointState name: what a corrupt record looks like.
#[derive(Serialize)]
struct BrokenJointState(u8);

impl RosMessage for BrokenJointState {
    const TYPE_NAME: &'static str = JointState::TYPE_NAME;
    fn definition(distro: Distro) -> String {
        JointState::definition(distro)
    }
}

#[test]
fn malformed_joint_states_are_skipped_and_counted() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("broken.mcap");
    let mut bag = BagWriter::create(&path).unwrap();
    let t = bag
        .add_topic::<JointState>("/joint_states", Distro::Jazzy, None)
        .unwrap();
    bag.write(t, 1, &joint_state(1)).unwrap();
    bag.write(t, 2, &BrokenJointState(7)).unwrap();
    bag.write(t, 3, &joint_state(3)).unwrap();
    bag.finish().unwrap();
    let read = read_topic::<JointState>(&path, "/joint_states").unwrap();
    assert_eq!(read.skipped, 1);
    let times: Vec<u64> = read.messages.iter().map(|m| m.0).collect();
    assert_eq!(times, [1, 3]);
    assert_eq!(read_joint_states(&path).unwrap().len(), 2);
}

#[test]
fn truncated_bag_keeps_flushed_messages() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("crash.mcap");
    let mut bag = BagWriter::create(&path).unwrap();
    let t = bag
        .add_topic::<JointState>("/joint_states", Distro::Jazzy, None)
        .unwrap();
    for k in 0..4 {
        bag.write(t, k, &joint_state(k as usize)).unwrap();
    }
    bag.flush().unwrap();
    // A recorder killed here leaves the file without summary or footer.
    let mut partial = std::fs::read(&path).unwrap();
    bag.write(t, 10, &joint_state(10)).unwrap();
    bag.finish().unwrap();
    partial.extend_from_slice(&[0x06, 0xff, 0xff]); // half a record
    let cut = dir.path().join("cut.mcap");
    std::fs::write(&cut, &partial).unwrap();
    let read = read_topic::<JointState>(&cut, "/joint_states").unwrap();
    assert_eq!(read.messages.len(), 4);
    assert!(read.truncated.is_some());
    assert_eq!(read_joint_states(&path).unwrap().len(), 5);
}

#[test]
fn reader_errors_name_the_culprit() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("nope.mcap");
    let e = read_joint_states(&missing).unwrap_err();
    assert!(matches!(e, BagError::Open { .. }), "{e}");
    assert!(e.to_string().contains("nope.mcap"));

    let text = dir.path().join("notes.mcap");
    std::fs::write(&text, "SQLite format 3\0 not an mcap").unwrap();
    let e = read_joint_states(&text).unwrap_err();
    assert!(matches!(e, BagError::NotMcap { .. }), "{e}");
    assert!(e.to_string().contains("notes.mcap"));

    let other = dir.path().join("other.mcap");
    let mut bag = BagWriter::create(&other).unwrap();
    let t = bag
        .add_topic::<RosString>("/chatter", Distro::Jazzy, None)
        .unwrap();
    bag.write(t, 1, &RosString { data: "hi".into() }).unwrap();
    bag.finish().unwrap();
    let e = read_joint_states(&other).unwrap_err();
    assert!(matches!(e, BagError::NoSuchTopic { .. }), "{e}");
    assert!(
        e.to_string().contains("/chatter") && e.to_string().contains("/joint_states"),
        "{e}"
    );

    let wrong = dir.path().join("wrong.mcap");
    let mut bag = BagWriter::create(&wrong).unwrap();
    let t = bag
        .add_topic::<RosString>("/joint_states", Distro::Jazzy, None)
        .unwrap();
    bag.write(t, 1, &RosString { data: "hi".into() }).unwrap();
    bag.finish().unwrap();
    let e = read_joint_states(&wrong).unwrap_err();
    assert!(matches!(e, BagError::TopicType { .. }), "{e}");
    assert!(e.to_string().contains("std_msgs/msg/String"), "{e}");
}

#[test]
fn writer_rejects_misuse_with_named_culprits() {
    let dir = tempfile::tempdir().unwrap();
    let e = BagWriter::create(dir.path().join("no/such/dir/x.mcap"))
        .err()
        .unwrap();
    assert!(
        matches!(e, BagError::Create { .. }) && e.to_string().contains("no/such/dir/x.mcap"),
        "{e}"
    );

    let mut bag = BagWriter::create(dir.path().join("x.mcap")).unwrap();
    let humble = bag
        .add_topic::<drape::ros::msg::Marker>("/m", Distro::Humble, None)
        .unwrap();
    // Same topic, same layout: same id. Other type or layout: refused.
    assert_eq!(
        bag.add_topic::<drape::ros::msg::Marker>("/m", Distro::Humble, None)
            .unwrap(),
        humble
    );
    assert!(matches!(
        bag.add_topic::<RosString>("/m", Distro::Humble, None),
        Err(BagError::TopicConflict { .. })
    ));
    assert!(matches!(
        bag.add_topic::<drape::ros::msg::Marker>("/m2", Distro::Jazzy, None),
        Err(BagError::MixedLayouts { .. })
    ));
    // JointState has one layout, so any distro may share its schema.
    let js = bag
        .add_topic::<JointState>("/joint_states", Distro::Humble, None)
        .unwrap();
    bag.add_topic::<JointState>("/joint_states2", Distro::Jazzy, None)
        .unwrap();
    let e = bag.write(js, 0, &RosString::default()).unwrap_err();
    assert!(
        matches!(e, BagError::WrongMessageType { .. }) && e.to_string().contains("/joint_states"),
        "{e}"
    );
    let (pos, _, tris) = cloth(0);
    let jazzy_marker = mesh_marker(Distro::Jazzy, Time::default(), "w", "c", &pos, &tris, COLOR);
    let e = bag.write(humble, 0, &jazzy_marker).unwrap_err();
    assert!(matches!(e, BagError::LayoutMismatch { .. }), "{e}");
    let e = bag
        .add_topic::<RosString>(
            "/q",
            Distro::Jazzy,
            Some("- history: keep_last\n  reliability: reliable"),
        )
        .unwrap_err();
    assert!(
        matches!(
            &e,
            BagError::InvalidQos {
                source: drape::ros::qos::QosError::NotInteger { key: "history", .. },
                ..
            }
        ) && e.to_string().contains("/q"),
        "{e}"
    );
}

#[test]
fn dropping_an_unfinished_writer_finishes_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("dropped.mcap");
    {
        let mut bag = BagWriter::create(&path).unwrap();
        let t = bag
            .add_topic::<JointState>("/joint_states", Distro::Jazzy, None)
            .unwrap();
        bag.write(t, 5, &joint_state(0)).unwrap();
    }
    let bytes = std::fs::read(&path).unwrap();
    assert!(bytes.ends_with(b"\x89MCAP0\r\n"), "footer magic missing");
    assert_eq!(read_joint_states(&path).unwrap().len(), 1);
}
