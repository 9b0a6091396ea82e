//! Coulomb friction of held contact vertices inside the implicit solve.
//!
//! A vertex held against a surface by the constraint filter slides in the filter's free
//! directions. Friction applied after the solve (zero the tangential velocity, move the vertex
//! back) ignores that its neighbours moved on during the step: a cloth edge shoved by a moving
//! press through a stiff spring would stick its neighbour for a whole substep and store
//! `k (v h)^2 / 2` per spring (tests/contact_wedge.rs), released the next substep.
//! Inside the solve, friction is a force in the filter's free directions `S`, affine in `v` so
//! backward Euler treats it exactly (`A += h J`, `b += h f(v0)`), in one of two modes chosen from
//! the slip `s = S (v - reference)` at the start of the step:
//!
//! - *sliding* (`|s|` above `STICK_SPEED` and above what friction against the vertex's load
//!   removes in one step, see [`Drag::fit`]): Coulomb's `-mu N t` along the slip direction `t`, plus its
//!   linearisation across it, `-(mu N / |s|) (S - t t^T) (v - reference)` (the direction turns
//!   without the magnitude changing). Along `t` the force is exact, so a cloth on a slope slides
//!   with `g (sin a - mu cos a)`;
//! - *sticking*: a stiff viscous drag `-(mu N / max(|s|, STICK_SPEED)) S (v - reference)`, which
//!   the springs act against within the same solve. Under a load `F` above `mu N` it slides
//!   from the next substep on (with modes decided from the slip alone, its slip would grow by
//!   only `F / (mu N)` per substep until it slid: dozens of substeps just above the limit).
//!
//! A pinch's vertices on one side (see [`Friction::patch`]) are fitted and refitted as one
//! patch, on their summed load and limit ([`fit_patches`], [`overloaded`]).
//!
//! `N` lags one substep (IPC's lagged friction), and so does the mode: it is chosen before the
//! solve from the slip at the start of the step and the tangential load the rest of the system
//! put on the vertex in the last step (see [`Drag::fit`]): a sticker whose drag held more than
//! `mu N` slides, a slider that Coulomb friction would stop within the step against that load
//! sticks. After the solve, a sticker whose drag came out far above the limit (a load that rose
//! within the step: a cloth edge shoved by a robot link) becomes a slider and the system is
//! solved once more; a slider whose slip reversed sticks from the next step on (the fit lets
//! only those slide that Coulomb would not stop against the last load, so a reversal needs the
//! load to drop within the step). Refitting both ways, with modes from the start slip only,
//! chatters on a cloth draped over a sphere: dozens of held vertices change mode after every
//! solve, and each step is solved about three times.

use crate::linalg::outer;
use crate::linalg::BlockCsr;
use crate::linalg::Filter;
use crate::{Mat3, Vec3};

/// Tangential speed (m/s) below which a held vertex counts as sticking: the drag is then
/// `mu N / STICK_SPEED` per m/s, so a vertex held by friction creeps at most this fast under a
/// tangential load just below `mu N` (0.1 mm/s: 6 mm a minute at the threshold, nothing below it).
pub const STICK_SPEED: f64 = 1e-4;

/// A sticking vertex is solved again as sliding when its drag exceeds the Coulomb limit by this
/// factor within the step; smaller excesses make it slide from the next step on (see
/// [`Drag::fit`]; a second solve costs as much as the first).
const OVERSHOOT: f64 = 1.25;

/// Friction of one held vertex: the Coulomb limit `mu N` (N) and the velocity of the surface
/// it rubs on (the mean over its surfaces when held by several).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Friction {
    pub vertex: u32,
    pub limit: f64,
    pub reference: Vec3,
    /// The surface's unit normal when a spring, not the filter, presses the vertex on it (a
    /// pinch): friction then acts in that surface's tangent plane, and sticks firmly (its
    /// sticking drag is `limit / STICK_SPEED` whatever the start slip: a gripper's pads
    /// accelerate, and a drag weakened by the slip their acceleration gives would let the
    /// cloth they carry creep off under its steady weight, faster every step; a drag over the
    /// limit at the step's end still slides, see [`Drag::overloaded`]). `None`: in the
    /// filter's free directions.
    pub normal: Option<Vec3>,
    /// The pinch this friction grips in (this side's obstacle, the facing one's), or `None`.
    /// A pinch's frictions on one side stick or slide together, on their summed load against
    /// their summed limit (see [`fit_patches`]).
    pub patch: Option<[u32; 2]>,
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
    /// The pinch patch it belongs to (see [`Friction::patch`]).
    patch: Option<[u32; 2]>,
    /// The tangential load (N) it was fitted against.
    load: Vec3,
}

