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
    #[error("more than {max} vertices")]
    TooManyVertices { max: usize },
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
    #[error(transparent)]
    Garment(crate::garment::GarmentError),
    #[error(transparent)]
    Collision(crate::collide::SpecProblem),
}

pub(super) type Invalid = (String, Problem);

/// Largest grid accepted (vertices): a typo such as `resolution: [10000, 10000]` must not
/// allocate gigabytes.
pub const MAX_VERTICES: usize = 4_000_000;
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
pub const MAX_DAMPING: f64 = 1e6;
pub const MAX_FRICTION: f64 = 100.0;
/// Largest strain limit (an edge allowed to 11 times its rest length limits nothing real).
pub const MAX_STRAIN_LIMIT: f64 = 10.0;
/// Wind: speed (m/s), gust frequency (Hz), air density (kg/m^3), drag coefficient.
pub const MAX_WIND: f64 = 1e3;
pub const MAX_FREQUENCY: f64 = 1e4;
pub const MAX_AIR_DENSITY: f64 = 1e3;
pub const MAX_DRAG: f64 = 1e3;
/// Largest time (s) in a key, waypoint or trajectory point.
pub const MAX_TIME: f64 = 1e9;
/// Largest joint position in a trajectory (rad or m).
pub const MAX_JOINT: f64 = 1e6;
