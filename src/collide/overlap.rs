//! Cloth that starts inside an obstacle: reported when the scene is built (how many vertices,
//! inside which obstacle, how deep the deepest one is), and led out over the first steps along
//! one direction per connected patch (a solid's inside is known; meshes are two-sided surfaces
//! and have none).
//!
//! Why one direction per patch: each vertex pushed to its own nearest face splits a patch
//! across the obstacle. A cape whose hem hangs 5 cm into drape_bot's base box (the box 10 cm
//! high) would have its lowest row pushed under the box and the row above onto its top: the
//! box would stay between them for good, the edges between them stretched over it, and the
//! guard would subdivide nearly every step. A patch leaves the way it came in: along the mean
//! outward normal where its mesh edges cross the surface to the cloth outside.

use super::exit::{slip_around, Exit};
use super::features::FeatureCollider;
use super::obstacle::{Obstacle, ON_SURFACE};
use super::ring::one_ring;
use super::stage::CollisionStage;
use crate::Vec3;

/// How far the crossing normals of a patch must agree (their sum's length over their count) for
/// the patch to leave along their mean. Below it the patch entered from several sides (an arm
/// lying in the cloth: the normals on its two sides cancel) and leaves across the cloth.
const AGREE: f64 = 0.5;

/// The cloth's mesh as the plan walks it: neighbours, shortest edges, normals.
struct Mesh {
    first: Vec<u32>,
    adjacent: Vec<u32>,
    shortest: Vec<f64>,
    /// Area-weighted vertex normals (world).
    normal: Vec<Vec3>,
}

impl Mesh {
    fn of(fc: &FeatureCollider, x: &[Vec3], n: usize) -> Mesh {
        let edges = fc.edges();
        let (first, adjacent) = one_ring(edges, n);
        let mut shortest = vec![f64::INFINITY; n];
        for &[a, b] in edges.iter().filter(|e| (e[1] as usize) < n) {
            let len = (x[a as usize] - x[b as usize]).length();
            for v in [a as usize, b as usize] {
                shortest[v] = shortest[v].min(len);
            }
        }
        let mut normal = vec![Vec3::ZERO; n];
        for t in fc.triangles() {
            let [a, b, c] = t.map(|v| v as usize);
            if a.max(b).max(c) < n {
                let m = (x[b] - x[a]).cross(x[c] - x[a]);
                for v in [a, b, c] {
                    normal[v] += m;
                }
            }
        }
        Mesh {
            first,
            adjacent,
            shortest,
            normal,
        }
    }

    fn neighbours(&self, v: usize) -> impl Iterator<Item = usize> + '_ {
        let range = self.first[v] as usize..self.first[v + 1] as usize;
        self.adjacent[range].iter().map(|&w| w as usize)
    }

    /// The mean cloth normal over `patch` (up when it has none: a crumpled patch).
    fn patch_normal(&self, patch: &[usize]) -> Vec3 {
        (patch.iter().map(|&v| self.normal[v]).sum::<Vec3>()).normalize_or(Vec3::Z)
    }
}

/// How deep local point `p` is inside solid `o`, when deeper than [`ON_SURFACE`].
fn depth_inside(o: &Obstacle, p: Vec3) -> Option<f64> {
    if !o.contains_local(p) {
        return None;
    }
    let depth = -o.closest_local(p, p).signed_distance;
    (depth > ON_SURFACE).then_some(depth)
}

/// The share of a vertex's shortest mesh edge one pass may move it out: the strain one
/// correction hands the next solve (as fast contact lets an obstacle move a third of a spacing
/// per substep, and self-contact pushes a pair at most a third of an edge).
pub(crate) const EXIT_STEP: f64 = 1.0 / 6.0;

/// The cloth vertices inside one obstacle.
#[derive(Debug, Clone, PartialEq)]
pub struct Overlap {
    pub obstacle: String,
    pub vertices: usize,
    /// Distance of the deepest one below the obstacle's surface (m).
    pub deepest: f64,
}

impl std::fmt::Display for Overlap {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} cloth vertices start inside obstacle '{}' (the deepest {:.1} mm below its \
             surface)",
            self.vertices,
            self.obstacle,
            self.deepest * 1e3
        )
    }
}

