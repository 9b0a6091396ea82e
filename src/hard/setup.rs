//! What the hard cases share: scene text with `@KEY@` placeholders, parsing and building it with
//! the case named in errors, and picking a value by resolution.

use super::{HardError, Resolution};
use crate::scene::Scene;
use crate::sim::Simulation;
use std::path::PathBuf;

pub(super) const G: f64 = 9.81;

/// The impact stretch bound plus 10 %: the strain behind a front of velocity `speed` on a sheet of
/// wave speed `c = sqrt(stretch / density)` is `speed / c`, plus the weight of `area` of cloth
/// on one spring.
pub(super) fn impact_stretch_bound(speed: f64, stretch: f64, density: f64, area: f64) -> f64 {
    let wave = (stretch / density).sqrt();
    1.1 * (1.0 + speed / wave + density * area * G / stretch)
}

/// Fills `@KEY@` placeholders (YAML flow maps use braces, so `format!` would be unreadable).
pub(super) fn fill(template: &str, values: &[(&str, String)]) -> String {
    values.iter().fold(template.to_string(), |t, (k, v)| {
        t.replace(&format!("@{k}@"), v)
    })
}

pub(super) fn parse(case: &'static str, text: &str) -> Result<Scene, HardError> {
    let mut s = Scene::from_yaml(text, case).map_err(|source| HardError::Scene { case, source })?;
    // Robot scenes name ../urdf/drape_bot.urdf relative to config/.
    s.base_dir = Some(PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("config"));
    Ok(s)
}

/// Bundled scene `file` of `config/`, loaded for `case`.
pub(super) fn bundled_scene(case: &'static str, file: &str) -> Result<Scene, HardError> {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("config")
        .join(file);
    Scene::load(&path).map_err(|source| HardError::Scene { case, source })
}

pub(super) fn build(case: &'static str, scene: &Scene) -> Result<Simulation, HardError> {
    scene
        .build()
        .map_err(|source| HardError::Scene { case, source })
}

pub(super) fn pick<T>(res: Resolution, ci: T, full: T) -> T {
    match res {
        Resolution::Ci => ci,
        Resolution::Full => full,
    }
}
