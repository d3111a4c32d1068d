//! `fitroom body measure|fit|size|export|ansur`: a shaped MakeHuman body, measured (seed 002
//! Table 4.1 / ISO 8559-1, convex-hull girths), fitted to measurements, sized against a size
//! chart, written as OBJ or glb in its rest pose, and the fit evaluated on ANSUR II.

use std::{fmt::Write as _, path::Path, time::Instant};

use anyhow::{Context, Result, bail};
use fitroom_body::{
    BodyModel, FitOptions, FitReport, FitRequest, Measure, Recommendation, Shape, ShapedBody,
    SizeChart,
    ansur::AnsurReport,
    measure::Measurements,
    segments::{BodySegment, Decay, RoughnessStudy, RoughnessStudyConfig},
};
use glam::Vec3;
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

/// The measurement flags of `fitroom body fit` (cm).
#[derive(Debug, Default, Clone, clap::Args)]
pub struct MeasurementArgs {
    #[arg(long)]
    pub stature: Option<f32>,
    /// Crotch height.
    #[arg(long)]
    pub inside_leg: Option<f32>,
    #[arg(long)]
    pub arm_length: Option<f32>,
    /// Biacromial breadth.
    #[arg(long)]
    pub shoulder_width: Option<f32>,
    /// Neck base girth.
    #[arg(long)]
    pub neck: Option<f32>,
    /// Bust (or chest) girth.
    #[arg(long, alias = "chest")]
    pub bust: Option<f32>,
    #[arg(long)]
    pub underbust: Option<f32>,
    /// Natural waist girth (EN 13402, the narrowest).
    #[arg(long)]
    pub waist: Option<f32>,
    /// Waist girth at the navel (ANSUR II's waist).
    #[arg(long)]
    pub navel_waist: Option<f32>,
    #[arg(long, alias = "hips")]
    pub hip: Option<f32>,
    #[arg(long)]
    pub thigh: Option<f32>,
    #[arg(long)]
    pub calf: Option<f32>,
}

impl MeasurementArgs {
    pub fn targets(&self) -> std::collections::BTreeMap<Measure, f32> {
        [
            (Measure::Stature, self.stature),
            (Measure::InsideLeg, self.inside_leg),
            (Measure::ArmLength, self.arm_length),
            (Measure::ShoulderWidth, self.shoulder_width),
            (Measure::Neck, self.neck),
            (Measure::Bust, self.bust),
            (Measure::Underbust, self.underbust),
            (Measure::Waist, self.waist),
            (Measure::NavelWaist, self.navel_waist),
            (Measure::Hip, self.hip),
            (Measure::Thigh, self.thigh),
            (Measure::Calf, self.calf),
        ]
        .into_iter()
        .filter_map(|(m, v)| v.map(|v| (m, v)))
        .collect()
    }
}

/// Parses `female`/`male` (or a 0..=1 slider value) into MakeHuman's gender slider.
pub fn parse_gender(text: &str) -> Result<f32> {
    match text.trim().to_ascii_lowercase().as_str() {
        "female" | "f" | "woman" => Ok(0.0),
        "male" | "m" | "man" => Ok(1.0),
        other => match other.parse::<f32>() {
            Ok(v) if (0.0..=1.0).contains(&v) => Ok(v),
            _ => bail!("--gender '{text}': use female or male (or a MakeHuman gender value 0..=1)"),
        },
    }
}

/// `fitroom body fit`: fits, optionally saves the shape, and returns the report.
pub fn fit(
    model: &BodyModel,
    gender: f32,
    age_years: Option<f32>,
    measurements: &MeasurementArgs,
    out: Option<&Path>,
) -> Result<FitReport> {
    let request = FitRequest {
        gender,
        age_years,
        targets: measurements.targets(),
    };
    if request.targets.is_empty() {
        bail!(
            "give at least one measurement to fit, in cm: --stature, --inside-leg, --arm-length, \
             --shoulder-width, --neck, --bust, --underbust, --waist, --navel-waist, --hip, \
             --thigh, --calf"
        );
    }
    let report = fitroom_body::fit(model, &request, &FitOptions::default())?;
    if let Some(out) = out {
        let text = ron::ser::to_string_pretty(&report.shape, ron::ser::PrettyConfig::default())
            .context("cannot write the shape as RON")?;
        std::fs::write(out, text + "\n")
            .with_context(|| format!("cannot write the shape file '{}'", out.display()))?;
    }
    Ok(report)
}

