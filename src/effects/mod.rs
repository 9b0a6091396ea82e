//! Force terms, each its own unit. A scene names the effects it wants; only those are built,
//! so an effect a scene does not name costs nothing in the step (there is no `if enabled` anywhere).
//!
//! Every effect gives forces and, where the implicit solver needs them, analytic force Jacobians
//! `df/dx` and `df/dv` over the sparsity pattern it declares.

mod damping;
mod gravity;
pub(crate) mod pair;
pub mod plan;
mod springs;
mod stencils;
mod wind;

pub use damping::{AirDrag, SpringDamping, VelocityDiffusion};
pub use gravity::Gravity;
pub use plan::{EffectPlan, Elements, Lattice, Term, WindPlan};
pub use springs::Springs;
pub use stencils::{Bending, StencilSet, Twist};
pub use wind::{Gust, Wind, WindKey};

use crate::integrate::{BlockCsr, PatternBuilder};
use crate::Vec3;
use std::sync::Mutex;

/// The state an effect is evaluated at.
#[derive(Clone, Copy)]
pub struct State<'a> {
    pub t: f64,
    pub x: &'a [Vec3],
    pub v: &'a [Vec3],
}

/// Upper bound of an effect's stiffness seen by one vertex, for step-size limits and for naming
/// the likely culprit when a step diverges.
#[derive(Debug, Clone, PartialEq)]
pub struct StiffnessBound {
    /// Bound on the largest `omega^2 = lambda_max(M^-1 K)` (1/s^2) the effect contributes.
    pub omega_sq: f64,
    /// The vertex where the bound is attained.
    pub vertex: usize,
    /// The scene parameter responsible, e.g. `cloth[0].material.stretch`.
    pub parameter: String,
}

pub trait Effect: Send + Sync {
    /// Name as written in a scene's effect list.
    fn name(&self) -> &'static str;

    /// Declares the vertex pairs the Jacobians couple (default: none, e.g. gravity).
    fn declare(&self, _pattern: &mut PatternBuilder) {}

    /// Sets the constant part of the air velocity (m/s, scripted keys and gusts still add);
    /// false for effects that are not wind.
    fn set_wind_velocity(&mut self, _velocity: Vec3) -> bool {
        false
    }

    /// Adds this effect's forces at `s` to `f`.
    fn add_forces(&self, s: &State, f: &mut [Vec3]);

    /// Adds `df/dx` and `df/dv` at `s`. Default: the force does not depend on state.
    fn add_jacobians(&self, _s: &State, _dfdx: &mut BlockCsr, _dfdv: &mut BlockCsr) {}

    /// True when the Jacobians do not depend on the state (quadratic energies, linear damping):
    /// the implicit solver assembles them once, and [`Effect::add_jacobians`] must then not read
    /// its state argument.
    fn constant_jacobians(&self) -> bool {
        false
    }

    /// Potential energy at `x` (conservative effects only; 0 otherwise).
    fn energy(&self, _x: &[Vec3]) -> f64 {
        0.0
    }

    /// True when the force depends on positions only (not on velocity or time): such forces
    /// computed alongside the energy at `x` serve the next force evaluation at the same `x`.
    fn position_only(&self) -> bool {
        false
    }

    /// Adds the forces at `s` to `f` and returns the energy at `s.x`. Elastic effects override
    /// this with one fused pass (the guard needs the energy of every substep's result).
    fn add_forces_energy(&self, s: &State, f: &mut [Vec3]) -> f64 {
        self.add_forces(s, f);
        self.energy(s.x)
    }

    /// [`Effect::add_forces_energy`] over the `part`-th of `parts` slices of the effect's elements,
    /// so that one pass can be split across threads. Default: part 0 does everything.
    fn add_forces_energy_part(&self, s: &State, f: &mut [Vec3], part: usize, _parts: usize) -> f64 {
        if part == 0 {
            self.add_forces_energy(s, f)
        } else {
            0.0
        }
    }

    /// True for effects that can add energy from outside the cloth (wind); the divergence guard
    /// accounts for their work so that a gust is not mistaken for an instability.
    fn injects_energy(&self) -> bool {
        false
    }

    /// Stiffness bound, for the elastic effects.
    fn stiffness(&self, _mass: &[f64]) -> Option<StiffnessBound> {
        None
    }
}

/// The built effects of a simulation, in scene order, with evaluation counts.
#[derive(Default)]
pub struct EffectSet {
    effects: Vec<Box<dyn Effect>>,
    evaluations: Vec<std::sync::atomic::AtomicU64>,
    gravity: Vec3,
    cache: Mutex<PositionForces>,
}

