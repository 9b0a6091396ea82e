//! [`DaeError`]: what is wrong inside a well-formed Collada document. The loader wraps it in
//! `MeshError::Collada` with the file and the geometry it was reading, so each variant holds
//! only the element, attribute or value at fault.

/// A Collada document that is valid XML but not usable geometry.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DaeError {
    #[error("root element is <{found}>, expected <COLLADA>")]
    Root { found: String },
    #[error("<unit meter=\"{value}\"> is not a positive number")]
    UnitMeter { value: String },
    #[error("unknown <up_axis> `{value}`")]
    UpAxis { value: String },
    #[error("node hierarchy deeper than {max} (cyclic instance_node?)")]
    NodeDepth { max: usize },
    #[error("<{element}> has {found} numbers, expected {expected}")]
    Arity {
        element: &'static str,
        found: usize,
        expected: usize,
    },
    #[error("`{token}` is not a number")]
    NotANumber { token: String },
    #[error("`{token}` is not an index")]
    NotAnIndex { token: String },
    #[error("instance_geometry references unknown geometry `{url}`")]
    UnknownGeometry { url: String },
    #[error("instance_node references unknown node `{url}`")]
    UnknownNode { url: String },
    /// A required child element or input is absent (`what` names it, e.g. "<mesh> without
    /// <vertices>").
    #[error("{what}")]
    Missing { what: &'static str },
    #[error("POSITION source `{id}` not found")]
    PositionSource { id: String },
    #[error("bad {attribute} `{value}`")]
    Attribute {
        attribute: &'static str,
        value: String,
    },
    #[error("position accessor stride {stride} < 3")]
    Stride { stride: usize },
    #[error("accessor count {count} x stride {stride} overflows")]
    AccessorOverflow { count: usize, stride: usize },
    #[error(
        "accessor wants {count} positions of stride {stride} but float_array has {numbers} numbers"
    )]
    AccessorShort {
        count: usize,
        stride: usize,
        numbers: usize,
    },
    #[error("<{primitive}> has no VERTEX input")]
    NoVertexInput { primitive: String },
    #[error("<p> shorter than the primitive's count implies")]
    ShortIndexList,
    #[error("vertex index {index} out of range (mesh has {positions} positions)")]
    IndexOutOfRange { index: usize, positions: usize },
    #[error("<{primitive}> primitives are not supported")]
    Unsupported { primitive: String },
    /// The scene's instancing places more triangles than a mesh may have.
    #[error("the scene places more than {max} triangles (instance_node and instance_geometry multiply them)")]
    TooManyTriangles { max: usize },
    #[error("the scene visits more than {max} nodes (instance_node multiplies them)")]
    TooManyNodes { max: usize },
    #[error("<vcount> sum overflows")]
    VcountOverflow,
}
