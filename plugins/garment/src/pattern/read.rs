//! Reading a garment file (RON) and validating it into a [`Pattern`]: every name resolved,
//! every panel wrapped, seams and attachments checked, the fabric and size chart read (sizes
//! from a size chart as in seed 002, EN 13402), each error with its file, line and field.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use crate::error::{GarmentError, ron_error, ron_options};
use crate::fabric::FabricSpec;
use crate::files::{DiskFiles, GarmentFiles};
use fitroom_body::sizing::SizeChart;

use super::file::{GarmentFile, Problems, quoted};
use super::validate::{panel_from_file, sizes_from_file};
use super::{Attach, Axis, EdgeRef, Pattern, Seam, Wrap};

impl Pattern {
    /// Reads and validates a garment file, its fabric (`<dir>/../fabrics/<fabric>.ron`) and its
    /// size chart, if it names one (relative to the garment file).
    pub fn load(path: impl AsRef<Path>) -> Result<Pattern, GarmentError> {
        Self::load_with(path.as_ref(), &DiskFiles)
    }

    /// [`Pattern::load`] with the garment file and the files it names read from `files`.
    pub fn load_with(path: &Path, files: &dyn GarmentFiles) -> Result<Pattern, GarmentError> {
        let text = files.read_text(path)?;
        let dir = path.parent().unwrap_or(Path::new("."));
        Self::from_ron_str_with(&text, &path.display().to_string(), dir, files)
    }

    /// Parses and validates a garment from RON text; `file` names it in errors and `dir` is the
    /// folder relative paths (fabric, size chart) are resolved against.
    pub fn from_ron_str(text: &str, file: &str, dir: &Path) -> Result<Pattern, GarmentError> {
        Self::from_ron_str_with(text, file, dir, &DiskFiles)
    }

    /// [`Pattern::from_ron_str`] with the fabric and size chart read from `files`.
    pub fn from_ron_str_with(
        text: &str,
        file: &str,
        dir: &Path,
        files: &dyn GarmentFiles,
    ) -> Result<Pattern, GarmentError> {
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
        let fabric = files
            .read_text(&fabric_path)
            .and_then(|text| FabricSpec::from_ron_str(&text, &fabric_path.display().to_string()))
            .map_err(|e| {
                match e {
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
        }
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
                let chart = files
                    .read_text(&path)
                    .map_err(|e| e.to_string())
                    .and_then(|text| {
                        SizeChart::from_ron_str(&text, &path.display().to_string())
                            .map_err(|e| e.to_string())
                    });
                Some(chart.map_err(|e| {
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
}

/// `<dir>/../fabrics/<name>.ron`, or `name` itself when it is a path to a `.ron` file.
pub fn fabric_path(dir: &Path, name: &str) -> PathBuf {
    if name.ends_with(".ron") {
        dir.join(name)
    } else {
        dir.join("..").join("fabrics").join(format!("{name}.ron"))
    }
}
