//! [`EffectSet`]: the effects a scene names, in scene order, summed into one force, Jacobian
//! and energy evaluation; position-only forces are reused from the guard's energy pass when the
//! positions are bitwise those of that pass (see [`super::cache`]).
//!
//! Gravity has a typed slot: the guard tells its potential from the elastic ones, and its
//! vector bounds the guard's error. Its turn in the summation order is where the scene names
//! it, so the sums are those of a plain list.

use super::cache::PositionForces;
use super::effect::{Effect, State, StiffnessBound};
use super::gravity::Gravity;
use crate::linalg::{BlockCsr, PatternBuilder};
use crate::par::{part_range, PAR_VERTICES};
use crate::Vec3;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;

/// The built effects of a simulation, in scene order, with evaluation counts.
#[derive(Default)]
pub struct EffectSet {
    /// The set's gravity (one at most), evaluated at the turn of [`Term::Gravity`].
    gravity: Option<Gravity>,
    /// The terms in scene order: the order forces, Jacobians and energies are summed in.
    terms: Vec<Term>,
    /// Force evaluations per term.
    evaluations: Vec<AtomicU64>,
    cache: Mutex<PositionForces>,
}

/// One term of the set: gravity's turn (the typed [`EffectSet::gravity`] slot) or an effect.
enum Term {
    Gravity,
    Effect(Box<dyn Effect>),
}

/// An effect of the set with its evaluation counter.
struct Entry<'a> {
    effect: &'a dyn Effect,
    evaluations: &'a AtomicU64,
    gravity: bool,
}

impl EffectSet {
    pub fn new() -> Self {
        Self::default()
    }

    /// Gives the set its gravity, summed at this point of the scene order. A set has one
    /// gravity: pushed again, the new one replaces the old in the old one's turn.
    pub fn push_gravity(&mut self, g: Gravity) {
        if self.gravity.replace(g).is_none() {
            self.push_term(Term::Gravity);
        } else {
            self.invalidate();
        }
    }

    pub fn push(&mut self, e: Box<dyn Effect>) {
        self.push_term(Term::Effect(e));
    }

    fn push_term(&mut self, t: Term) {
        self.terms.push(t);
        self.evaluations.push(Default::default());
        self.invalidate();
    }

    /// The cached forces lack a new or replaced effect.
    fn invalidate(&mut self) {
        self.cache
            .get_mut()
            .unwrap_or_else(|p| p.into_inner())
            .valid = false;
    }

