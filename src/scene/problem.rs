//! [`Problem`]: what is wrong with one value of a scene, and the limits validation holds every
//! value to (each with its reason). Its own file so `SceneError` (in `mod.rs`) and the
//! validation pass share it without a cycle.

/// What is wrong with one value of the scene.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum Problem {
    #[error("must be finite (got {value})")]
    NotFinite { value: f64 },
    #[error("must be > 0 (got {value})")]
    NotPositive { value: f64 },
    #[error("must be >= 0 (got {value})")]
    Negative { value: f64 },
    #[error("must be at most {max:e}{unit} (got {value:e})")]
    TooLarge {
        value: f64,
        max: f64,
        unit: &'static str,
    },
    #[error("must be at least {min:e}{unit} (got {value:e})")]
    TooSmall {
        value: f64,
        min: f64,
        unit: &'static str,
    },
    #[error("must be in {min}..={max} (got {value})")]
    CountOutOfRange { value: u64, min: u64, max: u64 },
    #[error("{dt} s step is longer than the {duration} s run")]
    StepLongerThanRun { dt: f64, duration: f64 },
    #[error(
        "{duration} s at {dt} s x {substeps} substeps is {count:e} substeps, more than {max:e}"
    )]
    TooManySteps {
        duration: f64,
        dt: f64,
        substeps: u32,
        count: f64,
        max: f64,
    },
    #[error("{rate:e} Hz for {duration} s is more than {max:e} frames")]
    TooManyFrames { rate: f64, duration: f64, max: f64 },
    #[error("times must increase ({value} after {previous})")]
    NotIncreasing { value: f64, previous: f64 },
    #[error("{name:?} is listed twice")]
    Duplicate { name: String },
    #[error("the effect list names wind but there is no wind section")]
    WindMissing,
    #[error("a scene needs at least one cloth")]
    NoCloth,
    #[error("a scene with garments cannot also have grid cloths")]
    GarmentsAndCloths,
    #[error("needs at least {min} vertices each way (got {got:?})")]
    TooFewVertices { got: [usize; 2], min: usize },
    /// All cloths of the scene together (grids and estimated garment meshes) pass
    /// [`MAX_VERTICES`]; `count` is the total up to and including this value.
    #[error(
        "the scene's cloth would have {count:.0} vertices, more than the {max} a scene may have (all cloths and garments together)"
    )]
    TooManyVertices { count: f64, max: usize },
    /// A grid or garment edge shorter than [`MIN_EDGE_LENGTH`].
    #[error("gives {edge:.3e} m edges, shorter than the {min:e} m a cloth edge may be")]
    EdgeTooShort { edge: f64, min: f64 },
    /// Self-collision on cloth whose thickness spans many of its edges: every vertex keeps
    /// the rest neighbours within its thickness, so the cost grows with `(1 + ratio)^2`.
    #[error(
        "with self_collision, {vertices:.0} vertices with a thickness {ratio:.3} times their shortest edge bring the scene's self-contact load (vertices x (1 + thickness / edge)^2, over all cloths) to {load:.3e}, more than {max:e}: use fewer vertices, a smaller thickness or no self_collision"
    )]
    SelfContactTooLarge {
        vertices: f64,
        ratio: f64,
        load: f64,
        max: f64,
    },
    /// A vertex mass (areal density times the area a vertex carries) that is zero or subnormal.
    #[error("gives each vertex a mass of {mass:.3e} kg, too small to simulate")]
    MassTooSmall { mass: f64 },
    #[error("give exactly one of vertex, vertices, region, near")]
    SelectionForm,
    #[error("vertex {vertex} out of range (cloth has {count})")]
    VertexOutOfRange { vertex: u32, count: usize },
    #[error("no {what} named {name:?}")]
    Unknown { what: &'static str, name: String },
    #[error("must not be empty")]
    Empty,
    #[error("{found} values for {expected} joint names")]
    Length { found: usize, expected: usize },
    #[error("has no effect without {needs}")]
    Without { needs: &'static str },
    /// A textile-lab key beside the spring-constant key it stands in for.
    #[error("gives the same property as `{other}`: give one of the two")]
    BothKeys { other: &'static str },
    /// A tensile stiffness per unit width on a garment: it is shared out over a grid's
    /// springs by their tributary widths, which a free triangle mesh does not have.
    #[error(
        "is shared out over a grid's springs; a garment's springs take `stretch` (N/m per spring)"
    )]
    NeedsGrid,
    #[error(transparent)]
    Garment(crate::garment::GarmentError),
    #[error(transparent)]
    Collision(crate::collide::SpecProblem),
}

pub(super) type Invalid = (String, Problem);

