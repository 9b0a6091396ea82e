//! Bounds on what a mesh file may make: triangles, coordinates and scale.

/// Farthest a mesh vertex may lie from the origin on any axis (m), after scaling: a thousand
/// kilometres, far beyond any robot or workcell, and small enough that contact arithmetic on
/// such coordinates keeps sub-millimetre precision.
pub const MAX_COORDINATE: f64 = 1e6;
/// Most triangles in one mesh (after a Collada scene's instancing): a detailed collision mesh
/// has tens of thousands; larger ones are simplified before use. Checked before the
/// triangles are built, so a file cannot make the loader allocate for more.
pub const MAX_TRIANGLES: usize = 2_000_000;
/// Smallest magnitude of a mesh scale component (a file in nanometres would need 1e-9).
pub const MIN_SCALE: f64 = 1e-9;
/// Largest magnitude of a mesh scale component.
pub const MAX_SCALE: f64 = 1e6;
