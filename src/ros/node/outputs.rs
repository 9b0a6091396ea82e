//! Messages the node publishes besides the cloth: `/diagnostics` and the obstacle markers.
//! Pure functions of the simulation state.

use super::messages::LoopStats;
use super::quality::QualityStatus;
use crate::robot::{Geometry, RobotDriver};
use crate::ros::msg::{
    ColorRGBA, DiagnosticArray, DiagnosticStatus, Distro, Header, KeyValue, Marker, MarkerArray,
    Point, Pose, Time, Vector3,
};
use crate::ros::telemetry::FrameQuality;

/// What one diagnostics message reports.
#[derive(Debug, Clone)]
pub struct DiagnosticsInput<'a> {
    pub name: &'a str,
    pub stamp: Time,
    pub paused: bool,
    /// Simulated over clock seconds in the window; `None` while paused or with no clock time.
    pub real_time_factor: Option<f64>,
    pub step_time_mean: f64,
    pub step_time_max: f64,
    /// The simulation's metrics over the window's steps, written as the recordings write them
    /// ([`crate::ros::telemetry::METRICS`]); its `max_edge_stretch` is the largest over the
    /// steps, so a state the guard kept at its deepest subdivision shows there.
    pub sim: &'a FrameQuality,
    pub stats: &'a LoopStats,
    pub dropped_steps: u64,
    /// Joint states dropped during the window.
    pub new_drops: u64,
    pub new_divergences: u64,
    /// The quality the loop runs at (adaptive or fixed).
    pub quality: QualityStatus,
}

/// Below this real-time factor the status is WARN.
pub const SLOW_RTF: f64 = 0.9;

/// One `DiagnosticStatus` named `<name>: simulation`: ERROR after a divergence in the window,
/// WARN when the cloth is tangled (self-intersecting, or pairs the fail-safe gave up on), when
/// held cloth is inside an obstacle, when real time cannot be held even at the lowest allowed quality, when slower than real
/// time or when inputs were dropped, else OK (saying so when quality is reduced).
pub fn diagnostics(d: &DiagnosticsInput) -> DiagnosticArray {
    let q = d.sim;
    let (level, message) = if d.new_divergences > 0 {
        (
            DiagnosticStatus::ERROR,
            format!("{} divergence(s): cloth restored", d.new_divergences),
        )
    } else if q.unresolved_contacts > 0 || q.self_intersections.is_some_and(|n| n > 0) {
        (
            DiagnosticStatus::WARN,
            format!(
                "cloth tangled: {} self-intersecting triangle pair(s), {} cloth-cloth pair(s) \
                 the collision fail-safe could not resolve",
                q.self_intersections
                    .map_or_else(|| "uncounted".into(), |n| n.to_string()),
                q.unresolved_contacts
            ),
        )
    } else if q.held_inside > 0 {
        (
            DiagnosticStatus::WARN,
            format!(
                "{} held cloth vertices inside an obstacle, up to {:.1} mm: the scene drives \
                 held cloth into a solid",
                q.held_inside,
                q.held_inside_depth * 1e3
            ),
        )
    } else if d.paused {
        (DiagnosticStatus::OK, "paused".to_string())
    } else if let Some(load) = d.quality.short_of_real_time {
        (
            DiagnosticStatus::WARN,
            format!(
                "cannot hold real time even at the lowest allowed quality ({}): real-time \
                 factor {:.2}",
                d.quality.quality,
                1.0 / load
            ),
        )
    } else if d.real_time_factor.is_some_and(|r| r < SLOW_RTF) {
        (
            DiagnosticStatus::WARN,
            format!(
                "slower than real time (factor {:.2})",
                d.real_time_factor.unwrap_or(0.0)
            ),
        )
    } else if d.new_drops > 0 {
        (
            DiagnosticStatus::WARN,
            format!("{} bad joint state(s) dropped", d.new_drops),
        )
    } else if q.exiting_vertices > 0 {
        (
            DiagnosticStatus::WARN,
            format!(
                "{} cloth vertices still on their way out of an obstacle they started inside",
                q.exiting_vertices
            ),
        )
    } else if d.quality.level > 0 {
        (
            DiagnosticStatus::OK,
            format!(
                "running at reduced quality, level {} of {} ({})",
                d.quality.level,
                d.quality.levels - 1,
                d.quality.quality
            ),
        )
    } else {
        (DiagnosticStatus::OK, "running".to_string())
    };
    let s = d.stats;
    let kv = |k: &str, v: String| KeyValue {
        key: k.to_string(),
        value: v,
    };
    let mut values = vec![
        kv(
            "real_time_factor",
            d.real_time_factor
                .map_or_else(|| "n/a".into(), |r| format!("{r:.3}")),
        ),
        kv(
            "step_time_mean_ms",
            format!("{:.3}", d.step_time_mean * 1e3),
        ),
        kv("step_time_max_ms", format!("{:.3}", d.step_time_max * 1e3)),
    ];
    values.extend(q.values());
    values.extend([
        kv("divergences", s.divergences.to_string()),
        kv("steps_total", s.steps.to_string()),
        kv("dropped_steps", d.dropped_steps.to_string()),
        kv("frames", s.frames.to_string()),
        kv("joint_states", s.joint_states.to_string()),
        kv("dropped_joint_states", s.dropped.total().to_string()),
        kv("dropped_non_finite", s.dropped.non_finite.to_string()),
        kv("dropped_wrong_length", s.dropped.wrong_length.to_string()),
        kv("dropped_unknown_joint", s.dropped.unknown_joint.to_string()),
        kv("dropped_out_of_order", s.dropped.out_of_order.to_string()),
        kv(
            "robot_descriptions_loaded",
            s.descriptions_loaded.to_string(),
        ),
        kv(
            "robot_description_failures",
            s.description_failures.to_string(),
        ),
        kv("resets", s.resets.to_string()),
    ]);
    values.extend(
        quality_values(&d.quality)
            .into_iter()
            .map(|(k, v)| kv(k, v)),
    );
    DiagnosticArray {
        header: Header::new(d.stamp, ""),
        status: vec![DiagnosticStatus {
            level,
            name: format!("{}: simulation", d.name),
            message,
            hardware_id: d.name.to_string(),
            values,
        }],
    }
}

