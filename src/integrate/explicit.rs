//! Forward Euler and symplectic (semi-implicit) Euler.
//!
//! Both run out of place ([`Integrator::step_into`]): one pass reads the start state and the
//! forces and writes the end state, so the simulation keeps the start state for its rollback
//! without a copy.

use super::dynamics::Dynamics;
use super::integrator::{Capabilities, Integrator, StepReport};
use crate::effects::State;
use crate::linalg::Filter;
use crate::par::PAR_VERTICES;
use crate::Vec3;
use std::ops::Range;

/// `x += h v(t); v += h a(t)`. First order; gains energy on any undamped oscillation, so it is here
/// as the survey's baseline and for the accuracy study, not for production.
pub type ExplicitEuler = Euler<false>;

/// `v += h a(x, v); x += h v_new`. First order but symplectic: energy stays bounded on undamped
/// oscillations while `h omega < 2`.
pub type SymplecticEuler = Euler<true>;

/// The two Euler variants share everything but the order of the position and velocity updates.
#[derive(Default)]
pub struct Euler<const SYMPLECTIC: bool> {
    f: Vec<Vec3>,
    /// The second part of split cached forces (see [`crate::effects::EffectSet::take_force_parts`]).
    half: Vec<Vec3>,
    inv_mass: InverseMass,
    start: StartState,
}

impl<const SYMPLECTIC: bool> Integrator for Euler<SYMPLECTIC> {
    fn name(&self) -> &'static str {
        if SYMPLECTIC {
            "symplectic_euler"
        } else {
            "explicit_euler"
        }
    }

    fn step(
        &mut self,
        d: &Dynamics,
        t: f64,
        h: f64,
        x: &mut [Vec3],
        v: &mut [Vec3],
        report: &mut StepReport,
    ) {
        let start = self.start.take(x, v);
        self.step_into(d, t, h, (&start.x, &start.v), x, v, report);
        self.start = start;
    }

    fn step_into(
        &mut self,
        d: &Dynamics,
        t: f64,
        h: f64,
        (x0, v0): (&[Vec3], &[Vec3]),
        x: &mut [Vec3],
        v: &mut [Vec3],
        report: &mut StepReport,
    ) {
        let split =
            d.effects
                .take_force_parts(&State { t, x: x0, v: v0 }, &mut self.f, &mut self.half);
        let inv_mass = self.inv_mass.of(d.mass);
        let (f, filter) = (&self.f[..], &d.constraints.filter[..]);
        let half = split.then_some(&self.half[..]);
        split_update(x, v, &|r, x, v| {
            let n = x.len();
            let (f, filter, inv_mass) = (&f[r.clone()], &filter[r.clone()], &inv_mass[r.clone()]);
            let half = half.map(|h| &h[r.clone()][..n]);
            let (x0, v0) = (&x0[r.clone()], &v0[r]);
            let ends = UpdateEnds { x, v: &mut v[..n] };
            let starts = UpdateStarts {
                x0: &x0[..n],
                v0: &v0[..n],
                f: &f[..n],
                half,
                filter: &filter[..n],
                inv_mass: &inv_mass[..n],
            };
            update::<SYMPLECTIC>(ends, starts, h);
        });
        report.explicit(1);
    }

    fn capabilities(&self) -> Capabilities {
        // Forward Euler undamped: unstable for every h > 0 (damping buys a small margin).
        Capabilities::explicit(if SYMPLECTIC { 2.0 } else { 0.0 })
    }
}

/// The end state an update writes (equal lengths).
struct UpdateEnds<'a> {
    x: &'a mut [Vec3],
    v: &'a mut [Vec3],
}

/// What an update reads, per vertex (all as long as the end state).
struct UpdateStarts<'a> {
    x0: &'a [Vec3],
    v0: &'a [Vec3],
    f: &'a [Vec3],
    /// Forces still to add to `f` (`f[i] + half[i]`), if any.
    half: Option<&'a [Vec3]>,
    filter: &'a [Filter],
    inv_mass: &'a [f64],
}

/// The Euler update of vertex `i`: `v = v0 + S(f / m) h`, and `x = x0 + v h` (symplectic) or
/// `x = x0 + v0 h` (forward).
#[inline(always)]
fn update_vertex<const SYMPLECTIC: bool>(e: &mut UpdateEnds, s: &UpdateStarts, i: usize, h: f64) {
    let f = match s.half {
        Some(half) => s.f[i] + half[i],
        None => s.f[i],
    };
    let vi = s.v0[i] + s.filter[i].apply(f * s.inv_mass[i]) * h;
    e.x[i] = s.x0[i] + if SYMPLECTIC { vi } else { s.v0[i] } * h;
    e.v[i] = vi;
}

/// The Euler update of every vertex (AVX2 blocks of four free vertices when the CPU has it).
fn update<const SYMPLECTIC: bool>(mut e: UpdateEnds, s: UpdateStarts, h: f64) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has AVX2 (checked just above).
        return unsafe { update_avx2::<SYMPLECTIC>(e, s, h) };
    }
    for i in 0..e.x.len() {
        update_vertex::<SYMPLECTIC>(&mut e, &s, i, h);
    }
}

