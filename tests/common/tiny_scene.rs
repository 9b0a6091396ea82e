//! The smallest scene the CLI tests run: a 4x4 sheet pinned at one corner, 0.1 s implicit. Its
//! name is a marker (`NAMEXYZ`) so a test can tell the scene's own text in a message apart.

pub const TINY_SCENE: &str = r#"name: NAMEXYZ
duration: 0.1
effects: [gravity, stretch, shear]
solver: { integrator: implicit, dt: 0.02 }
cloths:
  - name: sheet
    grid: { size: [0.2, 0.2], resolution: [4, 4], pose: { xyz: [0, 0, 1] } }
    pins: [ { region: top_left } ]
"#;

/// [`TINY_SCENE`] on a robot read from `urdf` (relative to the scene file).
#[allow(dead_code)] // not every test binary that includes this file drives a robot
pub fn tiny_robot_scene(urdf: &str) -> String {
    format!("{TINY_SCENE}robot:\n  urdf: {urdf}\n")
}
