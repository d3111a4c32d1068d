//! `fitroom body measure` and `fitroom body export`: a shaped MakeHuman body, measured (seed
//! 002 Table 4.1 / ISO 8559-1, convex-hull girths) or written as an OBJ in its rest pose.

use std::{fmt::Write as _, path::Path, time::Instant};

use anyhow::{Context, Result, bail};
use fitroom_body::{BodyModel, Shape, ShapedBody, measure::Measurements};
use serde::Serialize;

/// Reads a shape file (RON), or the default shape when there is none.
pub fn load_shape(path: Option<&Path>) -> Result<Shape> {
    let Some(path) = path else {
        return Ok(Shape::default());
    };
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("cannot read the shape file '{}'", path.display()))?;
    let shape: Shape = ron::from_str(&text).map_err(|e| {
        anyhow::anyhow!(
            "{}:{}:{}: {} (a shape file is a RON struct such as `(gender: 0.0, weight: 0.6, measures: {{\"waist-circ\": -0.3}})`)",
            path.display(),
            e.span.start.line,
            e.span.start.col,
            e.code
        )
    })?;
    shape
        .validate()
        .with_context(|| format!("in the shape file '{}'", path.display()))?;
    Ok(shape)
}

/// The JSON of `fitroom body measure`.
#[derive(Debug, Serialize)]
pub struct MeasureReport {
    pub shape: Shape,
    pub measurements: Measurements,
    /// Time to apply the shape (targets, normals, rest pose), ms.
    pub shape_ms: f64,
    /// Time to measure, ms.
    pub measure_ms: f64,
}

pub fn shaped(model: &BodyModel, shape: &Shape) -> Result<(ShapedBody, f64)> {
    let start = Instant::now();
    let body = model.shaped(shape)?;
    Ok((body, start.elapsed().as_secs_f64() * 1e3))
}

pub fn measure(model: &BodyModel, shape: Shape) -> Result<MeasureReport> {
    let (body, shape_ms) = shaped(model, &shape)?;
    let start = Instant::now();
    let measurements = model.measure(&body.positions)?;
    Ok(MeasureReport {
        shape,
        measurements,
        shape_ms,
        measure_ms: start.elapsed().as_secs_f64() * 1e3,
    })
}

/// Writes the shaped body as Wavefront OBJ: every vertex of the model in its order (metres,
/// +Y up, rest pose), the body's normals, and the body's triangles in group `body`. Helper
/// vertices (tights, joint cubes...) come after the body's and no face uses them; they keep
/// the file re-measurable, since landmarks use the rig's joint cubes.
pub fn write_obj(model: &BodyModel, body: &ShapedBody, out: &Path) -> Result<()> {
    let Some(ext) = out.extension().and_then(|e| e.to_str()) else {
        bail!("'{}': give the output a .obj extension", out.display());
    };
    if !ext.eq_ignore_ascii_case("obj") {
        bail!(
            "'{}': only .obj export exists so far (glTF is planned)",
            out.display()
        );
    }
    let mut text = String::with_capacity(body.positions.len() * 40 + model.triangles.len() * 30);
    let _ = writeln!(
        text,
        "# fitroom body export: MakeHuman hm08 (CC0), metres, +Y up, rest pose\n\
         # {} vertices ({} body, then helpers), {} triangles",
        body.positions.len(),
        model.body_vertex_count,
        model.triangles.len()
    );
    for p in &body.positions {
        let _ = writeln!(text, "v {:.6} {:.6} {:.6}", p.x, p.y, p.z);
    }
    for n in &body.normals {
        let _ = writeln!(text, "vn {:.5} {:.5} {:.5}", n.x, n.y, n.z);
    }
    text.push_str("g body\n");
    for t in &model.triangles {
        let [a, b, c] = t.map(|i| i + 1);
        let _ = writeln!(text, "f {a}//{a} {b}//{b} {c}//{c}");
    }
    if let Some(parent) = out.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(parent)
            .with_context(|| format!("cannot create '{}'", parent.display()))?;
    }
    std::fs::write(out, text).with_context(|| format!("cannot write '{}'", out.display()))?;
    Ok(())
}
