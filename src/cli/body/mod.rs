//! `fitroom body measure|fit|size|export|ansur|roughness|twist-study`: a shaped MakeHuman
//! body, measured (seed 002 Table 4.1 / ISO 8559-1, convex-hull girths), fitted to
//! measurements, sized against a size chart, written as OBJ or glb in its rest pose, and the
//! fit evaluated on ANSUR II.

use std::{
    path::{Path, PathBuf},
    time::Instant,
};

use anyhow::{Context, Result, bail};
use clap::Subcommand;
use fitroom_body::{
    BodyModel, Recommendation, Shape, ShapedBody, SizeChart, measure::Measurements,
};
use serde::Serialize;

use super::{BodyArg, OutputArgs};

pub mod ansur;
pub mod fit;
pub mod roughness;

pub use fit::{Gender, MeasurementArgs};

#[derive(Subcommand)]
pub enum BodyCommand {
    /// Measure a body (default shape, or a shape file): stature, inside leg, arm length,
    /// shoulder width and the neck, bust, under-bust, waist, hip, thigh and calf girths.
    Measure {
        /// A shape file (RON), e.g. `(gender: 0.0, weight: 0.6)`.
        #[arg(long)]
        shape: Option<PathBuf>,
        #[command(flatten)]
        body: BodyArg,
        #[command(flatten)]
        output: OutputArgs,
    },
    /// Fit a body to measurements (cm): bounded least squares over the MakeHuman sliders.
    Fit {
        #[arg(long, value_enum, ignore_case = true)]
        gender: Gender,
        /// Age in years (18-90; default 25).
        #[arg(long)]
        age: Option<f32>,
        #[command(flatten)]
        measurements: MeasurementArgs,
        /// Save the fitted shape (RON) here.
        #[arg(long)]
        out: Option<PathBuf>,
        #[command(flatten)]
        body: BodyArg,
        #[command(flatten)]
        output: OutputArgs,
    },
    /// Recommend a size of a size chart for a body (default shape, or a shape file).
    Size {
        /// A size chart (RON), e.g. assets/sizecharts/en13402-female-seed002.ron.
        #[arg(long)]
        chart: PathBuf,
        #[arg(long)]
        shape: Option<PathBuf>,
        #[command(flatten)]
        body: BodyArg,
        #[command(flatten)]
        output: OutputArgs,
    },
    /// Fit ANSUR II subjects (all, or a seeded sample per sex) and report the errors.
    Ansur(ansur::AnsurArgs),
    /// Segment-local morphing: roughness against interpolation per propagation depth (seed
    /// 002 Figs. 7.3-7.5), as a table, JSON or a plot.
    Roughness {
        /// Draw the Gaussian-propagation curves (PNG).
        #[arg(long)]
        plot: Option<PathBuf>,
        #[command(flatten)]
        body: BodyArg,
        #[command(flatten)]
        output: OutputArgs,
    },
    /// Write the shaped body in its rest pose (metres, +Y up) as OBJ or glb (by extension).
    Export {
        #[arg(long)]
        shape: Option<PathBuf>,
        #[arg(long)]
        out: PathBuf,
        #[command(flatten)]
        body: BodyArg,
    },
    /// Cross-section area of the forearm under a twist, single bone vs split (seed 000 §4.4.3).
    TwistStudy {
        #[arg(long, default_value_t = -90.0, allow_negative_numbers = true)]
        degrees: f32,
        #[command(flatten)]
        body: BodyArg,
        #[command(flatten)]
        output: OutputArgs,
    },
}

