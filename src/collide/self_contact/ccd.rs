//! Query: continuous collision of moving vertex-triangle and edge-edge pairs over the step;
//! each crossing pair is corrected to end a small gap apart on its starting side.

use super::collider::SelfCollider;
use super::jacobi::Correction;
use super::stencil::Stencil;
use crate::collide::narrow;
use crate::Vec3;
use rayon::prelude::*;

/// CCD hit tolerance as a fraction of the pair's contact distance.
const CCD_ETA_FRACTION: f64 = 1e-3;
/// Separation left after a CCD correction, as a fraction of the pair's contact distance.
const CCD_GAP_FRACTION: f64 = 0.1;

impl SelfCollider {
    /// One CCD pass over (x0 -> x1), Jacobi with averaging; corrects each crossing pair so
    /// it ends separated on its starting side. Returns the number of hits.
    pub(super) fn ccd_pass(
        &mut self,
        x0: &[Vec3],
        x1: &mut [Vec3],
        v1: &mut [Vec3],
        th: &[f64],
        correct: bool,
    ) -> usize {
        // After a correcting pass of this step only pairs with a changed vertex can hit anew
        // (`changed`); the zones' passes (not correcting) answer every pair.
        let since = if correct {
            self.ccd_changed.update(x1, None)
        } else {
            self.ccd_changed.forget();
            None
        };
        if since == Some(false) {
            return 0;
        }
        let changed = std::mem::take(&mut self.ccd_changed);
        self.broad_phase(
            x0,
            x1,
            |i| th[i] * CCD_ETA_FRACTION * 2.0,
            false,
            false,
            true,
            since.map(|_| changed.flags()),
        );
        self.ccd_changed = changed;
        let pairs = std::mem::take(&mut self.pairs);
        let pairs_ee = std::mem::take(&mut self.pairs_ee);
        // Detect and answer in parallel on the pass's start state, then move each vertex by
        // the mean of its answers (order-independent; see `jacobi`); hits the answers leave or
        // create are the next pass's.
        let mut found = std::mem::take(&mut self.found);
        {
            let this = &*self;
            let xr: &[Vec3] = x1;
            let answer = |h: Option<(Stencil, Vec3)>| {
                h.map(|(st, nrm)| this.ccd_correction(&st, nrm, x0, xr, th, correct))
            };
            found.clear();
            found.par_extend(
                pairs
                    .par_iter()
                    .map(|&(v, t)| answer(this.vt_hit(v, t, x0, xr, th)))
                    .chain(
                        pairs_ee
                            .par_iter()
                            .map(|&(a, b)| answer(this.ee_hit(a, b, x0, xr, th))),
                    )
                    .flatten(),
            );
        }
        let hits = found.len();
        if correct {
            let mut pass = std::mem::take(&mut self.jacobi);
            for c in &found {
                pass.add(c, &self.w);
                self.ccd_changed.answer_again(&c.st.idx[..c.st.len]);
            }
            self.report.slipping += pass.apply(x1, v1, &self.w_true);
            self.jacobi = pass;
        } else {
            for c in &found {
                self.merge(&c.st);
            }
        }
        self.found = found;
        self.pairs = pairs;
        self.pairs_ee = pairs_ee;
        self.report.ccd_passes += 1;
        self.report.ccd_hits += hits;
        hits
    }

    fn vt_hit(
        &self,
        v: u32,
        t: u32,
        x0: &[Vec3],
        x1: &[Vec3],
        th: &[f64],
    ) -> Option<(Stencil, Vec3)> {
        let tri = self.triangles[t as usize];
        let [a, b, c] = tri.map(|i| i as usize);
        let p = v as usize;
        let eta = CCD_ETA_FRACTION * (th[p] + (th[a] + th[b] + th[c]) / 3.0) + 1e-12;
        let hit = narrow::vertex_triangle_ccd(
            x0[p],
            x1[p],
            [x0[a], x0[b], x0[c]],
            [x1[a], x1[b], x1[c]],
            eta,
        )?;
        let st = self.vt_stencil(v, t, hit.bary);
        // All four vertices kinematic: the scene prescribes this motion and nothing here can
        // change it; as a hit it only grew impact zones around it (see `zones`).
        (st.inv_mass(&self.w) > 0.0).then_some((st, hit.normal))
    }

    fn ee_hit(
        &self,
        e1: u32,
        e2: u32,
        x0: &[Vec3],
        x1: &[Vec3],
        th: &[f64],
    ) -> Option<(Stencil, Vec3)> {
        let (a, b) = (self.edges[e1 as usize], self.edges[e2 as usize]);
        let [a0, a1] = a.map(|i| i as usize);
        let [b0, b1] = b.map(|i| i as usize);
        let eta = CCD_ETA_FRACTION * 0.5 * (th[a0] + th[a1] + th[b0] + th[b1]) + 1e-12;
        let hit = narrow::edge_edge_ccd(
            [x0[a0], x0[a1]],
            [x1[a0], x1[a1]],
            [x0[b0], x0[b1]],
            [x1[b0], x1[b1]],
            eta,
        )?;
        let st = self.ee_stencil(e1, e2, hit.s, hit.u);
        (st.inv_mass(&self.w) > 0.0).then_some((st, hit.normal))
    }

    /// The answer to a crossing pair: its end positions moved so that, along the hit normal
    /// oriented to the side the pair started on, it ends a small gap apart, and its approaching
    /// normal velocity removed (an inelastic impact). `correct` false: the hit only (zones).
    #[allow(clippy::too_many_arguments)]
    fn ccd_correction(
        &self,
        st: &Stencil,
        normal: Vec3,
        x0: &[Vec3],
        x1: &[Vec3],
        th: &[f64],
        correct: bool,
    ) -> Correction {
        let none = Correction {
            st: *st,
            dx: Vec3::ZERO,
            n: Vec3::ZERO,
            mu: 0.0,
            residual: 1.0,
            layers: None,
        };
        if !correct {
            return none;
        }
        let r0 = st.eval(x0);
        let mut n = normal.normalize_or_zero();
        if n == Vec3::ZERO {
            n = r0.normalize_or(Vec3::Z);
        }
        if n.dot(r0) < 0.0 {
            n = -n;
        }
        let gap = CCD_GAP_FRACTION * st.gap(th);
        let d1 = n.dot(st.eval(x1));
        if d1 >= gap {
            return none;
        }
        // The impact is inelastic: the pair's approaching normal velocity goes, nothing more
        // (`impulses`). Adding the position change over h instead would turn a deep correction
        // into speed (metres per second on robot_cape where the arms reverse).
        Correction {
            st: *st,
            dx: n * (gap - d1),
            n,
            mu: 0.0,
            residual: 1.0,
            layers: None,
        }
    }
}
