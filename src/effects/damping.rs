//! Damping: along springs, against the air, and velocity diffusion between neighbours.
//! All three are linear in velocity, so their `df/dv` is exact and constant in `v`.

use super::effect::{Effect, State};
use crate::linalg::outer;
use crate::linalg::{BlockCsr, PairSlots, PatternBuilder};
use crate::{Mat3, Vec3};

/// `f_i = -kd ((v_i - v_j) . n) n` along each spring direction `n`.
pub struct SpringDamping {
    pairs: Vec<(u32, u32)>,
    kd: Vec<f64>,
    /// Jacobian block slots of every pair (no search per step).
    slots: PairSlots,
}

impl SpringDamping {
    pub fn new(pairs: Vec<(u32, u32)>, kd: Vec<f64>) -> Self {
        Self {
            pairs,
            kd,
            slots: PairSlots::default(),
        }
    }
}

impl Effect for SpringDamping {
    fn name(&self) -> &'static str {
        "damping"
    }
    fn declare(&self, p: &mut PatternBuilder) {
        for &(i, j) in &self.pairs {
            p.couple(i, j);
        }
    }
    fn add_forces(&self, s: &State, f: &mut [Vec3]) {
        for (&(i, j), &kd) in self.pairs.iter().zip(&self.kd) {
            let n = (s.x[i as usize] - s.x[j as usize]).normalize_or_zero();
            let fi = n * (-kd * (s.v[i as usize] - s.v[j as usize]).dot(n));
            f[i as usize] += fi;
            f[j as usize] -= fi;
        }
    }
    fn add_jacobians(&self, s: &State, _dfdx: &mut BlockCsr, dfdv: &mut BlockCsr) {
        let slots = self.slots.get(dfdv, self.pairs.iter().copied());
        dfdv.add_pairs(&slots.1, |q| {
            let (i, j) = self.pairs[q];
            let n = (s.x[i as usize] - s.x[j as usize]).normalize_or_zero();
            outer(n, n) * -self.kd[q]
        });
    }
}

/// `f_i = -c m_i v_i`: drag against still air as a rate `c` (1/s).
pub struct AirDrag {
    cm: Vec<f64>,
}

impl AirDrag {
    pub fn new(rate: &[f64], mass: &[f64]) -> Self {
        Self {
            cm: rate.iter().zip(mass).map(|(c, m)| c * m).collect(),
        }
    }
}

impl Effect for AirDrag {
    fn name(&self) -> &'static str {
        "damping"
    }
    fn add_forces(&self, s: &State, f: &mut [Vec3]) {
        for ((fi, vi), cm) in f.iter_mut().zip(s.v).zip(&self.cm) {
            *fi -= *vi * *cm;
        }
    }
    fn constant_jacobians(&self) -> bool {
        true
    }
    fn add_jacobians(&self, _s: &State, _dfdx: &mut BlockCsr, dfdv: &mut BlockCsr) {
        for (i, cm) in self.cm.iter().enumerate() {
            dfdv.add(i as u32, i as u32, Mat3::IDENTITY * -cm);
        }
    }
}

/// `f_i = kdiff * sum_j (v_j - v_i)` over neighbour pairs: smooths velocity without damping
/// rigid motion.
pub struct VelocityDiffusion {
    pairs: Vec<(u32, u32)>,
    k: Vec<f64>,
}

impl VelocityDiffusion {
    pub fn new(pairs: Vec<(u32, u32)>, k: Vec<f64>) -> Self {
        Self { pairs, k }
    }
}

impl Effect for VelocityDiffusion {
    fn name(&self) -> &'static str {
        "damping"
    }
    fn declare(&self, p: &mut PatternBuilder) {
        for &(i, j) in &self.pairs {
            p.couple(i, j);
        }
    }
    fn add_forces(&self, s: &State, f: &mut [Vec3]) {
        for (&(i, j), &k) in self.pairs.iter().zip(&self.k) {
            let fi = (s.v[j as usize] - s.v[i as usize]) * k;
            f[i as usize] += fi;
            f[j as usize] -= fi;
        }
    }
    fn constant_jacobians(&self) -> bool {
        true
    }
    fn add_jacobians(&self, _s: &State, _dfdx: &mut BlockCsr, dfdv: &mut BlockCsr) {
        for (&(i, j), &k) in self.pairs.iter().zip(&self.k) {
            let m = Mat3::IDENTITY * k;
            dfdv.add(i, i, -m);
            dfdv.add(j, j, -m);
            dfdv.add(i, j, m);
            dfdv.add(j, i, m);
        }
    }
}
