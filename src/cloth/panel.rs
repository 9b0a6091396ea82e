//! One piece of cloth before it joins a simulation: rest (u, v) coordinates, placed positions,
//! triangles, and (for lattice meshes) the (i, j) lattice the bending stencils follow.

use crate::{Pose, Vec3};
use glam::DVec2;

/// A regular lattice of material coordinates: vertex (i, j) sits at `u = i * du`, `v = j * dv`;
/// `i` runs along the warp (u), `j` along the weft (v). `index[j * nu + i]` is the vertex there, if any
/// (a pattern cut from a lattice leaves holes).
#[derive(Debug, Clone)]
pub struct Lattice {
    pub nu: usize,
    pub nv: usize,
    pub du: f64,
    pub dv: f64,
    pub index: Vec<Option<u32>>,
}

impl Lattice {
    /// Vertex at lattice site (i, j); `None` outside the lattice or in a hole.
    pub fn at(&self, i: isize, j: isize) -> Option<u32> {
        if i < 0 || j < 0 || i as usize >= self.nu || j as usize >= self.nv {
            return None;
        }
        self.index[j as usize * self.nu + i as usize]
    }
}

/// A cloth piece in its rest state and its initial placement.
#[derive(Debug, Clone)]
pub struct Panel {
    pub name: String,
    /// Rest material coordinates in metres (u along warp, v along weft).
    pub uv: Vec<DVec2>,
    /// Initial world positions.
    pub positions: Vec<Vec3>,
    pub triangles: Vec<[u32; 3]>,
    pub lattice: Option<Lattice>,
}

/// Named vertex sets of a rectangular grid, used to pin or attach cloth in scene files.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum GridRegion {
    /// (u = 0, v = max)
    TopLeft,
    /// (u = max, v = max)
    TopRight,
    /// (u = 0, v = 0)
    BottomLeft,
    /// (u = max, v = 0)
    BottomRight,
    /// v = max
    TopEdge,
    /// v = 0
    BottomEdge,
    /// u = 0
    LeftEdge,
    /// u = max
    RightEdge,
}

impl Panel {
    /// A rectangular grid of `res[0] x res[1]` vertices spanning `size[0]` metres along u and
    /// `size[1]` along v, centred on the origin of `pose`'s frame in its local x-y plane
    /// (u along local x, v along local y, normal along local z).
    pub fn grid(name: &str, size: [f64; 2], res: [usize; 2], pose: &Pose) -> Panel {
        let (nu, nv) = (res[0].max(2), res[1].max(2));
        let du = size[0] / (nu - 1) as f64;
        let dv = size[1] / (nv - 1) as f64;
        let mut uv = Vec::with_capacity(nu * nv);
        let mut positions = Vec::with_capacity(nu * nv);
        for j in 0..nv {
            for i in 0..nu {
                let p = DVec2::new(i as f64 * du, j as f64 * dv);
                uv.push(p);
                let local = Vec3::new(p.x - 0.5 * size[0], p.y - 0.5 * size[1], 0.0);
                positions.push(pose.transform_point(local));
            }
        }
        let mut triangles = Vec::with_capacity(2 * (nu - 1) * (nv - 1));
        let id = |i: usize, j: usize| (j * nu + i) as u32;
        for j in 0..nv - 1 {
            for i in 0..nu - 1 {
                // Alternate the diagonal so the mesh has no preferred shear direction.
                if (i + j) % 2 == 0 {
                    triangles.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                    triangles.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
                } else {
                    triangles.push([id(i, j), id(i + 1, j), id(i, j + 1)]);
                    triangles.push([id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
                }
            }
        }
        let index = (0..(nu * nv) as u32).map(Some).collect();
        Panel {
            name: name.to_string(),
            uv,
            positions,
            triangles,
            lattice: Some(Lattice {
                nu,
                nv,
                du,
                dv,
                index,
            }),
        }
    }

    /// A panel from an arbitrary triangle mesh (the garment mesher's output).
    /// Bending stencils are then found from the rest (u, v) neighbourhood; twist needs a lattice.
    pub fn from_triangles(
        name: &str,
        uv: Vec<DVec2>,
        positions: Vec<Vec3>,
        triangles: Vec<[u32; 3]>,
    ) -> Result<Panel, String> {
        if uv.len() != positions.len() {
            return Err(format!(
                "panel {name}: {} rest coordinates for {} positions",
                uv.len(),
                positions.len()
            ));
        }
        for (k, t) in triangles.iter().enumerate() {
            if t.iter().any(|&i| i as usize >= positions.len()) {
                return Err(format!(
                    "panel {name}: triangle {k} indexes a missing vertex"
                ));
            }
        }
        Ok(Panel {
            name: name.to_string(),
            uv,
            positions,
            triangles,
            lattice: None,
        })
    }

    pub fn len(&self) -> usize {
        self.positions.len()
    }

    pub fn is_empty(&self) -> bool {
        self.positions.is_empty()
    }

    /// Vertices of a named grid region (empty for non-lattice panels).
    pub fn region(&self, region: GridRegion) -> Vec<u32> {
        let Some(l) = &self.lattice else {
            return Vec::new();
        };
        let (mu, mv) = (l.nu as isize - 1, l.nv as isize - 1);
        let sites: Vec<(isize, isize)> = match region {
            GridRegion::TopLeft => vec![(0, mv)],
            GridRegion::TopRight => vec![(mu, mv)],
            GridRegion::BottomLeft => vec![(0, 0)],
            GridRegion::BottomRight => vec![(mu, 0)],
            GridRegion::TopEdge => (0..=mu).map(|i| (i, mv)).collect(),
            GridRegion::BottomEdge => (0..=mu).map(|i| (i, 0)).collect(),
            GridRegion::LeftEdge => (0..=mv).map(|j| (0, j)).collect(),
            GridRegion::RightEdge => (0..=mv).map(|j| (mu, j)).collect(),
        };
        sites.into_iter().filter_map(|(i, j)| l.at(i, j)).collect()
    }

    /// Rest area of every triangle (in the flat pattern).
    pub fn rest_areas(&self) -> Vec<f64> {
        self.triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| self.uv[i as usize]);
                0.5 * (b - a).perp_dot(c - a).abs()
            })
            .collect()
    }
}
