//! Drives a robot inside a [`Simulation`]: every frame it evaluates the joint motion at the
//! frame's end time, runs FK, and hands the link poses to the collision obstacles and attachment
//! frames built from the robot, so the simulation moves them smoothly over the substeps.

use super::grasp::{Grasp, GraspEvent};
use super::{Geometry, JointInput, JointPositions, JointTrajectory, Robot};
use crate::collide::{Motion, Obstacle, ObstacleError};
use crate::sim::{Frames, Simulation};
use crate::{Pose, Vec3};
use glam::DQuat;

/// Where joint positions come from.
#[derive(Debug, Clone)]
pub enum JointSource {
    /// Hold the zero configuration.
    Still,
    /// Scripted waypoints (validated against the robot).
    Trajectory(JointTrajectory),
    /// Timestamped full joint states (seconds from the start), e.g. a bag's `/joint_states`,
    /// already validated; interpolated linearly in time, held outside the range.
    Stream(Vec<(f64, JointPositions)>),
}

/// A link's share of the simulation: its obstacles (index, shape pose in the link frame with the
/// URDF-to-parry axis fix) and its attachment frame.
#[derive(Debug, Clone, Default)]
struct LinkBinding {
    obstacles: Vec<(usize, Pose)>,
    frame: Option<usize>,
}

/// Owns the robot, its motion, and the mapping link -> obstacle indices / frame index.
#[derive(Debug, Clone)]
pub struct RobotDriver {
    robot: Robot,
    /// The URDF text, republished as `/robot_description`.
    urdf_text: String,
    source: JointSource,
    bindings: Vec<LinkBinding>,
    q: JointPositions,
    poses: Vec<Pose>,
    time: f64,
    clamp_warned: Vec<bool>,
    grasps: Vec<Grasp>,
}

/// URDF cylinders and capsules run along local z, parry's along y: a quarter turn about x maps
/// parry's y axis onto z.
pub fn urdf_axis_fix() -> Pose {
    Pose::new(
        crate::Vec3::ZERO,
        DQuat::from_rotation_x(std::f64::consts::FRAC_PI_2),
    )
}

/// The obstacles of one link's collision shapes at `link_pose`, external motion, named
/// `link/k`. Returns each obstacle with its pose in the link frame.
pub fn link_obstacles(
    link: &str,
    shapes: &[(Pose, Geometry)],
    link_pose: &Pose,
) -> Result<Vec<(Obstacle, Pose)>, ObstacleError> {
    let mut out = Vec::with_capacity(shapes.len());
    for (k, (shape_pose, g)) in shapes.iter().enumerate() {
        let name = format!("{link}/{k}");
        let (local, o) = match g {
            Geometry::Sphere { radius } => (
                *shape_pose,
                Obstacle::sphere(&name, *radius, Pose::IDENTITY)?,
            ),
            Geometry::Box { half_extents } => (
                *shape_pose,
                Obstacle::cuboid(&name, *half_extents, Pose::IDENTITY)?,
            ),
            Geometry::Cylinder { radius, length } => (
                shape_pose.mul(&urdf_axis_fix()),
                Obstacle::cylinder(&name, *radius, 0.5 * length, Pose::IDENTITY)?,
            ),
            Geometry::Capsule { radius, length } => (
                shape_pose.mul(&urdf_axis_fix()),
                Obstacle::capsule(&name, *radius, 0.5 * length, Pose::IDENTITY)?,
            ),
            Geometry::Mesh(m) => (
                *shape_pose,
                Obstacle::mesh(&name, &m.vertices, &m.indices, Pose::IDENTITY)?,
            ),
        };
        let mut o = o.with_motion(Motion::External);
        let world = link_pose.mul(&local);
        o.pose = world;
        o.pose_prev = world;
        o.initial_pose = world;
        out.push((o, local));
    }
    Ok(out)
}

