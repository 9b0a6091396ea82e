//! Forward kinematics of a URDF kinematic tree (root link frame), f64 throughout.
//!
//! Joint values live in a [`JointPositions`] vector indexed like [`Kinematics::joints`]; entries
//! of fixed and mimic joints are ignored (mimic joints follow their source). Floating and planar
//! joints take their motion from [`JointPositions::free_poses`].

use crate::{Pose, Vec3};
use glam::DQuat;
use std::collections::HashMap;

/// The motion a joint allows about/along its (unit) axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum JointKind {
    Fixed,
    Revolute,
    Continuous,
    Prismatic,
    /// Six degrees of freedom; pose taken from [`JointPositions::free_poses`].
    Floating,
    /// Motion in the plane normal to the axis; pose taken from [`JointPositions::free_poses`].
    Planar,
}

impl JointKind {
    /// Whether the joint has a scalar position in [`JointPositions::positions`].
    pub fn is_scalar(self) -> bool {
        matches!(
            self,
            JointKind::Revolute | JointKind::Continuous | JointKind::Prismatic
        )
    }
}

/// `value = multiplier * value(joint) + offset` (URDF `<mimic>`), already resolved through
/// chains of mimics down to an independent joint.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Mimic {
    pub joint: usize,
    pub multiplier: f64,
    pub offset: f64,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Joint {
    pub name: String,
    pub kind: JointKind,
    pub parent_link: usize,
    pub child_link: usize,
    /// Child frame at zero position, in the parent link frame.
    pub origin: Pose,
    /// Unit axis in the joint frame.
    pub axis: Vec3,
    /// `(lower, upper)` position limits, `None` when unlimited (continuous joints, URDF 1.2
    /// omitted limits, or the `lower = upper = 0` that URDF 1.0 parsers produce for a missing
    /// `<limit>`).
    pub limits: Option<(f64, f64)>,
    /// Velocity limit (rad/s or m/s) when the URDF gives a positive one.
    pub velocity_limit: Option<f64>,
    pub mimic: Option<Mimic>,
}

/// Joint inputs for FK. Build with [`Kinematics::zero_positions`] so the lengths match.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct JointPositions {
    /// One entry per joint (radians or metres); ignored for fixed, mimic and free joints.
    pub positions: Vec<f64>,
    /// One entry per joint; `Some` supplies the motion of a floating or planar joint
    /// (applied after the joint origin). `None` means identity.
    pub free_poses: Vec<Option<Pose>>,
}

impl JointPositions {
    pub fn zeros(joints: usize) -> Self {
        Self {
            positions: vec![0.0; joints],
            free_poses: vec![None; joints],
        }
    }

    /// Interpolates scalar positions linearly and free poses by [`Pose::lerp`]; used to move
    /// the robot across the substeps between two joint-state updates. `s` in [0, 1].
    pub fn lerp(&self, other: &JointPositions, s: f64) -> JointPositions {
        let positions = self
            .positions
            .iter()
            .zip(&other.positions)
            .map(|(a, b)| a + (b - a) * s)
            .collect();
        let free_poses = self
            .free_poses
            .iter()
            .zip(&other.free_poses)
            .map(|(a, b)| match (a, b) {
                (Some(a), Some(b)) => Some(a.lerp(b, s)),
                (a, b) => b.or(*a),
            })
            .collect();
        JointPositions {
            positions,
            free_poses,
        }
    }
}

/// What FK had to adjust, so the caller can warn once instead of every frame.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct FkReport {
    /// Independent joints whose position was outside its limits and got clamped.
    pub clamped: Vec<usize>,
    /// Floating/planar joints without a supplied pose (identity used).
    pub free_defaulted: Vec<usize>,
}

impl FkReport {
    pub fn is_clean(&self) -> bool {
        self.clamped.is_empty() && self.free_defaulted.is_empty()
    }
}

/// Largest length (m) a robot description may use for an offset or a size. Finite is not enough:
/// forward kinematics adds the offsets of a chain, and two origins of 1e308 m overflow to
/// infinity. A million metres is far beyond any robot and far below overflow for any chain.
pub const MAX_LENGTH: f64 = 1e6;

