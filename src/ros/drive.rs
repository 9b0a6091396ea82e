//! Driving a scene's robot from the `/joint_states` of a recorded bag (`drape record --joints`,
//! a sweep job's `joints`).

use crate::robot::{joint_stream, JointInput, JointSource, RobotDriver};
use std::path::Path;

/// Why a joint-states bag cannot drive the robot.
#[derive(Debug, thiserror::Error)]
pub enum DriveError {
    #[error("--joints {path}: {source}")]
    Bag {
        path: String,
        source: Box<crate::ros::BagError>,
    },
    #[error("--joints {path}: no usable /joint_states message ({dropped} dropped)")]
    Empty { path: String, dropped: usize },
}

/// Replaces the driver's trajectory with the bag's `/joint_states` (time 0 = first message).
/// Bad messages are dropped and counted (logged).
pub fn drive_from_bag(d: &mut RobotDriver, bag: &Path) -> Result<(), DriveError> {
    let path = bag.display().to_string();
    let msgs = crate::ros::read_joint_states(bag).map_err(|source| DriveError::Bag {
        path: path.clone(),
        source: Box::new(source),
    })?;
    let inputs = msgs.into_iter().map(|(ns, m)| {
        let velocities = (!m.velocity.is_empty()).then_some(m.velocity);
        let input = JointInput {
            names: m.name,
            positions: m.position,
            velocities,
        };
        (ns, input)
    });
    let (stream, dropped) = joint_stream(d.robot(), inputs);
    if stream.is_empty() {
        return Err(DriveError::Empty { path, dropped });
    }
    log::info!(
        "--joints {path}: {} joint states over {:.2} s ({dropped} dropped)",
        stream.len(),
        stream.last().map_or(0.0, |s| s.0)
    );
    d.set_source(JointSource::Stream(stream), 0.0);
    Ok(())
}
