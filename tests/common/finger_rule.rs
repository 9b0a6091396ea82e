//! A grasp rule between drape_bot's right fingers, for `config/robot_pinch_towel.yaml`: the
//! same pick held by the rule instead of by contact (the pinch bench, the held-inside test).

use drape::scene::{PadSpec, RobotGraspSpec};

/// Closes below a 12 mm opening per finger, opens above 20 mm; its pads are the space between
/// the fingers (palm frame: they span z -0.06 to -0.12, x +-0.01).
pub fn between_the_fingers() -> RobotGraspSpec {
    RobotGraspSpec {
        link: "right_palm".into(),
        fingers: vec!["right_finger_a_joint".into()],
        close_below: 0.012,
        open_above: 0.02,
        pads: PadSpec {
            xyz: [0.0, 0.0, -0.09],
            rpy: [0.0; 3],
            half_extents: [0.01, 0.012, 0.03],
        },
        cloth: None,
    }
}
