//! Cloth as the solver sees it: one flat particle system holding every piece of a scene,
//! with rest material coordinates, lumped masses, triangles and kinematic vertices.
//!
//! Pieces are kept as index ranges so that effects are built per piece (each with its own
//! material) while integrators and collisions run over one set of arrays.

mod material;
mod panel;
pub mod topology;

pub use material::{Damping, Material, Tensile, DEFAULT_KNEE_STIFFENING, STANDARD_GRAVITY};
pub use panel::{GridRegion, Lattice, Panel};

use crate::{Pose, Vec3};
use glam::DVec2;

/// Why a vertex does not move freely.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Kinematic {
    /// Fixed at a world position.
    Pinned(Vec3),
    /// Rigidly attached to a moving frame (a robot link, a gripper, a scripted handle):
    /// its world position is `frames[frame] * local`.
    Attached { frame: usize, local: Vec3 },
}

/// One named piece of cloth inside the particle system.
#[derive(Debug, Clone)]
pub struct Piece {
    pub name: String,
    /// First vertex of the piece in the flat arrays.
    pub first_vertex: usize,
    pub vertex_count: usize,
    /// First triangle of the piece.
    pub first_triangle: usize,
    pub triangle_count: usize,
    pub material: Material,
    /// The panel the piece was built from, with vertex indices local to the piece.
    pub panel: Panel,
}

impl Piece {
    pub fn vertices(&self) -> std::ops::Range<usize> {
        self.first_vertex..self.first_vertex + self.vertex_count
    }

    /// Global vertex index of a piece-local index.
    pub fn global(&self, local: u32) -> u32 {
        (self.first_vertex + local as usize) as u32
    }
}

/// All cloth of a scene in flat arrays (structure of arrays).
#[derive(Debug, Clone, Default)]
pub struct Cloth {
    pub x: Vec<Vec3>,
    pub v: Vec<Vec3>,
    /// Lumped mass per vertex (kg), from the areal density over the rest triangle areas.
    pub mass: Vec<f64>,
    /// Rest material coordinates (m).
    pub uv: Vec<DVec2>,
    /// Triangles over global vertex indices.
    pub triangles: Vec<[u32; 3]>,
    /// Per-vertex collision thickness and friction (copied from each piece's material).
    pub thickness: Vec<f64>,
    pub friction: Vec<f64>,
    /// Kinematic vertices; every other vertex is free.
    pub kinematic: Vec<(u32, Kinematic)>,
    pub pieces: Vec<Piece>,
}

impl Cloth {
    pub fn new() -> Self {
        Self::default()
    }

    pub fn len(&self) -> usize {
        self.x.len()
    }

    pub fn is_empty(&self) -> bool {
        self.x.is_empty()
    }

    /// Adds a panel as a new piece with the given material; returns the piece index.
    pub fn add_panel(&mut self, panel: Panel, material: Material) -> usize {
        let first_vertex = self.x.len();
        let first_triangle = self.triangles.len();
        let areas = panel.rest_areas();
        let mut mass = vec![0.0; panel.len()];
        for (t, area) in panel.triangles.iter().zip(&areas) {
            for &i in t {
                mass[i as usize] += material.density * area / 3.0;
            }
        }
        // A vertex that belongs to no triangle (or only to zero-area ones) still needs a mass so that
        // it moves under gravity instead of dividing by zero: give it the mean mass.
        let mean = mass.iter().sum::<f64>() / mass.len().max(1) as f64;
        let fallback = if mean > 0.0 { mean } else { 1e-6 };
        for m in &mut mass {
            if *m <= 0.0 {
                *m = fallback;
            }
        }
        self.x.extend_from_slice(&panel.positions);
        self.v.extend(std::iter::repeat_n(Vec3::ZERO, panel.len()));
        self.mass.extend_from_slice(&mass);
        self.uv.extend_from_slice(&panel.uv);
        self.thickness
            .extend(std::iter::repeat_n(material.thickness, panel.len()));
        self.friction
            .extend(std::iter::repeat_n(material.friction, panel.len()));
        let off = first_vertex as u32;
        self.triangles
            .extend(panel.triangles.iter().map(|t| t.map(|i| i + off)));
        self.pieces.push(Piece {
            name: panel.name.clone(),
            first_vertex,
            vertex_count: panel.len(),
            first_triangle,
            triangle_count: panel.triangles.len(),
            material,
            panel,
        });
        self.pieces.len() - 1
    }

