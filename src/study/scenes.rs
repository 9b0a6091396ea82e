//! The study's reference scenes, kept here as YAML so a clean checkout reproduces the study
//! whatever happens to the example scenes in `config/`.

use crate::scene::{Scene, SceneError};

/// A 1 m square sheet released flat and held by its two top corners, so it swings down and
/// back: large motion, stiff stretch springs, no external work.
const HANGING_SWING: &str = r#"
name: hanging_swing
gravity: [0.0, 0.0, -9.81]
effects: [gravity, stretch, shear, bending, twist, damping]
solver: { integrator: rk4, dt: 0.001 }
cloths:
  - name: sheet
    grid: { size: [1.0, 1.0], resolution: [16, 16], pose: { xyz: [0.0, 0.0, 1.5] } }
    material:
      density: 0.2
      stretch: 2000.0
      shear: 200.0
      bend_warp: 1.0e-4
      bend_weft: 1.0e-4
      twist: 1.0e-5
      damping: { spring: 0.05, air: 0.1 }
    pins: [ { region: top_left }, { region: top_right } ]
"#;

/// A flag pinned along its left edge in gusty, time-varying wind: forcing from outside.
const FLAG: &str = r#"
name: flag
effects: [gravity, stretch, shear, bending, wind, damping]
solver: { integrator: rk4, dt: 0.001 }
wind:
  velocity: [6.0, 0.0, 0.0]
  gusts:
    - { amplitude: [2.0, 0.0, 0.0], frequency: 0.5 }
    - { amplitude: [0.0, 1.5, 0.5], frequency: 1.3, phase: 0.7 }
  air_density: 1.2
  drag_coefficient: 1.0
cloths:
  - name: flag
    grid: { size: [0.9, 0.6], resolution: [16, 11], pose: { xyz: [0.45, 0.0, 2.0], rpy: [1.5707963267948966, 0.0, 0.0] } }
    material:
      density: 0.15
      stretch: 1500.0
      shear: 150.0
      bend_warp: 5.0e-5
      bend_weft: 5.0e-5
      damping: { spring: 0.02, air: 0.02 }
    pins: [ { region: left_edge } ]
"#;

/// A sheet dropped onto a sphere: contact, friction and (optionally) self-collision where the
/// corners fold. Continuous detection without self-collision unless a run says otherwise
/// (the reference too: self-collision is a knob of the collision sweep, compared against it).
const SPHERE_DRAPE: &str = r#"
name: sphere_drape
effects: [gravity, stretch, shear, bending, damping]
solver: { integrator: rk4, dt: 0.001 }
cloths:
  - name: sheet
    grid: { size: [1.2, 1.2], resolution: [16, 16], pose: { xyz: [0.0, 0.0, 0.62] } }
    material:
      density: 0.2
      stretch: 1500.0
      shear: 150.0
      bend_warp: 1.0e-4
      bend_weft: 1.0e-4
      damping: { spring: 0.05, air: 0.1 }
      thickness: 0.01
      friction: 0.4
obstacles:
  - { name: ball, shape: { type: sphere, radius: 0.4 }, pose: { xyz: [0.0, 0.0, 0.2] } }
collision: { mode: continuous, self_collision: false }
"#;

/// One of the study's scenes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum StudyScene {
    HangingSwing,
    Flag,
    SphereDrape,
}

impl StudyScene {
    pub const ALL: [StudyScene; 3] = [
        StudyScene::HangingSwing,
        StudyScene::Flag,
        StudyScene::SphereDrape,
    ];

    pub fn name(self) -> &'static str {
        match self {
            StudyScene::HangingSwing => "hanging_swing",
            StudyScene::Flag => "flag",
            StudyScene::SphereDrape => "sphere_drape",
        }
    }

    fn yaml(self) -> &'static str {
        match self {
            StudyScene::HangingSwing => HANGING_SWING,
            StudyScene::Flag => FLAG,
            StudyScene::SphereDrape => SPHERE_DRAPE,
        }
    }

    /// Grid resolution for a study resolution `n` (vertices along the longer side); the flag
    /// keeps its 3:2 aspect.
    pub fn resolution(self, n: usize) -> [usize; 2] {
        match self {
            StudyScene::HangingSwing | StudyScene::SphereDrape => [n, n],
            StudyScene::Flag => [n, ((n as f64) * 2.0 / 3.0).round().max(2.0) as usize],
        }
    }

    /// The scene at resolution `n` with its stretch and shear stiffness scaled by `stiffness`.
    pub fn scene(self, n: usize, stiffness: f64) -> Result<Scene, SceneError> {
        let mut s = Scene::from_yaml(self.yaml(), self.name())?;
        for c in &mut s.cloths {
            c.grid.resolution = self.resolution(n);
            c.material.stretch *= stiffness;
            c.material.shear *= stiffness;
        }
        Ok(s)
    }

    /// Length scale used to make energy errors relative: total mass x |g| x this length.
    pub fn length(self) -> f64 {
        match self {
            StudyScene::HangingSwing => 1.0,
            StudyScene::Flag => 0.9,
            StudyScene::SphereDrape => 1.2,
        }
    }
}
