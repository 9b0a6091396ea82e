//! Building the hierarchy once on the mesh's rest shape: median splits of quads along the
//! grid's directions, each node's disk contour, each leaf's own vertices and edges, and the
//! adjacent leaf pairs that form a disk together.

use super::{Node, TopologyBvh, LEAF};
use crate::Vec3;

impl TopologyBvh {
    /// Builds the hierarchy over `triangles` by median splits of their centroids at `x` (the
    /// rest shape), so nodes are compact pieces of the cloth.
    pub fn build(triangles: &[[u32; 3]], edges: &[[u32; 2]], x: &[Vec3]) -> TopologyBvh {
        let n_v = x.len();
        let ok = |t: &[u32; 3]| t.iter().all(|&i| (i as usize) < n_v);
        let order: Vec<u32> = (0..triangles.len() as u32)
            .filter(|&t| ok(&triangles[t as usize]))
            .collect();
        let centroid = |t: u32| {
            let [a, b, c] = triangles[t as usize].map(|i| x[i as usize]);
            let m = (a + b + c) / 3.0;
            if m.is_finite() {
                m
            } else {
                Vec3::ZERO
            }
        };
        // Split quads (triangle pairs), not triangles: a grid's nodes are then rectangles,
        // whose contours the star test accepts, not staircases of half-quads.
        let units = quads(triangles, &order, x);
        let unit_centroid = |u: u32| match units[u as usize] {
            [a, NONE] => centroid(a),
            [a, b] => 0.5 * (centroid(a) + centroid(b)),
        };
        let frame = grid_frame(triangles, &units, x);
        let mut by_unit: Vec<u32> = (0..units.len() as u32).collect();
        let mut nodes = Vec::new();
        if !by_unit.is_empty() {
            split(&mut by_unit, 0, &unit_centroid, &frame, &mut nodes);
        }
        // Unit ranges to triangle ranges.
        let mut start = Vec::with_capacity(by_unit.len() + 1);
        let mut order = Vec::with_capacity(order.len());
        for &u in &by_unit {
            start.push(order.len() as u32);
            order.extend(units[u as usize].iter().filter(|&&t| t != NONE));
        }
        start.push(order.len() as u32);
        for nd in &mut nodes {
            let (f, c) = (nd.first as usize, nd.count as usize);
            (nd.first, nd.count) = (start[f], start[f + c] - start[f]);
        }
        let mut bvh = TopologyBvh {
            nodes,
            order,
            ..Default::default()
        };
        bvh.topology(triangles, edges, n_v);
        bvh.leaf_unions(triangles, n_v);
        bvh
    }

    /// Per node: its contour when it is a disk; per leaf: its own vertices and edges.
    fn topology(&mut self, triangles: &[[u32; 3]], edges: &[[u32; 2]], n_v: usize) {
        let edge_index = |a: u32, b: u32| edges.binary_search(&[a.min(b), a.max(b)]).ok();
        let (mut v_owned, mut e_owned) = (vec![false; n_v], vec![false; edges.len()]);
        for k in 0..self.nodes.len() {
            let (first, n) = (self.nodes[k].first as usize, self.nodes[k].count as usize);
            let tris = &self.order[first..first + n];
            let start = self.contour.len() as u32;
            disk_contour(tris, triangles, &mut self.contour);
            self.nodes[k].contour = (start, self.contour.len() as u32);
            if self.nodes[k].is_leaf() {
                let vs = self.owned_v.len() as u32;
                let es = self.owned_e.len() as u32;
                for &t in tris {
                    let [a, b, c] = triangles[t as usize];
                    for v in [a, b, c] {
                        if !std::mem::replace(&mut v_owned[v as usize], true) {
                            self.owned_v.push(v);
                        }
                    }
                    for (p, q) in [(a, b), (b, c), (c, a)] {
                        if let Some(e) = edge_index(p, q) {
                            if !std::mem::replace(&mut e_owned[e], true) {
                                self.owned_e.push(e as u32);
                            }
                        }
                    }
                }
                self.nodes[k].verts = (vs, self.owned_v.len() as u32);
                self.nodes[k].edges = (es, self.owned_e.len() as u32);
            }
        }
    }

