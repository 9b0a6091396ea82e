//! Seam vertex pairs in the flat particle system and the sewing springs that pull them together.

use crate::effects::{Effect, State};
use crate::linalg::{outer, BlockCsr, PatternBuilder};
use crate::{Mat3, Vec3};

/// The vertex pairs of one seam, in global indices of the pre-weld cloth.
#[derive(Debug, Clone, PartialEq)]
pub struct SeamPairs {
    pub name: String,
    pub pairs: Vec<(u32, u32)>,
}

/// Distance between the two vertices of each pair.
pub fn gaps(x: &[Vec3], pairs: &[(u32, u32)]) -> Vec<f64> {
    pairs
        .iter()
        .map(|&(a, b)| (x[a as usize] - x[b as usize]).length())
        .collect()
}

/// Sewing springs: pair `(a, b)` has stiffness `k` and a rest length that shrinks linearly from
/// its initial gap to zero between `t0` and `t0 + close_time`. The shrinking rest length is a
/// scripted pull from outside the cloth, so the effect reports no potential energy and declares
/// that it injects energy (the divergence guard then budgets its work like wind's).
pub struct SeamSprings {
    pairs: Vec<(u32, u32)>,
    rest0: Vec<f64>,
    k: f64,
    t0: f64,
    close_time: f64,
}

impl SeamSprings {
    pub fn new(pairs: Vec<(u32, u32)>, x: &[Vec3], k: f64, t0: f64, close_time: f64) -> Self {
        let rest0 = gaps(x, &pairs);
        Self {
            pairs,
            rest0,
            k,
            t0,
            close_time,
        }
    }

    /// Rest length of pair `p` at time `t`.
    pub fn rest(&self, p: usize, t: f64) -> f64 {
        let s = if self.close_time > 0.0 {
            1.0 - (t - self.t0) / self.close_time
        } else {
            0.0
        };
        self.rest0[p] * s.clamp(0.0, 1.0)
    }
}

impl Effect for SeamSprings {
    fn name(&self) -> &'static str {
        "seam"
    }

    fn declare(&self, p: &mut PatternBuilder) {
        for &(a, b) in &self.pairs {
            p.couple(a, b);
        }
    }

    fn add_forces(&self, s: &State, f: &mut [Vec3]) {
        for (k, &(a, b)) in self.pairs.iter().enumerate() {
            let d = s.x[a as usize] - s.x[b as usize];
            let len = d.length();
            let rest = self.rest(k, s.t);
            // f = -k (|d| - L) d/|d|, which is exactly -k d once L = 0 (no direction needed).
            let fa = if rest == 0.0 {
                d * -self.k
            } else if len > 0.0 {
                d * (-self.k * (len - rest) / len)
            } else {
                continue;
            };
            f[a as usize] += fa;
            f[b as usize] -= fa;
        }
    }

    fn add_jacobians(&self, s: &State, dfdx: &mut BlockCsr, _dfdv: &mut BlockCsr) {
        for (k, &(a, b)) in self.pairs.iter().enumerate() {
            let d = s.x[a as usize] - s.x[b as usize];
            let len = d.length();
            let rest = self.rest(k, s.t);
            let kaa = if len > 0.0 && rest > 0.0 {
                let n = d / len;
                let nn = outer(n, n);
                // Compressed springs drop their (indefinite) transverse term.
                (nn + (Mat3::IDENTITY - nn) * (1.0 - rest / len).max(0.0)) * -self.k
            } else {
                Mat3::IDENTITY * -self.k
            };
            dfdx.add(a, a, kaa);
            dfdx.add(b, b, kaa);
            dfdx.add(a, b, -kaa);
            dfdx.add(b, a, -kaa);
        }
    }

    fn injects_energy(&self) -> bool {
        true
    }
}
