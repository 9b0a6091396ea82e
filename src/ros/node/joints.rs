//! The gate joint states pass on their way to the robot: stamps must not go back in time, the
//! state must fit the robot ([`JointInput::apply`]), and an accepted state becomes the command
//! the next step reaches. A dropped state says why ([`Dropped`]) and is counted per reason.

use super::messages::DroppedInputs;
use crate::robot::{JointInput, JointInputError, JointPositions, JointSource, RobotDriver};

/// Why a joint state was dropped.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Dropped {
    #[error("the scene has no robot")]
    NoRobot,
    #[error("stamp {:.6} s is older than the last accepted one", *stamp_ns as f64 * 1e-9)]
    OutOfOrder { stamp_ns: i64 },
    #[error(transparent)]
    Invalid(#[from] JointInputError),
}

impl Dropped {
    /// Counts this drop in its reason's slot of `d`.
    pub fn count(&self, d: &mut DroppedInputs) {
        let slot = match self {
            Dropped::NoRobot => &mut d.other,
            Dropped::OutOfOrder { .. } => &mut d.out_of_order,
            Dropped::Invalid(JointInputError::NotFinite { .. })
            | Dropped::Invalid(JointInputError::NonFinitePose(_)) => &mut d.non_finite,
            Dropped::Invalid(JointInputError::Empty)
            | Dropped::Invalid(JointInputError::LengthMismatch { .. }) => &mut d.wrong_length,
            Dropped::Invalid(JointInputError::UnknownJoint(_)) => &mut d.unknown_joint,
            Dropped::Invalid(_) => &mut d.other,
        };
        *slot += 1;
    }
}

/// The joint command state between joint-state messages and the steps that reach them.
#[derive(Debug, Clone)]
pub struct JointGate {
    /// Reach a command no faster than the URDF's joint velocity limits allow. A state the
    /// robot cannot have reached within a step (a sparse or jumping `/joint_states`) otherwise
    /// drives its links through the cloth at many times their speed: drape_bot's shoulder
    /// jumping 0.3 rad in one 1/60 s step moves the gripper at 9 m/s, where its 2 rad/s limit
    /// allows about 1, and a few such jumps leave the 64x64 towel with self-collision with
    /// intersecting layers and edges many times their rest length.
    pub velocity_limits: bool,
    /// The last accepted command (the pose a reset blends back to).
    pub commanded: Option<JointPositions>,
    /// A changed joint command arrived that no step has reached yet.
    pub fresh: bool,
    last_stamp: Option<i64>,
}

impl Default for JointGate {
    fn default() -> Self {
        Self::new(true)
    }
}

impl JointGate {
    /// A gate with nothing commanded yet.
    pub fn new(velocity_limits: bool) -> Self {
        Self {
            velocity_limits,
            commanded: None,
            fresh: false,
            last_stamp: None,
        }
    }

    /// Forgets the command and the last stamp (a new robot).
    pub fn clear(&mut self) {
        self.commanded = None;
        self.last_stamp = None;
    }

    /// Takes a joint state stamped `stamp_ns` (0: unstamped) at simulation time `t`: the robot
    /// reaches it at the end of the next step (`t + dt`), its links interpolated across the
    /// substeps, or (`velocity_limits`) later, when its joints move there at their limits.
    pub fn accept(
        &mut self,
        driver: Option<&mut RobotDriver>,
        t: f64,
        dt: f64,
        stamp_ns: i64,
        input: &JointInput,
    ) -> Result<(), Dropped> {
        let Some(d) = driver else {
            return Err(Dropped::NoRobot);
        };
        if stamp_ns != 0 && self.last_stamp.is_some_and(|last| stamp_ns < last) {
            return Err(Dropped::OutOfOrder { stamp_ns });
        }
        let base = self
            .commanded
            .clone()
            .unwrap_or_else(|| d.joint_positions().clone());
        let mut q = base.clone();
        input.apply(d.robot().kinematics(), &mut q)?;
        if stamp_ns != 0 {
            self.last_stamp = Some(stamp_ns);
        }
        let now_q = d.joint_positions().clone();
        let reach = if self.velocity_limits {
            d.robot().kinematics().slew_time(&now_q, &q).max(dt)
        } else {
            dt
        };
        d.set_source(
            JointSource::Stream(vec![(t, now_q), (t + reach, q.clone())]),
            t,
        );
        self.fresh |= q != base;
        self.commanded = Some(q);
        Ok(())
    }
}