impl RobotDriver {
    /// A driver for `robot`; positions at t = 0 come from `source`. Bind obstacles and frames
    /// with [`RobotDriver::bind_obstacle`] / [`RobotDriver::bind_frame`] while building.
    pub fn new(robot: Robot, urdf_text: String, source: JointSource) -> Self {
        let n_links = robot.link_names().len();
        let n_joints = robot.kinematics().joints().len();
        let mut d = Self {
            q: robot.zero_positions(),
            robot,
            urdf_text,
            source,
            bindings: vec![LinkBinding::default(); n_links],
            poses: Vec::with_capacity(n_links),
            time: 0.0,
            clamp_warned: vec![false; n_joints],
            grasps: Vec::new(),
        };
        d.update(0.0);
        d
    }

    pub fn robot(&self) -> &Robot {
        &self.robot
    }

    pub fn urdf_text(&self) -> &str {
        &self.urdf_text
    }

    /// Name of the root link: the frame the cloth and `/tf` are expressed in.
    pub fn root_link(&self) -> &str {
        &self.robot.link_names()[self.robot.kinematics().root_link()]
    }

    /// Joint positions at the time of the last [`RobotDriver::advance`] (or t = 0).
    pub fn joint_positions(&self) -> &JointPositions {
        &self.q
    }

    /// Link poses (root frame) at the time of the last advance, indexed like the robot's links.
    pub fn link_poses(&self) -> &[Pose] {
        &self.poses
    }

    /// Time the current state belongs to.
    pub fn time(&self) -> f64 {
        self.time
    }

    /// Replaces the joint motion (e.g. with a stream read from a bag) and re-poses at `t`.
    pub fn set_source(&mut self, source: JointSource, t: f64) {
        self.source = source;
        self.update(t);
    }

    /// Records that obstacle `index` of the collision stage is link `link`'s shape at `local`.
    pub fn bind_obstacle(&mut self, link: usize, index: usize, local: Pose) {
        self.bindings[link].obstacles.push((index, local));
    }

    /// Records that simulation frame `frame` follows link `link`.
    pub fn bind_frame(&mut self, link: usize, frame: usize) {
        self.bindings[link].frame = Some(frame);
    }

    /// The collision-stage obstacles of `link`: each one's index and its pose in the link frame.
    pub fn obstacles_of(&self, link: usize) -> &[(usize, Pose)] {
        self.bindings.get(link).map_or(&[], |b| &b.obstacles)
    }

    /// The frame bound to `link`, if any.
    pub fn frame_of(&self, link: usize) -> Option<usize> {
        self.bindings.get(link).and_then(|b| b.frame)
    }

    /// The frame that follows `link`: the one already bound, or a new frame `robot:<link>` in
    /// `frames` at the link's current pose, bound now. Cloth attachments, grasps and garment
    /// attachments to one link share it.
    pub fn link_frame(&mut self, link: usize, frames: &mut Frames) -> usize {
        if let Some(f) = self.frame_of(link) {
            return f;
        }
        let name = format!("robot:{}", self.robot().link_names()[link]);
        let f = frames.add(&name, self.poses[link]);
        self.bind_frame(link, f);
        f
    }

    /// Joint positions the source gives at time `t` (joints it does not name stay at zero).
    pub fn positions_at(&self, t: f64) -> JointPositions {
        let kin = self.robot.kinematics();
        let mut q = kin.zero_positions();
        match &self.source {
            JointSource::Still => {}
            JointSource::Trajectory(tr) => {
                // Validated at build time; a failure here would leave q at the zero pose.
                if let Err(e) = tr.input_at(t).apply(kin, &mut q) {
                    log::warn!("robot trajectory at t = {t}: {e}");
                }
            }
            JointSource::Stream(s) => q = stream_at(s, t).unwrap_or(q),
        }
        q
    }

    fn update(&mut self, t: f64) {
        self.q = self.positions_at(t);
        self.time = t;
        let report = self.robot.link_poses_into(&self.q, &mut self.poses);
        for ji in report.clamped {
            if !std::mem::replace(&mut self.clamp_warned[ji], true) {
                log::warn!(
                    "joint `{}` commanded outside its limits at t = {t:.3} s: clamped (warned once)",
                    self.robot.kinematics().joints()[ji].name
                );
            }
        }
    }

    /// Adds a grasp rule (its link should have a bound frame, see [`RobotDriver::bind_frame`]).
    pub fn add_grasp(&mut self, grasp: Grasp) {
        self.grasps.push(grasp);
    }

    pub fn grasps(&self) -> &[Grasp] {
        &self.grasps
    }

