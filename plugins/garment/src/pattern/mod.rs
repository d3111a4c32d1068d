//! Sewing patterns as data files: panels as 2D outlines in cm, seams between panel edges, how
//! each panel is wrapped around the body, which edges are attached to the body, which panels
//! are the static (skinned) part, the fabric, and the sizes the pattern is graded to.
//!
//! # The garment file (RON)
//!
//! ```text
//! Garment(
//!     name: "Skirt",
//!     fabric: "cotton",             // assets/fabrics/cotton.ron (../fabrics/ from the garment)
//!     target_edge_cm: 2.5,          // mesh edge length
//!     size_chart: "../sizecharts/en13402-female-seed002.ron",   // optional
//!     base_size: "40",              // the size the panels below are drafted in
//!     sizes: [                      // smallest first
//!         (label: "38", length_cm: 58),                       // body_cm from the chart
//!         (label: "40", length_cm: 60),
//!         (label: "M", body_cm: {"waist": 70, "hip": 96}),    // or given here
//!     ],
//!     panels: [
//!         (
//!             name: "front",
//!             // Counter-clockwise seen from the garment's outside, x across (toward the
//!             // wearer's left on a front panel), y up, cm. `edge` names the segment from this
//!             // point to the next; a point without `edge` continues the previous name.
//!             outline: [
//!                 (x: -26, y: -60, edge: "hem"),
//!                 (x: 26, y: -60, edge: "side_left"),
//!                 (x: 19, y: 0, edge: "waist"),
//!                 (x: -19, y: 0, edge: "side_right"),
//!             ],
//!             // Horizontal grading: at height y_cm the width scales by the size's girth
//!             // ratio of `measure` to the base size's; linear in between, constant beyond.
//!             grade_width: [(y_cm: -20, measure: "hip"), (y_cm: 0, measure: "waist")],
//!             grade_length: true,   // vertical grading by length_cm / base length_cm
//!         ),
//!     ],
//!     wraps: [
//!         (
//!             name: "skirt",
//!             around: trunk,    // body region: torso | trunk | leg_left | ... | arm_right | body
//!             // The axis: vertical at a landmark height (+ offset), with the panels' y = 0
//!             // there; or Lateral(shoulder_fraction: 0.5) across the shoulder at half the
//!             // shoulder half-width (+X, panels' y across it); or Bone(name: "upperarm_l",
//!             // offset_cm: 3), from the bone's tail to its head, y = 0 at head + offset.
//!             axis: Vertical(landmark: waist, offset_cm: 0),
//!             // Panels around the axis with the angle of their centre line: for a vertical
//!             // axis 0 = front (+Z), 90 = the wearer's left (+X); lateral: 0 = up, 90 = front.
//!             panels: [("front", 0), ("back", 180)],
//!             closed: true,     // the panels go all the way round (side by side, in order)
//!             ease_cm: 1.0,     // smallest distance to the body
//!         ),
//!     ],
//!     seams: [   // pairs of panel edges; `direction: same` when both run the same way
//!         (a: ("front", "side_left"), b: ("back", "side_right")),
//!     ],
//!     attach: [  // vertices pinned to the body: a panel edge, or a whole panel
//!         (panel: "front", edge: "waist", follows: torso),
//!     ],
//!     skinned: [],   // panels that are the static, skinned part (seed 000 §3.2.1)
//!     // Optional: body colliders the garment ignores (e.g. ["hand_l", "hand_r"] for a skirt
//!     // the swinging hands would otherwise catch and drag).
//!     ignore_colliders: [],
//! )
//! ```
//!
//! # Grading
//!
//! Each size of [`Pattern::sizes`] gives body measurements (cm; from `body_cm`, else from the
//! size chart's nominal value or range centre for that label) and optionally the garment
//! length. A panel is graded from the base size by scaling x by `r(y)`, the girth ratio
//! `size / base` of the measure of its `grade_width` rows (piecewise linear in y between the
//! rows), and y (about y = 0, the anchor) by the length ratio when `grade_length` is set. The
//! ease (garment girth minus body girth) thus scales with the girth, within a few percent of
//! constant-ease industrial grading for neighbouring sizes.
//!
//! # Modules
//!
//! - `file`: the garment file as written (RON), before validation.
//! - `read`: reading and validating it into a [`Pattern`] ([`Pattern::load`]).
//! - `validate`: a panel's outline and edges, and the sizes, checked.
//! - `grading`: the panels graded to a size (see [Grading](#grading)).
//! - `outline`: geometry of panel outlines (area, rows, edges).

