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

    /// The per-vertex moves that change `r` by `d` (None when no vertex can move).
    ///
    /// The minimal-energy distribution moves vertex k by `c_k w_k / M` times `d`: among free
    /// vertices that follows their masses, but where kinematic vertices carry most of both sides'
    /// weight, the free vertex of small weight `c` is thrown `d / c`: on robot_cape at 48x48 a
    /// vertex beside the attached edge, a small share of a triangle whose other corners are
    /// attached (and met by an attached vertex), would be thrown metres by one CCD correction.
    /// So the change is scaled by the free share of the freer side (1 when either side is all
    /// free, which leaves every such pair's arithmetic unscaled): the free vertices move as far
    /// as a free side would. What that leaves of the pair is mostly the scene's motion, and is the
    /// next pass's and the impact zones' (which move with kinematic vertices rigidly).
    pub fn moves(&self, w: &[f64], d: Vec3) -> Option<[Vec3; 4]> {
        let m = self.inv_mass(w);
        if m <= 0.0 {
            return None;
        }
        let share = self.free_share(w);
        let d = if share < 1.0 { d * share } else { d };
        let mut out = [Vec3::ZERO; 4];
        for k in 0..self.len {
            let i = self.idx[k] as usize;
            out[k] = d * (self.c[k] * w[i] / m);
        }
        Some(out)
    }

    /// The larger of the two sides' free weight over its whole weight (`r`'s positive and
    /// negative coefficients are its two sides: the vertex and the triangle, or the two edges).
    pub fn free_share(&self, w: &[f64]) -> f64 {
        let (mut free, mut all) = ([0.0; 2], [0.0; 2]);
        for k in 0..self.len {
            let (side, c) = if self.c[k] >= 0.0 {
                (0, self.c[k])
            } else {
                (1, -self.c[k])
            };
            all[side] += c;
            if w[self.idx[k] as usize] > 0.0 {
                free[side] += c;
            }
        }
        let share = |s: usize| if all[s] > 0.0 { free[s] / all[s] } else { 0.0 };
        share(0).max(share(1))
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
