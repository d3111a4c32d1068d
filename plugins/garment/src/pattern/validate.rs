//! Validation of the parts of a garment file: a panel's outline (enough distinct points,
//! counter-clockwise, simple) and its named edges and grading rows, and the sizes (labels,
//! body measurements from the file or the size chart, lengths).

use std::collections::BTreeMap;

use fitroom_body::Measure;
use fitroom_body::sizing::SizeChart;
use glam::Vec2;

use crate::error::GarmentError;

use super::file::{GarmentFile, PanelFile, Problems, quoted};
use super::outline::{self_intersection, signed_area};
use super::{GarmentSize, Panel, PanelEdge};

pub(super) fn panel_from_file(
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

pub(super) fn sizes_from_file(
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