/// A fit report as a table for people.
pub fn fit_table(r: &FitReport) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{:<16}{:>10}{:>10}{:>10}",
        "measure", "target", "achieved", "error"
    );
    for (m, t) in &r.targets {
        let a = m.of(&r.achieved);
        let flag = if (a - t).abs() > r.tolerance_cm {
            "  out of reach"
        } else {
            ""
        };
        let _ = writeln!(
            s,
            "{:<16}{:>10.1}{:>10.1}{:>+10.2}{flag}",
            m.name(),
            t,
            a,
            a - t
        );
    }
    let _ = writeln!(
        s,
        "{} in {:.0} ms ({} full measurements, {} steps, {} trial bodies)",
        if r.reachable {
            format!("reached within {} cm", r.tolerance_cm)
        } else {
            "NOT reachable by the model: the closest body is shown".to_owned()
        },
        r.time_ms,
        r.outer_iterations,
        r.iterations,
        r.evaluations
    );
    if !r.at_bounds.is_empty() {
        let _ = writeln!(s, "sliders at their limits: {}", r.at_bounds.join(", "));
    }
    s
}

/// `fitroom body size`: the recommendation of `chart` for the body of `shape`.
pub fn size(model: &BodyModel, chart: &Path, shape: Shape) -> Result<SizeAnswer> {
    let chart = SizeChart::load(chart)?;
    let report = measure(model, shape)?;
    let recommendation = fitroom_body::recommend(&chart, &report.measurements);
    Ok(SizeAnswer {
        chart: chart.name.clone(),
        measurements: report.measurements,
        recommendation,
    })
}

/// The JSON of `fitroom body size`.
#[derive(Debug, Serialize)]
pub struct SizeAnswer {
    pub chart: String,
    pub measurements: Measurements,
    pub recommendation: Recommendation,
}

/// Writes the shaped body as binary glTF 2.0 (`.glb`): one mesh with positions (metres, +Y
/// up, rest pose) and normals of the body vertices and its triangles.
pub fn write_glb(model: &BodyModel, body: &ShapedBody, out: &Path) -> Result<()> {
    let n = model.body_vertex_count as usize;
    let positions = &body.positions[..n];
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for p in positions {
        lo = lo.min(*p);
        hi = hi.max(*p);
    }
    let mut bin: Vec<u8> = Vec::with_capacity(n * 24 + model.triangles.len() * 12);
    for p in positions {
        for c in p.to_array() {
            bin.extend_from_slice(&c.to_le_bytes());
        }
    }
    for v in &body.normals[..n] {
        for c in v.to_array() {
            bin.extend_from_slice(&c.to_le_bytes());
        }
    }
    for t in &model.triangles {
        for i in t {
            bin.extend_from_slice(&i.to_le_bytes());
        }
    }
    let (pos_len, idx_len) = (n * 12, model.triangles.len() * 12);
    let json = serde_json::json!({
        "asset": {"version": "2.0", "generator": "fitroom body export (MakeHuman hm08, CC0)"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0, "name": "body"}],
        "meshes": [{"name": "body", "primitives": [{
            "attributes": {"POSITION": 0, "NORMAL": 1}, "indices": 2, "mode": 4
        }]}],
        "buffers": [{"byteLength": bin.len()}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": pos_len, "target": 34962},
            {"buffer": 0, "byteOffset": pos_len, "byteLength": pos_len, "target": 34962},
            {"buffer": 0, "byteOffset": 2 * pos_len, "byteLength": idx_len, "target": 34963}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": n, "type": "VEC3",
             "min": lo.to_array(), "max": hi.to_array()},
            {"bufferView": 1, "componentType": 5126, "count": n, "type": "VEC3"},
            {"bufferView": 2, "componentType": 5125, "count": model.triangles.len() * 3, "type": "SCALAR"}
        ]
    });
    let mut json = serde_json::to_vec(&json)?;
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut glb: Vec<u8> = Vec::with_capacity(total);
    glb.extend_from_slice(b"glTF");
    glb.extend_from_slice(&2u32.to_le_bytes());
    glb.extend_from_slice(&(total as u32).to_le_bytes());
    glb.extend_from_slice(&(json.len() as u32).to_le_bytes());
    glb.extend_from_slice(b"JSON");
    glb.extend_from_slice(&json);
    glb.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    glb.extend_from_slice(b"BIN\0");
    glb.extend_from_slice(&bin);
    if let Some(parent) = out.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(parent)
            .with_context(|| format!("cannot create '{}'", parent.display()))?;
    }
    std::fs::write(out, glb).with_context(|| format!("cannot write '{}'", out.display()))?;
    Ok(())
}