/// Why a joint/link graph is not a single tree.
#[derive(Debug, Clone, thiserror::Error, PartialEq)]
pub enum TreeError {
    #[error("duplicate link name `{0}`")]
    DuplicateLink(String),
    #[error("duplicate joint name `{0}`")]
    DuplicateJoint(String),
    #[error("joint `{joint}` references unknown link `{link}`")]
    UnknownLink { joint: String, link: String },
    #[error("link `{link}` is the child of two joints, `{first}` and `{second}`")]
    TwoParents {
        link: String,
        first: String,
        second: String,
    },
    #[error("the robot has no links")]
    NoLinks,
    #[error("no root link: the joints form a cycle")]
    NoRoot,
    #[error("several root links (the robot is not one tree): {0:?}")]
    SeveralRoots(Vec<String>),
    #[error("joints {0:?} are not reachable from the root (cycle)")]
    Unreachable(Vec<String>),
    #[error("joint `{joint}` mimics unknown joint `{target}`")]
    UnknownMimic { joint: String, target: String },
    #[error("joint `{joint}` mimics `{target}`, which has no scalar position")]
    MimicOfNonScalar { joint: String, target: String },
    #[error("mimic joints form a cycle through `{0}`")]
    MimicCycle(String),
    #[error("joint `{joint}`: axis {axis} has zero length or is not finite")]
    BadAxis { joint: String, axis: Vec3 },
    #[error("joint `{joint}`: origin is not finite or farther than {MAX_LENGTH:e} m")]
    BadOrigin { joint: String },
}

/// Joint description as read from a URDF before indices are resolved.
#[derive(Debug, Clone)]
pub struct JointSpec {
    pub name: String,
    pub kind: JointKind,
    pub parent: String,
    pub child: String,
    pub origin: Pose,
    pub axis: Vec3,
    pub lower: f64,
    pub upper: f64,
    pub velocity: f64,
    /// `(source joint name, multiplier, offset)`.
    pub mimic: Option<(String, f64, f64)>,
}

/// A validated kinematic tree with a precomputed traversal order.
#[derive(Debug, Clone)]
pub struct Kinematics {
    links: Vec<String>,
    joints: Vec<Joint>,
    /// Joint indices, parents before children.
    order: Vec<usize>,
    root: usize,
    parent_joint: Vec<Option<usize>>,
    link_index: HashMap<String, usize>,
    joint_index: HashMap<String, usize>,
}