mod file;
mod grading;
mod outline;
mod read;
mod validate;

use std::collections::BTreeMap;

use fitroom_body::Measure;
use glam::Vec2;
use serde::Deserialize;

use crate::body::{Landmark, Region};
use crate::fabric::FabricSpec;

pub use outline::{edge_polyline, row_extent, y_range};
pub use read::fabric_path;

/// A validated sewing pattern.
#[derive(Clone, Debug, PartialEq)]
pub struct Pattern {
    pub name: String,
    pub description: String,
    /// The file it was read from, and its text (to locate errors found later).
    pub file: String,
    pub source_text: String,
    pub fabric_name: String,
    pub fabric: FabricSpec,
    /// Target mesh edge length, cm.
    pub target_edge_cm: f32,
    /// Index into `sizes` of the size the panels are drafted in.
    pub base_size: usize,
    pub sizes: Vec<GarmentSize>,
    pub panels: Vec<Panel>,
    pub wraps: Vec<Wrap>,
    pub seams: Vec<Seam>,
    pub attach: Vec<Attach>,
    /// Panels of the static, skinned part.
    pub skinned: Vec<usize>,
    /// Body colliders this garment does not collide with (names of
    /// [`fitroom_body::colliders::collider_names`]).
    pub ignore_colliders: Vec<String>,
}

/// One size of a garment.
#[derive(Clone, Debug, PartialEq)]
pub struct GarmentSize {
    pub label: String,
    /// Body measurements this size is made for, cm.
    pub body_cm: BTreeMap<Measure, f32>,
    /// Garment length for vertical grading, cm.
    pub length_cm: Option<f32>,
}

/// A pattern panel: an outline in cm with named edges.
#[derive(Clone, Debug, PartialEq)]
pub struct Panel {
    pub name: String,
    /// Counter-clockwise seen from outside, cm.
    pub outline: Vec<Vec2>,
    /// Named edges, in outline order.
    pub edges: Vec<PanelEdge>,
    /// Horizontal grading rows `(y_cm, measure)`, sorted by y.
    pub grade_width: Vec<(f32, Measure)>,
    pub grade_length: bool,
}

/// A named run of outline segments: from point `start` to point `end` (indices into the
/// outline, going forward and wrapping; `end == start` covers the whole outline).
#[derive(Clone, Debug, PartialEq)]
pub struct PanelEdge {
    pub name: String,
    pub start: usize,
    pub end: usize,
}

/// An axis panels are wrapped around.
#[derive(Clone, Debug, PartialEq, Deserialize)]
pub enum Axis {
    /// Vertical (+Y); the panels' y = 0 at the landmark's height + offset.
    Vertical { landmark: Landmark, offset_cm: f32 },
    /// Across the body (+X) through the shoulders; the panels' y = 0 at
    /// `shoulder_fraction` × half the shoulder width from the midline (negative: the right).
    Lateral { shoulder_fraction: f32 },
    /// Along a bone from its tail to its head; y = 0 at the head + offset.
    Bone { name: String, offset_cm: f32 },
}

/// Panels wrapped around one axis.
#[derive(Clone, Debug, PartialEq)]
pub struct Wrap {
    pub name: String,
    pub around: Region,
    pub axis: Axis,
    /// `(panel index, angle of its centre line in degrees)`, in order around the axis.
    pub panels: Vec<(usize, f32)>,
    pub closed: bool,
    pub ease_cm: f32,
}

/// Which way two sewn edges run relative to each other.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SeamDirection {
    /// `a`'s start meets `b`'s end (two panels both counter-clockwise: the usual case).
    #[default]
    Opposite,
    /// `a`'s start meets `b`'s start.
    Same,
}

/// A panel edge.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct EdgeRef {
    pub panel: usize,
    pub edge: usize,
}

/// Two edges sewn together.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Seam {
    pub a: EdgeRef,
    pub b: EdgeRef,
    pub direction: SeamDirection,
}

/// Vertices pinned to the body.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Attach {
    pub panel: usize,
    /// An edge, or the whole panel.
    pub edge: Option<usize>,
    /// The body region the vertices are bound to.
    pub follows: Region,
}