pub fn run(command: BodyCommand) -> Result<()> {
    match command {
        BodyCommand::Measure {
            shape,
            body,
            output,
        } => {
            let model = body.load()?;
            let report = measure(&model, load_shape(shape.as_deref())?)?;
            output.print(&report, print_measurements)
        }
        BodyCommand::Fit {
            gender,
            age,
            measurements,
            out,
            body,
            output,
        } => {
            let model = body.load()?;
            let report = fit::fit(&model, gender.slider(), age, &measurements, out.as_deref())?;
            output.print(&report, |report| {
                print!("{}", fit::fit_table(report));
                if let Some(out) = &out {
                    println!("shape saved to {}", out.display());
                }
            })
        }
        BodyCommand::Size {
            chart,
            shape,
            body,
            output,
        } => {
            let model = body.load()?;
            let answer = size(&model, &chart, load_shape(shape.as_deref())?)?;
            output.print(&answer, |answer| {
                println!("{}: {}", answer.chart, answer.recommendation);
            })
        }
        BodyCommand::Ansur(args) => ansur::run(args),
        BodyCommand::Roughness { plot, body, output } => {
            let model = body.load()?;
            let study = roughness::roughness(&model)?;
            if let Some(path) = &plot {
                roughness::plot_roughness(&study, path)?;
            }
            output.print(&study, |study| {
                print!("{}", study.table());
                if let Some(path) = &plot {
                    println!("plot: {}", path.display());
                }
            })
        }
        BodyCommand::Export { shape, out, body } => {
            let model = body.load()?;
            let shape = load_shape(shape.as_deref())?;
            let (shaped, _) = shaped(&model, &shape)?;
            export(&model, &shaped, &out)?;
            println!("wrote {}", out.display());
            Ok(())
        }
        BodyCommand::TwistStudy {
            degrees,
            body,
            output,
        } => {
            let model = body.load()?;
            let report = fitroom_body::forearm::forearm_twist_study(&model, degrees)?;
            output.print(&report, print_twist_study)
        }
    }
}

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

/// The body `model` in `shape`, and the time it took, ms.
pub fn shaped(model: &BodyModel, shape: &Shape) -> Result<(ShapedBody, f64)> {
    let start = Instant::now();
    let body = model.shaped(shape)?;
    Ok((body, start.elapsed().as_secs_f64() * 1e3))
}

/// `fitroom body measure`: the measurements of the body in `shape`, timed.
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

fn print_measurements(report: &MeasureReport) {
    let m = &report.measurements;
    println!(
        "stature {:.1} cm, inside leg {:.1}, arm {:.1}, shoulders {:.1}\n\
         girths: neck {:.1}, bust {:.1}, under-bust {:.1}, waist {:.1}, hip {:.1}, thigh {:.1}, calf {:.1} cm\n\
         shape applied in {:.2} ms, measured in {:.0} ms",
        m.stature_cm,
        m.crotch_height_cm,
        m.arm_length_cm,
        m.shoulder_width_cm,
        m.neck_cm,
        m.bust_cm,
        m.underbust_cm,
        m.waist_cm,
        m.hip_cm,
        m.thigh_cm,
        m.calf_cm,
        report.shape_ms,
        report.measure_ms
    );
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

/// Writes `body` as OBJ ([`fitroom_body::export::body_obj`]) or glb
/// ([`fitroom_body::export::body_glb`]), by the extension of `out`.
pub fn export(model: &BodyModel, body: &ShapedBody, out: &Path) -> Result<()> {
    let bytes = match out
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .as_deref()
    {
        Some("obj") => fitroom_body::export::body_obj(model, body).into_bytes(),
        Some("glb") => fitroom_body::export::body_glb(model, body),
        _ => bail!(
            "'{}': give the output a .obj or .glb extension",
            out.display()
        ),
    };
    if let Some(parent) = out.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(parent)
            .with_context(|| format!("cannot create '{}'", parent.display()))?;
    }
    std::fs::write(out, bytes).with_context(|| format!("cannot write '{}'", out.display()))?;
    Ok(())
}

fn print_twist_study(r: &fitroom_body::ForearmTwistReport) {
    let place = |offset_m: f32| {
        if offset_m < 0.0 {
            format!("{:.1} cm above the elbow", -offset_m * 100.0)
        } else {
            format!("{:.1} cm below the elbow", offset_m * 100.0)
        }
    };
    println!(
        "{:.0}° twist of the {} forearm ({:.1} cm long); mid-forearm section {:.1} cm² at rest",
        r.twist_deg,
        r.side,
        r.forearm_length_m * 100.0,
        r.rest_mid_area_cm2
    );
    println!("area kept (posed / rest)     mid-forearm  closed form  worst section");
    let rows = [
        (
            "single forearm bone",
            r.mid_section.single_bone,
            r.theory_mid.single_bone,
            r.worst.single_bone,
        ),
        (
            "split, all twist distal",
            r.mid_section.split_literal,
            r.theory_mid.split_literal,
            r.worst.split_literal,
        ),
        (
            "split, twist shared (used)",
            r.mid_section.split_shared,
            r.theory_mid.split_shared,
            r.worst.split_shared,
        ),
    ];
    for (name, mid, theory, worst) in rows {
        println!(
            "{name:<28} {mid:>11.3}  {theory:>11.3}  {:.3} ({})",
            worst.ratio,
            place(worst.offset_m)
        );
    }
}
