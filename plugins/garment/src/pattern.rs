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

use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};

use fitroom_body::Measure;
use fitroom_body::sizing::SizeChart;
use glam::Vec2;
use serde::Deserialize;

use crate::body::{Landmark, Region};
use crate::error::{GarmentError, line_of, read_text, ron_error, ron_options};
use crate::fabric::FabricSpec;

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

// ---------------------------------------------------------------------------------------------
// The file as written.

#[derive(Debug, Deserialize)]
#[serde(rename = "Garment", deny_unknown_fields)]
struct GarmentFile {
    name: String,
    #[serde(default)]
    description: String,
    fabric: String,
    #[serde(default = "default_edge_cm")]
    target_edge_cm: f32,
    #[serde(default)]
    size_chart: Option<String>,
    base_size: String,
    sizes: Vec<SizeFile>,
    panels: Vec<PanelFile>,
    wraps: Vec<WrapFile>,
    #[serde(default)]
    seams: Vec<SeamFile>,
    #[serde(default)]
    attach: Vec<AttachFile>,
    #[serde(default)]
    skinned: Vec<String>,
    #[serde(default)]
    ignore_colliders: Vec<String>,
}

fn default_edge_cm() -> f32 {
    2.5
}

fn default_ease_cm() -> f32 {
    1.0
}

#[derive(Debug, Deserialize)]
#[serde(rename = "Size", deny_unknown_fields)]
struct SizeFile {
    label: String,
    #[serde(default)]
    body_cm: BTreeMap<String, f32>,
    #[serde(default)]
    length_cm: Option<f32>,
}

#[derive(Debug, Deserialize)]
#[serde(rename = "Panel", deny_unknown_fields)]
struct PanelFile {
    name: String,
    outline: Vec<PointFile>,
    #[serde(default)]
    grade_width: Vec<GradeRowFile>,
    #[serde(default)]
    grade_length: bool,
}

#[derive(Debug, Deserialize)]
#[serde(rename = "Point", deny_unknown_fields)]
struct PointFile {
    x: f32,
    y: f32,
    #[serde(default)]
    edge: Option<String>,
}

#[derive(Debug, Deserialize)]
#[serde(rename = "GradeRow", deny_unknown_fields)]
struct GradeRowFile {
    y_cm: f32,
    measure: String,
}

#[derive(Debug, Deserialize)]
#[serde(rename = "Wrap", deny_unknown_fields)]
struct WrapFile {
    name: String,
    around: Region,
    axis: Axis,
    panels: Vec<(String, f32)>,
    #[serde(default)]
    closed: bool,
    #[serde(default = "default_ease_cm")]
    ease_cm: f32,
}

#[derive(Debug, Deserialize)]
#[serde(rename = "Seam", deny_unknown_fields)]
struct SeamFile {
    a: (String, String),
    b: (String, String),
    #[serde(default)]
    direction: SeamDirection,
}

#[derive(Debug, Deserialize)]
#[serde(rename = "Attach", deny_unknown_fields)]
struct AttachFile {
    panel: String,
    #[serde(default)]
    edge: Option<String>,
    follows: Region,
}

/// Builds [`GarmentError::Invalid`] with the line found by [`line_of`].
struct Problems<'a> {
    text: &'a str,
    file: &'a str,
}