    /// Every two leaves that share a vertex and form a disk together, with their union's
    /// contour: the pairs between them are culled like a node's (`union_culls`).
    fn leaf_unions(&mut self, triangles: &[[u32; 3]], n_v: usize) {
        let mut at: Vec<(u32, u32)> = Vec::new();
        for (k, nd) in self.nodes.iter().enumerate().filter(|(_, nd)| nd.is_leaf()) {
            for &t in &self.order[nd.first as usize..(nd.first + nd.count) as usize] {
                for &v in &triangles[t as usize] {
                    if (v as usize) < n_v {
                        at.push((v, k as u32));
                    }
                }
            }
        }
        at.sort_unstable();
        at.dedup();
        let mut pairs: Vec<(u32, u32)> = Vec::new();
        for run in at.chunk_by(|a, b| a.0 == b.0) {
            for (i, a) in run.iter().enumerate() {
                pairs.extend(run[i + 1..].iter().map(|b| (a.1.min(b.1), a.1.max(b.1))));
            }
        }
        pairs.sort_unstable();
        pairs.dedup();
        let mut tris = Vec::new();
        for (a, b) in pairs {
            let leaf = |k: u32| {
                let nd = &self.nodes[k as usize];
                &self.order[nd.first as usize..(nd.first + nd.count) as usize]
            };
            tris.clear();
            tris.extend_from_slice(leaf(a));
            tris.extend_from_slice(leaf(b));
            let start = self.contour.len() as u32;
            disk_contour(&tris, triangles, &mut self.contour);
            if self.contour.len() as u32 > start {
                self.unions
                    .push(((a, b), (start, self.contour.len() as u32)));
            }
        }
    }
}

/// No triangle (the second of a unit that is a lone triangle).
const NONE: u32 = u32::MAX;

/// Pairs each triangle of `order` with its neighbour across its longest edge at `x` where
/// that edge is the neighbour's longest too (a grid's quads); the rest stay alone.
fn quads(triangles: &[[u32; 3]], order: &[u32], x: &[Vec3]) -> Vec<[u32; 2]> {
    let longest = |t: u32| {
        let [a, b, c] = triangles[t as usize];
        let len = |p: u32, q: u32| (x[p as usize] - x[q as usize]).length();
        let mut best = (a.min(b), a.max(b));
        let mut l = len(a, b);
        for (p, q) in [(b, c), (c, a)] {
            if len(p, q) > l {
                (best, l) = ((p.min(q), p.max(q)), len(p, q));
            }
        }
        best
    };
    let mut keys: Vec<((u32, u32), u32)> = order.iter().map(|&t| (longest(t), t)).collect();
    keys.sort_unstable();
    let mut paired = vec![false; triangles.len()];
    let mut units = Vec::with_capacity(order.len());
    for run in keys.chunk_by(|a, b| a.0 == b.0) {
        if let [(_, a), (_, b)] = *run {
            units.push([a, b]);
            paired[a as usize] = true;
            paired[b as usize] = true;
        }
    }
    units.extend(
        order
            .iter()
            .filter(|&&t| !paired[t as usize])
            .map(|&t| [t, NONE]),
    );
    units
}

/// Split directions: the two sides of the first quad and their normal (a grid's rows and
/// columns, however the cloth is turned), else the world axes.
fn grid_frame(triangles: &[[u32; 3]], units: &[[u32; 2]], x: &[Vec3]) -> [Vec3; 3] {
    let world = [Vec3::X, Vec3::Y, Vec3::Z];
    let Some(&[a, b]) = units.iter().find(|u| u[1] != NONE) else {
        return world;
    };
    // The quad's sides: the edges of its first triangle other than the shared diagonal.
    let (ta, tb) = (triangles[a as usize], triangles[b as usize]);
    let sides: Vec<Vec3> = [(0, 1), (1, 2), (2, 0)]
        .iter()
        .map(|&(i, j)| (ta[i], ta[j]))
        .filter(|(p, q)| !(tb.contains(p) && tb.contains(q)))
        .map(|(p, q)| x[q as usize] - x[p as usize])
        .collect();
    let [s, t] = sides[..] else {
        return world;
    };
    let u = s.normalize_or_zero();
    let w = (t - u * t.dot(u)).normalize_or_zero();
    let n = u.cross(w);
    if u == Vec3::ZERO || w == Vec3::ZERO || !n.is_finite() {
        return world;
    }
    [u, w, n]
}

