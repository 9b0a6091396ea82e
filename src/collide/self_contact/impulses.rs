//! The velocity answer of one pass: each pair's inelastic normal impulse and Coulomb friction,
//! applied as equal and opposite impulses on its two sides, so the pass conserves the cloth's
//! momentum (Bridson et al. 2002's proximity impulse, relaxed Jacobi over the pairs).
//!
//! Why not the positions' averaged moves (`jacobi`): a vertex's mean of its pairs' moves is no
//! sum of impulses, so the layer under a vertex receives less than the vertex gives (a towel
//! vertex shares many pairs and takes their mean): a napkin landing on a towel came out with
//! momentum of its own, and slid on (against the grain of the friction that should stop it).
//!
//! Here every pair's impulse is scaled by one factor for all its vertices, `1 / n_max`, the
//! most pairs any of its vertices takes part in, and the pairs are swept a few times on the
//! velocities the last sweep left: each sweep is order-independent (every pair reads the same
//! velocities) and conserves momentum, and no vertex is answered more than once over.
//! Per pair the impulses accumulate (Catto's accumulated impulse): the normal one never pulls
//! the pair together, the friction one never exceeds `mu` times the normal one.

use super::stencil::Stencil;
use crate::Vec3;

/// Most sweeps of one pass; what they leave of an approach, the layer springs of the next
/// substep stop inside the solve (`sim/coupling/layer_springs.rs`).
const SWEEPS: usize = 8;

/// Sweeps stop once no pair's relative velocity changes by more than this (m/s).
const SETTLED_SPEED: f64 = 1e-7;

/// A pair's velocity answer: along the unit normal `n` (towards the side it started on), no
/// approach; across it, Coulomb friction with coefficient `mu`.
#[derive(Debug, Clone, Copy)]
pub(super) struct Impact {
    pub st: Stencil,
    pub n: Vec3,
    pub mu: f64,
}

/// Scratch of [`Impulses::apply`], kept across passes; only the vertices a pass touches are
/// reset, so a pass costs its pairs, not the cloth.
#[derive(Default)]
pub(super) struct Impulses {
    count: Vec<u32>,
    change: Vec<Vec3>,
    touched: Vec<u32>,
    acc: Vec<(f64, Vec3)>,
    scale: Vec<f64>,
}