impl Drag {
    /// The drag for the slip at the vertex's velocity `v` over a step of `h_over_m` (step over
    /// the vertex's mass) under the tangential `load` (N) the rest of the system put on the
    /// vertex in the last step (zero when unknown): it slides when Coulomb friction against
    /// that load would not stop it within the step, `|s| + h (load . t - mu N) / m > 0` along
    /// the slip direction `t`, and sticks otherwise. With no load that is `|s| > h mu N / m`
    /// (a slow slider is not pushed backwards by a full step of Coulomb force); a sticker
    /// whose drag held more than `mu N` last step slides (Coulomb's threshold, lagged one
    /// step like the normal force).
    pub fn fit(f: &Friction, filter: &Filter, v: Vec3, h_over_m: f64, load: Vec3) -> Option<Self> {
        if !(f.limit.is_finite() && f.limit > 0.0 && f.reference.is_finite()) {
            return None;
        }
        if *filter == Filter::Fixed {
            return None;
        }
        // A free vertex pressed by a spring rubs in the surface's tangent plane; one the
        // filter holds, in the filter's free directions.
        let tangent = match f.normal {
            Some(n) if *filter == Filter::Free && n.is_finite() => Mat3::IDENTITY - outer(n, n),
            _ => filter.matrix(),
        };
        let mut d = Self::with_tangent(
            f.vertex as usize,
            f.limit,
            f.reference,
            tangent,
            v,
            h_over_m,
            load,
        );
        d.patch = f.patch;
        if f.normal.is_some() && matches!(d.mode, Mode::Sticking { .. }) {
            d.mode = Mode::Sticking {
                c: f.limit / STICK_SPEED,
            };
        }
        Some(d)
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
            Vec3::ZERO,
        ))
    }

    fn with_tangent(
        vertex: usize,
        limit: f64,
        reference: Vec3,
        tangent: Mat3,
        v: Vec3,
        h_over_m: f64,
        load: Vec3,
    ) -> Self {
        let mut d = Self {
            vertex,
            limit,
            reference,
            mode: Mode::Sticking { c: 0.0 },
            tangent,
            patch: None,
            load: tangent * load,
        };
        let slip = d.slip(v);
        d.mode = Mode::Sticking {
            c: limit / slip.length().max(STICK_SPEED),
        };
        let speed = slip.length();
        if speed > STICK_SPEED {
            let along = (d.tangent * load).dot(slip / speed);
            if speed + h_over_m * (along - limit) > 0.0 {
                d.mode = d.sliding(slip);
            }
        }
        d
    }

    fn slip(&self, v: Vec3) -> Vec3 {
        self.tangent * (v - self.reference)
    }

    /// Sliding along a patch's slip `slip` (not the vertex's own): Coulomb's force along
    /// it, and the turning damping of that speed.
    fn sliding_at(&self, slip: Vec3) -> Mode {
        let speed = slip.length().max(STICK_SPEED);
        Mode::Sliding {
            direction: slip / slip.length().max(f64::MIN_POSITIVE),
            across: self.limit / speed,
        }
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

    /// A sticker whose drag at the iterate's velocity `v` exceeds [`OVERSHOOT`] times the
    /// limit slides in the direction it was pulled (the held vertices' refit after the solve:
    /// a slider whose slip reversed sticks from the next step on, see [`Drag::fit`]).
    pub fn overloaded(&self, v: Vec3) -> Option<Mode> {
        match self.mode {
            Mode::Sticking { .. } => self.refit(v),
            Mode::Sliding { .. } => None,
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

impl Drag {
    /// [`Drag::refit`] for two cloth layers' contact point, whose drag is fitted with no load
    /// (`at_point`): a sticker still slipping faster than [`STICK_SPEED`] at the end of the step
    /// did not stick, so it slides. Without a load a slow slider is fitted as a sticker of drag
    /// `mu N / |s|`, which a load (gravity down an incline) keeps from stopping: its force falls
    /// with the slip, and a cloth slid down a cloth incline that Coulomb holds.
    pub fn refit_unloaded(&self, v: Vec3) -> Option<Mode> {
        let slip = self.slip(v);
        match self.mode {
            Mode::Sticking { .. } if slip.length() > STICK_SPEED => Some(self.sliding(slip)),
            _ => self.refit(v),
        }
    }
}

/// Fits the modes of the pinch patches' drags together (see [`Friction::patch`]): the cloth
/// between two pads is far stiffer in its plane than the friction that holds it, so it sticks
/// or slides as one piece, when the summed tangential load exceeds the summed limit
/// `mu (N_1 + ... + N_k)`. Fitted vertex by vertex, the few vertices where a hanging towel's
/// pull enters the pad would carry most of it, each slide on past its own share of the grip,
/// and the towel creep out of a grip three times its weight. The patch slides as one vertex of
/// the patch's mass would (see [`Drag::fit`]), at its mass-weighted mean slip; sticking, each
/// member keeps its firm drag. `v` and `mass` are per vertex, `h` the step.
pub(crate) fn fit_patches(drags: &mut [Drag], v: &[Vec3], mass: &[f64], h: f64) {
    let at = |i: usize| v.get(i).copied().unwrap_or(Vec3::ZERO);
    for (_, members) in patches(drags) {
        let Some(p) = Patch::of(drags, &members, at, mass) else {
            continue;
        };
        let (m, limit, load, slip) = (p.mass, p.limit, p.load, p.slip);
        let speed = slip.length();
        let slides = speed > STICK_SPEED && speed + h / m * (load.dot(slip / speed) - limit) > 0.0;
        for &k in &members {
            let g = &mut drags[k];
            g.mode = if slides {
                g.sliding_at(slip)
            } else {
                Mode::Sticking {
                    c: g.limit / STICK_SPEED,
                }
            };
        }
    }
}

/// The drags' new modes where the iterate's velocities (`at` a vertex) overload their
/// stickers (see [`Drag::overloaded`]), as (index into `drags`, mode): a pinch patch
/// slides when its summed drag exceeds [`OVERSHOOT`] times its summed limit, all its members
/// along their mass-weighted mean slip (`mass` per vertex); patches only when `patches_too`.
pub(crate) fn overloaded(
    drags: &[Drag],
    at: impl Fn(usize) -> Vec3,
    mass: &[f64],
    patches_too: bool,
) -> Vec<(usize, Mode)> {
    let mut out: Vec<(usize, Mode)> = (drags.iter().enumerate())
        .filter(|(_, g)| g.patch.is_none())
        .filter_map(|(k, g)| g.overloaded(at(g.vertex)).map(|mode| (k, mode)))
        .collect();
    if !patches_too {
        return out;
    }
    for (_, members) in patches(drags) {
        let sticking = (members.iter()).all(|&k| matches!(drags[k].mode, Mode::Sticking { .. }));
        let Some(p) = Patch::of(drags, &members, &at, mass).filter(|_| sticking) else {
            continue;
        };
        if p.drag.length() > OVERSHOOT * p.limit && p.slip.length() > 0.0 {
            out.extend(members.iter().map(|&k| (k, drags[k].sliding_at(p.slip))));
        }
    }
    out
}

/// A pinch patch's sums at its members' velocities: mass (kg), Coulomb limit and fitted load
/// (N), drag (N) and mass-weighted mean slip (m/s).
struct Patch {
    mass: f64,
    limit: f64,
    load: Vec3,
    drag: Vec3,
    slip: Vec3,
}

impl Patch {
    /// The sums over `members` (indices into `drags`) at the velocities `at` a vertex; `None`
    /// for a patch without mass or limit.
    fn of(
        drags: &[Drag],
        members: &[usize],
        at: impl Fn(usize) -> Vec3,
        mass: &[f64],
    ) -> Option<Self> {
        let mut p = Self {
            mass: 0.0,
            limit: 0.0,
            load: Vec3::ZERO,
            drag: Vec3::ZERO,
            slip: Vec3::ZERO,
        };
        for &k in members {
            let g = &drags[k];
            let (vi, mi) = (at(g.vertex), mass.get(g.vertex).copied().unwrap_or(0.0));
            p.mass += mi;
            p.limit += g.limit;
            p.load += g.load;
            p.drag += g.force(vi);
            p.slip += g.slip(vi) * mi;
        }
        (p.mass > 0.0 && p.limit > 0.0).then(|| Self {
            slip: p.slip / p.mass,
            ..p
        })
    }
}

/// The pinch patches among `drags`: each patch's key and its members' indices.
fn patches(drags: &[Drag]) -> Vec<([u32; 2], Vec<usize>)> {
    let mut out: Vec<([u32; 2], Vec<usize>)> = Vec::new();
    for (k, g) in drags.iter().enumerate() {
        let Some(key) = g.patch else { continue };
        match out.iter_mut().find(|p| p.0 == key) {
            Some(p) => p.1.push(k),
            None => out.push((key, vec![k])),
        }
    }
    out
}

/// Adds `h (-df/dv)` of every drag to the diagonal blocks of `a`.
pub(crate) fn add_to_matrix(a: &mut BlockCsr, drags: &[Drag], h: f64) {
    for d in drags {
        let i = d.vertex;
        a.add(i as u32, i as u32, d.damping() * h);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One side of a two-vertex pinch on a plane of normal z, each vertex limited to 1 N, at
    /// rest, with the tangential loads `loads` (N) of the last step.
    fn patch(loads: [f64; 2]) -> Vec<Drag> {
        let filter = Filter::Free;
        (0..2)
            .filter_map(|i| {
                let f = Friction {
                    vertex: i as u32,
                    limit: 1.0,
                    reference: Vec3::ZERO,
                    normal: Some(Vec3::Z),
                    patch: Some([0, 1]),
                };
                Drag::fit(&f, &filter, Vec3::ZERO, 1.0, Vec3::X * loads[i])
            })
            .collect()
    }

    /// A pinch whose load falls unevenly on its vertices sticks while the sum stays under the
    /// summed limit (one vertex loaded past its own limit included), and slides along the
    /// patch's slip once the summed drag at the solved velocity exceeds it.
    #[test]
    fn a_pinch_patch_sticks_and_slides_on_its_summed_load_and_limit() {
        let (mass, h) = ([1e-3; 2], 1e-2);
        let mut drags = patch([1.5, 0.2]);
        fit_patches(&mut drags, &[Vec3::ZERO; 2], &mass, h);
        assert!(drags
            .iter()
            .all(|g| matches!(g.mode, Mode::Sticking { .. })));
        // Solved: the first vertex creeps at 1.5 STICK_SPEED (its drag 1.5 N), the second at
        // 0.2: together 1.7 N of 2.
        let v = [Vec3::X * 1.5 * STICK_SPEED, Vec3::X * 0.2 * STICK_SPEED];
        assert!(overloaded(&drags, |i| v[i], &mass, true).is_empty());
        // Each alone past the overshoot: 2.6 N of 2 together.
        let v = [Vec3::X * 1.3 * STICK_SPEED, Vec3::X * 1.3 * STICK_SPEED];
        let refits = overloaded(&drags, |i| v[i], &mass, true);
        assert_eq!(refits.len(), 2);
        for (_, mode) in refits {
            let Mode::Sliding { direction, .. } = mode else {
                panic!("{mode:?}");
            };
            assert!((direction - Vec3::X).length() < 1e-12);
        }
        // Patches are refitted only on the tight answer.
        assert!(overloaded(&drags, |i| v[i], &mass, false).is_empty());
    }
}