/// Writes `body` as OBJ or glb, by the extension of `out`.
pub fn export(model: &BodyModel, body: &ShapedBody, out: &Path) -> Result<()> {
    match out
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .as_deref()
    {
        Some("obj") => write_obj(model, body, out),
        Some("glb") => write_glb(model, body, out),
        _ => bail!(
            "'{}': give the output a .obj or .glb extension",
            out.display()
        ),
    }
}

/// `fitroom body ansur`: fits ANSUR II subjects and summarises the errors.
pub fn ansur(
    model: &BodyModel,
    data: &Path,
    per_sex: Option<usize>,
    seed: u64,
    threads: usize,
) -> Result<AnsurReport> {
    let mut subjects = Vec::new();
    for all in fitroom_body::ansur::read_survey(data)? {
        subjects.extend(match per_sex {
            Some(n) => fitroom_body::ansur::sample(&all, n, seed),
            None => all,
        });
    }
    let bar = indicatif::ProgressBar::new(subjects.len() as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "fitting {pos}/{len} [{bar:40}] {per_sec} eta {eta}",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    let report = fitroom_body::ansur::evaluate(
        model,
        &subjects,
        &FitOptions::default(),
        threads,
        &|done, _| bar.set_position(done as u64),
    );
    bar.finish_and_clear();
    Ok(report)
}

/// The report of `fitroom body ansur` as Markdown (without the per-subject list).
pub fn ansur_markdown(r: &AnsurReport, title: &str) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "### {title}\n\n{} subjects, {} (subject, measurement) pairs: **{:.1}%** within ±{} cm; \
         {} subjects with every measurement within; {} failed fits; fit time mean {:.0} ms, \
         max {:.0} ms.\n",
        r.subjects,
        r.pairs,
        100.0 * r.pairs_within_tolerance,
        r.tolerance_cm,
        r.subjects_reachable,
        r.failed_fits,
        r.mean_fit_ms,
        r.max_fit_ms
    );
    let _ = writeln!(
        s,
        "| measure | within ±{} cm | median abs cm | p90 | p95 | max | bias cm |\n|---|---|---|---|---|---|---|",
        r.tolerance_cm
    );
    for m in &r.per_measure {
        let _ = writeln!(
            s,
            "| {} | {:.1}% | {:.2} | {:.2} | {:.2} | {:.1} | {:+.2} |",
            m.measure.name(),
            100.0 * m.within_tolerance,
            m.median_abs_cm,
            m.p90_abs_cm,
            m.p95_abs_cm,
            m.max_abs_cm,
            m.bias_cm
        );
    }
    let _ = writeln!(s, "\n|abs error| histogram (cm: pairs): {}", {
        r.histogram_abs_cm
            .iter()
            .map(|(b, c)| {
                if *b >= 2.0 {
                    format!(">2.0: {c}")
                } else {
                    format!("{b:.1}: {c}")
                }
            })
            .collect::<Vec<_>>()
            .join(", ")
    });
    s
}