    /// Pins a vertex where it is now.
    pub fn pin(&mut self, vertex: u32) {
        let p = self.x[vertex as usize];
        self.set_kinematic(vertex, Kinematic::Pinned(p));
    }

    /// Attaches a vertex to a frame, keeping its current offset from the frame's `pose`.
    pub fn attach(&mut self, vertex: u32, frame: usize, pose: &Pose) {
        let local = pose.inverse_transform_point(self.x[vertex as usize]);
        self.set_kinematic(vertex, Kinematic::Attached { frame, local });
    }

    fn set_kinematic(&mut self, vertex: u32, k: Kinematic) {
        match self.kinematic.iter_mut().find(|(i, _)| *i == vertex) {
            Some(slot) => slot.1 = k,
            None => self.kinematic.push((vertex, k)),
        }
    }

    /// Releases a kinematic vertex (it keeps its current velocity).
    pub fn release(&mut self, vertex: u32) {
        self.kinematic.retain(|(i, _)| *i != vertex);
    }

    /// How a vertex is held, if it is.
    pub fn kinematic_of(&self, vertex: u32) -> Option<Kinematic> {
        self.kinematic
            .iter()
            .find(|(i, _)| *i == vertex)
            .map(|(_, k)| *k)
    }

    pub fn is_kinematic(&self, vertex: u32) -> bool {
        self.kinematic_of(vertex).is_some()
    }

    /// Inverse masses with kinematic vertices at zero (infinite mass).
    pub fn inverse_masses(&self) -> Vec<f64> {
        let mut inv = Vec::new();
        self.inverse_masses_into(&mut inv);
        inv
    }

    /// [`Cloth::inverse_masses`] into `w` (a step's reused buffer).
    pub fn inverse_masses_into(&self, w: &mut Vec<f64>) {
        w.clear();
        w.extend(self.mass.iter().map(|m| 1.0 / m));
        for (i, _) in &self.kinematic {
            w[*i as usize] = 0.0;
        }
    }

    /// Largest relative stretch `|x_i - x_j| / |uv_i - uv_j| - 1` over the triangle edges (0 at
    /// rest length; edges of zero rest length are skipped), as recordings and the hard cases
    /// report it.
    pub fn max_edge_stretch(&self) -> f64 {
        let mut worst = f64::NEG_INFINITY;
        for t in &self.triangles {
            for k in 0..3 {
                let (i, j) = (t[k] as usize, t[(k + 1) % 3] as usize);
                let (Some(xi), Some(xj), Some(ui), Some(uj)) =
                    (self.x.get(i), self.x.get(j), self.uv.get(i), self.uv.get(j))
                else {
                    continue;
                };
                let rest = ui.distance(*uj);
                if rest > 0.0 {
                    worst = worst.max(xi.distance(*xj) / rest - 1.0);
                }
            }
        }
        if worst.is_finite() {
            worst
        } else {
            0.0
        }
    }

    /// Area-weighted vertex normals (unit; zero for isolated vertices).
    pub fn vertex_normals(&self) -> Vec<Vec3> {
        let mut n = vec![Vec3::ZERO; self.len()];
        for t in &self.triangles {
            let [a, b, c] = t.map(|i| self.x[i as usize]);
            let face = (b - a).cross(c - a);
            for &i in t {
                n[i as usize] += face;
            }
        }
        for v in &mut n {
            *v = v.normalize_or_zero();
        }
        n
    }

    /// The piece a vertex belongs to.
    pub fn piece_of(&self, vertex: usize) -> Option<&Piece> {
        self.pieces.iter().find(|p| p.vertices().contains(&vertex))
    }
}