impl Problems<'_> {
    fn at(
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

fn quoted(s: &str) -> String {
    format!("\"{s}\"")
}

impl Pattern {
    /// Reads and validates a garment file, its fabric (`<dir>/../fabrics/<fabric>.ron`) and its
    /// size chart, if it names one (relative to the garment file).
    pub fn load(path: impl AsRef<Path>) -> Result<Pattern, GarmentError> {
        let path = path.as_ref();
        let text = read_text(path)?;
        let dir = path.parent().unwrap_or(Path::new("."));
        Self::from_ron_str(&text, &path.display().to_string(), dir)
    }

    /// Parses and validates a garment from RON text; `file` names it in errors and `dir` is the
    /// folder relative paths (fabric, size chart) are resolved against.
    pub fn from_ron_str(text: &str, file: &str, dir: &Path) -> Result<Pattern, GarmentError> {
        let raw: GarmentFile = ron_options()
            .from_str(text)
            .map_err(|e| ron_error(file, text, e))?;
        let problems = Problems { text, file };

        if !(0.5..=20.0).contains(&raw.target_edge_cm) {
            return Err(problems.at(
                &["target_edge_cm"],
                "target_edge_cm",
                format!("is {} cm; accepted 0.5..=20 cm", raw.target_edge_cm),
            ));
        }

        // Fabric.
        let fabric_path = fabric_path(dir, &raw.fabric);
        let fabric = FabricSpec::load(&fabric_path).map_err(|e| match e {
            GarmentError::Read { .. } => problems.at(
                &["fabric"],
                "fabric",
                format!(
                    "no fabric file '{}' for fabric \"{}\"; the fabrics are the .ron files in {}",
                    fabric_path.display(),
                    raw.fabric,
                    fabric_path
                        .parent()
                        .map_or(String::new(), |p| p.display().to_string())
                ),
            ),
            other => other,
        })?;

        // Panels.
        let mut panels = Vec::with_capacity(raw.panels.len());
        let mut panel_index: HashMap<String, usize> = HashMap::new();
        if raw.panels.is_empty() {
            return Err(problems.at(&["panels"], "panels", "is empty; give at least one panel"));
        }
        for (i, p) in raw.panels.iter().enumerate() {
            let name_q = quoted(&p.name);
            let at = |field: &str, problem: String| {
                problems.at(
                    &["panels", &name_q, field],
                    format!("panels[{i}] ({}).{field}", p.name),
                    problem,
                )
            };
            if p.name.trim().is_empty() {
                return Err(problems.at(&["panels"], format!("panels[{i}].name"), "is empty"));
            }
            if panel_index.insert(p.name.clone(), i).is_some() {
                return Err(at(
                    "name",
                    "another panel has this name; panel names must be unique".into(),
                ));
            }
            panels.push(panel_from_file(p, &at)?);
        }
        let find_panel = |name: &str, path: &[&str], field: &str| {
            panel_index.get(name).copied().ok_or_else(|| {
                problems.at(
                    path,
                    field,
                    format!(
                        "no panel \"{name}\"; the panels are: {}",
                        raw.panels
                            .iter()
                            .map(|p| p.name.as_str())
                            .collect::<Vec<_>>()
                            .join(", ")
                    ),
                )
            })
        };
        let find_edge = |panel: usize, edge: &str, path: &[&str], field: &str| {
            panels[panel]
                .edges
                .iter()
                .position(|e| e.name == edge)
                .ok_or_else(|| {
                    problems.at(
                        path,
                        field,
                        format!(
                            "panel \"{}\" has no edge \"{edge}\"; its edges are: {}",
                            panels[panel].name,
                            panels[panel]
                                .edges
                                .iter()
                                .map(|e| e.name.as_str())
                                .collect::<Vec<_>>()
                                .join(", ")
                        ),
                    )
                })
        };

        // Wraps: every panel in exactly one.
        let mut wraps = Vec::with_capacity(raw.wraps.len());
        let mut wrapped: Vec<Option<usize>> = vec![None; panels.len()];
        for (w, wf) in raw.wraps.iter().enumerate() {
            let name_q = quoted(&wf.name);
            if !(0.0..=30.0).contains(&wf.ease_cm) {
                return Err(problems.at(
                    &["wraps", &name_q, "ease_cm"],
                    format!("wraps[{w}] ({}).ease_cm", wf.name),
                    format!("is {} cm; accepted 0..=30 cm", wf.ease_cm),
                ));
            }
            if let Axis::Lateral { shoulder_fraction } = wf.axis
                && !(-1.5..=1.5).contains(&shoulder_fraction)
            {
                return Err(problems.at(
                    &["wraps", &name_q, "shoulder_fraction"],
                    format!("wraps[{w}] ({}).axis.shoulder_fraction", wf.name),
                    format!("is {shoulder_fraction}; accepted -1.5..=1.5 (fraction of half the shoulder width)"),
                ));
            }
            if wf.panels.is_empty() {
                return Err(problems.at(
                    &["wraps", &name_q],
                    format!("wraps[{w}] ({}).panels", wf.name),
                    "is empty",
                ));
            }
            let mut list = Vec::new();
            for (name, angle) in &wf.panels {
                let field = format!("wraps[{w}] ({}).panels", wf.name);
                let p = find_panel(name, &["wraps", &name_q, "panels", &quoted(name)], &field)?;
                if let Some(other) = wrapped[p] {
                    return Err(problems.at(
                        &["wraps", &name_q, "panels", &quoted(name)],
                        field,
                        format!(
                            "panel \"{name}\" is already in wrap \"{}\"; a panel is wrapped once",
                            raw.wraps[other].name
                        ),
                    ));
                }
                if !angle.is_finite() {
                    return Err(problems.at(
                        &["wraps", &name_q, &quoted(name)],
                        field,
                        "the angle is not a number",
                    ));
                }
                wrapped[p] = Some(w);
                list.push((p, *angle));
            }
            wraps.push(Wrap {
                name: wf.name.clone(),
                around: wf.around,
                axis: wf.axis.clone(),
                panels: list,
                closed: wf.closed,
                ease_cm: wf.ease_cm,
            });
        }
        if let Some(p) = wrapped.iter().position(Option::is_none) {
            return Err(problems.at(
                &["panels", &quoted(&panels[p].name)],
                format!("panels[{p}] ({})", panels[p].name),
                "is in no wrap; list it in one of `wraps` so that it can be placed on the body",
            ));
        }

        // Seams.
        let mut seams = Vec::with_capacity(raw.seams.len());
        let mut sewn: HashMap<EdgeRef, usize> = HashMap::new();
        for (s, sf) in raw.seams.iter().enumerate() {
            let mut ends = [EdgeRef { panel: 0, edge: 0 }; 2];
            for (k, (panel, edge)) in [&sf.a, &sf.b].into_iter().enumerate() {
                let side = ["a", "b"][k];
                let (panel_q, edge_q) = (quoted(panel), quoted(edge));
                let path: &[&str] = &["seams", &panel_q, &edge_q];
                let field = format!("seams[{s}].{side}");
                let p = find_panel(panel, path, &field)?;
                let e = find_edge(p, edge, path, &field)?;
                let r = EdgeRef { panel: p, edge: e };
                if let Some(other) = sewn.insert(r, s) {
                    return Err(problems.at(
                        path,
                        field,
                        format!("edge \"{panel}\".\"{edge}\" is already sewn by seams[{other}]; an edge is sewn once"),
                    ));
                }
                ends[k] = r;
            }
            if ends[0] == ends[1] {
                return Err(problems.at(
                    &["seams"],
                    format!("seams[{s}]"),
                    "sews an edge to itself",
                ));
            }
            seams.push(Seam {
                a: ends[0],
                b: ends[1],
                direction: sf.direction,
            });
        }

        // Attachments and the skinned part.
        let mut attach = Vec::with_capacity(raw.attach.len());
        for (a, af) in raw.attach.iter().enumerate() {
            let field = format!("attach[{a}]");
            let p = find_panel(&af.panel, &["attach", &quoted(&af.panel)], &field)?;
            let edge = match &af.edge {
                Some(e) => Some(find_edge(
                    p,
                    e,
                    &["attach", &quoted(&af.panel), &quoted(e)],
                    &field,
                )?),
                None => None,
            };
            attach.push(Attach {
                panel: p,
                edge,
                follows: af.follows,
            });
        }
        let mut skinned = Vec::new();
        for (k, name) in raw.skinned.iter().enumerate() {
            let p = find_panel(name, &["skinned", &quoted(name)], &format!("skinned[{k}]"))?;
            if !skinned.contains(&p) {
                skinned.push(p);
            }
        }

        let known = fitroom_body::colliders::collider_names();
        for (k, name) in raw.ignore_colliders.iter().enumerate() {
            if !known.contains(&name.as_str()) {
                return Err(problems.at(
                    &["ignore_colliders", &quoted(name)],
                    format!("ignore_colliders[{k}]"),
                    format!(
                        "no body collider \"{name}\"; the colliders are: {}",
                        known.join(", ")
                    ),
                ));
            }
        }

        // Sizes.
        let chart = match &raw.size_chart {
            Some(rel) => {
                let path = dir.join(rel);
                Some(SizeChart::load(&path).map_err(|e| {
                    problems.at(
                        &["size_chart"],
                        "size_chart",
                        format!("cannot use the size chart: {e}"),
                    )
                })?)
            }
            None => None,
        };
        let sizes = sizes_from_file(&raw, chart.as_ref(), &problems)?;
        let base_size = sizes
            .iter()
            .position(|s| s.label == raw.base_size)
            .ok_or_else(|| {
                problems.at(
                    &["base_size"],
                    "base_size",
                    format!(
                        "\"{}\" is not one of the sizes: {}",
                        raw.base_size,
                        sizes
                            .iter()
                            .map(|s| s.label.as_str())
                            .collect::<Vec<_>>()
                            .join(", ")
                    ),
                )
            })?;
        // Every size must give what grading needs.
        for (p, panel) in panels.iter().enumerate() {
            for &(_, m) in &panel.grade_width {
                if let Some(s) = sizes.iter().find(|s| !s.body_cm.contains_key(&m)) {
                    return Err(problems.at(
                        &["sizes", &quoted(&s.label)],
                        format!("sizes ({})", s.label),
                        format!(
                            "gives no {m} girth, which panel \"{}\" is graded by; give it in `body_cm` or in the size chart",
                            panels[p].name
                        ),
                    ));
                }
            }
            if panel.grade_length
                && let Some(s) = sizes.iter().find(|s| s.length_cm.is_none())
            {
                return Err(problems.at(
                    &["sizes", &quoted(&s.label)],
                    format!("sizes ({})", s.label),
                    format!(
                        "gives no `length_cm`, which panel \"{}\" is graded by",
                        panels[p].name
                    ),
                ));
            }
        }

        Ok(Pattern {
            name: raw.name,
            description: raw.description,
            file: file.to_owned(),
            source_text: text.to_owned(),
            fabric_name: raw.fabric,
            fabric,
            target_edge_cm: raw.target_edge_cm,
            base_size,
            sizes,
            panels,
            wraps,
            seams,
            attach,
            skinned,
            ignore_colliders: raw.ignore_colliders,
        })
    }

    /// Index of the size labelled `label`.
    pub fn size_index(&self, label: &str) -> Option<usize> {
        self.sizes.iter().position(|s| s.label == label)
    }

    /// The size labels, smallest first.
    pub fn size_labels(&self) -> Vec<&str> {
        self.sizes.iter().map(|s| s.label.as_str()).collect()
    }

    /// The panels graded to size `size` (index into [`Pattern::sizes`]); see the
    /// [module docs](self).
    pub fn graded_panels(&self, size: usize) -> Vec<Panel> {
        let base = &self.sizes[self.base_size];
        let target = &self.sizes[size.min(self.sizes.len() - 1)];
        self.panels
            .iter()
            .map(|panel| {
                let ratio = |m: Measure| match (base.body_cm.get(&m), target.body_cm.get(&m)) {
                    (Some(&b), Some(&t)) if b > 0.0 => t / b,
                    _ => 1.0,
                };
                let rows: Vec<(f32, f32)> = panel
                    .grade_width
                    .iter()
                    .map(|&(y, m)| (y, ratio(m)))
                    .collect();
                let length = match (panel.grade_length, base.length_cm, target.length_cm) {
                    (true, Some(b), Some(t)) if b > 0.0 => t / b,
                    _ => 1.0,
                };
                let outline = panel
                    .outline
                    .iter()
                    .map(|p| Vec2::new(p.x * width_ratio(&rows, p.y), p.y * length))
                    .collect();
                Panel {
                    outline,
                    ..panel.clone()
                }
            })
            .collect()
    }
}

/// The horizontal grading ratio at height `y`: piecewise linear between the rows, constant
/// beyond them, 1 without rows.
fn width_ratio(rows: &[(f32, f32)], y: f32) -> f32 {
    match rows {
        [] => 1.0,
        [(_, r)] => *r,
        _ => {
            if y <= rows[0].0 {
                return rows[0].1;
            }
            for w in rows.windows(2) {
                let ((y0, r0), (y1, r1)) = (w[0], w[1]);
                if y <= y1 {
                    let t = if y1 > y0 { (y - y0) / (y1 - y0) } else { 1.0 };
                    return r0 + (r1 - r0) * t;
                }
            }
            rows[rows.len() - 1].1
        }
    }
}

/// `<dir>/../fabrics/<name>.ron`, or `name` itself when it is a path to a `.ron` file.
pub fn fabric_path(dir: &Path, name: &str) -> PathBuf {
    if name.ends_with(".ron") {
        dir.join(name)
    } else {
        dir.join("..").join("fabrics").join(format!("{name}.ron"))
    }
}

fn panel_from_file(
    p: &PanelFile,
    at: &dyn Fn(&str, String) -> GarmentError,
) -> Result<Panel, GarmentError> {
    if p.outline.len() < 3 {
        return Err(at(
            "outline",
            format!("has {} points; a panel needs at least 3", p.outline.len()),
        ));
    }
    let outline: Vec<Vec2> = p.outline.iter().map(|q| Vec2::new(q.x, q.y)).collect();
    if let Some(k) = outline
        .iter()
        .position(|q| !q.is_finite() || q.abs().max_element() > 500.0)
    {
        return Err(at(
            "outline",
            format!(
                "point {k} {:?} is not a number or beyond ±500 cm",
                outline[k]
            ),
        ));
    }
    let n = outline.len();
    for k in 0..n {
        if outline[k].distance(outline[(k + 1) % n]) < 0.05 {
            return Err(at(
                "outline",
                format!(
                    "points {k} and {} coincide (closer than 0.5 mm)",
                    (k + 1) % n
                ),
            ));
        }
    }
    let area = signed_area(&outline);
    if area <= 0.0 {
        return Err(at(
            "outline",
            format!(
                "runs clockwise (signed area {area:.1} cm²); list the points counter-clockwise as seen \
                 from the garment's outside (x across, y up)"
            ),
        ));
    }
    if let Some((i, j)) = self_intersection(&outline) {
        return Err(at(
            "outline",
            format!("segments {i} and {j} cross; the outline must be a simple polygon"),
        ));
    }
    // Edge names: a point without `edge` continues the previous segment's name.
    let mut names: Vec<String> = Vec::with_capacity(n);
    let first = p.outline.iter().position(|q| q.edge.is_some());
    let mut current = match first {
        // The run that wraps around the outline's end carries the last given name.
        Some(_) => p
            .outline
            .iter()
            .rev()
            .find_map(|q| q.edge.clone())
            .unwrap_or_default(),
        None => "outline".to_owned(),
    };
    for q in &p.outline {
        if let Some(e) = &q.edge {
            current = e.clone();
        }
        names.push(current.clone());
    }
    let mut edges: Vec<PanelEdge> = Vec::new();
    if names.iter().all(|s| *s == names[0]) {
        edges.push(PanelEdge {
            name: names[0].clone(),
            start: 0,
            end: 0,
        });
    } else {
        // Runs start where the name changes.
        for k in 0..n {
            if names[k] != names[(k + n - 1) % n] {
                let mut end = (k + 1) % n;
                while names[end] == names[k] {
                    end = (end + 1) % n;
                }
                if edges.iter().any(|e| e.name == names[k]) {
                    return Err(at(
                        "outline",
                        format!(
                            "edge \"{}\" is named on two separate runs of segments; name each edge once",
                            names[k]
                        ),
                    ));
                }
                edges.push(PanelEdge {
                    name: names[k].clone(),
                    start: k,
                    end,
                });
            }
        }
        edges.sort_by_key(|e| e.start);
    }
    let mut grade_width = Vec::with_capacity(p.grade_width.len());
    for row in &p.grade_width {
        let m = Measure::from_name(&row.measure).ok_or_else(|| {
            at(
                "grade_width",
                format!(
                    "unknown measure \"{}\"; known: {}",
                    row.measure,
                    Measure::names()
                ),
            )
        })?;
        if !row.y_cm.is_finite() {
            return Err(at("grade_width", "y_cm is not a number".into()));
        }
        grade_width.push((row.y_cm, m));
    }
    grade_width.sort_by(|a, b| a.0.total_cmp(&b.0));
    Ok(Panel {
        name: p.name.clone(),
        outline,
        edges,
        grade_width,
        grade_length: p.grade_length,
    })
}

fn sizes_from_file(
    raw: &GarmentFile,
    chart: Option<&SizeChart>,
    problems: &Problems,
) -> Result<Vec<GarmentSize>, GarmentError> {
    if raw.sizes.is_empty() {
        return Err(problems.at(
            &["sizes"],
            "sizes",
            "is empty; list at least one size, smallest first",
        ));
    }
    let mut sizes: Vec<GarmentSize> = Vec::with_capacity(raw.sizes.len());
    for (k, sf) in raw.sizes.iter().enumerate() {
        let path = ["sizes", &quoted(&sf.label)];
        let field = format!("sizes[{k}] ({})", sf.label);
        if sf.label.trim().is_empty() {
            return Err(problems.at(&["sizes"], format!("sizes[{k}].label"), "is empty"));
        }
        if sizes.iter().any(|s| s.label == sf.label) {
            return Err(problems.at(
                &path,
                field,
                "another size has this label; labels must be unique",
            ));
        }
        let mut body_cm = BTreeMap::new();
        if let Some(size) = chart.and_then(|c| c.size(&sf.label)) {
            for (m, range) in &size.ranges_cm {
                let v = size.nominal_cm.get(m).copied().unwrap_or(range.centre_cm());
                body_cm.insert(*m, v);
            }
        }
        for (name, &v) in &sf.body_cm {
            let m = Measure::from_name(name).ok_or_else(|| {
                problems.at(
                    &path,
                    field.clone(),
                    format!("unknown measure \"{name}\"; known: {}", Measure::names()),
                )
            })?;
            let (lo, hi) = m.plausible_range_cm();
            if !(lo..=hi).contains(&v) {
                return Err(problems.at(
                    &path,
                    field.clone(),
                    format!("{m} is {v} cm, outside the accepted {lo}..={hi} cm (values in cm)"),
                ));
            }
            body_cm.insert(m, v);
        }
        if let Some(l) = sf.length_cm
            && !(5.0..=250.0).contains(&l)
        {
            return Err(problems.at(
                &path,
                field,
                format!("length_cm is {l}; accepted 5..=250 cm"),
            ));
        }
        if body_cm.is_empty() && chart.is_some() && sf.body_cm.is_empty() {
            return Err(problems.at(
                &path,
                field,
                "the size chart has no size with this label and `body_cm` is not given",
            ));
        }
        sizes.push(GarmentSize {
            label: sf.label.clone(),
            body_cm,
            length_cm: sf.length_cm,
        });
    }
    Ok(sizes)
}

/// Twice-free signed area (positive counter-clockwise), cm².
pub(crate) fn signed_area(poly: &[Vec2]) -> f32 {
    let n = poly.len();
    0.5 * (0..n)
        .map(|i| poly[i].perp_dot(poly[(i + 1) % n]))
        .sum::<f32>()
}

/// The first pair of non-adjacent segments that intersect, if any.
fn self_intersection(poly: &[Vec2]) -> Option<(usize, usize)> {
    let n = poly.len();
    for i in 0..n {
        for j in i + 1..n {
            if j == i + 1 || (i == 0 && j == n - 1) {
                continue;
            }
            let (a, b) = (poly[i], poly[(i + 1) % n]);
            let (c, d) = (poly[j], poly[(j + 1) % n]);
            if segments_intersect(a, b, c, d) {
                return Some((i, j));
            }
        }
    }
    None
}

fn segments_intersect(a: Vec2, b: Vec2, c: Vec2, d: Vec2) -> bool {
    let o = |p: Vec2, q: Vec2, r: Vec2| (q - p).perp_dot(r - p);
    let (d1, d2) = (o(c, d, a), o(c, d, b));
    let (d3, d4) = (o(a, b, c), o(a, b, d));
    ((d1 > 0.0) != (d2 > 0.0))
        && ((d3 > 0.0) != (d4 > 0.0))
        && d1 != 0.0
        && d2 != 0.0
        && d3 != 0.0
        && d4 != 0.0
}

/// The horizontal extent `(min x, max x)` of the outline at height `y` (its row), or `None`
/// when `y` is outside the outline's vertical range.
pub fn row_extent(outline: &[Vec2], y: f32) -> Option<(f32, f32)> {
    let n = outline.len();
    let mut lo = f32::INFINITY;
    let mut hi = f32::NEG_INFINITY;
    for i in 0..n {
        let (a, b) = (outline[i], outline[(i + 1) % n]);
        if y < a.y.min(b.y) || y > a.y.max(b.y) {
            continue;
        }
        if (b.y - a.y).abs() < 1e-6 {
            lo = lo.min(a.x.min(b.x));
            hi = hi.max(a.x.max(b.x));
        } else {
            let x = a.x + (b.x - a.x) * (y - a.y) / (b.y - a.y);
            lo = lo.min(x);
            hi = hi.max(x);
        }
    }
    (lo <= hi).then_some((lo, hi))
}

/// The outline's vertical range `(min y, max y)`.
pub fn y_range(outline: &[Vec2]) -> (f32, f32) {
    outline
        .iter()
        .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(p.y), hi.max(p.y))
        })
}