/// Sum of the position-only forces at the configuration `x` of the last energy evaluation.
///
/// The divergence guard evaluates the energy of every substep's result `x_{n+1}`; doing so in the
/// same pass as the forces and keeping those forces means the next substep, which starts from
/// `x_{n+1}`, does not evaluate them again. The cache is used only when the positions are
/// bitwise identical, so it never changes a result.
#[derive(Default)]
struct PositionForces {
    x: Vec<Vec3>,
    f: Vec<Vec3>,
    /// The second half's forces when the pass is split across two threads.
    half: Vec<Vec3>,
    /// `f` still lacks `half` (the sum is left to the consumer, which can do it in parallel).
    split: bool,
    valid: bool,
}

impl PositionForces {
    /// Whether the cached forces are those at exactly `x`.
    /// Compares bit patterns (a `memcmp`), the criterion that guarantees identical forces.
    fn hit(&self, x: &[Vec3]) -> bool {
        self.valid && self.f.len() == x.len() && bits(&self.x) == bits(x)
    }
}

/// Vertex count from which the energy-and-force pass is split in two halves run on two threads
/// (below it, waking a thread costs about as much as the pass). The split depends on the size
/// only, so results do not depend on the number of threads.
pub(crate) const PAR_VERTICES: usize = 2048;

/// The index range of the `part`-th of `parts` near-equal slices of `len` elements.
pub(crate) fn part_range(len: usize, part: usize, parts: usize) -> std::ops::Range<usize> {
    len * part / parts..len * (part + 1) / parts
}

impl EffectSet {
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds gravity (kept as a vector too, for the divergence guard's error bound).
    pub fn push_gravity(&mut self, g: Gravity) {
        self.gravity += g.g;
        self.push(Box::new(g));
    }

    pub fn push(&mut self, e: Box<dyn Effect>) {
        self.effects.push(e);
        self.evaluations.push(Default::default());
        // The cached forces lack the new effect.
        self.cache
            .get_mut()
            .unwrap_or_else(|p| p.into_inner())
            .valid = false;
    }

    pub fn iter(&self) -> impl Iterator<Item = &dyn Effect> {
        self.effects.iter().map(|e| e.as_ref())
    }

    pub fn names(&self) -> Vec<&'static str> {
        self.effects.iter().map(|e| e.name()).collect()
    }

    pub fn is_empty(&self) -> bool {
        self.effects.is_empty()
    }

    /// How many times each effect's forces were evaluated, by name.
    pub fn evaluation_counts(&self) -> Vec<(&'static str, u64)> {
        self.effects
            .iter()
            .zip(&self.evaluations)
            .map(|(e, c)| (e.name(), c.load(std::sync::atomic::Ordering::Relaxed)))
            .collect()
    }

    pub fn declare(&self, p: &mut PatternBuilder) {
        for e in &self.effects {
            e.declare(p);
        }
    }

    /// Sets the constant wind velocity of every wind effect (a live change, e.g. from the node's
    /// `wind` parameter); false when the set has no wind (a scene that does not name wind).
    pub fn set_wind_velocity(&mut self, velocity: Vec3) -> bool {
        let mut any = false;
        for e in &mut self.effects {
            any |= e.set_wind_velocity(velocity);
        }
        any
    }

    /// Sum of all forces at `s` (overwrites `f`). Position-only forces come from the cache when
    /// the last energy evaluation was at exactly these positions.
    pub fn forces(&self, s: &State, f: &mut [Vec3]) {
        let cached = {
            let cache = self.cache.lock().unwrap_or_else(|p| p.into_inner());
            let hit = cache.hit(s.x);
            if hit && cache.split {
                for ((o, a), b) in f.iter_mut().zip(&cache.f).zip(&cache.half) {
                    *o = *a + *b;
                }
            } else if hit {
                f.copy_from_slice(&cache.f);
            }
            hit
        };
        self.add_uncached(s, f, cached);
    }

    /// [`EffectSet::forces`] for the last consumer of the forces at these positions (the
    /// integrator): a cached result is handed over by swapping buffers instead of copied, which
    /// spends the cache. `f` is resized to the vertex count.
    pub fn take_forces(&self, s: &State, f: &mut Vec<Vec3>) {
        let mut half = Vec::new();
        if self.take_force_parts(s, f, &mut half) {
            for (a, b) in f.iter_mut().zip(&half) {
                *a += *b;
            }
            self.return_half(half);
        }
    }

