//! Coulomb friction of held contact vertices inside the implicit solve.
//!
//! A vertex held against a surface by the constraint filter slides in the filter's free
//! directions. Friction applied after the solve (zero the tangential velocity, move the vertex
//! back) ignores that its neighbours moved on during the step: a cloth edge shoved by a moving
//! press through a stiff spring stuck its neighbour for a whole substep and stored
//! `k (v h)^2 / 2` per spring (0.4 J in tests/contact_wedge.rs), released the next substep.
//! Inside the solve, friction is a force in the filter's free directions `S`, affine in `v` so
//! backward Euler treats it exactly (`A += h J`, `b += h f(v0)`), in one of two modes chosen from
//! the slip `s = S (v - reference)` at the start of the step:
//!
//! - *sliding* (`|s|` above `STICK_SPEED` and above the `h mu N / m` that friction alone
//!   removes in one step): Coulomb's `-mu N t` along the slip direction `t`, plus its
//!   linearisation across it, `-(mu N / |s|) (S - t t^T) (v - reference)` (the direction turns
//!   without the magnitude changing). Along `t` the force is exact, so a cloth on a slope slides
//!   with `g (sin a - mu cos a)`;
//! - *sticking*: a stiff viscous drag `-(mu N / max(|s|, STICK_SPEED)) S (v - reference)`, which
//!   the springs act against within the same solve. Under a load `F` above `mu N` the slip grows
//!   by `F / (mu N)` per substep until the vertex slides: the onset of sliding lags by
//!   `ln(h mu N / (m STICK_SPEED)) / ln(F / (mu N))` substeps (~30 at 1.2 times the limit).
//!
//! `N` lags one substep (IPC's lagged friction). After the solve a slider whose slip reversed
//! (it stopped within the step) becomes a sticker, and a sticker whose drag came out far above
//! the Coulomb limit (its neighbours pull much harder than `mu N`: a cloth edge shoved by a
//! robot link) becomes a slider; the system is then solved once more with the new modes.

use crate::linalg::outer;
use crate::linalg::BlockCsr;
use crate::linalg::Filter;
use crate::{Mat3, Vec3};

/// Tangential speed (m/s) below which a held vertex counts as sticking: the drag is then
/// `mu N / STICK_SPEED` per m/s, so a vertex held by friction creeps at most this fast under a
/// tangential load just below `mu N` (0.1 mm/s: 6 mm a minute at the threshold, nothing below it).
pub const STICK_SPEED: f64 = 1e-4;

/// A sticking vertex is solved again as sliding when its drag exceeds the Coulomb limit by this
/// factor; smaller excesses grow its slip by their ratio per substep instead (a second solve
/// costs as much as the first, and settling cloth has many mildly overloaded contacts).
const OVERSHOOT: f64 = 1.25;

/// Friction of one held vertex: the Coulomb limit `mu N` (N) and the velocity of the surface
/// it rubs on (the mean over its surfaces when held by several).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Friction {
    pub vertex: u32,
    pub limit: f64,
    pub reference: Vec3,
}

/// How a vertex's friction acts during a step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Mode {
    /// Coulomb force along the unit slip direction; `across` (N s/m) damps turning.
    Sliding { direction: Vec3, across: f64 },
    /// Viscous drag `c` (N s/m).
    Sticking { c: f64 },
}

/// The friction of one vertex during a step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Drag {
    pub vertex: usize,
    pub limit: f64,
    pub reference: Vec3,
    pub mode: Mode,
    /// The directions the drag acts in: the filter's free ones `S` for a held vertex, the
    /// surface's tangent plane `I - n n^T` for a contact point (symmetric positive
    /// semi-definite either way).
    tangent: Mat3,
}