impl Kinematics {
    /// Validates the graph (one root, one parent per link, no cycles, mimic targets exist)
    /// and orders joints from the root outwards.
    pub fn new(links: Vec<String>, specs: Vec<JointSpec>) -> Result<Self, TreeError> {
        if links.is_empty() {
            return Err(TreeError::NoLinks);
        }
        let mut link_index = HashMap::new();
        for (i, l) in links.iter().enumerate() {
            if link_index.insert(l.clone(), i).is_some() {
                return Err(TreeError::DuplicateLink(l.clone()));
            }
        }
        let mut joint_index = HashMap::new();
        for (i, j) in specs.iter().enumerate() {
            if joint_index.insert(j.name.clone(), i).is_some() {
                return Err(TreeError::DuplicateJoint(j.name.clone()));
            }
        }
        let lookup = |joint: &str, link: &str| {
            link_index
                .get(link)
                .copied()
                .ok_or_else(|| TreeError::UnknownLink {
                    joint: joint.to_string(),
                    link: link.to_string(),
                })
        };
        let mut parent_joint: Vec<Option<usize>> = vec![None; links.len()];
        let mut joints = Vec::with_capacity(specs.len());
        for (ji, s) in specs.iter().enumerate() {
            let parent_link = lookup(&s.name, &s.parent)?;
            let child_link = lookup(&s.name, &s.child)?;
            if let Some(first) = parent_joint[child_link] {
                return Err(TreeError::TwoParents {
                    link: s.child.clone(),
                    first: specs[first].name.clone(),
                    second: s.name.clone(),
                });
            }
            parent_joint[child_link] = Some(ji);
            if !s.origin.is_finite() || s.origin.translation.length() > MAX_LENGTH {
                return Err(TreeError::BadOrigin {
                    joint: s.name.clone(),
                });
            }
            let needs_axis = s.kind != JointKind::Fixed && s.kind != JointKind::Floating;
            let axis = if needs_axis {
                let len = s.axis.length();
                if !(len.is_finite() && len > 1e-12) {
                    return Err(TreeError::BadAxis {
                        joint: s.name.clone(),
                        axis: s.axis,
                    });
                }
                s.axis / len
            } else {
                Vec3::X
            };
            let limited = matches!(s.kind, JointKind::Revolute | JointKind::Prismatic)
                && s.lower.is_finite()
                && s.upper.is_finite()
                && s.lower <= s.upper
                && !(s.lower == 0.0 && s.upper == 0.0);
            joints.push(Joint {
                name: s.name.clone(),
                kind: s.kind,
                parent_link,
                child_link,
                origin: s.origin,
                axis,
                limits: limited.then_some((s.lower, s.upper)),
                velocity_limit: (s.velocity.is_finite() && s.velocity > 0.0).then_some(s.velocity),
                mimic: None,
            });
        }
        // Mimics: resolve chains to an independent source, composing the affine maps.
        for ji in 0..specs.len() {
            let mut cur = ji;
            let (mut mul, mut off) = (1.0, 0.0);
            let mut steps = 0;
            while let Some((target, m, o)) = &specs[cur].mimic {
                let t = *joint_index
                    .get(target)
                    .ok_or_else(|| TreeError::UnknownMimic {
                        joint: specs[cur].name.clone(),
                        target: target.clone(),
                    })?;
                if !specs[t].kind.is_scalar() {
                    return Err(TreeError::MimicOfNonScalar {
                        joint: specs[cur].name.clone(),
                        target: target.clone(),
                    });
                }
                // value(cur) = m * value(t) + o, and value(ji) = mul * value(cur) + off.
                off += mul * o;
                mul *= m;
                cur = t;
                steps += 1;
                if steps > specs.len() {
                    return Err(TreeError::MimicCycle(specs[ji].name.clone()));
                }
            }
            if cur != ji && specs[ji].kind.is_scalar() {
                joints[ji].mimic = Some(Mimic {
                    joint: cur,
                    multiplier: mul,
                    offset: off,
                });
            }
        }
        let roots: Vec<usize> = (0..links.len())
            .filter(|&l| parent_joint[l].is_none())
            .collect();
        let root = match roots.as_slice() {
            [] => return Err(TreeError::NoRoot),
            [r] => *r,
            many => {
                return Err(TreeError::SeveralRoots(
                    many.iter().map(|&l| links[l].clone()).collect(),
                ))
            }
        };
        let mut children: Vec<Vec<usize>> = vec![Vec::new(); links.len()];
        for (ji, j) in joints.iter().enumerate() {
            children[j.parent_link].push(ji);
        }
        let mut order = Vec::with_capacity(joints.len());
        let mut queue = std::collections::VecDeque::from([root]);
        while let Some(l) = queue.pop_front() {
            for &ji in &children[l] {
                order.push(ji);
                queue.push_back(joints[ji].child_link);
            }
        }
        if order.len() != joints.len() {
            let mut reached = vec![false; joints.len()];
            for &j in &order {
                reached[j] = true;
            }
            return Err(TreeError::Unreachable(
                (0..joints.len())
                    .filter(|&j| !reached[j])
                    .map(|j| joints[j].name.clone())
                    .collect(),
            ));
        }
        Ok(Self {
            links,
            joints,
            order,
            root,
            parent_joint,
            link_index,
            joint_index,
        })
    }

    pub fn links(&self) -> &[String] {
        &self.links
    }

    pub fn joints(&self) -> &[Joint] {
        &self.joints
    }

    pub fn root_link(&self) -> usize {
        self.root
    }

    /// The joint whose child is `link` (`None` for the root).
    pub fn parent_joint(&self, link: usize) -> Option<usize> {
        self.parent_joint.get(link).copied().flatten()
    }

