//! The guard's strain check: edges the collision pass stretched beyond the largest stretch the
//! material and the speeds in the scene can make.
//!
//! The bound. A chain of springs of stiffness `k` and spacing `l` between vertices of mass `m`
//! carries waves at `c = l sqrt(k / m)`; for a grid of areal density `rho` and structural
//! stiffness `k` (N/m, per spring) that is `sqrt(k / rho)`, whatever the spacing. A vertex set
//! moving at `v` (an impact) sends a front behind which the strain is `v / c`; a front reflected
//! at a held end (a pin, an attachment, cloth stuck on an obstacle) doubles it. The fastest
//! impact a substep can see is between the fastest cloth vertex and the fastest obstacle point
//! (their relative speed is at most the sum of their speeds), so the dynamic part of the bound
//! is `2 v / c` with `v` that sum and `c` the slowest piece's wave speed. The static part is what
//! the scene's own loads explain: the whole cloth's weight hung on one spring of the softest
//! piece stretches it by `M |g| / k`. Edges are measured against the longer of their rest length
//! and their length when the check was set up, so a scene that starts stretched (a garment
//! after welding) is judged from its start. Bending and damping only resist stretch; shear,
//! skip-one and wind are not covered by this bound, so scenes whose structural springs are
//! absent, or with forces from outside the material (sewing springs), are not checked.

use crate::cloth::Cloth;
use crate::effects::EffectSet;
use crate::Vec3;

/// Effects whose forces the bound accounts for (all others switch the check off).
const COVERED: [&str; 7] = [
    "gravity", "stretch", "shear", "skip_one", "bending", "twist", "damping",
];

/// The strain check of one cloth (rebuilt when the cloth changes).
#[derive(Debug, Clone)]
pub(super) struct StrainModel {
    /// `(i, j, reference length)` of every mesh edge.
    edges: Vec<(u32, u32, f64)>,
    /// Per vertex: its shortest reference edge (the local spacing).
    spacing: Vec<f64>,
    /// Slowest wave speed `sqrt(stretch / density)` over the pieces (m/s); `None` where the
    /// bound does not apply.
    wave_speed: Option<f64>,
    max_spacing: f64,
    /// The cloth's weight on one spring of the softest piece, `M |g| / k_min`, plus the largest
    /// push out of the thickness layer over the shortest edge, `th_max / l_min`.
    static_strain: f64,
    vertices: usize,
    triangles: usize,
}

/// The worst edge of a state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Worst {
    /// Edge length over reference length.
    pub ratio: f64,
    pub vertices: (usize, usize),
    /// The edge's reference length (m).
    pub length: f64,
}

impl StrainModel {
    /// The check for `cloth` at its current state (its bound infinite where it does not apply:
    /// no structural springs, or forces the bound does not cover).
    pub fn of(cloth: &Cloth, effects: &EffectSet) -> Self {
        let names = effects.names();
        let covered = names.contains(&"stretch") && names.iter().all(|n| COVERED.contains(n));
        let wave_speed = (cloth.pieces.iter())
            .map(|p| (p.material.stretch / p.material.density).sqrt())
            .fold(f64::INFINITY, f64::min);
        let k_min = (cloth.pieces.iter())
            .map(|p| p.material.stretch)
            .fold(f64::INFINITY, f64::min);
        let applies = covered && wave_speed.is_finite() && wave_speed > 0.0 && k_min > 0.0;
        let n = cloth.len();
        let mut spacing = vec![f64::INFINITY; n];
        let edges: Vec<(u32, u32, f64)> = crate::cloth::topology::unique_edges(&cloth.triangles)
            .into_iter()
            .filter(|&(i, j)| (i as usize) < n && (j as usize) < n)
            .map(|(i, j)| {
                let (a, b) = (i as usize, j as usize);
                let rest = (cloth.uv[a] - cloth.uv[b]).length();
                let now = (cloth.x[a] - cloth.x[b]).length();
                (i, j, rest.max(now))
            })
            .filter(|e| e.2 > 0.0 && e.2.is_finite())
            .collect();
        for &(i, j, l) in &edges {
            spacing[i as usize] = spacing[i as usize].min(l);
            spacing[j as usize] = spacing[j as usize].min(l);
        }
        let max_spacing = (spacing.iter())
            .copied()
            .filter(|s| s.is_finite())
            .fold(0.0, f64::max);
        let mass: f64 = cloth.mass.iter().sum();
        let shortest = edges.iter().map(|e| e.2).fold(f64::INFINITY, f64::min);
        let th = cloth.thickness.iter().copied().fold(0.0, f64::max);
        let layer = if shortest.is_finite() {
            th / shortest
        } else {
            0.0
        };
        Self {
            edges,
            spacing,
            max_spacing,
            wave_speed: applies.then_some(wave_speed),
            static_strain: mass * effects.gravity().length() / k_min + layer,
            vertices: n,
            triangles: cloth.triangles.len(),
        }
    }

    /// Whether the bound applies to this cloth.
    pub fn applies(&self) -> bool {
        self.wave_speed.is_some()
    }

    /// Whether this check was set up for `cloth` (same vertex and triangle counts).
    pub fn fits(&self, cloth: &Cloth) -> bool {
        self.vertices == cloth.len() && self.triangles == cloth.triangles.len()
    }

    /// The local cloth spacing at vertex `i` (m; infinite for a vertex on no edge).
    pub fn spacing(&self, i: usize) -> f64 {
        self.spacing.get(i).copied().unwrap_or(f64::INFINITY)
    }

    /// The longest local spacing (m; 0 for a cloth without edges).
    pub fn max_spacing(&self) -> f64 {
        self.max_spacing
    }

    /// The largest stretch `x` can have when the fastest impact is at relative speed `v` (m/s);
    /// see the module doc.
    pub fn bound(&self, v: f64) -> f64 {
        match self.wave_speed {
            Some(c) => 1.0 + 2.0 * v / c + self.static_strain,
            None => f64::INFINITY,
        }
    }

    /// The most stretched edge of `after` among those beyond `bound` there and within it in
    /// `before` (a non-finite length counts as beyond), of those `judged(a, b)` keeps.
    pub fn grown_beyond(
        &self,
        before: &[Vec3],
        after: &[Vec3],
        bound: f64,
        judged: impl Fn(usize, usize) -> bool,
    ) -> Option<Worst> {
        let mut w: Option<Worst> = None;
        for &(i, j, l) in &self.edges {
            let (a, b) = (i as usize, j as usize);
            let r = after[a].distance(after[b]) / l;
            if r <= bound || w.is_some_and(|w| r <= w.ratio) {
                continue;
            }
            if before[a].distance(before[b]) / l <= bound && judged(a, b) {
                w = Some(Worst {
                    ratio: r,
                    vertices: (a, b),
                    length: l,
                });
            }
        }
        w
    }
}
