//! The node's DDS endpoints: the participant ([`context`]), topic names ([`resolve_topic`]),
//! the QoS profiles, and every subscription, publisher and service the node opens
//! ([`endpoints`]), each failure naming the endpoint.

use super::network::Network;
use super::params::{NodeParams, ServiceWire};
use super::NodeError;
use crate::ros::msg::{
    Clock, DiagnosticArray, JointState, Marker, MarkerArray, PointCloud2, RosString,
    TriggerRequest, TriggerResponse,
};
use ros2_client::dds::rustdds;
use ros2_client::qos::{Durability, History, Reliability, WhenFull};
use ros2_client::{
    Context, MessageTypeName, Name, Node, Publisher, QosProfile, Server, ServiceMapping,
    ServiceTypeName, Subscription,
};
use std::time::Duration;

/// The node's subscriptions, publishers and services.
/// Resolves a topic name: `~/x` is private to the node (`/<ns>/<node>/x`), `/x` absolute,
/// anything else relative to the namespace.
pub fn resolve_topic(topic: &str, namespace: &str, node: &str) -> Result<Name, NodeError> {
    let full = match topic.strip_prefix("~/") {
        Some(rest) => format!("{}/{node}/{rest}", namespace.trim_end_matches('/')),
        None => topic.to_string(),
    };
    Name::parse(&full).map_err(|source| NodeError::Topic {
        topic: topic.to_string(),
        resolved: full.clone(),
        source,
    })
}

/// A DDS participant for `net`: on `domain_id`, restricted to loopback when localhost-only.
pub fn context(net: Network) -> Result<Context, NodeError> {
    let mut b = rustdds::DomainParticipantBuilder::new(net.domain_id);
    if net.localhost_only {
        b = b.with_only_networks([std::net::Ipv4Addr::LOCALHOST]);
    }
    let dp = b.build().map_err(|source| NodeError::Participant {
        domain_id: net.domain_id,
        source,
    })?;
    Context::from_domain_participant(dp).map_err(NodeError::Context)
}

fn qos_sensor(depth: usize) -> QosProfile {
    QosProfile::subscription_default().history(History::KeepLast { depth })
}

fn qos_reliable(depth: usize) -> QosProfile {
    QosProfile::publisher_default()
        .reliability(Reliability::Reliable {
            when_full: WhenFull::Wait(Duration::from_millis(10)),
        })
        .history(History::KeepLast { depth })
}

fn qos_latched() -> QosProfile {
    qos_reliable(1).durability(Durability::TransientLocal)
}

pub struct Endpoints {
    pub joint_states: Subscription<JointState>,
    pub description: Option<Subscription<RosString>>,
    pub clock: Option<Subscription<Clock>>,
    pub mesh: Publisher<Marker>,
    pub points: Publisher<PointCloud2>,
    pub obstacles: Publisher<MarkerArray>,
    pub diagnostics: Publisher<DiagnosticArray>,
    pub reset: Server<TriggerRequest, TriggerResponse>,
    pub pause: Server<TriggerRequest, TriggerResponse>,
    pub resume: Server<TriggerRequest, TriggerResponse>,
}

pub fn endpoints(node: &mut Node, p: &NodeParams) -> Result<Endpoints, NodeError> {
    let (ns, name) = (p.namespace.as_str(), p.name.as_str());
    let topic = |t: &str| resolve_topic(t, ns, name);
    let dds = |what: &str, source: ros2_client::CreateError| NodeError::Endpoint {
        endpoint: what.to_string(),
        source,
    };
    let t = &p.topics;
    let mk_topic = |node: &mut Node, n: &str, pkg: &str, ty: &str, q: &QosProfile| {
        node.create_topic(&topic(n)?, MessageTypeName::new(pkg, ty), q)
            .map_err(|e| dds(n, e))
    };
    let js_t = mk_topic(
        node,
        &t.joint_states,
        "sensor_msgs",
        "JointState",
        &qos_sensor(10),
    )?;
    let joint_states = node
        .create_subscription(&js_t, Some(qos_sensor(10)))
        .map_err(|e| dds(&t.joint_states, e))?;
    let description = if p.robot_description_from_topic {
        let tt = mk_topic(
            node,
            &t.robot_description,
            "std_msgs",
            "String",
            &qos_latched(),
        )?;
        Some(
            node.create_subscription(&tt, Some(qos_latched()))
                .map_err(|e| dds(&t.robot_description, e))?,
        )
    } else {
        None
    };
    let clock = if p.use_sim_time {
        let ct = mk_topic(node, &t.clock, "rosgraph_msgs", "Clock", &qos_sensor(1))?;
        Some(
            node.create_subscription(&ct, Some(qos_sensor(1)))
                .map_err(|e| dds(&t.clock, e))?,
        )
    } else {
        None
    };
    let frames = qos_reliable(1);
    let mt = mk_topic(node, &t.mesh, "visualization_msgs", "Marker", &frames)?;
    let pt = mk_topic(node, &t.points, "sensor_msgs", "PointCloud2", &frames)?;
    let ot = mk_topic(
        node,
        &t.obstacles,
        "visualization_msgs",
        "MarkerArray",
        &frames,
    )?;
    let dt = mk_topic(
        node,
        &t.diagnostics,
        "diagnostic_msgs",
        "DiagnosticArray",
        &qos_reliable(10),
    )?;
    let mapping = match p.service_wire {
        ServiceWire::Enhanced => ServiceMapping::Enhanced,
        ServiceWire::Cyclone => ServiceMapping::Cyclone,
    };
    let svc_qos = qos_reliable(10);
    let server = |node: &mut Node, n: &str| {
        node.create_server(
            mapping,
            &topic(n)?,
            &ServiceTypeName::new("std_srvs", "Trigger"),
            svc_qos.clone(),
            svc_qos.clone(),
        )
        .map_err(|e| dds(n, e))
    };
    Ok(Endpoints {
        joint_states,
        description,
        clock,
        mesh: node
            .create_publisher(&mt, None)
            .map_err(|e| dds("mesh", e))?,
        points: node
            .create_publisher(&pt, None)
            .map_err(|e| dds("points", e))?,
        obstacles: node
            .create_publisher(&ot, None)
            .map_err(|e| dds("obstacles", e))?,
        diagnostics: node
            .create_publisher(&dt, None)
            .map_err(|e| dds("diagnostics", e))?,
        reset: server(node, "~/reset")?,
        pause: server(node, "~/pause")?,
        resume: server(node, "~/resume")?,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use ros2_client::NodeName;

    #[test]
    fn tilde_topics_resolve_under_the_node() {
        let n = NodeName::new("/", "drape").unwrap();
        let dds = |t: &str, ns: &str| {
            resolve_topic(t, ns, "drape")
                .unwrap()
                .to_dds_name("rt", &n, "")
        };
        assert_eq!(dds("~/mesh", "/"), "rt/drape/mesh");
        assert_eq!(dds("~/mesh", "/robot1"), "rt/robot1/drape/mesh");
        assert_eq!(dds("/joint_states", "/robot1"), "rt/joint_states");
        assert!(resolve_topic("~/", "/", "drape").is_err());
        assert!(resolve_topic("bad topic", "/", "drape").is_err());
    }
}
