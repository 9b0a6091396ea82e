//! The feature set of one obstacle in its local frame: corner points and segments (rod axes,
//! box and sharp mesh edges) inflated by a common radius, with the box features' normal cones.

use crate::collide::obstacle::{Geom, Obstacle};
use crate::Vec3;

/// Meshes with more unique edges than this get no edge features (the cost would be
/// features x candidate cloth edges per step); their vertices still collide with the cloth.
pub(crate) const MAX_MESH_EDGES: usize = 4096;

/// Feature set of one obstacle, in its local frame.
#[derive(Debug, Clone, Default)]
pub(crate) struct Features {
    pub(super) points: Vec<Vec3>,
    pub(super) segments: Vec<[Vec3; 2]>,
    pub(super) radius: f64,
    /// Box features only (else empty): per point, then per segment, the signs of the faces the
    /// feature lies on (`+-1` per such axis, 0 otherwise). Its outward normal cone is the set
    /// of `n` with `n_k cone_k >= 0` on those axes: see [`in_cone`].
    pub(super) cones: Vec<Vec3>,
}

/// Whether local normal `n` lies in the outward normal cone `cone` of a box feature (corner or
/// edge), i.e. whether the feature is the box's closest point to a point off it along `n`.
/// A cloth face or edge that wraps around a box edge, its chord passing inside the edge,
/// gives the CCD a normal pointing into the box; answering it pushes the cloth into the faces'
/// vertex contacts, which push back next step: the jitter of cloth resting on box edges. Such
/// a pair is not this feature's contact (the faces own it), so it is skipped. The tolerance
/// admits normals along a face normal up to rounding.
pub(super) fn in_cone(cone: Vec3, n: Vec3) -> bool {
    const TOL: f64 = 1e-9;
    (0..3).all(|k| cone[k] == 0.0 || n[k] * cone[k] >= -TOL)
}

impl Features {
    /// Spheres and planes have none (a sphere's curvature radius exceeds the cloth spacing
    /// for any sphere the vertex test cannot already hold).
    pub fn of(o: &Obstacle) -> Features {
        let axis = |hh: f64, radius: f64| {
            let (a, b) = (Vec3::new(0.0, -hh, 0.0), Vec3::new(0.0, hh, 0.0));
            Features {
                points: vec![a, b],
                segments: vec![[a, b]],
                radius,
                cones: Vec::new(),
            }
        };
        match o.geom {
            Geom::Ball { .. } | Geom::HalfSpace { .. } => Features::default(),
            Geom::Capsule {
                radius,
                half_height,
            } => axis(half_height, radius),
            Geom::Cuboid { half } => {
                let corner = |k: usize| {
                    Vec3::new(
                        if k & 1 == 0 { -half.x } else { half.x },
                        if k & 2 == 0 { -half.y } else { half.y },
                        if k & 4 == 0 { -half.z } else { half.z },
                    )
                };
                let points: Vec<Vec3> = (0..8).map(corner).collect();
                let mut segments = Vec::with_capacity(12);
                for k in 0..8 {
                    for bit in [1, 2, 4] {
                        if k & bit == 0 {
                            segments.push([points[k], points[k | bit]]);
                        }
                    }
                }
                let sign = |p: Vec3| Vec3::new(p.x.signum(), p.y.signum(), p.z.signum());
                let cones = points
                    .iter()
                    .map(|&p| sign(p))
                    .chain(segments.iter().map(|[a, b]| {
                        // The segment's own axis is where its ends differ: no face there.
                        let (sa, sb) = (sign(*a), sign(*b));
                        Vec3::select(sa.cmpeq(sb), sa, Vec3::ZERO)
                    }))
                    .collect();
                Features {
                    points,
                    segments,
                    radius: 0.0,
                    cones,
                }
            }
            Geom::Solid => match o.shape.as_cylinder() {
                Some(c) => cylinder(f64::from(c.half_height), f64::from(c.radius)),
                None => Features::default(),
            },
            Geom::Surface => match o.shape.as_trimesh() {
                Some(m) => {
                    let vertices: Vec<Vec3> = m.vertices().iter().map(|v| v.as_dvec3()).collect();
                    let (points, mut segments) = sharp_features(&vertices, m.indices());
                    if segments.len() > MAX_MESH_EDGES {
                        log::warn!(
                            "obstacle '{}': {} sharp mesh edges exceed {MAX_MESH_EDGES}; only its \
                             vertices are tested against cloth faces",
                            o.name,
                            segments.len()
                        );
                        segments.clear();
                    }
                    Features {
                        points,
                        segments,
                        radius: 0.0,
                        cones: Vec::new(),
                    }
                }
                None => Features::default(),
            },
        }
    }

