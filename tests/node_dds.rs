//! The node in-process over DDS, inside a private network namespace: a peer node in the same
//! process publishes `/clock` (rosgraph_msgs/msg/Clock), a latched `/robot_description` before
//! the node starts, good and bad joint states, and calls `~/reset`; it checks the points follow
//! sim time, the description was loaded from the topic, bad inputs were dropped and counted, and
//! publishing never stopped.
#![cfg(feature = "ros")]

#[path = "support/netns.rs"]
mod netns;

use drape::ros::msg::{
    Clock, DiagnosticArray, Header, JointState, PointCloud2, RosString, Time, TriggerRequest,
    TriggerResponse,
};
use drape::ros::node::{context, run_node, Network, NodeParams};
use ros2_client::qos::{Durability, History};
use ros2_client::rcl_interfaces::{SetParametersRequest, SetParametersResponse};
use ros2_client::{
    MessageTypeName, Name, NodeName, NodeOptions, Parameter, ParameterValue, QosProfile,
    ServiceMapping, ServiceTypeName,
};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

const CLOCK0: f64 = 50.0;

fn value(d: &DiagnosticArray, key: &str) -> u64 {
    d.status[0]
        .values
        .iter()
        .find(|kv| kv.key == key)
        .and_then(|kv| kv.value.parse().ok())
        .unwrap_or_else(|| panic!("diagnostics without integer {key}"))
}

fn js(names: &[&str], positions: &[f64], stamp: f64) -> JointState {
    JointState {
        header: Header::new(Time::from_nanos((stamp * 1e9) as u64), ""),
        name: names.iter().map(|s| s.to_string()).collect(),
        position: positions.to_vec(),
        ..JointState::default()
    }
}

