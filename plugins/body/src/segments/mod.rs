//! Segment-local morphing of the body and its roughness measure, after seed 002 (B. Uğur,
//! *Parametric Human Body Modeling for Virtual Dressing*, 2008) §4.3 "Segmentation Tool",
//! §4.4 "Local Morphing" and §7.1 "Smoothness Measure for Morphed Objects".
//!
//! # Segments (§4.3)
//!
//! The body is marked with anthropometric *segments*: each has a *core* vertex set, and the
//! cores partition the body vertices, so that every vertex belongs to exactly one core. They are
//! derived from the mesh and the rig, never from vertex lists ([`BodySegmentation::new`]):
//!
//! 1. Each body vertex goes to the segment kind of its *dominant skin bone* (its largest weight)
//!    or, if that bone names none, of its nearest ancestor that does: `upperarm*` → upper arm,
//!    `lowerarm*` (with the twist half) → forearm, `hand*` (with the fingers) → hand, `thigh*`
//!    → thigh, `calf*` → shank, `foot*` (with `ball*`) → foot, `neck*` / `head` → head and neck;
//!    everything else (`Root`, `pelvis`, `spine_*`, `clavicle_*`) is the torso.
//! 2. Left and right: the side of the x of that bone's head in the rest pose (+X is the body's
//!    left).
//! 3. The torso, and the thigh vertices above the crotch, are cut into three horizontal bands by
//!    the waist, hip and crotch landmarks that [`BodyModel::measure`] finds on the base mesh
//!    (heights above the sole): the *waist* band is centred on the waist line and as tall as the
//!    waist line is above the hip line (half that distance up and half down); the *chest* is
//!    everything above it (under-bust, bust, shoulders), the *hip* everything below. The legs
//!    start at the crotch height: a thigh vertex above it belongs to the hip band.
//!
//! On the MakeHuman base mesh (waist line 108.3 cm, hip line 87.6 cm) the waist band spans 98.0
//! to 118.7 cm above the sole, about ten edge rings at the torso's 2 cm edges.
//!
//! # Propagation (§4.3, eq. 4.1, Figure 4.8)
//!
//! From a core set, a breadth-first search over the mesh edge graph reaches the vertices at
//! `k = 1, 2, ...` hops (the *depth of the vertex*: its shortest graph distance to the core) up
//! to the *propagation depth* `d`. Each gets the weight `f(k, d)`, 1 on the core (`k = 0`), 0
//! beyond `d`. With `p = d + 1` (so that the last reached ring keeps a non-zero weight and
//! `d = 0` is the hard segment, the core alone):
//!
//! | [`Decay`] | `f(k, d)` for `0 <= k <= d` | seed Figure 4.8 |
//! | --- | --- | --- |
//! | `Linear` | `1 - k / p` | (a) `w = (p - d) / p` |
//! | `Square` | `1 - k² / p²` | (b) `w = 1 - d²/p²` |
//! | `Gaussian` | `exp(-k² / (2σ²))`, `σ = p / 3` | (c) `w = exp(-d²/2σ²)`, `σ = p·c`, here `c = 1/3` |
//!
//! The Gaussian's constant `c = 1/3` puts the first vertex that is *not* reached three standard
//! deviations out, where the curve has fallen to `exp(-4.5) = 0.011`, so cutting it there leaves
//! almost no step.
//!
//! # Local morphing (§4.4, eqs. 4.5 and 4.6)
//!
//! A source body `S` morphs towards a target `T` by amounts `u_j` per segment `j`. A vertex `k`
//! reached by the segments `j` with weights `w_kj` moves by the weighted mean (eq. 4.6):
//!
//! ```text
//! B(u)'_k = s_k + (t_k - s_k) · Σ_j u_j w_kj / Σ_j w_kj
//! ```
//!
//! Every segment takes part, the ones not being edited with `u_j = 0`: their weights in the
//! denominator are what makes the boundary regions blend. A vertex reached by one segment only
//! moves by that segment's `u_j` (the seed's special case, which the formula already gives);
//! with all `u_j = 1` every vertex morphs completely, the seed's requirement. [`AreaBlend`] does
//! this on any mesh; [`BodySegmentation::morph`] on the body, where the target may also be given
//! per segment (a girth scaling about the segment's own axis, [`SegmentTarget::RadialScale`],
//! the horizontal scaling at a girth position of §4.1.2 / §4.2): then `t_k - s_k` becomes
//! segment `j`'s displacement `δ_kj` inside the sum, `s_k + Σ_j u_j w_kj δ_kj / Σ_j w_kj`, which
//! is eq. 4.6 when all segments share one target. Helper vertices (tights, hair...) are copied
//! unchanged.
//!
//! [`SegmentMorph`] edits one segment with the rest of the body held (`u = 0`), and
//! [`SegmentMorph::edit_girth`] / [`edit_waist_girth`] are the designer's local edits: they find
//! the radial scale factor that brings the measured girth of the segment (waist, hip, bust...)
//! to the requested value, by secant steps on [`BodyModel::measure`], since the neighbours'
//! weights dilute the edit near the core's edges.
//!
//! # Roughness (§7.1, eqs. 7.1 and 7.2)
//!
//! The Laplacian coordinate of a vertex is the mean of its 1-ring neighbours (the uniform
//! Laplacian, eq. 7.1); the roughness of a vertex set is the mean distance of its vertices from
//! their Laplacian coordinates (eq. 7.2 divided by the vertex count, as the seed's figures
//! plot), [`MeshGraph::roughness_m`]. A vertex on an open boundary has a Laplacian in the
//! tangent plane too, so a flat grid is exactly 0 on its interior only.
//!
//! [`roughness_study`] repeats the seed's Figures 7.3-7.5: two neighbouring segments interpolated
//! separately and together towards a target, the roughness of their region against the amount,
//! for increasing propagation depths and each decay.
//!
//! # Where things are
//!
//! - `mesh_graph`: [`MeshGraph`], the edge graph: hops from a core, propagation, roughness.
//! - `propagation`: [`Decay`], [`Propagation`] and the [`SegmentWeights`] they give.
//! - `area_blend`: [`AreaBlend`], eq. 4.6 on any mesh.
//! - `body_segment`: the sixteen [`BodySegment`]s.
//! - `segmentation`: [`BodySegmentation`], the rules above and the body's local morph
//!   ([`SegmentTarget`], [`SegmentEdit`]).
//! - `girth_edit`: [`SegmentMorph`], [`edit_waist_girth`]: one segment at a time.
//! - `study`: [`roughness_study`], Figures 7.3-7.5.
//!
//! [`BodyModel::measure`]: crate::BodyModel::measure

