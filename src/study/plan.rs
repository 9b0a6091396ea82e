//! Which runs a study makes: the quick set (for tests and a first look) and the full set.

use super::run::{Horizon, RunSettings};
use super::scenes::StudyScene;
use crate::collide::DetectionMode;
use crate::integrate::IntegratorKind;

/// CG settings used wherever the implicit solve is not itself the subject: tight enough that
/// the solve error sits far below the time-discretisation error.
pub const TIGHT_CG: (f64, u32) = (1e-8, 1000);

#[derive(Debug, Clone)]
pub struct Plan {
    pub horizon: Horizon,
    pub scenes: Vec<StudyScene>,
    /// Resolution of the integrator x step sweep and the CG sweep.
    pub base_n: usize,
    /// Factors on stretch and shear stiffness of the step sweep (1 = the scene as written).
    pub stiffnesses: Vec<f64>,
    /// Step levels of the integrator sweep (`dt = 1/(60 2^level)`).
    pub dt_levels: Vec<u32>,
    /// Step level of the references of the step sweep (RK4), well below its smallest step.
    pub reference_level: u32,
    /// Step level of the references at other resolutions (below every step tried there).
    pub resolution_reference_level: u32,
    pub cg_tolerances: Vec<f64>,
    pub cg_caps: Vec<u32>,
    /// Step level of the CG sweep.
    pub cg_dt_level: u32,
    /// Resolutions of the resolution sweep; the largest (if more than two) only for the first scene.
    pub resolutions: Vec<usize>,
    /// Step levels tried at each resolution by the explicit integrators and RK4.
    pub res_dt_levels_explicit: Vec<u32>,
    /// Step levels tried at each resolution by the implicit integrator.
    pub res_dt_levels_implicit: Vec<u32>,
    /// Collision sweep (scenes with obstacles): integrator and step level of each run, each
    /// tried with every detection mode, self-collision off and on.
    pub collision_runs: Vec<(IntegratorKind, u32)>,
}

/// A run and the parts of the study it belongs to.
#[derive(Debug, Clone)]
pub struct PlannedRun {
    pub groups: Vec<&'static str>,
    pub settings: RunSettings,
}

impl Plan {
    /// Small enough for a test: 12x12 grids, 0.3 s simulated.
    pub fn quick() -> Plan {
        Plan {
            horizon: Horizon {
                sample_frames: vec![6, 12, 18],
            },
            scenes: StudyScene::ALL.to_vec(),
            base_n: 12,
            stiffnesses: vec![1.0, 0.01],
            dt_levels: (0..=6).collect(),
            reference_level: 9,
            resolution_reference_level: 9,
            cg_tolerances: vec![1e-2, 1e-4, 1e-6],
            cg_caps: vec![5, 1000],
            cg_dt_level: 2,
            resolutions: vec![12, 16],
            res_dt_levels_explicit: vec![0, 3, 6],
            res_dt_levels_implicit: vec![0, 3],
            collision_runs: vec![(IntegratorKind::Implicit, 0), (IntegratorKind::Implicit, 2)],
        }
    }

    /// The full study: steps 1/60 to 1/30720 s, resolutions 16 to 64, 0.5 s simulated.
    pub fn full() -> Plan {
        Plan {
            horizon: Horizon {
                sample_frames: vec![10, 20, 30],
            },
            scenes: StudyScene::ALL.to_vec(),
            base_n: 16,
            stiffnesses: vec![1.0, 0.1, 0.01],
            dt_levels: (0..=9).collect(),
            reference_level: 12,
            resolution_reference_level: 10,
            cg_tolerances: vec![1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8],
            cg_caps: vec![10, 50, 1000],
            cg_dt_level: 2,
            resolutions: vec![16, 32, 64],
            res_dt_levels_explicit: vec![0, 3, 6, 9],
            res_dt_levels_implicit: vec![0, 3],
            collision_runs: vec![
                (IntegratorKind::Implicit, 0),
                (IntegratorKind::Implicit, 2),
                (IntegratorKind::Implicit, 4),
                (IntegratorKind::SymplecticEuler, 6),
            ],
        }
    }

    /// RK4 step level of the reference for a resolution and stiffness.
    pub fn reference_level_for(&self, n: usize, stiffness: f64) -> u32 {
        if n == self.base_n || stiffness != 1.0 {
            self.reference_level
        } else {
            self.resolution_reference_level
        }
    }

    /// Every run, each distinct setting once.
    pub fn runs(&self) -> Vec<PlannedRun> {
        let mut runs: Vec<PlannedRun> = Vec::new();
        let mut add = |group: &'static str, s: RunSettings| {
            if let Some(r) = runs.iter_mut().find(|r| r.settings == s) {
                if !r.groups.contains(&group) {
                    r.groups.push(group);
                }
            } else {
                runs.push(PlannedRun {
                    groups: vec![group],
                    settings: s,
                });
            }
        };
        let setting =
            |scene, n, stiffness, integrator, dt_level, (tol, cap): (f64, u32)| RunSettings {
                scene,
                n,
                stiffness,
                integrator,
                dt_level,
                cg_tolerance: tol,
                cg_max_iterations: cap,
                collision: None,
            };
        let largest = self.resolutions.iter().copied().max().unwrap_or(0);
        for (si, &scene) in self.scenes.iter().enumerate() {
            for &k in &self.stiffnesses {
                for &integ in &IntegratorKind::ALL {
                    for &l in &self.dt_levels {
                        add("dt", setting(scene, self.base_n, k, integ, l, TIGHT_CG));
                    }
                }
            }
            for &tol in &self.cg_tolerances {
                for &cap in &self.cg_caps {
                    let s = setting(
                        scene,
                        self.base_n,
                        1.0,
                        IntegratorKind::Implicit,
                        self.cg_dt_level,
                        (tol, cap),
                    );
                    add("cg", s);
                }
            }
            let collides = scene
                .scene(self.base_n, 1.0)
                .map(|s| !s.obstacles.is_empty())
                .unwrap_or(false);
            if collides {
                for &(integ, l) in &self.collision_runs {
                    for mode in [
                        DetectionMode::Spheres,
                        DetectionMode::Proximity,
                        DetectionMode::Continuous,
                    ] {
                        for self_collision in [false, true] {
                            let mut s = setting(scene, self.base_n, 1.0, integ, l, TIGHT_CG);
                            s.collision = Some((mode, self_collision));
                            add("collision", s);
                        }
                    }
                }
            }
            for &n in &self.resolutions {
                if n == largest && si > 0 && self.resolutions.len() > 2 {
                    continue;
                }
                for &integ in &IntegratorKind::ALL {
                    let levels = if integ == IntegratorKind::Implicit {
                        &self.res_dt_levels_implicit
                    } else {
                        &self.res_dt_levels_explicit
                    };
                    for &l in levels {
                        add("resolution", setting(scene, n, 1.0, integ, l, TIGHT_CG));
                    }
                }
            }
        }
        runs
    }
}
