//! Query: proximity of close vertex-triangle and edge-edge (or vertex-vertex) pairs at the end
//! positions, answered by inelastic repulsion with Coulomb friction (Bridson et al. 2002).

use super::collider::SelfCollider;
use super::stencil::Stencil;
use crate::collide::narrow;
use crate::Vec3;
use rayon::prelude::*;

impl SelfCollider {
    /// One Gauss-Seidel pass of proximity repulsion on end positions; returns pairs corrected.
    /// `with_edges`: edge-edge pairs too (without CCD behind it); with CCD the vertex-triangle
    /// pairs keep the layers apart and CCD answers edges that cross, at half the cost
    /// (robot_pick_towel: the collision stage 11.1 s -> 5.1 s over 4 s simulated, still no
    /// self-intersection).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn repulsion_pass(
        &mut self,
        x0: &[Vec3],
        x1: &mut [Vec3],
        v1: &mut [Vec3],
        th: &[f64],
        friction: &[f64],
        h: f64,
        vertex_vertex: bool,
        with_edges: bool,
    ) -> usize {
        // Query boxes: end positions inflated by twice the radius (pair distance).
        let max_th = th.iter().copied().fold(0.0, f64::max);
        self.broad_phase(x1, x1, |i| th[i] + max_th, vertex_vertex, true, with_edges);
        let pairs = std::mem::take(&mut self.pairs);
        let pairs_ee = std::mem::take(&mut self.pairs_ee);
        // Find close pairs in parallel, then answer them in order (Gauss-Seidel), re-measuring
        // each on the updated positions.
        let (mut flag_vt, mut flag_ee) = std::mem::take(&mut self.flags);
        {
            let this = &*self;
            let xr: &[Vec3] = x1;
            let close = |st: &Stencil| (st.eval(xr).length() < st.gap(th)) as u8;
            pairs
                .par_iter()
                .map(|&(a, b)| close(&this.close_stencil(a, b, xr, vertex_vertex)))
                .collect_into_vec(&mut flag_vt);
            pairs_ee
                .par_iter()
                .map(|&(a, b)| close(&this.ee_close_stencil(a, b, xr)))
                .collect_into_vec(&mut flag_ee);
        }
        let mut count = 0;
        for (&(a, b), _) in pairs.iter().zip(&flag_vt).filter(|(_, f)| **f != 0) {
            let st = self.close_stencil(a, b, x1, vertex_vertex);
            count += self.repel(&st, x0, x1, v1, th, friction, h) as usize;
        }
        for (&(e1, e2), _) in pairs_ee.iter().zip(&flag_ee).filter(|(_, f)| **f != 0) {
            let st = self.ee_close_stencil(e1, e2, x1);
            count += self.repel(&st, x0, x1, v1, th, friction, h) as usize;
        }
        self.flags = (flag_vt, flag_ee);
        self.pairs = pairs;
        self.pairs_ee = pairs_ee;
        self.report.repulsions += count;
        count
    }

    /// Closest-point stencil of a vertex-triangle (or vertex-vertex) pair at positions `x`.
    fn close_stencil(&self, a: u32, b: u32, x: &[Vec3], vertex_vertex: bool) -> Stencil {
        if vertex_vertex {
            return Stencil {
                idx: [a, b, 0, 0],
                c: [1.0, -1.0, 0.0, 0.0],
                len: 2,
            };
        }
        let t = self.triangles[b as usize];
        let (_, bary) = narrow::point_triangle_closest(
            x[a as usize],
            x[t[0] as usize],
            x[t[1] as usize],
            x[t[2] as usize],
        );
        self.vt_stencil(a, b, bary)
    }

    /// Closest-point stencil of an edge-edge pair at positions `x`.
    fn ee_close_stencil(&self, e1: u32, e2: u32, x: &[Vec3]) -> Stencil {
        let (a, b) = (self.edges[e1 as usize], self.edges[e2 as usize]);
        let (s, u, _, _) = narrow::segment_segment_closest(
            x[a[0] as usize],
            x[a[1] as usize],
            x[b[0] as usize],
            x[b[1] as usize],
        );
        self.ee_stencil(e1, e2, s, u)
    }

    /// Separates a close pair to its contact distance along the normal of the side it started on,
    /// removes approaching normal velocity and applies Coulomb friction to the tangential part.
    #[allow(clippy::too_many_arguments)]
    fn repel(
        &self,
        st: &Stencil,
        x0: &[Vec3],
        x1: &mut [Vec3],
        v1: &mut [Vec3],
        th: &[f64],
        friction: &[f64],
        h: f64,
    ) -> bool {
        let gap = st.gap(th);
        let r = st.eval(x1);
        let d = r.length();
        if d >= gap {
            return false;
        }
        let r0 = st.eval(x0);
        let n = if d > 1e-12 * gap.max(1e-12) {
            r / d
        } else {
            r0.normalize_or_zero()
        };
        if n == Vec3::ZERO {
            return false;
        }
        if n.dot(r0) < 0.0 {
            // Seen from the start of the step the pair is on the other side: either it crossed
            // (CCD's case, with the crossing's own normal) or its closest feature changed. Pushed
            // here by `gap + d` through the other element, it went 26 m/s where robot_cape's
            // attachments squeeze the cloth between the torso and a shoulder.
            return false;
        }
        let dist = n.dot(r);
        if !st.apply(x1, &self.w, n * (gap - dist)) {
            return false;
        }
        let _ = h;
        let vr = st.eval(v1);
        let vn = vr.dot(n);
        if vn < 0.0 {
            let vt = vr - n * vn;
            let mu = (0..st.len)
                .map(|k| friction[st.idx[k] as usize] * st.c[k].abs())
                .sum::<f64>()
                / (0..st.len).map(|k| st.c[k].abs()).sum::<f64>();
            let vt_len = vt.length();
            let dvt = if vt_len <= -mu * vn {
                -vt
            } else {
                vt * (mu * vn / vt_len)
            };
            st.apply(v1, &self.w, n * (-vn) + dvt);
        }
        true
    }
}