impl Impulses {
    /// Answers `impacts` on velocities `v`, distributing each pair's impulses by the true
    /// inverse masses `w` (equal and opposite on the two layers). Not by the positions' weights
    /// (`resolve`'s heavier vertices against an obstacle): a normal across the layers is tilted
    /// where a layer lands at an angle, and the obstacle cannot carry the tangential part of
    /// that impulse (a frictionless table under a towel), so the two layers would gain momentum.
    /// Returns how many pairs ended sliding: friction at its Coulomb limit in the last sweep,
    /// the pair still slipping.
    pub fn apply(&mut self, impacts: &[Impact], w: &[f64], v: &mut [Vec3]) -> usize {
        let n = v.len().min(w.len());
        if self.count.len() < n {
            self.count.resize(n, 0);
            self.change.resize(n, Vec3::ZERO);
        }
        let usable = |m: &Impact| m.st.idx[..m.st.len].iter().all(|&i| (i as usize) < n);
        let movable = |st: &Stencil, k: usize| st.c[k] != 0.0 && w[st.idx[k] as usize] > 0.0;
        for m in impacts.iter().filter(|m| usable(m)) {
            for k in (0..m.st.len).filter(|&k| movable(&m.st, k)) {
                let i = m.st.idx[k];
                if self.count[i as usize] == 0 {
                    self.touched.push(i);
                }
                self.count[i as usize] += 1;
            }
        }
        self.scale.clear();
        self.scale.extend(impacts.iter().map(|m| {
            let most = (0..m.st.len)
                .filter(|&k| usable(m) && movable(&m.st, k))
                .map(|k| self.count[m.st.idx[k] as usize])
                .max()
                .unwrap_or(0);
            if most > 0 {
                1.0 / f64::from(most)
            } else {
                0.0
            }
        }));
        self.acc.clear();
        self.acc.resize(impacts.len(), (0.0, Vec3::ZERO));
        let mut sliding = 0;
        for _ in 0..SWEEPS {
            let mut largest: f64 = 0.0;
            sliding = 0;
            for ((m, &s), acc) in impacts.iter().zip(&self.scale).zip(&mut self.acc) {
                if s <= 0.0 {
                    continue;
                }
                let vr = m.st.eval(v);
                let vn = m.n.dot(vr);
                // Normal: remove the approach, never pull the pair together.
                let dn = (-vn * s).max(-acc.0);
                acc.0 += dn;
                // Friction: towards stopping the slip, within `mu` of the normal impulse.
                let vt = vr - m.n * vn;
                let mut want = acc.1 - vt * s;
                let limit = m.mu * acc.0;
                if want.length() > limit {
                    want *= limit / want.length();
                    if vt.length() > 0.0 && limit > 0.0 {
                        sliding += 1;
                    }
                }
                let dt = want - acc.1;
                acc.1 = want;
                largest = largest.max(dn.abs()).max(dt.length());
                if let Some(moves) = m.st.moves(w, m.n * dn + dt) {
                    for k in 0..m.st.len {
                        self.change[m.st.idx[k] as usize] += moves[k];
                    }
                }
            }
            for &i in &self.touched {
                let i = i as usize;
                v[i] += self.change[i];
                self.change[i] = Vec3::ZERO;
            }
            if largest <= SETTLED_SPEED {
                break;
            }
        }
        for &i in &self.touched {
            self.count[i as usize] = 0;
        }
        self.touched.clear();
        sliding
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MASS: [f64; 5] = [0.02, 0.01, 0.03, 0.015, 0.025];
    const MU: f64 = 0.3;

    fn vt(p: u32, b: [f64; 3]) -> Impact {
        Impact {
            st: Stencil {
                idx: [p, 1, 2, 3],
                c: [1.0, -b[0], -b[1], -b[2]],
                len: 4,
            },
            n: Vec3::Z,
            mu: MU,
        }
    }

    fn momentum(v: &[Vec3]) -> Vec3 {
        v.iter().zip(&MASS).map(|(v, m)| *v * *m).sum()
    }

    fn answered(impacts: &[Impact]) -> (Vec<Vec3>, Vec<Vec3>) {
        let w: Vec<f64> = MASS.iter().map(|m| 1.0 / m).collect();
        let v0 = vec![
            Vec3::new(0.4, 0.1, -1.0),
            Vec3::ZERO,
            Vec3::ZERO,
            Vec3::ZERO,
            Vec3::new(-0.2, 0.0, -0.5),
        ];
        let mut v = v0.clone();
        Impulses::default().apply(impacts, &w, &mut v);
        (v0, v)
    }

    /// One vertex falling onto a triangle while sliding over it: one sweep stops the approach
    /// exactly, friction removes `mu` times that from the slip (the slip is larger: it slides),
    /// and the four vertices' momentum is what it was.
    #[test]
    fn one_pair_stops_its_approach_with_coulomb_friction_and_conserves_momentum() {
        let m = vt(0, [0.2, 0.3, 0.5]);
        let (v0, v) = answered(&[m]);
        assert!((momentum(&v) - momentum(&v0)).length() < 1e-15);
        let (before, after) = (m.st.eval(&v0), m.st.eval(&v));
        assert!(after.z.abs() < 1e-12, "still approaching: {after:?}");
        let slip = |u: Vec3| Vec3::new(u.x, u.y, 0.0).length();
        let removed = slip(before) - slip(after);
        assert!((removed - MU * before.z.abs()).abs() < 1e-12, "{removed}");
    }

    /// Two pairs sharing a triangle: each is answered at half weight per sweep, and the sweeps
    /// conserve momentum and leave both pairs approaching less than they did (one may end
    /// separating: the other's impulse pushes the shared triangle away from it).
    #[test]
    fn pairs_sharing_vertices_conserve_momentum() {
        let impacts = [vt(0, [0.2, 0.3, 0.5]), vt(4, [0.6, 0.2, 0.2])];
        let (v0, v) = answered(&impacts);
        assert!((momentum(&v) - momentum(&v0)).length() < 1e-15);
        for m in &impacts {
            let (before, after) = (m.st.eval(&v0).z, m.st.eval(&v).z);
            assert!(after > before, "{before} -> {after}");
        }
    }
}