/// Most cloth vertices a scene may have, all grids and garments together (a garment's vertices
/// estimated from its outlines and `edge_length` before any meshing). A vertex takes about
/// 4.8 kB to build and check and 9.5 kB to record (implicit integrator, every effect; peak
/// resident memory of `drape check` / `drape record` on grids of 200x200 to 316x316), so
/// everything accepted is built in about 0.5 GB and recorded in about 1 GB, well under 2 GB
/// (self-contact adds its own load, bounded by [`MAX_SELF_CONTACT_LOAD`]).
pub const MAX_VERTICES: usize = 100_000;
/// Most self-contact load a scene with `self_collision` may have: the sum over its cloths of
/// `vertices (1 + thickness / shortest edge)^2`. Self-contact keeps, per vertex, the rest
/// neighbours within its thickness, so its memory grows with that ratio squared: measured at
/// 1.6 to 2.2 kB per unit of load on top of the vertex's own, this bounds it to about 330 MB
/// (37,500 vertices with a thickness of one edge record in 0.6 GB; a 1e-9 m cloth is refused
/// outright).
pub const MAX_SELF_CONTACT_LOAD: f64 = 150_000.0;
/// Shortest cloth edge (m), of a grid (`size / (resolution - 1)`) or a garment (`edge_length`):
/// ten micrometres, far below any woven thread's spacing, and far above lengths whose squares
/// (areas, masses) leave f64's normal range.
pub const MIN_EDGE_LENGTH: f64 = 1e-5;
/// Largest coordinate, size or distance (m): far inside f64's range, so squared distances,
/// products with rates and sums over a grid stay finite.
pub const MAX_LENGTH: f64 = crate::robot::kinematics::MAX_LENGTH;
/// Largest angle (rad) in a pose: beyond this, `sin`/`cos` of an f64 lose all precision.
pub const MAX_ANGLE: f64 = 1e6;
/// Fastest scripted linear motion (m/s) and rotation (rad/s).
pub const MAX_SPEED: f64 = 1e4;
/// Strongest gravity (m/s^2): a thousand g.
pub const MAX_GRAVITY: f64 = 1e4;
/// Frame step bounds (s): below the lower one a second of simulation takes a million steps;
/// above the upper one nothing in a cloth is resolved.
pub const MIN_DT: f64 = 1e-6;
pub const MAX_DT: f64 = 1.0;
/// Most frame steps x substeps one run may ask for (`duration / dt * substeps`), and most
/// frames it may write (`publish_rate * duration`; a frame is written at most once per step).
pub const MAX_TOTAL_SUBSTEPS: f64 = 1e7;
/// Longest run (s): about eleven days of simulated time (the substep cap usually binds first).
pub const MAX_DURATION: f64 = 1e6;
/// Most inner iterations a setting may ask for per step (CG, collision passes).
pub const MAX_ITERATIONS: u64 = 100_000;
/// Material bounds: areal density (kg/m^2), spring stiffness (N/m), bending and twist
/// rigidity (N m), damping coefficients, friction coefficient.
pub const MAX_DENSITY: f64 = 1e4;
pub const MAX_STIFFNESS: f64 = 1e8;
pub const MAX_RIGIDITY: f64 = 1e4;
/// Longest bending length (cm): a 10 m cantilever of cloth stands straight out; nothing a
/// textile lab measures comes near.
pub const MAX_BENDING_LENGTH: f64 = 1e3;
pub const MAX_DAMPING: f64 = 1e6;
pub const MAX_FRICTION: f64 = 100.0;
/// Largest through-thickness compressive modulus (Pa): a gigapascal is a stiff plastic, far past
/// any fabric.
pub const MAX_MODULUS: f64 = 1e9;
/// Largest strain limit (an edge allowed to 11 times its rest length limits nothing real).
pub const MAX_STRAIN_LIMIT: f64 = 10.0;
/// Largest knee strain: a fabric that stiffens only past twice its length does not stiffen.
pub const MAX_STRETCH_KNEE: f64 = 1.0;
/// Stiffening past the knee, at most: far beyond any fabric's, and short of making the tangent
/// stiffness's sum with the rest of the system matrix lose the rest to rounding.
pub const MAX_KNEE_STIFFENING: f64 = 1e4;
/// Wind: speed (m/s), gust frequency (Hz), air density (kg/m^3), drag coefficient.
pub const MAX_WIND: f64 = 1e3;
pub const MAX_FREQUENCY: f64 = 1e4;
pub const MAX_AIR_DENSITY: f64 = 1e3;
pub const MAX_DRAG: f64 = 1e3;
/// Largest time (s) in a key, waypoint or trajectory point.
pub const MAX_TIME: f64 = 1e9;
/// Largest joint position in a trajectory (rad or m).
pub const MAX_JOINT: f64 = 1e6;