/// [`update`] on blocks of four vertices: where all four are free, their twelve components go
/// through AVX registers as three vectors, with the scalar code's operations in its order (no
/// fused multiply-adds), so the results are bitwise equal; other blocks and the tail go vertex by
/// vertex.
///
/// Safety: AVX2 is available.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn update_avx2<const SYMPLECTIC: bool>(mut e: UpdateEnds, s: UpdateStarts, h: f64) {
    use crate::linalg::{flat, flat_mut};
    use std::arch::x86_64::*;
    let n = e.x.len();
    let (x0, v0, f) = (flat(s.x0), flat(s.v0), flat(s.f));
    let half = s.half.map(flat);
    let blocks = n / 4 * 4;
    let hv = _mm256_set1_pd(h);
    for b in (0..blocks).step_by(4) {
        if !s.filter[b..b + 4].iter().all(|c| matches!(c, Filter::Free)) {
            for i in b..b + 4 {
                update_vertex::<SYMPLECTIC>(&mut e, &s, i, h);
            }
            continue;
        }
        let (xe, ve) = (flat_mut(&mut e.x[b..b + 4]), flat_mut(&mut e.v[b..b + 4]));
        let c = 3 * b;
        let (x0, v0, f) = (&x0[c..c + 12], &v0[c..c + 12], &f[c..c + 12]);
        let half = half.map(|h| &h[c..c + 12]);
        let m = &s.inv_mass[b..b + 4];
        // SAFETY: loads and stores of 4 elements at offsets 0, 4, 8 of 12-element slices, and
        // of the 4-element `m`.
        unsafe {
            let mv = _mm256_loadu_pd(m.as_ptr());
            // Each component's own vertex's 1/m: (m0 m0 m0 m1), (m1 m1 m2 m2), (m2 m3 m3 m3).
            let ms = [
                _mm256_permute4x64_pd::<0x40>(mv),
                _mm256_permute4x64_pd::<0xA5>(mv),
                _mm256_permute4x64_pd::<0xFE>(mv),
            ];
            for (q, mq) in ms.into_iter().enumerate() {
                let o = 4 * q;
                let v0q = _mm256_loadu_pd(v0.as_ptr().add(o));
                let mut fq = _mm256_loadu_pd(f.as_ptr().add(o));
                if let Some(h) = half {
                    fq = _mm256_add_pd(fq, _mm256_loadu_pd(h.as_ptr().add(o)));
                }
                let a = _mm256_mul_pd(fq, mq);
                let vi = _mm256_add_pd(v0q, _mm256_mul_pd(a, hv));
                let step = if SYMPLECTIC { vi } else { v0q };
                let xi =
                    _mm256_add_pd(_mm256_loadu_pd(x0.as_ptr().add(o)), _mm256_mul_pd(step, hv));
                _mm256_storeu_pd(xe.as_mut_ptr().add(o), xi);
                _mm256_storeu_pd(ve.as_mut_ptr().add(o), vi);
            }
        }
    }
    for i in blocks..n {
        update_vertex::<SYMPLECTIC>(&mut e, &s, i, h);
    }
}

/// A per-vertex update over a range of vertices and their positions and velocities.
pub(super) type VertexUpdate<'a> = dyn Fn(Range<usize>, &mut [Vec3], &mut [Vec3]) + Sync + 'a;

/// Runs a per-vertex update `body(range, x[range], v[range])` over all vertices: on two threads
/// (two halves) from [`PAR_VERTICES`] vertices on, where the pass outweighs waking a thread.
/// Each vertex's result does not depend on the split.
pub(super) fn split_update(x: &mut [Vec3], v: &mut [Vec3], body: &VertexUpdate) {
    let n = x.len().min(v.len());
    if n >= PAR_VERTICES {
        let mid = n / 2;
        let (xa, xb) = x[..n].split_at_mut(mid);
        let (va, vb) = v[..n].split_at_mut(mid);
        crate::par::join(|| body(0..mid, xa, va), || body(mid..n, xb, vb));
    } else {
        body(0..n, &mut x[..n], &mut v[..n]);
    }
}

/// Reciprocal masses, recomputed only when the masses change: one multiply per vertex in the
/// update loops instead of a division per component.
#[derive(Default)]
pub(super) struct InverseMass {
    mass: Vec<f64>,
    inv: Vec<f64>,
}

impl InverseMass {
    /// `1 / m` per vertex for these masses.
    pub(super) fn of(&mut self, mass: &[f64]) -> &[f64] {
        // Bit patterns (a `memcmp`): a float comparison costs a scalar loop per step.
        if crate::linalg::flat_bits(&self.mass) != crate::linalg::flat_bits(mass) {
            self.mass.clear();
            self.mass.extend_from_slice(mass);
            self.inv.clear();
            self.inv.extend(mass.iter().map(|m| 1.0 / m));
        }
        &self.inv
    }
}

/// A copy of the start state, for the in-place [`Integrator::step`] (the simulation itself uses
/// [`Integrator::step_into`] and needs no copy).
#[derive(Default)]
pub(super) struct StartState {
    pub(super) x: Vec<Vec3>,
    pub(super) v: Vec<Vec3>,
}

impl StartState {
    /// Moves the buffers out of `self`, filled with `(x, v)`; put them back after the step.
    pub(super) fn take(&mut self, x: &[Vec3], v: &[Vec3]) -> StartState {
        let mut s = std::mem::take(self);
        s.x.clear();
        s.x.extend_from_slice(x);
        s.v.clear();
        s.v.extend_from_slice(v);
        s
    }
}