    /// [`EffectSet::take_forces`] that may leave the last step of the cached sum to the caller:
    /// when it returns true, the forces are `f + half` (each vertex summed as `f[i] + half[i]`),
    /// which the caller adds where it reads them, e.g. split across its own threads. Hand `half`
    /// back with [`EffectSet::return_half`] to spare the next pass an allocation.
    pub fn take_force_parts(&self, s: &State, f: &mut Vec<Vec3>, half: &mut Vec<Vec3>) -> bool {
        let (cached, split) = {
            let mut cache = self.cache.lock().unwrap_or_else(|p| p.into_inner());
            let hit = cache.hit(s.x);
            let split = hit && cache.split;
            if hit {
                std::mem::swap(&mut cache.f, f);
                cache.valid = false;
            }
            if split {
                std::mem::swap(&mut cache.half, half);
            }
            (hit, split)
        };
        if !cached {
            crate::integrate::scratch(f, s.x.len());
        }
        if split && self.effects.iter().any(|e| !e.position_only()) {
            // Velocity-dependent effects add to the full sum, in the order of a plain pass.
            for (a, b) in f.iter_mut().zip(half.iter()) {
                *a += *b;
            }
            self.add_uncached(s, f, cached);
            return false;
        }
        self.add_uncached(s, f, cached);
        split
    }

    /// Gives a buffer taken by [`EffectSet::take_force_parts`] back to the cache.
    pub fn return_half(&self, mut half: Vec<Vec3>) {
        let mut cache = self.cache.lock().unwrap_or_else(|p| p.into_inner());
        if cache.half.capacity() < half.capacity() {
            std::mem::swap(&mut cache.half, &mut half);
        }
    }

    /// Completes `f` with the effects the cache does not hold (all of them, zeroing `f` first,
    /// when `cached` is false).
    fn add_uncached(&self, s: &State, f: &mut [Vec3], cached: bool) {
        if !cached {
            f.iter_mut().for_each(|v| *v = Vec3::ZERO);
        }
        for (e, c) in self.effects.iter().zip(&self.evaluations) {
            if cached && e.position_only() {
                continue;
            }
            c.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            e.add_forces(s, f);
        }
    }

    /// Forces of the effects that inject energy only (overwrites `f`); false if there are none.
    pub fn injecting_forces(&self, s: &State, f: &mut [Vec3]) -> bool {
        let mut any = false;
        f.iter_mut().for_each(|v| *v = Vec3::ZERO);
        for e in self.effects.iter().filter(|e| e.injects_energy()) {
            e.add_forces(s, f);
            any = true;
        }
        any
    }

    pub fn jacobians(&self, s: &State, dfdx: &mut BlockCsr, dfdv: &mut BlockCsr) {
        dfdx.clear();
        dfdv.clear();
        for e in &self.effects {
            e.add_jacobians(s, dfdx, dfdv);
        }
    }

    /// The state-independent Jacobians alone (overwrites both matrices).
    pub fn constant_jacobians(&self, dfdx: &mut BlockCsr, dfdv: &mut BlockCsr) {
        dfdx.clear();
        dfdv.clear();
        let none = State {
            t: 0.0,
            x: &[],
            v: &[],
        };
        for e in self.effects.iter().filter(|e| e.constant_jacobians()) {
            e.add_jacobians(&none, dfdx, dfdv);
        }
    }

    /// Adds the state-dependent Jacobians at `s` (the complement of
    /// [`EffectSet::constant_jacobians`]).
    pub fn add_varying_jacobians(&self, s: &State, dfdx: &mut BlockCsr, dfdv: &mut BlockCsr) {
        for e in self.effects.iter().filter(|e| !e.constant_jacobians()) {
            e.add_jacobians(s, dfdx, dfdv);
        }
    }

    pub fn energy(&self, x: &[Vec3]) -> f64 {
        self.effects.iter().map(|e| e.energy(x)).sum()
    }

    /// (elastic, gravity) potential energies at `x`. The position-only forces at `x` are
    /// computed in the same pass and kept for the next [`EffectSet::forces`] at `x`.
    pub fn energy_split(&self, x: &[Vec3]) -> (f64, f64) {
        self.energy_split_with(x, |_| ()).0
    }

