//! The impact front of a moving link's drag, for the implicit solve's linearisation.
//!
//! A link that drags cloth sideways at speed `u` sends a front through it behind which the
//! springs carry the strain `u / c` (`c = sqrt(stretch / density)`), doubled where it reflects
//! (the guard's strain bound, `sim/strain.rs`, has the same `2 v / c`). At the start of a
//! substep that tension is not there yet: a spring at rest length has no transverse stiffness
//! in the linearisation, so the solve moves the carried vertices and leaves their neighbours,
//! and the edges between stretch by the whole drag, which fast contact answers by splitting
//! substeps until the drag per substep is a third of a spacing (`sim/fast.rs`). Given the
//! front's strain around the carried vertices, the springs there are linearised at that tension
//! ([`crate::effects::Effect::add_front_stiffness`]): the solve takes the neighbours along, the
//! cloth stays within the same strain bound, and the link's cloth moves with it in fewer
//! substeps (`benches/fast_links.rs` counts them).
//!
//! The strain is the longitudinal front's `2 u / c`, an upper bound of what a transverse drag
//! builds: the classical transverse impact on a string (Smith, McCrackin and Schiefer 1958,
//! `u / c = sqrt(e (2 sqrt(e (1 + e)) - e))`) gives 5-8 times less at 5-20 m/s, but linearised
//! at that smaller strain the solve again leaves the carried vertices' edges beyond the bound
//! and fast contact splits more. The bound over-couples where pins hold the cloth behind the
//! link (a sheet pinned along its top row and dragged by a thin capsule stretches beyond the
//! impact bound with or without the front; `tests/fast_links.rs`).

use super::fast::REACH_RINGS;
use crate::cloth::Cloth;
use crate::integrate::ContactSpring;

/// The cloth's mesh edges, kept across substeps for the front's rings.
#[derive(Debug, Default)]
pub(super) struct Front {
    edges: Vec<(u32, u32)>,
    /// Vertex and triangle counts the edges were built for.
    built_for: (usize, usize),
    /// The strains before the current ring (scratch).
    last: Vec<f64>,
}

impl Front {
    /// Per vertex, the strain of the front that `moving` springs (moving features dragging the
    /// cloth to where they end the substep of length `h`) send through the cloth, into `out`:
    /// `2 u / c` at the vertices they carry (`u` the drag's speed, the spring's depth over `h`),
    /// and the largest neighbouring value across [`REACH_RINGS`] rings of edges, the vertices
    /// that trail what a link carries. Empty when nothing is dragged.
    pub fn strain(
        &mut self,
        cloth: &Cloth,
        springs: &[ContactSpring],
        moving: &[usize],
        h: f64,
        out: &mut Vec<f64>,
    ) {
        out.clear();
        let n = cloth.len();
        let mut any = false;
        for spring in moving.iter().filter_map(|&k| springs.get(k)) {
            let depth = spring.depth(&cloth.x);
            if !(depth > 0.0 && h > 0.0) {
                continue;
            }
            if out.is_empty() {
                out.resize(n, 0.0);
            }
            for (i, _) in spring.slots() {
                let e = 2.0 * depth / h / wave_speed(cloth, i);
                if e.is_finite() && e > out[i] {
                    out[i] = e;
                    any = true;
                }
            }
        }
        if !any {
            out.clear();
            return;
        }
        if self.built_for != (n, cloth.triangles.len()) {
            self.edges = crate::cloth::topology::unique_edges(&cloth.triangles);
            self.edges
                .retain(|&(i, j)| (i as usize) < n && (j as usize) < n);
            self.built_for = (n, cloth.triangles.len());
        }
        // Rings by relaxation over the edges: a vertex takes its neighbours' largest strain.
        for _ in 0..REACH_RINGS as usize {
            self.last.clone_from(out);
            let last = &self.last;
            for &(i, j) in &self.edges {
                let (i, j) = (i as usize, j as usize);
                let e = last[i].max(last[j]);
                out[i] = out[i].max(e);
                out[j] = out[j].max(e);
            }
        }
    }
}

/// Longitudinal wave speed `sqrt(stretch / density)` of the piece vertex `i` belongs to (m/s;
/// infinite, so no front, for a vertex outside every piece).
fn wave_speed(cloth: &Cloth, i: usize) -> f64 {
    cloth
        .pieces
        .iter()
        .find(|p| p.vertices().contains(&i))
        .map_or(f64::INFINITY, |p| {
            (p.material.stretch / p.material.density).sqrt()
        })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cloth::{Material, Panel};
    use crate::{Pose, Vec3};

    /// A 7 x 7 grid (10 cm spacing) with a spring under its middle vertex pushed 1 mm in a 1 ms
    /// substep (1 m/s): the middle vertex gets `2 u / c`, the rings one and two edges out the
    /// same, the border three edges out nothing; a spring not pushed gives no front at all.
    #[test]
    fn a_dragged_vertex_sends_its_front_two_rings_out() {
        let mut cloth = Cloth::new();
        cloth.add_panel(
            Panel::grid("s", [0.6, 0.6], [7, 7], &Pose::default()),
            Material::default(),
        );
        let id = |i: usize, j: usize| j * 7 + i;
        let middle = id(3, 3);
        let c = wave_speed(&cloth, middle);
        assert!(c.is_finite() && c > 0.0);
        let spring = ContactSpring {
            verts: [middle as u32; 4],
            weights: [1.0, 0.0, 0.0, 0.0],
            normal: Vec3::Z,
            point: cloth.x[middle] - Vec3::Z * 1e-3,
            gap: 2e-3,
            stiffness: 1.0,
            friction: 0.0,
        };
        let mut front = Front::default();
        let mut out = Vec::new();
        front.strain(&cloth, &[spring], &[0], 1e-3, &mut out);
        let e = 2.0 * 1.0 / c;
        assert!((out[middle] - e).abs() < 1e-9 * e, "{} vs {e}", out[middle]);
        for (i, j) in [
            (2, 2),
            (4, 4),
            (2, 4),
            (4, 2),
            (3, 2),
            (1, 3),
            (3, 5),
            (5, 3),
        ] {
            assert_eq!(out[id(i, j)], out[middle], "vertex ({i}, {j})");
        }
        for k in 0..7 {
            for v in [id(0, k), id(6, k), id(k, 0), id(k, 6)] {
                assert_eq!(out[v], 0.0, "border vertex {v}");
            }
        }
        let mut resting = spring;
        resting.gap = 0.0;
        front.strain(&cloth, &[resting], &[0], 1e-3, &mut out);
        assert!(out.is_empty());
    }
}
