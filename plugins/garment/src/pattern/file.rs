//! The garment file as written (RON, read with serde), before [`super::read`] validates it
//! into a [`super::Pattern`]; the format is described in the [module docs](super).

use std::collections::BTreeMap;

use serde::Deserialize;

use crate::body::Region;
use crate::error::{GarmentError, line_of};

use super::{Axis, SeamDirection};

#[derive(Debug, Deserialize)]
#[serde(rename = "Garment", deny_unknown_fields)]
pub(super) struct GarmentFile {
    pub(super) name: String,
    #[serde(default)]
    pub(super) description: String,
    pub(super) fabric: String,
    #[serde(default = "default_edge_cm")]
    pub(super) target_edge_cm: f32,
    #[serde(default)]
    pub(super) size_chart: Option<String>,
    pub(super) base_size: String,
    pub(super) sizes: Vec<SizeFile>,
    pub(super) panels: Vec<PanelFile>,
    pub(super) wraps: Vec<WrapFile>,
    #[serde(default)]
    pub(super) seams: Vec<SeamFile>,
    #[serde(default)]
    pub(super) attach: Vec<AttachFile>,
    #[serde(default)]
    pub(super) skinned: Vec<String>,
    #[serde(default)]
    pub(super) ignore_colliders: Vec<String>,
}

fn default_edge_cm() -> f32 {
    2.5
}

fn default_ease_cm() -> f32 {
    1.0
}

#[derive(Debug, Deserialize)]
#[serde(rename = "Size", deny_unknown_fields)]
pub(super) struct SizeFile {
    pub(super) label: String,
    #[serde(default)]
    pub(super) body_cm: BTreeMap<String, f32>,
    #[serde(default)]
    pub(super) length_cm: Option<f32>,
}

#[derive(Debug, Deserialize)]
#[serde(rename = "Panel", deny_unknown_fields)]
pub(super) struct PanelFile {
    pub(super) name: String,
    pub(super) outline: Vec<PointFile>,
    #[serde(default)]
    pub(super) grade_width: Vec<GradeRowFile>,
    #[serde(default)]
    pub(super) grade_length: bool,
}

#[derive(Debug, Deserialize)]
#[serde(rename = "Point", deny_unknown_fields)]
pub(super) struct PointFile {
    pub(super) x: f32,
    pub(super) y: f32,
    #[serde(default)]
    pub(super) edge: Option<String>,
}

#[derive(Debug, Deserialize)]
#[serde(rename = "GradeRow", deny_unknown_fields)]
pub(super) struct GradeRowFile {
    pub(super) y_cm: f32,
    pub(super) measure: String,
}

#[derive(Debug, Deserialize)]
#[serde(rename = "Wrap", deny_unknown_fields)]
pub(super) struct WrapFile {
    pub(super) name: String,
    pub(super) around: Region,
    pub(super) axis: Axis,
    pub(super) panels: Vec<(String, f32)>,
    #[serde(default)]
    pub(super) closed: bool,
    #[serde(default = "default_ease_cm")]
    pub(super) ease_cm: f32,
}

#[derive(Debug, Deserialize)]
#[serde(rename = "Seam", deny_unknown_fields)]
pub(super) struct SeamFile {
    pub(super) a: (String, String),
    pub(super) b: (String, String),
    #[serde(default)]
    pub(super) direction: SeamDirection,
}

#[derive(Debug, Deserialize)]
#[serde(rename = "Attach", deny_unknown_fields)]
pub(super) struct AttachFile {
    pub(super) panel: String,
    #[serde(default)]
    pub(super) edge: Option<String>,
    pub(super) follows: Region,
}

/// Builds [`GarmentError::Invalid`] with the line found by [`line_of`].
pub(super) struct Problems<'a> {
    pub(super) text: &'a str,
    pub(super) file: &'a str,
}

impl Problems<'_> {
    pub(super) fn at(
        &self,
        path: &[&str],
        field: impl Into<String>,
        problem: impl Into<String>,
    ) -> GarmentError {
        GarmentError::Invalid {
            file: self.file.to_owned(),
            line: line_of(self.text, path),
            field: field.into(),
            problem: problem.into(),
        }
    }
}

pub(super) fn quoted(s: &str) -> String {
    format!("\"{s}\"")
}
