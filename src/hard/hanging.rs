//! Hanging-cloth cases: a square hung from two corners, made stiff (near and over the explicit
//! limit, and implicit), light, heavy, tiny and huge.

use super::setup::{build, fill, parse, pick, G};
use super::{Case, Criteria, HardError, Resolution};
use crate::scene::Scene;
use crate::sim::Simulation;
use crate::Vec3;

/// A horizontal square cloth at height `z`, hanging from two corners.
const HANGING: &str = r#"
effects: [gravity, stretch, shear, bending, damping]
solver: { integrator: @INTEGRATOR@, dt: @DT@, substeps: 1 }
cloths:
  - name: cloth
    grid: { size: [@SIZE@, @SIZE@], resolution: [@RES@, @RES@], pose: { xyz: [0, 0, @Z@] } }
    material:
      density: @DENSITY@
      stretch: @STRETCH@
      shear: @SHEAR@
      bend_warp: @BEND@
      bend_weft: @BEND@
      damping: { spring: @KD@, air: 0.05 }
    pins: [ { region: top_left }, { region: top_right } ]
"#;

struct Hanging {
    integrator: &'static str,
    dt: f64,
    size: f64,
    res: usize,
    density: f64,
    stretch: f64,
    bend: f64,
    spring_damping: f64,
}

impl Hanging {
    fn new(size: f64, res: usize) -> Self {
        Self {
            integrator: "implicit",
            dt: 1.0 / 60.0,
            size,
            res,
            density: 0.2,
            stretch: 1000.0,
            bend: 1e-4,
            spring_damping: 0.05,
        }
    }

    fn scene(&self, case: &'static str) -> Result<Scene, HardError> {
        let z = self.size;
        parse(
            case,
            &fill(
                HANGING,
                &[
                    ("INTEGRATOR", self.integrator.into()),
                    ("DT", format!("{:e}", self.dt)),
                    ("SIZE", format!("{:e}", self.size)),
                    ("RES", self.res.to_string()),
                    ("Z", format!("{z:e}")),
                    ("DENSITY", format!("{:e}", self.density)),
                    ("STRETCH", format!("{:e}", self.stretch)),
                    ("SHEAR", format!("{:e}", 0.1 * self.stretch)),
                    ("BEND", format!("{:e}", self.bend)),
                    ("KD", format!("{:e}", self.spring_damping)),
                ],
            ),
        )
    }

    /// Bounds of a cloth hanging from two corners, from energy: no point can get further from a
    /// pin than the diagonal (stretched by `strain`), and no vertex can be faster than if the whole
    /// fall of the cloth's centre of mass (at most the diagonal) went into that one vertex's kinetic
    /// energy: `v^2 <= 2 g d M / m_min`.
    fn criteria(&self, sim: &Simulation, strain: f64) -> Criteria {
        let diag = self.size * std::f64::consts::SQRT_2;
        let pin = Vec3::new(0.5 * self.size, 0.5 * self.size, self.size).length();
        let m_total: f64 = sim.cloth.mass.iter().sum();
        let m_min = sim.cloth.mass.iter().copied().fold(f64::INFINITY, f64::min);
        let v_max = (2.0 * G * diag * (1.0 + strain) * m_total / m_min).sqrt();
        Criteria::base(pin + diag * (1.0 + strain), v_max)
    }
}

fn hanging_case(
    name: &'static str,
    description: String,
    h: Hanging,
    duration: f64,
    strain: f64,
) -> Result<Case, HardError> {
    let sim = build(name, &h.scene(name)?)?;
    let criteria = h.criteria(&sim, strain);
    Ok(Case {
        name,
        description,
        sim,
        driver: None,
        duration,
        criteria,
    })
}