impl CollisionStage {
    /// Plans how the cloth at `x` leaves the solid obstacles it starts inside (replacing any
    /// earlier plan). The vertices inside any obstacle are split into patches connected by mesh
    /// edges (one patch may lie in several touching obstacles: forearm, palm and fingers), and
    /// each patch leaves along one direction: the mean outward normal where its edges cross the
    /// surface to cloth outside (the way it came in), or, where those disagree or there are
    /// none, across the cloth to the side with the shorter total way out. Vertices then move
    /// out by at most [`EXIT_STEP`] of their shortest edge per collision pass, so the solve
    /// carries the cloth around them along. The patch's rim (vertices connected to it outside
    /// the solid but inside a solid's contact layer), and any patch vertex in another solid's
    /// layer, leaves that layer along the same direction, unless the direction leads into the
    /// solid there.
    ///
    /// A patch holding a kinematic vertex (`kinematic`: pinned or attached inside by the scene)
    /// gets no plan: it cannot leave as one, and its free vertices are projected to their
    /// nearest face each pass (a sheet pinned at a ball's centre).
    pub fn plan_exits(&mut self, x: &[Vec3], kinematic: &[u32]) {
        self.exits.clear();
        self.exit_neighbours.clear();
        let n = self.n_vertices.min(x.len());
        let obstacles = &self.obstacles;
        // Per vertex, the obstacles it is inside (rarely more than one).
        let inside_of = |p: Vec3| {
            (obstacles.iter().enumerate())
                .filter(move |(_, o)| depth_inside(o, o.pose.inverse_transform_point(p)).is_some())
                .map(|(k, _)| k)
        };
        let inside: Vec<Vec<usize>> = x[..n].iter().map(|&p| inside_of(p).collect()).collect();
        if inside.iter().all(Vec::is_empty) {
            return;
        }
        let mesh = Mesh::of(&self.feature_collider, x, n);
        let thickness = &self.thickness;
        // The solids whose contact layer vertex `v` lies in without being inside (`rim`).
        let layer_of = |v: usize| -> Vec<usize> {
            (obstacles.iter().enumerate())
                .filter(|(_, o)| {
                    let local = o.pose.inverse_transform_point(x[v]);
                    o.in_layer(local, thickness[v]).is_some()
                })
                .map(|(k, _)| k)
                .collect()
        };
        let mut rim: Vec<Vec<usize>> = vec![Vec::new(); n];
        let mut seen = vec![false; n];
        let mut patch = Vec::new();
        for seed in 0..n {
            if inside[seed].is_empty() || seen[seed] {
                continue;
            }
            // One patch, by a walk over the edges between vertices inside or in the contact
            // layer (the rim: left to the vertex pass, each would be pushed to its nearest face
            // at once, in the cloth's plane where the cloth cuts a solid).
            seen[seed] = true;
            patch.clear();
            patch.push(seed);
            let (mut crossing, mut crossings, mut k) = (Vec3::ZERO, 0, 0);
            while k < patch.len() {
                let v = patch[k];
                k += 1;
                for w in mesh.neighbours(v) {
                    if !inside[w].is_empty() {
                        if !seen[w] {
                            seen[w] = true;
                            patch.push(w);
                        }
                        continue;
                    }
                    for &oi in &inside[v] {
                        let o = &obstacles[oi];
                        let (lw, lv) = (
                            o.pose.inverse_transform_point(x[w]),
                            o.pose.inverse_transform_point(x[v]),
                        );
                        if let Some(hit) = o.cast_local(lw, lv) {
                            crossing += o.pose.transform_vector(hit.normal);
                            crossings += 1;
                        }
                    }
                    if !seen[w] && !kinematic.contains(&(w as u32)) {
                        rim[w] = layer_of(w);
                        if !rim[w].is_empty() {
                            seen[w] = true;
                            patch.push(w);
                        }
                    }
                }
            }
            if (patch.iter()).any(|&v| !inside[v].is_empty() && kinematic.contains(&(v as u32))) {
                continue;
            }
            let dir = if crossings > 0 && crossing.length() >= AGREE * crossings as f64 {
                crossing.normalize()
            } else {
                let way = |d: Vec3| -> f64 {
                    (patch.iter())
                        .flat_map(|&v| inside[v].iter().map(move |&oi| (v, oi)))
                        .map(|(v, oi)| {
                            let o = &obstacles[oi];
                            let local = o.pose.inverse_transform_point(x[v]);
                            let d = o.pose.rotation.inverse() * d;
                            o.exit_along(local, d).unwrap_or(f64::INFINITY)
                        })
                        .sum()
                };
                let core: Vec<usize> = (patch.iter().copied())
                    .filter(|&v| !inside[v].is_empty())
                    .collect();
                let m = mesh.patch_normal(&core);
                if way(-m) < way(m) {
                    -m
                } else {
                    m
                }
            };
            for &v in &patch {
                // Every vertex leaves the solids it is in and the contact layers `dir` leads out
                // of (one under a face `dir` leads into stays the vertex pass's). A vertex inside
                // the palm and in a finger's layer, left to the vertex pass for the finger, would
                // be pushed millimetres along the cloth in one pass, stretching its edges.
                let local_dir = |oi: usize| obstacles[oi].pose.rotation.inverse() * dir;
                if !inside[v].is_empty() {
                    rim[v] = layer_of(v);
                }
                let mut leaves = inside[v].clone();
                leaves.extend((rim[v].iter().copied()).filter(|&oi| {
                    let o = &obstacles[oi];
                    let local = o.pose.inverse_transform_point(x[v]);
                    o.layer_step(local, local_dir(oi), thickness[v]).is_some()
                }));
                if leaves.is_empty() {
                    continue;
                }
                // A vertex without edges (or only zero-length ones) moves a thickness a pass.
                let edge = Some(mesh.shortest[v]).filter(|e| e.is_finite() && *e > 0.0);
                let cap = edge.map_or(thickness[v], |e| EXIT_STEP * e);
                let first = self.exit_neighbours.len() as u32;
                self.exit_neighbours
                    .extend(mesh.neighbours(v).map(|w| w as u32));
                let count = self.exit_neighbours.len() as u32 - first;
                for oi in leaves {
                    self.exits.push(Exit {
                        vertex: v as u32,
                        obstacle: oi as u32,
                        dir: local_dir(oi),
                        cap,
                        edge_inside: false,
                        first,
                        count,
                    });
                }
            }
        }
        self.exits.sort_unstable_by_key(|e| (e.vertex, e.obstacle));
        slip_around(&self.exits, &self.exit_neighbours, &mut self.exit_slip);
    }

