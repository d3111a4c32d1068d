//! The MakeHuman body for fitroom: model, import, rig, skinning.
//!
//! The avatar is the MakeHuman hm08 base mesh (CC0) with the MPFB2 `game_engine` skeleton, its
//! skin weights, and the macro and measurement morph targets. Everything here is plain Rust
//! over glam types; the Bevy adapter is the `plugin` module (feature `plugin`).
//!
//! - [`import`]: reads the MakeHuman data (OBJ, vertex groups, rig, weights, targets) into a
//!   [`BodyModel`], splitting each forearm in two (seed 000 §4.4.3).
//! - [`asset`]: the compact `.fitbody` file the product ships (format below).
//! - [`rig`]: the rest pose derived from a (morphed) mesh, bone frames as Blender builds them;
//!   morph target application; vertex normals.
//! - [`skinning`]: forward kinematics and CPU linear blend skinning.
//! - [`forearm`]: the forearm-twist cross-section study (seed 000 Figure 4.3).
//! - [`segments`]: anthropometric segments, propagation and segment-local morphing, and the
//!   roughness measure with its study (seed 002 §4.3-4.4, §7.1).
//! - [`sizing`]: size charts as RON data files (EN 13402, seed 002 Tables 4.2/4.3) and a size
//!   recommendation from [`Measurements`].
//!
//! # Spaces and units
//!
//! Model space is MakeHuman's mesh space scaled from decimetres to metres: +Y up, the body
//! faces +Z, +X is the body's left; the bare hm08 mesh stands from y = -0.817 to +0.849 (166.6 cm).
//! The rig file's `default_position`s and rolls are in MakeHuman's Blender space (Z up, facing
//! -Y): Blender `(x, y, z)` = model `(x, -z, y)` ([`rig::model_to_blender`]).
//!
//! # The `.fitbody` format (version 1)
//!
//! All integers in the header are little-endian.
//!
//! | offset | size | content |
//! | --- | --- | --- |
//! | 0 | 8 | magic bytes `FITBODY\0` (`46 49 54 42 4f 44 59 00`) |
//! | 8 | 4 | format version, `u32` (this build: [`FORMAT_VERSION`] = 1) |
//! | 12 | 8 | length in bytes of the uncompressed payload, `u64` |
//! | 20 | 4 | CRC-32 (IEEE 802.3, the zlib/gzip/PNG one) of the uncompressed payload, `u32` |
//! | 24 | rest | the payload compressed as one raw DEFLATE stream (RFC 1951: no zlib or gzip wrapper) |
//!
//! The payload is the [postcard 1.x](https://postcard.jamesmunns.com/wire-format) encoding of
//! [`BodyModel`]: struct fields in declaration order with no names or tags; unsigned integers
//! (`u16`, `u32`, `u64`, `usize`) as LEB128 varints; signed integers (`i16`) as zigzag then
//! varint; `f32` as 4 bytes little-endian; a `Vec` or `String` as a varint length followed by
//! its items (UTF-8 bytes for strings); fixed-size arrays and glam vectors (`Vec2`, `Vec3`) as
//! their items with no length; `Option` as a byte 0 (`None`) or 1 followed by the value; an
//! enum as a varint variant index followed by its fields.
//!
//! ```text
//! BodyModel {
//!     positions: Vec<Vec3>,          // all vertices, metres; body first
//!     body_vertex_count: u32,
//!     triangles: Vec<[u32; 3]>,      // body triangles, counter-clockwise from outside
//!     uvs: Vec<Vec2>,                // one per body vertex (OBJ convention: v up)
//!     triangle_uvs: Vec<[Vec2; 3]>,  // per body triangle corner
//!     helpers: Vec<HelperGroup { name: String, first_vertex: u32, last_vertex: u32,
//!                                triangles: Vec<[u32; 3]> }>,
//!     bones: Vec<Bone { name: String, parent: Option<usize>, head_placement: JointPlacement,
//!                       tail_placement: JointPlacement, roll: f32 }>,   // parents first
//!     skin_joints: Vec<[u16; 4]>,    // per body vertex
//!     skin_weights: Vec<[f32; 4]>,
//!     helper_skin_joints: Vec<[u16; 4]>,   // per helper vertex
//!     helper_skin_weights: Vec<[f32; 4]>,
//!     targets: Vec<MorphTarget>,
//! }
//! JointPlacement = 0: Mean(Vec<u32>) | 1: Vertex(u32) | 2: Lerp { from: JointPlacement,
//!                                                                  to: JointPlacement, t: f32 }
//! MorphTarget {
//!     name: String,
//!     indices: Vec<u32>,       // coded as gaps: first index, then index[k] - index[k-1]
//!     deltas: [Vec<i16>; 3],   // three planes (x, y, z), each a Vec (own length, equal to the
//!                              // number of indices) of differences d[k] - d[k-1] (d[-1] = 0),
//!                              // wrapping i16 arithmetic
//!     scale_m: f32,            // metres = delta * scale_m
//! }
//! ```
//!
//! A reader checks the magic, the version, inflates exactly the announced length, checks the
//! CRC, decodes, and then checks indices and lengths ([`BodyModel::validate`]). Any change to
//! the payload layout bumps [`FORMAT_VERSION`].

#![forbid(unsafe_code)]

pub mod ansur;
pub mod asset;
mod codec;
pub mod colliders;
pub mod export;
pub mod fit;
pub mod forearm;
pub mod import;
pub mod measure;
pub mod model;
pub mod modifiers;
#[cfg(feature = "plugin")]
pub mod plugin;
#[cfg(feature = "plugin")]
pub mod reload;
pub mod rig;
pub mod segments;
pub mod sizing;
pub mod skinning;
#[cfg(feature = "plugin")]
pub mod twin;

pub use asset::{AssetError, FORMAT_VERSION, MAGIC};
pub use fit::{FitError, FitOptions, FitReport, FitRequest, fit};
pub use forearm::{ForearmStudyError, ForearmTwistReport, forearm_twist_study};
pub use import::{ImportError, ImportReport, import_makehuman, import_makehuman_with_report};
pub use measure::{Landmarks, Measure, MeasureError, Measurements};
pub use model::*;
pub use modifiers::{Shape, ShapeError, ShapedBody};
pub use rig::{bone_frame, compute_normals, vec_roll_to_mat3_normalized};
pub use segments::{
    AreaBlend, BodySegment, BodySegmentation, Decay, GirthEdit, MeshGraph, Propagation,
    RoughnessCurve, RoughnessStudy, RoughnessStudyConfig, SegmentEdit, SegmentError, SegmentMorph,
    SegmentTarget, SegmentWeights, StudyTarget, edit_waist_girth, roughness_study,
};
pub use sizing::{
    ChartProblem, FitAtSize, Gender, MeasureAdvice, Placement, RangeCm, Recommendation, Size,
    SizeChart, SizeChartError, SizeRange, recommend, recommend_with,
};
pub use skinning::{RigidTransform, forward_kinematics, skin_positions, skin_with_matrices};
