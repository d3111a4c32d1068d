//! Errors of the cloth core: every message names the offending item and what to fix.

/// Why a cloth could not be built or an input was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ClothError {
    /// The mesh has no vertices or no triangles.
    #[error(
        "the cloth mesh is empty ({vertices} vertices, {triangles} triangles): give at least one triangle"
    )]
    EmptyMesh { vertices: usize, triangles: usize },
    /// More vertices than the solver's `u32` indices can address.
    #[error("the cloth mesh has {count} vertices; at most {max} are supported")]
    TooManyVertices { count: usize, max: usize },
    /// A vertex position is NaN or infinite.
    #[error("vertex {index} is not finite ({value:?}): fix the garment's positions")]
    NonFiniteVertex { index: usize, value: [f32; 3] },
    /// A triangle refers to a vertex that does not exist.
    #[error(
        "triangle {triangle} refers to vertex {vertex}, but the mesh has only {vertex_count} vertices"
    )]
    IndexOutOfRange {
        triangle: usize,
        vertex: u32,
        vertex_count: usize,
    },
    /// A triangle uses the same vertex twice.
    #[error("triangle {triangle} uses vertex {vertex} twice: remove the degenerate triangle")]
    RepeatedVertex { triangle: usize, vertex: u32 },
    /// A triangle has (numerically) zero area.
    #[error("triangle {triangle} has zero area ({area_m2} m²): remove it or weld its vertices")]
    DegenerateTriangle { triangle: usize, area_m2: f32 },
    /// An attachment names a vertex that does not exist.
    #[error(
        "attachment {index} names vertex {vertex}, but the mesh has only {vertex_count} vertices"
    )]
    AttachmentOutOfRange {
        index: usize,
        vertex: u32,
        vertex_count: usize,
    },
    /// The same vertex is attached twice.
    #[error("vertex {vertex} is attached twice (attachments {first} and {second})")]
    DuplicateAttachment {
        vertex: u32,
        first: usize,
        second: usize,
    },
    /// A slice has the wrong length.
    #[error("expected {expected} {what}, got {got}")]
    LengthMismatch {
        what: &'static str,
        expected: usize,
        got: usize,
    },
    /// A parameter is out of its valid range.
    #[error("{what} must be {requirement}, got {value}")]
    InvalidParameter {
        what: &'static str,
        requirement: &'static str,
        value: f64,
    },
    /// An input value (target, collider, reset position) is NaN or infinite.
    #[error("{what} {index} is not finite: the caller must pass finite values")]
    NonFiniteInput { what: &'static str, index: usize },
    /// A capsule joins a sphere that was not given.
    #[error("capsule {capsule} joins sphere {sphere}, but only {sphere_count} spheres were given")]
    CapsuleOutOfRange {
        capsule: usize,
        sphere: u32,
        sphere_count: usize,
    },
    /// Too many colliders for the per-chunk candidate list.
    #[error("{count} colliders were given; at most {max} are supported")]
    TooManyColliders { count: usize, max: usize },
}

pub(crate) fn positive(what: &'static str, value: f32) -> Result<(), ClothError> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(ClothError::InvalidParameter {
            what,
            requirement: "finite and > 0",
            value: value as f64,
        })
    }
}

pub(crate) fn non_negative(what: &'static str, value: f32) -> Result<(), ClothError> {
    if value >= 0.0 && !value.is_nan() {
        Ok(())
    } else {
        Err(ClothError::InvalidParameter {
            what,
            requirement: ">= 0 (infinity allowed where it means rigid)",
            value: value as f64,
        })
    }
}