    /// Drops the exits of vertices that are out of the solid and of its contact layer along
    /// their way, with their mesh neighbours out and every mesh edge of theirs clear of the solid
    /// (`x` the positions a pass ended in), and of kinematic
    /// ones (`inv_mass` 0: pinned or held inside by the scene, not on their way out). A vertex
    /// out of the solid whose edge still cuts through it keeps going along its way out: retired
    /// alone, the forearm's axis pushed such an edge, 9 mm from the axis of a 40 mm cylinder,
    /// 3.9 cm in one pass.
    pub(super) fn retire_exits(&mut self, x: &[Vec3], inv_mass: &[f64]) {
        if self.exits.is_empty() {
            return;
        }
        let (obstacles, neighbours) = (&self.obstacles, &self.exit_neighbours);
        let thickness = &self.thickness;
        self.exits.retain_mut(|e| {
            let o = &obstacles[e.obstacle as usize];
            let i = e.vertex as usize;
            let (Some(&w), Some(&p)) = (inv_mass.get(i), x.get(i)) else {
                return false;
            };
            if w <= 0.0 {
                return false;
            }
            let local = o.pose.inverse_transform_point(p);
            if o.contains_local(local) || o.layer_step(local, e.dir, thickness[i]).is_some() {
                return true;
            }
            // Out: it waits for its neighbours, and goes on out while an edge of its cuts the
            // solid. Let go while the one next to it is still inside, a vertex of the arm's
            // patch (friction 0.5) can end on the far side of the forearm from it, their edge
            // (skipped by the features meanwhile) through the axis and stretched across it.
            let (mut waits, mut cuts) = (false, false);
            for &k in &neighbours[e.first as usize..(e.first + e.count) as usize] {
                let Some(q) = x.get(k as usize) else { continue };
                let other = o.pose.inverse_transform_point(*q);
                if o.contains_local(other) {
                    waits = true;
                } else if o.cast_local(local, other).is_some()
                    || o.cast_local(other, local).is_some()
                {
                    cuts = true;
                }
            }
            e.edge_inside = cuts;
            waits || cuts
        });
        slip_around(&self.exits, &self.exit_neighbours, &mut self.exit_slip);
    }

    /// The obstacles that vertices `x` are inside (at the obstacles' current poses), with their
    /// counts; empty when the cloth starts clear.
    pub fn overlaps(&self, x: &[Vec3]) -> Vec<Overlap> {
        let mut out = Vec::new();
        for o in &self.obstacles {
            let (mut vertices, mut deepest) = (0, 0.0f64);
            for p in x {
                let local = o.pose.inverse_transform_point(*p);
                if let Some(depth) = depth_inside(o, local) {
                    vertices += 1;
                    deepest = deepest.max(depth);
                }
            }
            if vertices > 0 {
                out.push(Overlap {
                    obstacle: o.name.clone(),
                    vertices,
                    deepest,
                });
            }
        }
        out
    }
}
