//! A self-contact pair as a weighted sum of up to four vertices, `r = sum c_k x_k`, and the
//! minimal-kinetic-energy way to change it.

use crate::Vec3;

#[derive(Debug, Clone, Copy)]
pub(super) struct Stencil {
    pub idx: [u32; 4],
    pub c: [f64; 4],
    pub len: usize,
}

impl Stencil {
    pub fn eval(&self, x: &[Vec3]) -> Vec3 {
        (0..self.len)
            .map(|k| x[self.idx[k] as usize] * self.c[k])
            .sum()
    }

    pub fn inv_mass(&self, w: &[f64]) -> f64 {
        (0..self.len)
            .map(|k| self.c[k] * self.c[k] * w[self.idx[k] as usize])
            .sum()
    }

    /// Changes `r` by `d` (if any vertex can move), returning false otherwise.
    pub fn apply(&self, x: &mut [Vec3], w: &[f64], d: Vec3) -> bool {
        let m = self.inv_mass(w);
        if m <= 0.0 {
            return false;
        }
        for k in 0..self.len {
            let i = self.idx[k] as usize;
            x[i] += d * (self.c[k] * w[i] / m);
        }
        true
    }

    /// Contact distance of the pair from the per-vertex thickness `th`.
    pub fn gap(&self, th: &[f64]) -> f64 {
        // Contact distance: first vertex's radius plus the (weighted) radius of the other side.
        let mut a = 0.0;
        let mut b = 0.0;
        for k in 0..self.len {
            let t = th[self.idx[k] as usize];
            if self.c[k] > 0.0 {
                a += self.c[k] * t;
            } else {
                b -= self.c[k] * t;
            }
        }
        a + b
    }
}