/// Median split of `order` (units of one or two triangles) along the `frame` direction of the
/// widest extent of its centroids, down to `LEAF / 2` units. The cut goes between two rows of
/// centroids (equal projections go to one side) nearest the median, so a grid's nodes are
/// rectangles. Appends nodes in pre-order and returns the index of the node made.
fn split(
    order: &mut [u32],
    first: usize,
    centroid: &impl Fn(u32) -> Vec3,
    frame: &[Vec3; 3],
    nodes: &mut Vec<Node>,
) -> usize {
    let k = nodes.len();
    nodes.push(Node {
        first: first as u32,
        count: order.len() as u32,
        right: 0,
        contour: (0, 0),
        verts: (0, 0),
        edges: (0, 0),
    });
    if order.len() <= LEAF / 2 {
        return k;
    }
    let extent = |d: Vec3| {
        let (lo, hi) = order
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &t| {
                let p = centroid(t).dot(d);
                (lo.min(p), hi.max(p))
            });
        hi - lo
    };
    let (axis, ext) =
        frame
            .iter()
            .map(|&d| (d, extent(d)))
            .fold(
                (frame[0], f64::NEG_INFINITY),
                |a, b| if b.1 > a.1 { b } else { a },
            );
    let key = |t: u32| centroid(t).dot(axis);
    order.sort_unstable_by(|&a, &b| {
        key(a)
            .partial_cmp(&key(b))
            .unwrap_or(std::cmp::Ordering::Equal)
    });
    let tol = 1e-6 * ext.max(f64::MIN_POSITIVE);
    let n = order.len();
    let mid = n / 2;
    // Nearest gap between rows to the median (either side); none: the median itself.
    let gap = |i: usize| key(order[i]) - key(order[i - 1]) > tol;
    let cut = (0..n / 2)
        .flat_map(|d| [mid - d, mid + d])
        .find(|&i| i > 0 && i < n && gap(i))
        .unwrap_or(mid);
    let (left, right) = order.split_at_mut(cut);
    split(left, first, centroid, frame, nodes);
    let r = split(right, first + cut, centroid, frame, nodes);
    nodes[k].right = r as u32;
    k
}

/// Appends the boundary loop of triangles `tris` (ordered along their orientation) to `out`
/// when they form a topological disk: edge-connected, manifold, one boundary loop, Euler
/// characteristic 1. Appends nothing otherwise.
fn disk_contour(tris: &[u32], triangles: &[[u32; 3]], out: &mut Vec<u32>) {
    let n = tris.len();
    if n == 0 {
        return;
    }
    // Undirected edges with the triangle using them, grouped.
    let mut keys: Vec<(u32, u32, u32)> = Vec::with_capacity(3 * n);
    for (i, &t) in tris.iter().enumerate() {
        let [a, b, c] = triangles[t as usize];
        for (p, q) in [(a, b), (b, c), (c, a)] {
            keys.push((p.min(q), p.max(q), i as u32));
        }
    }
    keys.sort_unstable();
    let mut parent: Vec<u32> = (0..n as u32).collect();
    let (mut n_edges, mut manifold) = (0i64, true);
    let mut next: Vec<(u32, u32)> = Vec::new();
    for run in keys.chunk_by(|a, b| (a.0, a.1) == (b.0, b.1)) {
        for w in run.windows(2) {
            union(&mut parent, w[0].2, w[1].2);
        }
        n_edges += 1;
        manifold &= run.len() <= 2;
        if let [(lo, hi, tri)] = *run {
            // A boundary edge, directed as its triangle runs.
            let [a, b, c] = triangles[tris[tri as usize] as usize];
            let forward = [(a, b), (b, c), (c, a)].contains(&(lo, hi));
            next.push(if forward { (lo, hi) } else { (hi, lo) });
        }
    }
    let root = find(&mut parent, 0);
    let connected = (0..n as u32).all(|i| find(&mut parent, i) == root);
    let mut verts: Vec<u32> = tris.iter().flat_map(|&t| triangles[t as usize]).collect();
    verts.sort_unstable();
    verts.dedup();
    let euler = verts.len() as i64 - n_edges + n as i64;
    if !(connected && manifold && euler == 1) || next.is_empty() {
        return;
    }
    next.sort_unstable();
    // A vertex with two outgoing boundary edges pinches the loop: not a disk.
    if next.windows(2).any(|w| w[0].0 == w[1].0) {
        return;
    }
    let start = out.len();
    let first = next[0].0;
    let mut v = first;
    loop {
        out.push(v);
        match next.binary_search_by_key(&v, |e| e.0) {
            Ok(e) => v = next[e].1,
            Err(_) => break,
        }
        if v == first || out.len() - start > next.len() {
            break;
        }
    }
    // One loop through every boundary edge, or none.
    if v != first || out.len() - start != next.len() {
        out.truncate(start);
    }
}

fn find(parent: &mut [u32], mut i: u32) -> u32 {
    while parent[i as usize] != i {
        parent[i as usize] = parent[parent[i as usize] as usize];
        i = parent[i as usize];
    }
    i
}

fn union(parent: &mut [u32], a: u32, b: u32) {
    let (ra, rb) = (find(parent, a), find(parent, b));
    if ra != rb {
        parent[ra.max(rb) as usize] = ra.min(rb);
    }
}
