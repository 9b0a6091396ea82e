//! The element tests between two leaves (or inside one): each owned vertex against the other
//! leaf's triangles, each owned edge against the other leaf's edges, boxes within margins.

use super::{near, Node, TopologyBvh};
use crate::collide::broad::Aabb;

impl TopologyBvh {
    /// Whether vertex `v`'s query box (with its margin) overlaps triangle `t`'s box.
    pub fn vt_overlap(&self, v: u32, t: u32) -> bool {
        match (self.vbox.get(v as usize), self.tbox.get(t as usize)) {
            (Some(b), Some(tb)) => near(b, tb, self.margin[v as usize]),
            _ => false,
        }
    }

    /// Whether edges `e` and `f` come nearer than the largest margin of their four ends.
    pub fn ee_overlap(&self, edges: &[[u32; 2]], e: u32, f: u32) -> bool {
        match (self.ebox.get(e as usize), self.ebox.get(f as usize)) {
            (Some(b), Some(fb)) => near(
                b,
                fb,
                self.edge_margin(edges, e).max(self.edge_margin(edges, f)),
            ),
            _ => false,
        }
    }

    fn edge_margin(&self, edges: &[[u32; 2]], e: u32) -> f64 {
        let m = |i: u32| self.margin.get(i as usize).copied().unwrap_or(0.0);
        edges.get(e as usize).map_or(0.0, |[p, q]| m(*p).max(m(*q)))
    }

    /// The element pairs of leaves `a` and `b` (`a == b`: inside one leaf).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn leaf_elements(
        &self,
        a: u32,
        b: u32,
        triangles: &[[u32; 3]],
        edges: &[[u32; 2]],
        with_edges: bool,
        accept_vt: &(impl Fn(u32, u32) -> bool + Sync),
        accept_ee: &(impl Fn(u32, u32) -> bool + Sync),
        vt: &mut Vec<(u32, u32)>,
        ee: &mut Vec<(u32, u32)>,
    ) {
        let (na, nb) = (&self.nodes[a as usize], &self.nodes[b as usize]);
        let tris = |n: &Node| &self.order[n.first as usize..(n.first + n.count) as usize];
        let verts = |n: &Node| &self.owned_v[n.verts.0 as usize..n.verts.1 as usize];
        let own_e = |n: &Node| &self.owned_e[n.edges.0 as usize..n.edges.1 as usize];
        let mut vt_side = |vn: &Node, tn: &Node, tbox_node: &Aabb| {
            for &v in verts(vn) {
                let (q, m) = (&self.vbox[v as usize], self.margin[v as usize]);
                if !near(q, tbox_node, m) {
                    continue;
                }
                for &t in tris(tn) {
                    if near(q, &self.tbox[t as usize], m)
                        && !triangles[t as usize].contains(&v)
                        && accept_vt(v, t)
                    {
                        vt.push((v, t));
                    }
                }
            }
        };
        vt_side(na, nb, &self.nbox[b as usize]);
        if a != b {
            vt_side(nb, na, &self.nbox[a as usize]);
        }
        if !with_edges {
            return;
        }
        let (ea, eb) = (own_e(na), own_e(nb));
        let box_b = &self.nbox[b as usize];
        for (i, &e) in ea.iter().enumerate() {
            let (q, me) = (&self.ebox[e as usize], self.edge_margin(edges, e));
            // `f`'s margin may be the larger: the node's bounds both.
            if !near(q, box_b, me.max(self.nmargin[b as usize])) {
                continue;
            }
            let others = if a == b { &ea[i + 1..] } else { eb };
            for &f in others {
                let (lo, hi) = (e.min(f), e.max(f));
                let (el, eh) = (&edges[lo as usize], &edges[hi as usize]);
                if near(
                    q,
                    &self.ebox[f as usize],
                    me.max(self.edge_margin(edges, f)),
                ) && !el.iter().any(|v| eh.contains(v))
                    && accept_ee(lo, hi)
                {
                    ee.push((lo, hi));
                }
            }
        }
    }
}
