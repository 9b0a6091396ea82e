//! The rest shape's close pairs, as sorted lists per element (built by `exempt`, read by the
//! broad phase).

/// The shortest fold that holds two layers a contact distance apart, over that distance: pairs
/// nearer than this many contact distances at rest are near (`RestShape::near_vt`).
pub(super) const FOLD_ARC: f64 = std::f64::consts::FRAC_PI_2;

/// Sorted lists per element (CSR): `items[start[k]..start[k + 1]]`.
#[derive(Default)]
pub(super) struct Csr {
    start: Vec<u32>,
    items: Vec<u32>,
}

impl Csr {
    /// Appends the next element's row (sorted and deduplicated here; `row` is left empty).
    pub fn push(&mut self, row: &mut Vec<u32>) {
        if self.start.is_empty() {
            self.start.push(0);
        }
        row.sort_unstable();
        row.dedup();
        self.items.extend_from_slice(row);
        self.start.push(self.items.len() as u32);
        row.clear();
    }

    pub fn contains(&self, k: u32, item: u32) -> bool {
        match (self.start.get(k as usize), self.start.get(k as usize + 1)) {
            (Some(&s), Some(&e)) => self.items[s as usize..e as usize]
                .binary_search(&item)
                .is_ok(),
            _ => false,
        }
    }

    pub fn row(&self, k: usize) -> &[u32] {
        match (self.start.get(k), self.start.get(k + 1)) {
            (Some(&s), Some(&e)) => &self.items[s as usize..e as usize],
            _ => &[],
        }
    }

    /// Rows pushed so far.
    pub fn rows(&self) -> usize {
        self.start.len().saturating_sub(1)
    }

    pub fn len(&self) -> usize {
        self.items.len()
    }
}

/// The pairs that are closer than their contact distance in the rest shape (and near in the
/// mesh), built from the first state the collider sees: per vertex its triangles and vertices,
/// per edge its edges.
#[derive(Default)]
pub(super) struct RestShape {
    /// The positions the lists were built from.
    pub x: Vec<crate::Vec3>,
    /// The longest edge there (m).
    pub max_edge: f64,
    pub vt: Csr,
    pub vv: Csr,
    pub ee: Csr,
    /// The pairs proximity answers in the cloth's own plane (`proximity::vt_close`) that are not
    /// exempt: nearer than `FOLD_ARC` contact distances at rest, or (vertex-triangle) touching
    /// the vertex's 1-ring. The broad phase tests them even where a normal cone culls (`bvh`).
    pub near_vt: Csr,
    pub near_ee: Csr,
}

impl RestShape {
    /// Rest-close pairs: vertex-triangle plus edge-edge (each edge pair once).
    pub fn pairs(&self) -> usize {
        self.vt.len() + self.ee.len() / 2
    }

    /// The pair's separation in the rest shape (infinite where its vertices are not in it).
    pub(super) fn distance(&self, st: &super::stencil::Stencil) -> f64 {
        self.distance_squared(st).map_or(f64::INFINITY, f64::sqrt)
    }

    /// The square of `distance` (None where its vertices are not in the rest shape).
    pub(super) fn distance_squared(&self, st: &super::stencil::Stencil) -> Option<f64> {
        if st.idx[..st.len].iter().any(|&i| i as usize >= self.x.len()) {
            return None;
        }
        Some(st.eval(&self.x).length_squared())
    }
}