    /// The effects in scene order, gravity at its turn, with their counters.
    fn entries(&self) -> impl Iterator<Item = Entry<'_>> {
        self.terms
            .iter()
            .zip(&self.evaluations)
            .filter_map(|(t, evaluations)| {
                let (effect, gravity): (&dyn Effect, bool) = match t {
                    Term::Gravity => (self.gravity.as_ref()?, true),
                    Term::Effect(e) => (e.as_ref(), false),
                };
                Some(Entry {
                    effect,
                    evaluations,
                    gravity,
                })
            })
    }

    /// The effects in scene order (gravity at its turn).
    pub fn iter(&self) -> impl Iterator<Item = &dyn Effect> {
        self.entries().map(|e| e.effect)
    }

    /// The scene's effects that built force terms, in scene order, each once (`damping` builds
    /// up to three terms: along springs, against the air, diffusion).
    pub fn names(&self) -> Vec<&'static str> {
        let mut names: Vec<&'static str> = Vec::new();
        for name in self.iter().map(|e| e.name()) {
            if !names.contains(&name) {
                names.push(name);
            }
        }
        names
    }

    pub fn is_empty(&self) -> bool {
        self.terms.is_empty()
    }

    /// How many times each effect's forces were evaluated, by name.
    pub fn evaluation_counts(&self) -> Vec<(&'static str, u64)> {
        self.entries()
            .map(|e| (e.effect.name(), e.evaluations.load(Ordering::Relaxed)))
            .collect()
    }

    pub fn declare(&self, p: &mut PatternBuilder) {
        for e in self.iter() {
            e.declare(p);
        }
    }

    /// Sets the constant wind velocity of every wind effect (a live change, e.g. from the node's
    /// `wind` parameter); false when the set has no wind (a scene that does not name wind).
    pub fn set_wind_velocity(&mut self, velocity: Vec3) -> bool {
        let mut any = false;
        for t in &mut self.terms {
            if let Term::Effect(e) = t {
                any |= e.set_wind_velocity(velocity);
            }
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
            crate::linalg::scratch(f, s.x.len());
        }
        if split && self.iter().any(|e| !e.position_only()) {
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
        for e in self.entries() {
            if cached && e.effect.position_only() {
                continue;
            }
            e.evaluations.fetch_add(1, Ordering::Relaxed);
            e.effect.add_forces(s, f);
        }
    }

    /// Forces of the effects that inject energy only (overwrites `f`); false if there are none.
    pub fn injecting_forces(&self, s: &State, f: &mut [Vec3]) -> bool {
        let mut any = false;
        f.iter_mut().for_each(|v| *v = Vec3::ZERO);
        for e in self.iter().filter(|e| e.injects_energy()) {
            e.add_forces(s, f);
            any = true;
        }
        any
    }

    pub fn jacobians(&self, s: &State, dfdx: &mut BlockCsr, dfdv: &mut BlockCsr) {
        dfdx.clear();
        dfdv.clear();
        for e in self.iter() {
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
        for e in self.iter().filter(|e| e.constant_jacobians()) {
            e.add_jacobians(&none, dfdx, dfdv);
        }
    }

    /// Adds the state-dependent Jacobians at `s` (the complement of
    /// [`EffectSet::constant_jacobians`]).
    pub fn add_varying_jacobians(&self, s: &State, dfdx: &mut BlockCsr, dfdv: &mut BlockCsr) {
        for e in self.iter().filter(|e| !e.constant_jacobians()) {
            e.add_jacobians(s, dfdx, dfdv);
        }
    }

    /// Adds every effect's impact-front stiffness at `s` (see [`Effect::add_front_stiffness`]).
    pub fn add_front_stiffness(&self, s: &State, front_strain: &[f64], dfdx: &mut BlockCsr) {
        for e in self.iter() {
            e.add_front_stiffness(s, front_strain, dfdx);
        }
    }

    pub fn energy(&self, x: &[Vec3]) -> f64 {
        self.iter().map(|e| e.energy(x)).sum()
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
            crate::linalg::scratch(&mut cache.x, n);
            let (lo, hi) = (part_range(n, 0, 2), part_range(n, 1, 2));
            let (xa, xb) = cache.x.split_at_mut(hi.start);
            let (f, half) = (&mut cache.f, &mut cache.half);
            let extra = &extra;
            let (a, b) = crate::par::join(
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
        for e in self.entries() {
            if e.effect.position_only() {
                e.evaluations.fetch_add(1, Ordering::Relaxed);
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
        for Entry {
            effect, gravity, ..
        } in self.entries()
        {
            let energy = if effect.position_only() {
                effect.add_forces_energy_part(&s, f, part, parts)
            } else if part == 0 {
                effect.energy(x)
            } else {
                0.0
            };
            if gravity {
                gr += energy;
            } else {
                el += energy;
            }
        }
        (el, gr)
    }

    /// The gravity vector if a gravity effect is present (zero otherwise).
    pub fn gravity(&self) -> Vec3 {
        self.gravity.as_ref().map_or(Vec3::ZERO, |g| g.g)
    }

    /// Stiffness bounds of every elastic effect, stiffest first.
    pub fn stiffness(&self, mass: &[f64]) -> Vec<StiffnessBound> {
        let mut b: Vec<StiffnessBound> = self.iter().filter_map(|e| e.stiffness(mass)).collect();
        b.sort_by(|a, b| b.omega_sq.total_cmp(&a.omega_sq));
        b
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cloth::topology::Spring;
    use crate::effects::{AirDrag, Springs};

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