/// `fitroom body roughness`: seed 002 Figures 7.3-7.5 as data (and a plot): the roughness of
/// the waist/chest region against the interpolation amount, per propagation depth.
pub fn roughness(model: &BodyModel) -> Result<RoughnessStudy> {
    Ok(fitroom_body::segments::roughness_study(
        model,
        &RoughnessStudyConfig::default(),
    )?)
}

/// Draws the Gaussian-decay curves of `study`: one panel per interpolation (first segment,
/// second, both), one line per propagation depth.
pub fn plot_roughness(study: &RoughnessStudy, path: &Path) -> Result<()> {
    use plotters::prelude::*;
    plotters::style::register_font(
        "sans-serif",
        FontStyle::Normal,
        epaint_default_fonts::UBUNTU_LIGHT,
    )
    .map_err(|_| anyhow::anyhow!("cannot load the plot font"))?;
    let draw = |e: DrawingAreaErrorKind<_>| anyhow::anyhow!("cannot draw the plot: {e:?}");
    let root = BitMapBackend::new(path, (1500, 520)).into_drawing_area();
    root.fill(&WHITE).map_err(draw)?;
    let (title, body) = root.split_vertically(44);
    title
        .titled(
            &format!(
                "Roughness (mean Laplacian distance) vs interpolation, Gaussian propagation \
                 (seed 002 Figs. 7.3-7.5); {} vertices around the {} and {} cores",
                study.region_vertex_count, study.segments[0], study.segments[1]
            ),
            ("sans-serif", 20),
        )
        .map_err(draw)?;
    let panels = body.split_evenly((1, 3));
    let [a, b] = study.segments;
    let interpolations: [Vec<BodySegment>; 3] = [vec![a], vec![b], vec![a, b]];
    let curves: Vec<&fitroom_body::segments::RoughnessCurve> = study
        .curves
        .iter()
        .filter(|c| c.decay == Decay::Gaussian)
        .collect();
    let (lo, hi) = curves
        .iter()
        .flat_map(|c| c.roughness_mm.iter())
        .fold((f32::MAX, f32::MIN), |(l, h), &v| (l.min(v), h.max(v)));
    if lo > hi {
        bail!("the roughness study has no Gaussian curves");
    }
    let pad = (hi - lo) * 0.08;
    let palette = [
        RGBColor(200, 60, 50),
        RGBColor(230, 150, 30),
        RGBColor(60, 160, 80),
        RGBColor(40, 110, 200),
        RGBColor(120, 60, 170),
        RGBColor(40, 40, 40),
    ];
    for (panel, interpolated) in panels.iter().zip(&interpolations) {
        let names: Vec<&str> = interpolated.iter().map(|s| s.name()).collect();
        let mut chart = ChartBuilder::on(panel)
            .caption(
                format!("interpolated: {}", names.join(" + ")),
                ("sans-serif", 18),
            )
            .margin(10)
            .x_label_area_size(36)
            .y_label_area_size(56)
            .build_cartesian_2d(0f32..1f32, (lo - pad)..(hi + pad))
            .map_err(draw)?;
        chart
            .configure_mesh()
            .x_desc("interpolation amount u")
            .y_desc("roughness (mm)")
            .light_line_style(WHITE)
            .label_style(("sans-serif", 14))
            .draw()
            .map_err(draw)?;
        for (k, c) in curves
            .iter()
            .filter(|c| &c.interpolated == interpolated)
            .enumerate()
        {
            let color = palette[k % palette.len()];
            let points: Vec<(f32, f32)> = study
                .amounts
                .iter()
                .copied()
                .zip(c.roughness_mm.iter().copied())
                .collect();
            let label = if c.depth == 0 {
                "depth 0 (hard segment)".to_owned()
            } else {
                format!("depth {}", c.depth)
            };
            chart
                .draw_series(LineSeries::new(points, color.stroke_width(2)))
                .map_err(draw)?
                .label(label)
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 22, y)], color.stroke_width(3))
                });
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperLeft)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font(("sans-serif", 14))
            .draw()
            .map_err(draw)?;
    }
    root.present()
        .with_context(|| format!("cannot write the plot '{}'", path.display()))?;
    Ok(())
}