    /// World velocity at time `t` of the material point of `link` that is at world position `p`
    /// at the current time (central difference of FK over +-0.1 ms: exact for joint motion that
    /// is linear in time, the mean of both sides at a trajectory waypoint).
    pub fn link_point_velocity(&self, link: usize, p: Vec3, t: f64) -> Vec3 {
        const DT: f64 = 1e-4;
        let local = self.poses[link].inverse_transform_point(p);
        let pose = |t: f64| self.robot.link_poses(&self.positions_at(t))[link];
        (pose(t + DT).transform_point(local) - pose(t - DT).transform_point(local)) / (2.0 * DT)
    }

    /// Runs the grasp rules on the current joint state: closing fingers attach the free cloth
    /// vertices between their pads, opening fingers release them with the gripper's velocity.
    fn apply_grasps(&mut self, sim: &mut Simulation) {
        for k in 0..self.grasps.len() {
            let opening = self.grasps[k].opening(self.robot.kinematics(), &self.q);
            let link = self.grasps[k].link;
            let name = &self.robot.link_names()[link];
            match self.grasps[k].update(opening) {
                Some(GraspEvent::Close) => {
                    let g = &self.grasps[k];
                    let picked = g.between_pads(&sim.cloth.x, &self.poses[link], |v| {
                        sim.cloth.is_kinematic(v)
                    });
                    let held = sim.attach_vertices(&picked, g.frame);
                    log::info!(
                        "t = {:.3} s: `{name}` grasps {} cloth vertices",
                        self.time,
                        held.len()
                    );
                    self.grasps[k].set_held(held);
                }
                Some(GraspEvent::Open) => {
                    let held = self.grasps[k].take_held();
                    let released: Vec<(u32, Vec3)> = held
                        .iter()
                        .map(|&v| {
                            let p = sim.cloth.x[v as usize];
                            (v, self.link_point_velocity(link, p, self.time))
                        })
                        .collect();
                    let n = sim.release_vertices(&released);
                    log::info!(
                        "t = {:.3} s: `{name}` releases {n} cloth vertices",
                        self.time
                    );
                }
                None => {}
            }
        }
    }

    /// Runs the grasp rules on the current state, then poses the robot for the end of the next
    /// frame (`t_next`) and tells the simulation where its obstacles and frames will be; call
    /// before [`Simulation::step`].
    pub fn advance(&mut self, sim: &mut Simulation, t_next: f64) {
        self.apply_grasps(sim);
        self.update(t_next);
        for (link, b) in self.bindings.iter().enumerate() {
            let pose = self.poses[link];
            for (idx, local) in &b.obstacles {
                sim.set_obstacle_target(*idx, pose.mul(local));
            }
            if let Some(f) = b.frame {
                sim.set_frame_target(f, pose);
            }
        }
    }
}

fn stream_at(s: &[(f64, JointPositions)], t: f64) -> Option<JointPositions> {
    let (first, last) = (s.first()?, s.last()?);
    if t <= first.0 {
        return Some(first.1.clone());
    }
    if t >= last.0 {
        return Some(last.1.clone());
    }
    let k = s.partition_point(|p| p.0 <= t).clamp(1, s.len() - 1);
    let (a, b) = (&s[k - 1], &s[k]);
    let span = b.0 - a.0;
    let u = if span > 0.0 { (t - a.0) / span } else { 1.0 };
    Some(a.1.lerp(&b.1, u))
}

/// Why [`joint_stream`] dropped a message (logged, not returned: the stream goes on).
#[derive(Debug, thiserror::Error)]
enum StreamDrop {
    #[error("time {t:.6} s goes backwards")]
    Backwards { t: f64 },
    #[error(transparent)]
    Input(crate::robot::JointInputError),
}