/// The points of an edge's polyline, from its start point to its end point inclusive.
pub fn edge_polyline(outline: &[Vec2], edge: &PanelEdge) -> Vec<Vec2> {
    let n = outline.len();
    let mut out = vec![outline[edge.start]];
    let mut k = edge.start;
    loop {
        k = (k + 1) % n;
        out.push(outline[k]);
        if k == edge.end {
            break;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn width_ratio_interpolates() {
        let rows = [(0.0, 1.0), (10.0, 2.0)];
        assert_eq!(width_ratio(&rows, -5.0), 1.0);
        assert_eq!(width_ratio(&rows, 5.0), 1.5);
        assert_eq!(width_ratio(&rows, 20.0), 2.0);
        assert_eq!(width_ratio(&[], 3.0), 1.0);
    }

    #[test]
    fn row_extent_of_a_trapezoid() {
        let poly = [
            Vec2::new(-20.0, -10.0),
            Vec2::new(20.0, -10.0),
            Vec2::new(10.0, 0.0),
            Vec2::new(-10.0, 0.0),
        ];
        assert_eq!(row_extent(&poly, -5.0), Some((-15.0, 15.0)));
        assert_eq!(row_extent(&poly, 0.0), Some((-10.0, 10.0)));
        assert_eq!(row_extent(&poly, 1.0), None);
        assert!(signed_area(&poly) > 0.0);
        assert_eq!(self_intersection(&poly), None);
    }
}