pub(super) fn stiff_implicit(res: Resolution) -> Result<Case, HardError> {
    let mut h = Hanging::new(0.5, pick(res, 12, 32));
    h.stretch = 1e6;
    hanging_case(
        "stiff_implicit",
        "0.5 m cloth, stretch 1e6 N/m (shear 1e5), implicit at dt = 1/60 s, dropped from two corners"
            .into(),
        h,
        pick(res, 2.0, 5.0),
        // Weight over stiffness: 0.05 kg * g / 1e6 N/m per spring is far below 1 %.
        0.01,
    )
}

/// A symplectic Euler run at `h * omega_bound = ratio` of the stiff cloth.
fn stiff_explicit(name: &'static str, res: Resolution, ratio: f64) -> Result<Case, HardError> {
    let mut h = Hanging::new(0.5, pick(res, 8, 16));
    h.stretch = 1e6;
    h.integrator = "symplectic_euler";
    // Find omega from the built cloth, then rebuild at the step that gives the ratio.
    let probe = build(name, &h.scene(name)?)?;
    // The same bound the simulation uses: omega^2 <= the sum of every elastic effect's bound.
    let bounds = probe.effects().stiffness(&probe.cloth.mass);
    let omega = (!bounds.is_empty())
        .then(|| bounds.iter().map(|b| b.omega_sq).sum::<f64>().sqrt())
        .ok_or(HardError::NoElasticEffect { case: name })?;
    h.dt = ratio / omega;
    let description = format!(
        "as stiff_implicit at {}x{} with symplectic Euler at h*omega_bound = {ratio} (limit 2), \
         guard policy subdivide",
        h.res, h.res
    );
    hanging_case(name, description, h, pick(res, 0.1, 0.5), 0.01)
}

pub(super) fn stiff_explicit_near_limit(res: Resolution) -> Result<Case, HardError> {
    stiff_explicit("stiff_explicit_near_limit", res, 1.9)
}

pub(super) fn stiff_explicit_over_limit(res: Resolution) -> Result<Case, HardError> {
    let mut c = stiff_explicit("stiff_explicit_over_limit", res, 4.0)?;
    c.criteria.expect_subdivisions = true;
    Ok(c)
}

pub(super) fn light_cloth(res: Resolution) -> Result<Case, HardError> {
    let mut h = Hanging::new(0.5, pick(res, 12, 32));
    h.density = 0.002;
    hanging_case(
        "light_cloth",
        "0.5 m cloth of 0.002 kg/m^2 (100x lighter than cotton), implicit at 1/60 s".into(),
        h,
        pick(res, 2.0, 5.0),
        0.01,
    )
}

pub(super) fn heavy_cloth(res: Resolution) -> Result<Case, HardError> {
    let mut h = Hanging::new(0.5, pick(res, 12, 32));
    h.density = 20.0;
    hanging_case(
        "heavy_cloth",
        "0.5 m cloth of 20 kg/m^2 (100x heavier than cotton, 1e4 x the light one) on the same \
         1000 N/m springs, implicit at 1/60 s"
            .into(),
        h,
        pick(res, 2.0, 5.0),
        // 5 kg on 1000 N/m springs stretches a lot: allow the diagonal to double.
        1.0,
    )
}

pub(super) fn tiny_cloth(res: Resolution) -> Result<Case, HardError> {
    let h = Hanging::new(0.01, pick(res, 8, 16));
    hanging_case(
        "tiny_cloth",
        "1 cm cloth (cotton material), implicit at 1/60 s".into(),
        h,
        pick(res, 2.0, 5.0),
        0.01,
    )
}

pub(super) fn huge_cloth(res: Resolution) -> Result<Case, HardError> {
    let mut h = Hanging::new(10.0, pick(res, 16, 48));
    h.bend = 1e-2;
    hanging_case(
        "huge_cloth",
        "10 m cloth (cotton density, 1000 N/m), implicit at 1/60 s".into(),
        h,
        pick(res, 4.0, 10.0),
        // 20 kg on 1000 N/m springs: the diagonal may stretch by half.
        0.5,
    )
}