    /// [`EffectSet::energy_split`] that also runs `extra` over the vertex range of each part of
    /// the pass, on the part's thread (the guard's per-vertex checks ride along this way). The
    /// pass has one part, or two from `PAR_VERTICES` (2048) vertices on; the second result is
    /// `None` with one part.
    pub fn energy_split_with<T: Send>(
        &self,
        x: &[Vec3],
        extra: impl Fn(std::ops::Range<usize>) -> T + Sync,
    ) -> ((f64, f64), T, Option<T>) {
        let mut cache = self.cache.lock().unwrap_or_else(|p| p.into_inner());
        let cache = &mut *cache;
        let n = x.len();
        let (energies, first, second) = if n >= PAR_VERTICES {
            crate::integrate::scratch(&mut cache.x, n);
            let (lo, hi) = (part_range(n, 0, 2), part_range(n, 1, 2));
            let (xa, xb) = cache.x.split_at_mut(hi.start);
            let (f, half) = (&mut cache.f, &mut cache.half);
            let extra = &extra;
            let (a, b) = pair::join(
                || {
                    xa.copy_from_slice(&x[lo.clone()]);
                    (self.energy_part(x, f, 0, 2), extra(lo))
                },
                || {
                    xb.copy_from_slice(&x[hi.clone()]);
                    (self.energy_part(x, half, 1, 2), extra(hi))
                },
            );
            // The halves' sum is left to the consumer (see `PositionForces::split`).
            ((a.0 .0 + b.0 .0, a.0 .1 + b.0 .1), a.1, Some(b.1))
        } else {
            cache.x.clear();
            cache.x.extend_from_slice(x);
            let e = self.energy_part(x, &mut cache.f, 0, 1);
            (e, extra(0..n), None)
        };
        for (e, c) in self.effects.iter().zip(&self.evaluations) {
            if e.position_only() {
                c.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            }
        }
        cache.split = n >= PAR_VERTICES;
        cache.valid = true;
        (energies, first, second)
    }

    /// (elastic, gravity) energies of one part of the elements, and the position-only forces of
    /// that part (overwriting `f`).
    fn energy_part(&self, x: &[Vec3], f: &mut Vec<Vec3>, part: usize, parts: usize) -> (f64, f64) {
        f.clear();
        f.resize(x.len(), Vec3::ZERO);
        // Position-only effects read neither velocity nor time.
        let s = State { t: 0.0, x, v: &[] };
        let (mut el, mut gr) = (0.0, 0.0);
        for e in &self.effects {
            let energy = if e.position_only() {
                e.add_forces_energy_part(&s, f, part, parts)
            } else if part == 0 {
                e.energy(x)
            } else {
                0.0
            };
            if e.name() == "gravity" {
                gr += energy;
            } else {
                el += energy;
            }
        }
        (el, gr)
    }

    /// The gravity vector if a gravity effect is present (zero otherwise).
    pub fn gravity(&self) -> Vec3 {
        self.gravity
    }

    /// Stiffness bounds of every elastic effect, stiffest first.
    pub fn stiffness(&self, mass: &[f64]) -> Vec<StiffnessBound> {
        let mut b: Vec<StiffnessBound> = self
            .effects
            .iter()
            .filter_map(|e| e.stiffness(mass))
            .collect();
        b.sort_by(|a, b| b.omega_sq.total_cmp(&a.omega_sq));
        b
    }
}

/// Positions or forces as one flat `[x0, y0, z0, x1, ...]` slice.
pub(crate) fn flat(v: &[Vec3]) -> &[f64] {
    const _: () = assert!(std::mem::size_of::<Vec3>() == 3 * std::mem::size_of::<f64>());
    // SAFETY: `Vec3` (glam's DVec3) is `#[repr(C)]` with three f64 fields and no padding (size
    // checked above), so `v` is `3 v.len()` contiguous, initialised, aligned f64 values.
    unsafe { std::slice::from_raw_parts(v.as_ptr().cast::<f64>(), 3 * v.len()) }
}

/// The bit patterns of positions, for exact comparison.
fn bits(v: &[Vec3]) -> &[u64] {
    // SAFETY: as in `flat`; u64 has the size and alignment of f64 and every bit pattern is valid.
    unsafe { std::slice::from_raw_parts(v.as_ptr().cast::<u64>(), 3 * v.len()) }
}

/// The bit patterns of `f64` values, for exact comparison by `memcmp`.
pub(crate) fn flat_bits(v: &[f64]) -> &[u64] {
    // SAFETY: u64 has the size and alignment of f64 and every bit pattern is valid.
    unsafe { std::slice::from_raw_parts(v.as_ptr().cast::<u64>(), v.len()) }
}