mod area_blend;
mod body_segment;
mod girth_edit;
mod mesh_graph;
mod propagation;
mod segmentation;
mod study;

pub use area_blend::AreaBlend;
pub use body_segment::BodySegment;
pub use girth_edit::{GIRTH_TOLERANCE_CM, GirthEdit, SegmentMorph, edit_waist_girth};
pub use mesh_graph::MeshGraph;
pub use propagation::{Decay, Propagation, SegmentWeights};
pub use segmentation::{BodySegmentation, SegmentEdit, SegmentTarget, TorsoCuts};
pub use study::{
    RoughnessCurve, RoughnessStudy, RoughnessStudyConfig, StudyTarget, roughness_study,
    roughness_study_with,
};

use crate::measure::MeasureError;
use crate::modifiers::ShapeError;

/// Why a segmentation, a local morph, a girth edit or a roughness study cannot be made.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SegmentError {
    #[error(
        "triangles[{triangle}] names vertex {vertex}, past the {vertex_count} vertices of the \
         mesh graph; pass the triangles of the same mesh (body triangles only for a body)"
    )]
    TriangleIndex {
        triangle: usize,
        vertex: u32,
        vertex_count: usize,
    },
    #[error(
        "{field} names vertex {vertex}, past the {vertex_count} vertices of the mesh graph; \
         vertex indices must be below the graph's vertex count"
    )]
    VertexIndex {
        field: &'static str,
        vertex: u32,
        vertex_count: usize,
    },
    #[error("{field} has {got} entries, expected {expected}; {fix}")]
    Length {
        field: &'static str,
        got: usize,
        expected: usize,
        fix: &'static str,
    },
    #[error("{field} is {value}, expected {expected}")]
    BadValue {
        field: &'static str,
        value: f32,
        expected: &'static str,
    },
    #[error("the body model is invalid: {0}; re-import it with the body importer")]
    InvalidModel(String),
    #[error(
        "segment `{0}` has no core vertex: the rig lacks the bone it is derived from (see the \
         segmentation rules in the segments module), or the landmarks put its band outside the \
         body; check the rig's bone names and the body's measurements"
    )]
    EmptySegment(BodySegment),
    #[error("the landmarks for the torso bands could not be measured on the base mesh: {0}")]
    Measure(#[from] MeasureError),
    #[error("the study target shape cannot be applied: {0}")]
    Shape(#[from] ShapeError),
    #[error(
        "segment `{0}` is edited twice in one morph; give each segment at most one edit (combine \
         the amounts)"
    )]
    DuplicateEdit(BodySegment),
    #[error(
        "segment `{0}` has no girth that the body measurement reports; girth edits work on \
         head-neck (neck), chest (bust), waist, hip, thigh-left (thigh) and shank-left (calf)"
    )]
    NoGirth(BodySegment),
    #[error(
        "the requested {segment} girth {requested_cm:.2} cm is {ratio:.2} times the current \
         {current_cm:.2} cm; request between 0.5 and 2 times the current girth"
    )]
    GirthOutOfReach {
        segment: BodySegment,
        requested_cm: f32,
        current_cm: f32,
        ratio: f32,
    },
    #[error(
        "the {segment} girth edit stopped at {achieved_cm:.3} cm instead of {requested_cm:.3} cm \
         (scale factor {factor}); a deeper propagation or a smaller change may reach it"
    )]
    GirthNotReached {
        segment: BodySegment,
        requested_cm: f32,
        achieved_cm: f32,
        factor: f32,
    },
    #[error("roughness study: {0}")]
    StudyConfig(String),
}
