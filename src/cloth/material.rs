//! Material parameters of one cloth piece.

use serde::{Deserialize, Serialize};

/// Damping terms; all default to zero (off).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Damping {
    /// Spring damping along each stretch/shear spring (N s/m).
    pub spring: f64,
    /// Air drag on absolute velocity, as a rate (1/s): `f = -air * m * v`.
    pub air: f64,
    /// Velocity diffusion between neighbours (N s/m): `f_i = diffusion * sum_j (v_j - v_i)`.
    pub diffusion: f64,
}

/// The default through-thickness compressive modulus (Pa, see [`Material::compressive_modulus`]).
pub const DEFAULT_COMPRESSIVE_MODULUS: f64 = 1.2e4;

/// Material of a cloth piece. Stiffnesses are per spring / per stencil, in SI units.
///
/// Stretch energy of a spring is `E = k/2 (|xi - xj| - l)^2`, so `k` is Hooke's constant in N/m
/// (the survey writes `k (|ri - rj| - l)^2`: its `k` is our `k/2`).
/// Bending is `B/2 * integral |d2r/du2|^2` along the warp (and likewise weft), in N m;
/// twist is `T/2 * integral |d2r/du dv|^2`, in N m.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Material {
    /// Areal density (kg/m^2).
    pub density: f64,
    /// Structural (warp/weft edge) spring stiffness (N/m).
    pub stretch: f64,
    /// Shear (diagonal) spring stiffness (N/m).
    pub shear: f64,
    /// Skip-one spring stiffness (N/m), used by the `skip_one` effect.
    pub skip_one: f64,
    /// Bending rigidity along the warp (u) direction (N m).
    pub bend_warp: f64,
    /// Bending rigidity along the weft (v) direction (N m).
    pub bend_weft: f64,
    /// Twist rigidity (mixed derivative) (N m).
    pub twist: f64,
    pub damping: Damping,
    /// Collision thickness (m).
    pub thickness: f64,
    /// Coulomb friction coefficient against obstacles and itself.
    pub friction: f64,
    /// Through-thickness compressive modulus (Pa). Squeezed between two surfaces closer than
    /// its two contact layers (`2 thickness`, the cloth's thickness in a pinch), the cloth
    /// presses on each with `compressive_modulus * area * compressed fraction`: the grip a
    /// pinch holds it with (`sim::coupling`'s pinch springs). The default, 12 kPa, is a
    /// modelling default: a linear law through the middle of the compressibility Kawabata's
    /// compression test (KES-FB3) measures on apparel fabrics, 20 to 60 % thinner at 4.9 kPa
    /// than at 49 Pa; it compresses a cloth by 25 % under 3 kPa.
    pub compressive_modulus: f64,
    /// Largest elongation of a mesh edge, as a fraction of its rest length (0.1: 10 %). Edges
    /// the solve leaves longer are shortened after it (`sim::limit`, Provot 1995); absent, the
    /// springs alone resist stretch and nothing is spent on it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub strain_limit: Option<f64>,
    /// Strain at which the stretch and shear springs stiffen (0.03: 3 %), as woven fabric does
    /// once its yarns are straight (its tensile curve is J-shaped). Past it a spring's tangent
    /// stiffness is `knee_stiffening` times its own, inside the solve (`effects::springs`);
    /// absent, the springs are linear and nothing is spent on it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stretch_knee: Option<f64>,
    /// Tangent stiffness past `stretch_knee` over the stiffness below it (default
    /// [`DEFAULT_KNEE_STIFFENING`]); read only with `stretch_knee`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub knee_stiffening: Option<f64>,
    /// Areal density as a textile lab reports it (g/m^2), instead of `density`; the scene
    /// converts it ([`Material::resolve_textile`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub areal_density: Option<f64>,
    /// Bending length `c` of the cantilever test along the warp (cm), instead of `bend_warp`:
    /// `B = w c^3` with `w` the weight per unit area ([`Material::resolve_textile`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bending_length_warp: Option<f64>,
    /// Bending length along the weft (cm), instead of `bend_weft`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bending_length_weft: Option<f64>,
    /// Tensile stiffness per unit width, instead of `stretch`: the structural springs of a grid
    /// get it shared out by their tributary widths (`cloth::topology::spring_stiffness`), and
    /// the scene sets `stretch` to its inner springs' constant for what reads one per cloth.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tensile: Option<Tensile>,
}

/// Stiffening past the knee where a material names `stretch_knee` alone.
pub const DEFAULT_KNEE_STIFFENING: f64 = 100.0;

impl Material {
    /// Where this material's stretch and shear springs stiffen: `(knee strain, stiffening)`;
    /// `None` for linear springs.
    pub fn knee(&self) -> Option<(f64, f64)> {
        self.stretch_knee
            .map(|s| (s, self.knee_stiffening.unwrap_or(DEFAULT_KNEE_STIFFENING)))
    }
}

/// A strip test's tensile stiffness: force per unit width over strain (N/m), warp and weft, as
/// the secant at the strain it was measured at.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Tensile {
    /// Along the warp (u), N/m.
    pub warp: f64,
    /// Along the weft (v), N/m.
    pub weft: f64,
    /// The strain the stiffness was measured at (0.02: 2 %). Linear springs use the stiffness at
    /// every strain; a stretch that stiffens past a knee reads where the measurement stands
    /// against its knee from here.
    pub strain: f64,
}

/// Standard gravity (m/s^2): bending lengths are measured under it (`B = rho g c^3`).
pub const STANDARD_GRAVITY: f64 = 9.80665;

impl Material {
    /// Replaces the textile keys that have an internal equivalent by it: `areal_density` (g/m^2)
    /// becomes `density` (kg/m^2), a bending length `c` (cm) the rigidity `B = rho g c^3` (N m)
    /// along its direction, with `rho` the (converted) density and `g` standard gravity. Those
    /// keys are then cleared; `tensile` stays (its springs need the grid's spacing). The scene
    /// refuses a textile key beside the key it replaces before this runs.
    pub fn resolve_textile(&mut self) {
        if let Some(g_m2) = self.areal_density.take() {
            self.density = g_m2 * 1e-3;
        }
        let w = self.density * STANDARD_GRAVITY;
        if let Some(c) = self.bending_length_warp.take() {
            self.bend_warp = w * (c * 1e-2).powi(3);
        }
        if let Some(c) = self.bending_length_weft.take() {
            self.bend_weft = w * (c * 1e-2).powi(3);
        }
    }
}

impl Default for Material {
    /// A cotton-like sheet.
    fn default() -> Self {
        Self {
            density: 0.2,
            stretch: 1000.0,
            shear: 100.0,
            skip_one: 0.0,
            bend_warp: 1e-4,
            bend_weft: 1e-4,
            twist: 1e-5,
            damping: Damping {
                spring: 0.05,
                air: 0.05,
                diffusion: 0.0,
            },
            thickness: 0.005,
            friction: 0.3,
            compressive_modulus: DEFAULT_COMPRESSIVE_MODULUS,
            strain_limit: None,
            stretch_knee: None,
            knee_stiffening: None,
            areal_density: None,
            bending_length_warp: None,
            bending_length_weft: None,
            tensile: None,
        }
    }
}