    pub fn is_empty(&self) -> bool {
        self.points.is_empty() && self.segments.is_empty()
    }

    /// Inflation radius of the features (the rod radius; 0 for edges).
    pub fn radius(&self) -> f64 {
        self.radius
    }
}

/// Angle (rad) below which a mesh edge's fold, or a mesh vertex's angle defect, counts as
/// smooth. A fold of exterior angle `a` under a cloth face of size `L` rises at most
/// `(L / 2) tan(a / 2)` above the chord the vertex test already holds off: below half the
/// thickness for 20 degrees as long as the cloth spacing stays under ~5.7 thicknesses (the
/// bundled robot scenes, whose head is a mesh: 1.3 to 3.3). Smooth parts are left to the vertex
/// test, as spheres are; a coarser cloth over a finely curved mesh can let a fold graze a face.
pub(crate) const SHARP_ANGLE: f64 = 20.0 * std::f64::consts::PI / 180.0;

/// The sharp features of a triangle mesh: edges whose adjacent faces fold by more than
/// [`SHARP_ANGLE`] (and boundary or non-manifold edges), and the vertices that end such an edge
/// or whose angle defect (2 pi minus the face angles around it; a cone tip) exceeds it.
/// A finely tessellated smooth part (a ball, a rounded link) has none; a cube keeps its 12 edges
/// and 8 corners but not its face diagonals.
fn sharp_features(v: &[Vec3], tris: &[[u32; 3]]) -> (Vec<Vec3>, Vec<[Vec3; 2]>) {
    // (min, max, face, same direction as min->max) per directed edge of every face.
    let mut half: Vec<(u32, u32, u32, bool)> = Vec::with_capacity(3 * tris.len());
    let mut defect = vec![2.0 * std::f64::consts::PI; v.len()];
    let normal = |t: &[u32; 3]| {
        let [a, b, c] = t.map(|i| v[i as usize]);
        (b - a).cross(c - a).normalize_or_zero()
    };
    for (f, t) in tris.iter().enumerate() {
        for k in 0..3 {
            let (a, b, c) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
            half.push((a.min(b), a.max(b), f as u32, a < b));
            let (e1, e2) = (v[b as usize] - v[a as usize], v[c as usize] - v[a as usize]);
            defect[a as usize] -= e1.angle_between(e2);
        }
    }
    half.sort_unstable();
    let mut sharp_vertex: Vec<bool> = defect
        .iter()
        .map(|d| d.abs() > SHARP_ANGLE || !d.is_finite())
        .collect();
    let mut edges: Vec<[u32; 2]> = Vec::new();
    for group in half.chunk_by(|x, y| (x.0, x.1) == (y.0, y.1)) {
        let sharp = match group {
            [p, q] => {
                let (n1, n2) = (normal(&tris[p.2 as usize]), normal(&tris[q.2 as usize]));
                // Consistent winding walks a shared edge in opposite directions.
                let n2 = if p.3 == q.3 { -n2 } else { n2 };
                n1 == Vec3::ZERO || n2 == Vec3::ZERO || n1.angle_between(n2) > SHARP_ANGLE
            }
            _ => true,
        };
        if sharp {
            let (a, b) = (group[0].0, group[0].1);
            edges.push([a, b]);
            sharp_vertex[a as usize] = true;
            sharp_vertex[b as usize] = true;
        }
    }
    let points = v
        .iter()
        .zip(&sharp_vertex)
        .filter(|(_, s)| **s)
        .map(|(p, _)| *p)
        .collect();
    let segments = edges
        .iter()
        .map(|e| [v[e[0] as usize], v[e[1] as usize]])
        .collect();
    (points, segments)
}