/// Turns timestamped joint messages (ns, names/positions/velocities) into a validated stream:
/// times relative to the first message, each good message applied by name on top of the last
/// good state, bad ones (unknown joint, NaN, length mismatch, time going backwards) dropped with
/// a rate-limited warning. Returns the stream and the number of messages dropped.
pub fn joint_stream(
    robot: &Robot,
    messages: impl IntoIterator<Item = (u64, JointInput)>,
) -> (Vec<(f64, JointPositions)>, usize) {
    const WARN_FIRST: usize = 5;
    let kin = robot.kinematics();
    let mut q = kin.zero_positions();
    let mut out: Vec<(f64, JointPositions)> = Vec::new();
    let mut t0 = None;
    let mut dropped = 0usize;
    for (k, (ns, input)) in messages.into_iter().enumerate() {
        let start = *t0.get_or_insert(ns);
        let t = (ns as f64 - start as f64) * 1e-9;
        let result = if out.last().is_some_and(|(tl, _)| t < *tl) {
            Err(StreamDrop::Backwards { t })
        } else {
            input.apply(kin, &mut q).map_err(StreamDrop::Input)
        };
        match result {
            Ok(()) => out.push((t, q.clone())),
            Err(e) => {
                dropped += 1;
                if dropped <= WARN_FIRST {
                    log::warn!("joint state {k} dropped: {e}");
                } else if dropped.is_power_of_two() {
                    log::warn!("{dropped} joint states dropped so far (latest: message {k}: {e})");
                }
            }
        }
    }
    (out, dropped)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::robot::UrdfOptions;
    use crate::Vec3;

    const ARM: &str = r#"<robot name="arm">
      <link name="base"/>
      <link name="upper"><collision><origin xyz="0 0 0.2"/>
        <geometry><cylinder radius="0.05" length="0.4"/></geometry></collision></link>
      <joint name="shoulder" type="revolute"><parent link="base"/><child link="upper"/>
        <axis xyz="0 1 0"/><limit lower="-2" upper="2" effort="1" velocity="1"/></joint>
    </robot>"#;

    fn arm() -> Robot {
        Robot::from_urdf_str(ARM, None, &UrdfOptions::default()).unwrap()
    }

    #[test]
    fn urdf_cylinder_axis_becomes_parry_y() {
        // A point on the URDF cylinder's z axis, 0.2 m out, must be on parry's local y axis.
        let fix = urdf_axis_fix();
        let local = fix.inverse_transform_point(Vec3::new(0.0, 0.0, 0.2));
        assert!(
            (local - Vec3::new(0.0, 0.2, 0.0)).length() < 1e-12,
            "{local}"
        );
        let r = arm();
        let built = link_obstacles("upper", &r.collision_shapes()[1], &Pose::IDENTITY).unwrap();
        assert_eq!(built.len(), 1);
        let (o, _) = &built[0];
        // The cylinder spans z in [0, 0.4] in the link frame: its world AABB does too.
        let aabb = o.shape.compute_aabb(&parry3d::math::Pose::from_parts(
            o.pose.translation.as_vec3(),
            o.pose.rotation.as_quat(),
        ));
        assert!((aabb.mins.z as f64).abs() < 1e-6 && (aabb.maxs.z as f64 - 0.4).abs() < 1e-6);
        assert!((aabb.maxs.x as f64 - 0.05).abs() < 1e-6);
    }

    #[test]
    fn joint_stream_drops_bad_messages_and_interpolates() {
        let r = arm();
        let input = |names: &[&str], p: f64| JointInput {
            names: names.iter().map(|s| s.to_string()).collect(),
            positions: vec![p],
            velocities: None,
        };
        let msgs = vec![
            (5_000_000_000, input(&["shoulder"], 0.0)),
            (5_500_000_000, input(&["elbow"], 1.0)),
            (5_600_000_000, input(&["shoulder"], f64::NAN)),
            (6_000_000_000, input(&["shoulder"], 1.0)),
            (5_900_000_000, input(&["shoulder"], 9.0)),
        ];
        let (stream, dropped) = joint_stream(&r, msgs);
        assert_eq!(dropped, 3);
        assert_eq!(stream.len(), 2);
        assert_eq!(stream[1].0, 1.0);
        let mut d = RobotDriver::new(r, String::new(), JointSource::Stream(stream));
        let j = d.robot().joint_index("shoulder").unwrap();
        assert!((d.positions_at(0.25).positions[j] - 0.25).abs() < 1e-12);
        assert_eq!(d.positions_at(3.0).positions[j], 1.0);
        d.set_source(JointSource::Still, 0.0);
        assert_eq!(d.joint_positions().positions[j], 0.0);
    }
}