/// The quality keys of `/diagnostics`: what the step runs at now and, while real time cannot
/// be held at the lowest allowed quality, the real-time factor it reaches there.
fn quality_values(q: &QualityStatus) -> Vec<(&'static str, String)> {
    vec![
        ("quality_adaptive", q.adaptive.to_string()),
        ("quality_level", q.level.to_string()),
        ("quality_lowest_level", (q.levels - 1).to_string()),
        ("quality_substeps", q.quality.substeps.to_string()),
        (
            "quality_cg_tolerance",
            format!("{:e}", q.quality.cg_tolerance),
        ),
        (
            "quality_cg_max_iterations",
            q.quality.cg_max_iterations.to_string(),
        ),
        (
            "quality_linearisation_tolerance",
            q.quality.linearisation_tolerance.to_string(),
        ),
        (
            "real_time_factor_at_lowest_quality",
            q.short_of_real_time
                .map_or_else(|| "n/a".into(), |l| format!("{:.3}", 1.0 / l)),
        ),
    ]
}

/// One marker per collision shape of the robot, at the link poses the solver uses, in the
/// robot's root frame: spheres, boxes and cylinders as such, capsules as cylinders spanning
/// their full length, meshes as TRIANGLE_LISTs.
pub fn obstacle_markers(
    d: &RobotDriver,
    distro: Distro,
    stamp: Time,
    frame_id: &str,
) -> MarkerArray {
    let mut markers = Vec::new();
    let poses = d.link_poses();
    for (link, shapes) in d.robot().collision_shapes().iter().enumerate() {
        let Some(link_pose) = poses.get(link) else {
            continue;
        };
        for (shape_pose, g) in shapes {
            let world = link_pose.mul(shape_pose);
            let (r#type, scale, points) = match g {
                Geometry::Sphere { radius } => (Marker::SPHERE, [2.0 * radius; 3], Vec::new()),
                Geometry::Box { half_extents } => {
                    (Marker::CUBE, (2.0 * *half_extents).to_array(), Vec::new())
                }
                Geometry::Cylinder { radius, length } => (
                    Marker::CYLINDER,
                    [2.0 * radius, 2.0 * radius, *length],
                    Vec::new(),
                ),
                Geometry::Capsule { radius, length } => (
                    Marker::CYLINDER,
                    [2.0 * radius, 2.0 * radius, length + 2.0 * radius],
                    Vec::new(),
                ),
                Geometry::Mesh(m) => (
                    Marker::TRIANGLE_LIST,
                    [1.0; 3],
                    m.indices
                        .iter()
                        .flatten()
                        .filter_map(|&i| m.vertices.get(i as usize))
                        .map(|&v| Point::from(v))
                        .collect(),
                ),
            };
            markers.push(Marker {
                distro,
                header: Header::new(stamp, frame_id),
                ns: "obstacles".into(),
                id: i32::try_from(markers.len()).unwrap_or(i32::MAX),
                r#type,
                action: Marker::ADD,
                pose: Pose {
                    position: world.translation.into(),
                    orientation: world.rotation.into(),
                },
                scale: Vector3 {
                    x: scale[0],
                    y: scale[1],
                    z: scale[2],
                },
                color: ColorRGBA::new(0.3, 0.6, 0.9, 0.5),
                points,
                ..Marker::default()
            });
        }
    }
    MarkerArray { markers }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::robot::{JointSource, Robot, UrdfOptions};

    #[test]
    fn obstacle_markers_follow_links() {
        let urdf = r#"<robot name="r"><link name="base"/>
          <link name="arm"><collision><origin xyz="0 0 0.5"/>
            <geometry><box size="0.2 0.4 1.0"/></geometry></collision></link>
          <joint name="j" type="prismatic"><parent link="base"/><child link="arm"/>
            <axis xyz="1 0 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
          </robot>"#;
        let robot = Robot::from_urdf_str(urdf, None, &UrdfOptions::default()).unwrap();
        let mut d = RobotDriver::new(robot, urdf.into(), JointSource::Still);
        let j = d.robot().joint_index("j").unwrap();
        let mut q = d.robot().zero_positions();
        q.positions[j] = 0.3;
        d.set_source(JointSource::Stream(vec![(0.0, q)]), 0.0);
        let a = obstacle_markers(&d, Distro::Humble, Time::default(), "base");
        assert_eq!(a.markers.len(), 1);
        let m = &a.markers[0];
        assert_eq!(m.r#type, Marker::CUBE);
        assert_eq!((m.scale.x, m.scale.y, m.scale.z), (0.2, 0.4, 1.0));
        assert!((m.pose.position.x - 0.3).abs() < 1e-12 && (m.pose.position.z - 0.5).abs() < 1e-12);
        assert_eq!(m.distro, Distro::Humble);
    }

    #[test]
    fn diagnostics_levels() {
        let stats = LoopStats::default();
        let full = crate::ros::node::Quality {
            substeps: 2,
            cg_tolerance: 1e-5,
            cg_max_iterations: 200,
            linearisation_tolerance: 0.1,
        };
        let base = FrameQuality {
            sim_time: 1.0,
            contacts: 3,
            max_edge_stretch: 0.02,
            ..FrameQuality::default()
        };
        let mut d = DiagnosticsInput {
            name: "drape",
            stamp: Time::default(),
            paused: false,
            real_time_factor: Some(1.0),
            step_time_mean: 0.001,
            step_time_max: 0.002,
            sim: &base,
            stats: &stats,
            dropped_steps: 0,
            new_drops: 0,
            new_divergences: 0,
            quality: crate::ros::node::QualityController::new(
                full,
                &crate::ros::node::QualityBounds::default(),
                true,
            )
            .status(),
        };
        assert_eq!(diagnostics(&d).status[0].level, DiagnosticStatus::OK);
        // At the lowest quality and still slow: WARN with the factor reached there.
        d.quality.level = 7;
        d.quality.short_of_real_time = Some(1.6);
        let s = &diagnostics(&d).status[0];
        assert_eq!(s.level, DiagnosticStatus::WARN);
        assert!(s.message.contains("factor 0.62"), "{}", s.message);
        assert!(s
            .values
            .iter()
            .any(|kv| kv.key == "real_time_factor_at_lowest_quality" && kv.value == "0.625"));
        d.quality.short_of_real_time = None;
        let s = &diagnostics(&d).status[0];
        assert_eq!(s.level, DiagnosticStatus::OK);
        assert!(s.message.contains("reduced quality"), "{}", s.message);
        d.real_time_factor = Some(0.5);
        let s = &diagnostics(&d).status[0];
        assert_eq!(s.level, DiagnosticStatus::WARN);
        assert!(s
            .values
            .iter()
            .any(|kv| kv.key == "real_time_factor" && kv.value == "0.500"));
        d.real_time_factor = Some(1.0);
        let mut sim = base.clone();
        let with = |sim: &FrameQuality| {
            diagnostics(&DiagnosticsInput { sim, ..d.clone() }).status[0].clone()
        };
        sim.exiting_vertices = 40;
        let s = with(&sim);
        assert_eq!(s.level, DiagnosticStatus::WARN);
        assert!(s.message.contains("40 cloth vertices"), "{}", s.message);
        assert!(s
            .values
            .iter()
            .any(|kv| kv.key == "exiting_vertices" && kv.value == "40"));
        sim.exiting_vertices = 0;
        // A pinch: its vertices and grip, only while there is one.
        assert!(!with(&sim)
            .values
            .iter()
            .any(|kv| kv.key == "pinched_vertices"));
        (sim.pinched_vertices, sim.grip_normal_force) = (12, 0.25);
        let values = with(&sim).values;
        assert!(values
            .iter()
            .any(|kv| kv.key == "pinched_vertices" && kv.value == "12"));
        assert!(values
            .iter()
            .any(|kv| kv.key == "grip_normal_force_n" && kv.value == "0.25"));
        sim.pinched_vertices = 0;
        // Held cloth inside a solid: WARN with how many and how deep.
        (sim.held_inside, sim.held_inside_depth) = (3, 0.0042);
        let s = with(&sim);
        assert_eq!(s.level, DiagnosticStatus::WARN);
        assert!(s.message.contains("3 held cloth vertices"), "{}", s.message);
        assert!(s.message.contains("4.2 mm"), "{}", s.message);
        assert!(s
            .values
            .iter()
            .any(|kv| kv.key == "held_inside_vertices" && kv.value == "3"));
        (sim.held_inside, sim.held_inside_depth) = (0, 0.0);
        assert!(!with(&sim)
            .values
            .iter()
            .any(|kv| kv.key.starts_with("held_inside")));
        sim.self_intersections = Some(0);
        assert_eq!(with(&sim).level, DiagnosticStatus::OK);
        // A tangle: self-intersections, or pairs the fail-safe gave up on.
        sim.self_intersections = Some(218);
        let s = with(&sim);
        assert_eq!(s.level, DiagnosticStatus::WARN);
        assert!(s.message.contains("tangled: 218"), "{}", s.message);
        sim.self_intersections = None;
        sim.unresolved_contacts = 685;
        let s = with(&sim);
        assert_eq!(s.level, DiagnosticStatus::WARN);
        assert!(s.message.contains("uncounted") && s.message.contains("685"));
        assert!(s
            .values
            .iter()
            .any(|kv| kv.key == "unresolved_contacts" && kv.value == "685"));
        // The recordings' rows and formats: the exact value.
        assert!(s
            .values
            .iter()
            .any(|kv| kv.key == "max_edge_stretch" && kv.value == "0.02"));
        d.new_divergences = 1;
        assert_eq!(diagnostics(&d).status[0].level, DiagnosticStatus::ERROR);
    }
}