#[test]
fn node_in_process_sim_time_description_and_bad_inputs() {
    if !netns::enter("node_in_process_sim_time_description_and_bad_inputs") {
        return;
    }
    let root = env!("CARGO_MANIFEST_DIR");
    let urdf = std::fs::read_to_string(format!("{root}/urdf/drape_bot.urdf")).unwrap();
    let urdf = urdf.replacen("name=\"drape_bot\"", "name=\"drape_bot_topic\"", 1);
    assert!(urdf.contains("drape_bot_topic"));

    let ctx = context(Network::default()).expect("peer context");
    let mut peer = ctx
        .new_node(
            NodeName::new("/", "peer").unwrap(),
            NodeOptions::new().enable_rosout(false),
        )
        .unwrap();
    let topic = |peer: &mut ros2_client::Node, name: &str, pkg: &str, ty: &str| {
        peer.create_topic(
            &Name::parse(name).unwrap(),
            MessageTypeName::new(pkg, ty),
            &QosProfile::publisher_default(),
        )
        .unwrap()
    };
    let latched = QosProfile::publisher_default()
        .durability(Durability::TransientLocal)
        .history(History::KeepLast { depth: 1 });
    let t = topic(&mut peer, "/robot_description", "std_msgs", "String");
    let desc = peer
        .create_publisher::<RosString>(&t, Some(latched))
        .unwrap();
    // Published before the node exists: only transient-local durability delivers it.
    desc.publish(RosString { data: urdf }).unwrap();
    let t = topic(&mut peer, "/clock", "rosgraph_msgs", "Clock");
    let clock = peer
        .create_publisher::<Clock>(&t, Some(QosProfile::subscription_default()))
        .unwrap();
    let t = topic(&mut peer, "/joint_states", "sensor_msgs", "JointState");
    // Depth 10 as joint_state_publisher: a depth-1 writer may replace a burst before sending.
    let depth10 = QosProfile::publisher_default().history(History::KeepLast { depth: 10 });
    let joints = peer
        .create_publisher::<JointState>(&t, Some(depth10))
        .unwrap();
    let reliable = QosProfile::publisher_default().history(History::KeepLast { depth: 50 });
    let t = topic(&mut peer, "/drape/points", "sensor_msgs", "PointCloud2");
    let points = peer
        .create_subscription::<PointCloud2>(&t, Some(reliable.clone()))
        .unwrap();
    let t = topic(
        &mut peer,
        "/diagnostics",
        "diagnostic_msgs",
        "DiagnosticArray",
    );
    let diags = peer
        .create_subscription::<DiagnosticArray>(&t, Some(reliable.clone()))
        .unwrap();
    let reset = peer
        .create_client::<TriggerRequest, TriggerResponse>(
            ServiceMapping::Enhanced,
            &Name::parse("/drape/reset").unwrap(),
            &ServiceTypeName::new("std_srvs", "Trigger"),
            reliable.clone(),
            reliable.clone(),
        )
        .unwrap();
    let set_params = peer
        .create_client::<SetParametersRequest, SetParametersResponse>(
            ServiceMapping::Enhanced,
            &Name::parse("/drape/set_parameters").unwrap(),
            &ServiceTypeName::new("rcl_interfaces", "SetParameters"),
            reliable.clone(),
            reliable,
        )
        .unwrap();

    let params = NodeParams {
        scene: format!("{root}/config/robot_towel.yaml").into(),
        robot_description_from_topic: true,
        use_sim_time: true,
        publish_rate: 20.0,
        diagnostics_rate: 2.0,
        ..NodeParams::default()
    };
    let stop = Arc::new(AtomicBool::new(false));
    let flag = stop.clone();
    let node = std::thread::spawn(move || run_node(&params, flag));

    let start = Instant::now();
    let mut sim_t = CLOCK0;
    let mut stamps = Vec::new();
    let mut last_diag = None;
    let mut bad_sent_at = None;
    let mut reset_answer = None;
    let mut reset_sent = Instant::now() - Duration::from_secs(10);
    let arm = ["right_shoulder_pitch", "right_elbow"];
    let mut params_answer = None;
    let mut params_sent = Instant::now() - Duration::from_secs(10);
    let mut paused_reported = false;
    let mut k = 0u64;
    while start.elapsed() < Duration::from_secs(7) {
        k += 1;
        sim_t += 0.01;
        clock
            .publish(Clock {
                clock: Time::from_nanos((sim_t * 1e9) as u64),
            })
            .unwrap();
        if k.is_multiple_of(2) {
            let s = -1.5 + 0.3 * (sim_t - CLOCK0).sin();
            joints.publish(js(&arm, &[s, -0.2], sim_t)).unwrap();
        }
        if k == 300 {
            bad_sent_at = Some(stamps.len());
            joints.publish(js(&arm, &[f64::NAN, 0.0], sim_t)).unwrap();
            joints.publish(js(&arm, &[0.1], sim_t)).unwrap();
            joints.publish(js(&["tail"], &[0.1], sim_t)).unwrap();
        }
        if k > 350 && reset_answer.is_none() && reset_sent.elapsed() > Duration::from_millis(500) {
            reset.send_request(TriggerRequest::default()).unwrap();
            reset_sent = Instant::now();
        }
        while let Ok(Some((_, r))) = reset.receive_response() {
            reset_answer = Some(r);
        }
        // Live parameters through ros2-client's parameter services: pause, and a bad rate.
        if reset_answer.is_some()
            && params_answer.is_none()
            && params_sent.elapsed() > Duration::from_millis(500)
        {
            let set = |name: &str, value| Parameter {
                name: name.into(),
                value,
            };
            let req = SetParametersRequest {
                parameter: vec![
                    set("paused", ParameterValue::Boolean(true)).into(),
                    set("publish_rate", ParameterValue::Double(-5.0)).into(),
                ],
            };
            set_params.send_request(req).unwrap();
            params_sent = Instant::now();
        }
        while let Ok(Some((_, r))) = set_params.receive_response() {
            params_answer = Some(r);
        }
        while let Ok(Some((p, _))) = points.take() {
            assert_eq!(p.header.frame_id, "base_link");
            assert_eq!(p.width, 400);
            stamps.push(p.header.stamp.as_nanos() as f64 * 1e-9);
        }
        while let Ok(Some((d, _))) = diags.take() {
            paused_reported |= d.status[0].message == "paused";
            last_diag = Some(d);
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    let stop_at = Instant::now();
    stop.store(true, Ordering::Relaxed);
    let result = node.join().expect("node thread");
    let shutdown = stop_at.elapsed();
    let summary = result.expect("node ran");
    eprintln!(
        "node: {summary:?}, shut down in {shutdown:?}, {} point clouds",
        stamps.len()
    );

    // Stamps follow /clock: simulated seconds from 50 s, never wall-clock time, increasing.
    assert!(stamps.len() > 40, "only {} point clouds", stamps.len());
    assert!(
        stamps.iter().all(|&s| s >= CLOCK0 && s <= sim_t + 1e-6),
        "{stamps:?}"
    );
    assert!(
        stamps.windows(2).all(|w| w[1] >= w[0]),
        "stamps go back: {stamps:?}"
    );
    let bad_at = bad_sent_at.expect("bad inputs sent");
    assert!(
        stamps.len() > bad_at + 20,
        "publishing stopped after bad inputs"
    );
    let d = last_diag.expect("diagnostics arrived");
    assert_eq!(value(&d, "robot_descriptions_loaded"), 1, "{d:?}");
    assert_eq!(value(&d, "robot_description_failures"), 0);
    assert_eq!(value(&d, "dropped_non_finite"), 1, "{d:?}");
    assert_eq!(value(&d, "dropped_wrong_length"), 1);
    assert_eq!(value(&d, "dropped_unknown_joint"), 1);
    assert!(value(&d, "joint_states") > 100);
    let r = reset_answer.expect("~/reset answered");
    assert!(r.success, "{r:?}");
    assert!(value(&d, "resets") >= 1);
    let p = params_answer.expect("set_parameters answered");
    let ok: Vec<bool> = p.results.iter().map(|r| r.successful).collect();
    assert_eq!(
        ok,
        [true, false],
        "paused accepted, negative rate rejected: {p:?}"
    );
    assert!(paused_reported, "diagnostics never said paused");
    assert!(
        shutdown < Duration::from_secs(5),
        "shutdown took {shutdown:?}"
    );
}