/// Cylinder (axis y) features, inside the shape so cloth resting on it at its thickness is
/// never pushed: the axis shortened by the radius at each end, inflated by the radius. Only for
/// cylinders longer than wide (rods); a wide, flat cylinder (a table top) is left to the vertex
/// test, whose curvature-radius argument holds for its faces (its sharp rims are a known gap).
fn cylinder(hh: f64, r: f64) -> Features {
    if hh <= r {
        return Features::default();
    }
    let (a, b) = (Vec3::new(0.0, r - hh, 0.0), Vec3::new(0.0, hh - r, 0.0));
    Features {
        points: vec![a, b],
        segments: vec![[a, b]],
        radius: r,
        cones: Vec::new(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cube() -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let v: Vec<Vec3> = (0..8)
            .map(|k| Vec3::new((k & 1) as f64, ((k >> 1) & 1) as f64, ((k >> 2) & 1) as f64))
            .collect();
        // Two triangles per face, outward winding.
        let quads = [
            [0, 2, 3, 1],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 4, 6, 2],
            [1, 3, 7, 5],
        ];
        let t = quads
            .iter()
            .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
            .collect();
        (v, t)
    }

    #[test]
    fn cube_keeps_edges_and_corners_but_not_face_diagonals() {
        let (v, mut t) = cube();
        let (points, segments) = sharp_features(&v, &t);
        assert_eq!((points.len(), segments.len()), (8, 12));
        // Flip one triangle's winding: the fold test must not mistake its diagonal for sharp.
        t[0].swap(1, 2);
        let (_, segments) = sharp_features(&v, &t);
        assert_eq!(segments.len(), 12);
        // Every kept segment is an axis-aligned unit edge.
        assert!(segments
            .iter()
            .all(|[a, b]| ((*b - *a).abs().max_element() - 1.0).abs() < 1e-12
                && ((*b - *a).length() - 1.0).abs() < 1e-12));
    }

    #[test]
    fn fine_sphere_has_no_sharp_features_coarse_one_does() {
        let sphere = |stacks: usize, slices: usize| {
            let mut v = vec![Vec3::Z];
            for i in 1..stacks {
                let th = std::f64::consts::PI * i as f64 / stacks as f64;
                for j in 0..slices {
                    let ph = std::f64::consts::TAU * j as f64 / slices as f64;
                    v.push(Vec3::new(
                        th.sin() * ph.cos(),
                        th.sin() * ph.sin(),
                        th.cos(),
                    ));
                }
            }
            v.push(-Vec3::Z);
            let bottom = (v.len() - 1) as u32;
            let ring = |i: usize, j: usize| (1 + (i - 1) * slices + j % slices) as u32;
            let mut t = Vec::new();
            for j in 0..slices {
                t.push([0, ring(1, j), ring(1, j + 1)]);
                t.push([bottom, ring(stacks - 1, j + 1), ring(stacks - 1, j)]);
            }
            for i in 1..stacks - 1 {
                for j in 0..slices {
                    t.push([ring(i, j), ring(i + 1, j), ring(i + 1, j + 1)]);
                    t.push([ring(i, j), ring(i + 1, j + 1), ring(i, j + 1)]);
                }
            }
            (v, t)
        };
        let (v, t) = sphere(24, 48);
        let (points, segments) = sharp_features(&v, &t);
        assert_eq!((points.len(), segments.len()), (0, 0));
        // An octahedron-like 2 x 4 sphere folds by 90 degrees everywhere.
        let (v, t) = sphere(2, 4);
        let (points, segments) = sharp_features(&v, &t);
        assert_eq!((points.len(), segments.len()), (6, 12));
    }
}
