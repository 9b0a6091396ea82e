//! What the solver tells the collision stage about the substep it just solved: an explicit
//! input of [`super::CollisionStage::resolve`], rebuilt by the caller every substep.
//!
//! The implicit solver's constraint filter holds contact vertices on their surfaces and takes
//! the normal impulse out of the stage's sight (a held vertex arrives with no approaching
//! velocity), it may apply the Coulomb friction of those surfaces itself, and it may hold static
//! obstacles' edges as springs. The stage needs all three to answer the same contacts without
//! losing friction or applying it twice. An empty feedback (the default) means the solver held
//! nothing: every contact is the stage's alone.

use crate::Vec3;

/// Up to three (normal, normal velocity change) a vertex was held with (zero: unused).
pub(crate) type Held = [(Vec3, f64); 3];

/// The solver's feedback for one `resolve` (see the module doc). Buffers keep their capacity
/// across substeps: [`SolverFeedback::clear`] and refill.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SolverFeedback {
    /// Vertex count the per-vertex entries are for.
    n_vertices: usize,
    /// Per vertex (empty when no vertex is held), the normals and normal velocity changes
    /// (m/s) the filter applied, one per held surface.
    held: Vec<Held>,
    /// Per vertex (empty when none), the normals of held surfaces whose friction the solver
    /// applied (zero: unused).
    friction_solved: Vec<[Vec3; 3]>,
    /// The cloth faces and edges (`verts` of [`super::FeatureContact`]) the solver held with an
    /// edge spring, sorted and deduplicated.
    sprung: Vec<[u32; 3]>,
    /// Per vertex (empty when none), the two obstacles whose squeeze of it the solver took
    /// with pinch springs (`None`: not pinched).
    squeezed: Vec<Option<[usize; 2]>>,
}

impl SolverFeedback {
    /// Empties the feedback for a cloth of `n_vertices` vertices.
    pub fn clear(&mut self, n_vertices: usize) {
        self.n_vertices = n_vertices;
        self.held.clear();
        self.friction_solved.clear();
        self.sprung.clear();
        self.squeezed.clear();
    }

    /// Records that the solver took the squeeze of `vertex` between `obstacles` with pinch
    /// springs of the cloth's compliance: `resolve` keeps it out of their solids, not out of
    /// their contact layers, and leaves its velocity to the solve.
    pub fn squeeze(&mut self, vertex: usize, obstacles: [usize; 2]) {
        if vertex >= self.n_vertices {
            return;
        }
        if self.squeezed.len() != self.n_vertices {
            self.squeezed.clear();
            self.squeezed.resize(self.n_vertices, None);
        }
        self.squeezed[vertex] = Some(obstacles);
    }

    /// Whether the solver took `vertex`'s squeeze by `obstacle` (see [`Self::squeeze`]).
    pub(crate) fn squeezed_by(&self, vertex: usize, obstacle: usize) -> bool {
        (self.squeezed.get(vertex)).is_some_and(|p| p.is_some_and(|p| p.contains(&obstacle)))
    }

    /// The two obstacles whose squeeze of `vertex` the solver took, if any.
    pub(crate) fn squeeze_of(&self, vertex: usize) -> Option<[usize; 2]> {
        self.squeezed.get(vertex).copied().flatten()
    }

    /// Records that the solver held `vertex` against a surface of normal `normal`, removing the
    /// normal velocity `dvn` (m/s, > 0) the other forces would have given it (the filter's
    /// normal impulse per unit mass). Coulomb friction in `resolve` adds `dvn` to the normal
    /// velocity change it sees; without it a held vertex slides frictionless. A vertex held by
    /// several surfaces (a wedge) gets one call per surface; a fourth one is ignored, and so
    /// are non-finite or non-positive values and vertices out of range.
    pub fn hold(&mut self, vertex: usize, normal: Vec3, dvn: f64) {
        if vertex >= self.n_vertices || !(dvn.is_finite() && dvn > 0.0) || !normal.is_finite() {
            return;
        }
        if self.held.len() != self.n_vertices {
            self.held.clear();
            self.held.resize(self.n_vertices, [(Vec3::ZERO, 0.0); 3]);
        }
        if let Some(slot) = self.held[vertex].iter_mut().find(|s| s.1 == 0.0) {
            *slot = (normal, dvn);
        }
    }

    /// Records that the solver applied the Coulomb friction of the surface with `normal` to
    /// `vertex` (held against it, see [`SolverFeedback::hold`]): `resolve` leaves the tangential
    /// velocity of that contact alone instead of applying friction a second time.
    pub fn friction_solved(&mut self, vertex: usize, normal: Vec3) {
        if vertex >= self.n_vertices || !normal.is_finite() {
            return;
        }
        if self.friction_solved.len() != self.n_vertices {
            self.friction_solved.clear();
            self.friction_solved
                .resize(self.n_vertices, [Vec3::ZERO; 3]);
        }
        if let Some(slot) = self.friction_solved[vertex]
            .iter_mut()
            .find(|s| **s == Vec3::ZERO)
        {
            *slot = normal;
        }
    }

    /// Records which feature contacts (their cloth faces and edges, `verts` of
    /// [`super::FeatureContact`]) the solver held with edge springs: `resolve` leaves those to
    /// the solver unless they end deep (see [`super::FEATURE_DEEP`]).
    pub fn set_sprung(&mut self, contacts: impl IntoIterator<Item = [u32; 3]>) {
        self.sprung.clear();
        self.sprung.extend(contacts);
        self.sprung.sort_unstable();
        self.sprung.dedup();
    }

    /// The surfaces `vertex` was held against (all zero when none).
    pub(crate) fn held(&self, vertex: usize) -> Held {
        self.held
            .get(vertex)
            .copied()
            .unwrap_or([(Vec3::ZERO, 0.0); 3])
    }

    /// Per vertex, the normals whose friction the solver applied (empty: none).
    pub(crate) fn friction_solved_all(&self) -> &[[Vec3; 3]] {
        &self.friction_solved
    }

    /// The feature contacts held as springs (sorted).
    pub(crate) fn sprung(&self) -> &[[u32; 3]] {
        &self.sprung
    }
}
