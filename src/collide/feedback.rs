//! What the solver tells the collision stage about the substep it just solved.

use crate::Vec3;

/// Up to three (normal, normal velocity change) a vertex was held with (zero: unused).
pub(crate) type Held = [(Vec3, f64); 3];