    pub fn link_index(&self, name: &str) -> Option<usize> {
        self.link_index.get(name).copied()
    }

    pub fn joint_index(&self, name: &str) -> Option<usize> {
        self.joint_index.get(name).copied()
    }

    /// All-zero positions (free joints at identity), sized for this tree.
    pub fn zero_positions(&self) -> JointPositions {
        JointPositions::zeros(self.joints.len())
    }

    /// The shortest time in which every commanded joint with a velocity limit gets from `from`
    /// to `to` (positions as FK uses them, clamped to their limits) at or below that limit; 0
    /// when none has one or none moves. Free and mimic joints follow what is commanded.
    pub fn slew_time(&self, from: &JointPositions, to: &JointPositions) -> f64 {
        self.slowest_joint(from, to).map_or(0.0, |(_, t)| t)
    }

    /// The joint that takes longest at its velocity limit from `from` to `to`, and how long
    /// (see [`Kinematics::slew_time`]).
    pub fn slowest_joint(
        &self,
        from: &JointPositions,
        to: &JointPositions,
    ) -> Option<(usize, f64)> {
        self.actuated_joints()
            .filter_map(|(ji, j)| {
                let v = j.velocity_limit?;
                let d = self.effective_position(to, ji).0 - self.effective_position(from, ji).0;
                Some((ji, d.abs() / v))
            })
            .reduce(|a, b| if b.1 > a.1 { b } else { a })
    }

    /// Names of the joints a user commands: scalar, not mimic (in joint index order).
    pub fn actuated_joints(&self) -> impl Iterator<Item = (usize, &Joint)> {
        self.joints
            .iter()
            .enumerate()
            .filter(|(_, j)| j.kind.is_scalar() && j.mimic.is_none())
    }

    /// The position FK uses for scalar joint `ji`: mimic-resolved and clamped to limits.
    /// The flag says whether clamping changed the independent source value.
    pub fn effective_position(&self, q: &JointPositions, ji: usize) -> (f64, bool) {
        let (src, mul, off) = match self.joints[ji].mimic {
            Some(m) => (m.joint, m.multiplier, m.offset),
            None => (ji, 1.0, 0.0),
        };
        let raw = q.positions.get(src).copied().unwrap_or(0.0);
        let clamped = match self.joints[src].limits {
            Some((lo, hi)) => raw.clamp(lo, hi),
            None => raw,
        };
        (mul * clamped + off, clamped != raw)
    }

    /// Pose of every link in the root link frame, indexed like [`Kinematics::links`].
    pub fn link_poses(&self, q: &JointPositions) -> Vec<Pose> {
        let mut out = Vec::new();
        self.link_poses_into(q, &mut out);
        out
    }

    /// Allocation-free FK when `out` already has capacity (and the report stays empty).
    /// Missing entries of `q` count as zero.
    pub fn link_poses_into(&self, q: &JointPositions, out: &mut Vec<Pose>) -> FkReport {
        out.clear();
        out.resize(self.links.len(), Pose::IDENTITY);
        let mut report = FkReport::default();
        for &ji in &self.order {
            let j = &self.joints[ji];
            let motion = match j.kind {
                JointKind::Fixed => Pose::IDENTITY,
                JointKind::Revolute | JointKind::Continuous | JointKind::Prismatic => {
                    let (v, clamped) = self.effective_position(q, ji);
                    if clamped && j.mimic.is_none() {
                        report.clamped.push(ji);
                    }
                    if j.kind == JointKind::Prismatic {
                        Pose::from_translation(j.axis * v)
                    } else {
                        Pose::new(Vec3::ZERO, DQuat::from_axis_angle(j.axis, v))
                    }
                }
                JointKind::Floating | JointKind::Planar => {
                    match q.free_poses.get(ji).copied().flatten() {
                        Some(p) => p,
                        None => {
                            report.free_defaulted.push(ji);
                            Pose::IDENTITY
                        }
                    }
                }
            };
            let parent = out[j.parent_link];
            out[j.child_link] = parent.mul(&j.origin).mul(&motion);
        }
        report
    }
}