/// Mutable [`flat`].
pub(crate) fn flat_mut(v: &mut [Vec3]) -> &mut [f64] {
    // SAFETY: as in `flat`; the result borrows `v` mutably and exclusively.
    unsafe { std::slice::from_raw_parts_mut(v.as_mut_ptr().cast::<f64>(), 3 * v.len()) }
}

/// Outer product `a b^T`.
#[inline]
pub(crate) fn outer_pub(a: Vec3, b: Vec3) -> crate::Mat3 {
    outer(a, b)
}

/// Outer product `a b^T`.
#[inline]
pub(crate) fn outer(a: Vec3, b: Vec3) -> crate::Mat3 {
    crate::Mat3::from_cols(a * b.x, a * b.y, a * b.z)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cloth::topology::Spring;

    /// A bent chain of 5 particles with springs (position-only), gravity and air drag
    /// (velocity-dependent), plus the springs' own reference sum.
    fn chain() -> (EffectSet, Vec<Vec3>, Vec<Vec3>, Vec<f64>) {
        let x: Vec<Vec3> = (0..5)
            .map(|i| Vec3::new(i as f64 * 0.1, (i * i) as f64 * 0.013, -0.02 * i as f64))
            .collect();
        let v: Vec<Vec3> = (0..5)
            .map(|i| Vec3::new(0.3, -0.1 * i as f64, 0.2))
            .collect();
        let mass = vec![0.01, 0.02, 0.015, 0.01, 0.03];
        let springs = (0..4)
            .map(|i| Spring {
                i,
                j: i + 1,
                rest: 0.09,
            })
            .collect();
        let mut set = EffectSet::new();
        set.push_gravity(Gravity::new(Vec3::new(0.0, 0.0, -9.81), &mass));
        set.push(Box::new(Springs::new(
            "stretch",
            springs,
            vec![50.0, 60.0, 70.0, 80.0],
            "k".into(),
        )));
        set.push(Box::new(AirDrag::new(&[0.5; 5], &mass)));
        (set, x, v, mass)
    }

    /// Sum of each effect's forces evaluated on its own (no cache involved).
    fn reference(set: &EffectSet, s: &State) -> Vec<Vec3> {
        let mut f = vec![Vec3::ZERO; s.x.len()];
        for e in set.iter() {
            e.add_forces(s, &mut f);
        }
        f
    }

    /// `EffectSet::forces` (cached or not) at `x, v` equals each effect's forces summed afresh.
    fn forces_match_reference(set: &EffectSet, x: &[Vec3], v: &[Vec3]) {
        let s = State { t: 0.0, x, v };
        let mut f = vec![Vec3::ZERO; x.len()];
        set.forces(&s, &mut f);
        close(&f, &reference(set, &s));
    }

    fn close(a: &[Vec3], b: &[Vec3]) {
        for (p, q) in a.iter().zip(b) {
            // Same terms, possibly summed in another order: a few ulps of the largest term.
            assert!(
                (*p - *q).length() <= 1e-12 * (1.0 + q.length()),
                "{p} vs {q}"
            );
        }
    }

    #[test]
    fn cached_forces_equal_fresh_forces_and_skip_the_position_only_pass() {
        let (set, mut x, v, _) = chain();
        set.energy_split(&x);
        forces_match_reference(&set, &x, &v);
        // The springs were evaluated once (in the energy pass), the drag at every call.
        let counts = set.evaluation_counts();
        assert_eq!(counts, vec![("gravity", 1), ("stretch", 1), ("damping", 1)]);

        // Moved positions miss the cache and are evaluated afresh.
        x[2].y += 1e-3;
        forces_match_reference(&set, &x, &v);
        assert_eq!(set.evaluation_counts()[1], ("stretch", 2));
    }

    #[test]
    fn energy_pass_matches_the_energies_and_a_new_effect_invalidates_the_cache() {
        let (mut set, x, v, mass) = chain();
        let (el, gr) = set.energy_split(&x);
        let springs_energy: f64 = set
            .iter()
            .filter(|e| e.name() == "stretch")
            .map(|e| e.energy(&x))
            .sum();
        let gravity_energy: f64 = -x
            .iter()
            .zip(&mass)
            .map(|(p, m)| m * -9.81 * p.z)
            .sum::<f64>();
        assert!((el - springs_energy).abs() <= 1e-15 * springs_energy.abs().max(1e-30));
        assert!((gr - gravity_energy).abs() <= 1e-14 * gravity_energy.abs());
        set.push_gravity(Gravity::new(Vec3::new(1.0, 0.0, 0.0), &mass));
        forces_match_reference(&set, &x, &v);
    }
}