impl Drag {
    /// The drag for the slip at the vertex's velocity `v` over a step of `h_over_m` (step over
    /// the vertex's mass): a vertex that friction alone would stop within the step
    /// (`|s| <= h mu N / m`) starts sticking, so that a slow slider is not pushed backwards by
    /// a full step of Coulomb force.
    pub fn fit(f: &Friction, filter: &Filter, v: Vec3, h_over_m: f64) -> Option<Self> {
        if !(f.limit.is_finite() && f.limit > 0.0 && f.reference.is_finite()) {
            return None;
        }
        if *filter == Filter::Fixed {
            return None;
        }
        Some(Self::with_tangent(
            f.vertex as usize,
            f.limit,
            f.reference,
            filter.matrix(),
            v,
            h_over_m,
        ))
    }

    /// The drag of a contact point (`vertex` unused) moving at `u` on a static surface of unit
    /// normal `n`, for a step over the point's effective mass `h_over_m`: friction acts on the
    /// point's slip in the tangent plane, shared by its vertices as the normal force is.
    pub fn at_point(limit: f64, n: Vec3, u: Vec3, h_over_m: f64) -> Option<Self> {
        if !(limit.is_finite() && limit > 0.0 && n.is_finite() && u.is_finite()) {
            return None;
        }
        let tangent = Mat3::IDENTITY - outer(n, n);
        Some(Self::with_tangent(
            usize::MAX,
            limit,
            Vec3::ZERO,
            tangent,
            u,
            h_over_m,
        ))
    }

    fn with_tangent(
        vertex: usize,
        limit: f64,
        reference: Vec3,
        tangent: Mat3,
        v: Vec3,
        h_over_m: f64,
    ) -> Self {
        let mut d = Self {
            vertex,
            limit,
            reference,
            mode: Mode::Sticking { c: 0.0 },
            tangent,
        };
        let slip = d.slip(v);
        d.mode = Mode::Sticking {
            c: limit / slip.length().max(STICK_SPEED),
        };
        if slip.length() > STICK_SPEED.max(limit * h_over_m) {
            d.mode = d.sliding(slip);
        }
        d
    }

    fn slip(&self, v: Vec3) -> Vec3 {
        self.tangent * (v - self.reference)
    }

    fn sliding(&self, slip: Vec3) -> Mode {
        let speed = slip.length();
        Mode::Sliding {
            direction: slip / speed,
            across: self.limit / speed,
        }
    }

    /// The force at velocity `v`.
    pub fn force(&self, v: Vec3) -> Vec3 {
        let slip = self.slip(v);
        match self.mode {
            Mode::Sticking { c } => -slip * c,
            Mode::Sliding { direction, across } => {
                let along = direction.dot(slip);
                -direction * self.limit - (slip - direction * along) * across
            }
        }
    }

    /// `-df/dv`, a symmetric positive semi-definite block.
    pub fn damping(&self) -> Mat3 {
        match self.mode {
            Mode::Sticking { c } => self.tangent * c,
            Mode::Sliding { direction, across } => {
                (self.tangent - outer(direction, direction)) * across
            }
        }
    }

    /// The mode the iterate's velocity `v` calls for, when it differs: a slider that stopped
    /// (its slip reversed) sticks; a sticker whose drag exceeds [`OVERSHOOT`] times the limit
    /// slides in the direction it was pulled.
    pub fn refit(&self, v: Vec3) -> Option<Mode> {
        let slip = self.slip(v);
        match self.mode {
            Mode::Sliding { direction, .. } => {
                (direction.dot(slip) <= 0.0).then_some(Mode::Sticking {
                    c: self.limit / STICK_SPEED,
                })
            }
            Mode::Sticking { c } => (c * slip.length() > OVERSHOOT * self.limit
                && slip.length() > 0.0)
                .then(|| self.sliding(slip)),
        }
    }
}

/// Adds `h (-df/dv)` of every drag to the diagonal blocks of `a`.
pub(crate) fn add_to_matrix(a: &mut BlockCsr, drags: &[Drag], h: f64) {
    for d in drags {
        let i = d.vertex;
        a.add(i as u32, i as u32, d.damping() * h);
    }
}
