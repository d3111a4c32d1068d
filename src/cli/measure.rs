//! `fitroom measure`: measuring people from depth. `prior` learns the shape prior from ANSUR
//! II, `eval` measures ANSUR II subjects filmed by the synthetic Kinect with both methods,
//! `plot` draws an evaluation's error distributions, `record` films a calibration into a
//! dump and `dump` measures the person in one.

use std::fmt::Write as _;
use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use clap::Subcommand;
use fitroom_body::SizeChart;
use fitroom_body::ansur::{read_survey, sample};
use fitroom_measure::eval::{
    Detailer, EvalOptions, MeasureReport, PoseSource, evaluate, held_out, training,
};
use fitroom_measure::prior::learn;
use fitroom_measure::{FitSettings, ShapePrior};

use crate::cli::BodyArg;

#[derive(Subcommand)]
pub enum MeasureCommand {
    /// Learn the shape prior (how the body's sliders go together in people) from ANSUR II
    /// subjects the evaluation never uses (even positions of each survey file).
    Prior(PriorArgs),
    /// Measure ANSUR II subjects (odd positions: the prior never saw them) filmed in the
    /// calibration pose by the synthetic Kinect v1, with the seed's method and ours, against
    /// the filmed bodies' own measurements.
    Eval(EvalArgs),
    /// Plot the error distributions of an evaluation's JSON report (`eval --report`).
    Plot(PlotArgs),
    /// Film a held-out ANSUR II subject's calibration (a second facing the sensor, a second
    /// turned) with the synthetic Kinect into a fakenect dump, the truth beside it.
    Record(super::measure_dump::RecordArgs),
    /// Measure the person in a dump (a Kinect recording or `measure record`'s): the frames go
    /// through the tracker and the calibration's checks as in the kiosk.
    Dump(super::measure_dump::DumpArgs),
}

#[derive(clap::Args)]
pub struct PlotArgs {
    /// The evaluation's JSON report.
    pub report: PathBuf,
    /// The picture to write (PNG).
    #[arg(long)]
    pub out: PathBuf,
}

#[derive(clap::Args)]
pub struct SurveyArgs {
    /// The folder with the ANSUR II files (default: the repository's `data/ansur2`).
    #[arg(long, default_value = concat!(env!("CARGO_MANIFEST_DIR"), "/data/ansur2"))]
    pub data: PathBuf,
    /// Subjects (a seeded random sample of the half the command uses).
    #[arg(long)]
    pub subjects: Option<usize>,
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    #[arg(long, default_value_t = 2)]
    pub threads: usize,
    #[command(flatten)]
    pub body: BodyArg,
}

#[derive(clap::Args)]
pub struct PriorArgs {
    #[command(flatten)]
    pub survey: SurveyArgs,
    /// Where to write the prior (default: the assets' bodies/shape-prior.ron).
    #[arg(long)]
    pub out: Option<PathBuf>,
}

#[derive(clap::Args)]
pub struct EvalArgs {
    #[command(flatten)]
    pub survey: SurveyArgs,
    /// Where the pose and the person's pixels come from: `tracker` (our tracker on the
    /// frames, as in the kiosk), `truth` (the filmed pose: the measurement alone) or
    /// `tracker-pixels` (the tracker's pixels, the fit started from the filmed pose).
    #[arg(long, value_enum, default_value = "tracker")]
    pub pose: PoseArg,
    /// Calibration frames per view (30: one second).
    #[arg(long, default_value_t = 30)]
    pub frames: usize,
    /// The second view's turn to the side, degrees (as the kiosk asks); 0: the front view
    /// alone.
    #[arg(long, default_value_t = fitroom_measure::eval::TURN_DEG)]
    pub turn: f32,
    /// Dress the subjects in this garment (a pattern garment such as
    /// `assets/garments/tshirt.ron`; each in the size its table gives them).
    #[arg(long)]
    pub garment: Option<PathBuf>,
    /// Weight of surface points outside the fitted skin against those inside (1: the bare
    /// body the kiosk assumes; lower trusts the surface seen less where clothes may hang,
    /// see docs/measure.md).
    #[arg(long, default_value_t = 1.0)]
    pub outside_weight: f32,
    /// Give each body detail no shape slider has: its chest, waist, hip, upper arms, thighs
    /// and shanks each scaled about their axis by up to this many per cent (drawn per
    /// subject); 0: the slider bodies themselves.
    #[arg(long, default_value_t = 0.0)]
    pub detail: f32,
    /// Print the report as JSON (every subject) instead of the summary.
    #[arg(long)]
    pub json: bool,
    /// Write the JSON report here.
    #[arg(long)]
    pub report: Option<PathBuf>,
    /// Write the summary (Markdown) here.
    #[arg(long)]
    pub summary: Option<PathBuf>,
    /// Draw the error distributions here (PNG).
    #[arg(long)]
    pub plot: Option<PathBuf>,
}

#[derive(Clone, Copy, clap::ValueEnum)]
pub enum PoseArg {
    Tracker,
    Truth,
    /// The tracker's pixels with the filmed pose as the fit's start (a diagnosis: the
    /// tracker's pose's share of the error).
    TrackerPixels,
}

pub fn run(command: MeasureCommand) -> Result<()> {
    match command {
        MeasureCommand::Prior(args) => prior(args),
        MeasureCommand::Eval(args) => eval(args),
        MeasureCommand::Plot(args) => plot(args),
        MeasureCommand::Record(args) => super::measure_dump::record_calibration(args),
        MeasureCommand::Dump(args) => super::measure_dump::measure_dump(args),
    }
}

fn plot(args: PlotArgs) -> Result<()> {
    let text = std::fs::read_to_string(&args.report)
        .with_context(|| format!("cannot read '{}'", args.report.display()))?;
    let report: MeasureReport = serde_json::from_str(&text).with_context(|| {
        format!(
            "'{}' is not an evaluation report (write one with `fitroom measure eval --report`)",
            args.report.display()
        )
    })?;
    crate::cli::measure_plot::plot_errors(&report, &args.out)?;
    println!("wrote {}", args.out.display());
    Ok(())
}

fn bar(total: usize, what: &str) -> indicatif::ProgressBar {
    let bar = indicatif::ProgressBar::new(total as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template(&format!(
            "{{elapsed_precise}} [{{bar:40}}] {{pos}}/{{len}} {what} (eta {{eta}})"
        ))
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    bar
}

/// Both survey files, women then men, as one list (each file's own order kept).
pub(super) fn survey(data: &std::path::Path) -> Result<Vec<fitroom_body::ansur::AnsurSubject>> {
    let [women, men] = read_survey(data)
        .with_context(|| format!("cannot read the ANSUR II survey in '{}'", data.display()))?;
    Ok(women.into_iter().chain(men).collect())
}

fn prior(args: PriorArgs) -> Result<()> {
    let s = &args.survey;
    let model = s.body.load()?;
    let all = survey(&s.data)?;
    let pool = training(&all);
    let subjects = match s.subjects {
        Some(n) => sample(&pool, n, s.seed),
        None => pool,
    };
    let progress = bar(subjects.len(), "subjects fitted");
    let prior = learn(&model, &subjects, s.threads, &|_, _| progress.inc(1))?;
    progress.finish_and_clear();
    let out = match args.out {
        Some(p) => p,
        None => crate::assets::assets_dir()?.join("bodies/shape-prior.ron"),
    };
    let text = format!(
        "// The shape prior: mean and covariance of the body's sliders over people, per gender.\n\
         // Made by `fitroom measure prior` (do not edit by hand). {}\n{}\n",
        prior.source,
        ron::ser::to_string_pretty(&prior, ron::ser::PrettyConfig::default())?
    );
    std::fs::write(&out, text).with_context(|| format!("cannot write '{}'", out.display()))?;
    println!(
        "shape prior from {} women and {} men written to {}",
        prior.female.subjects,
        prior.male.subjects,
        out.display()
    );
    Ok(())
}

pub(super) fn chart(name: &str) -> Result<SizeChart> {
    let path = crate::assets::assets_dir()?.join("sizecharts").join(name);
    SizeChart::load(&path)
        .with_context(|| format!("cannot read the size chart '{}'", path.display()))
}

fn eval(args: EvalArgs) -> Result<()> {
    let s = &args.survey;
    if !(args.outside_weight > 0.0 && args.outside_weight <= 1.0) {
        bail!(
            "--outside-weight {} is out of range: give a weight in (0, 1]",
            args.outside_weight
        );
    }
    if args.frames < fitroom_measure::MIN_FRAMES {
        bail!(
            "--frames {} is too few: a calibration needs at least {}",
            args.frames,
            fitroom_measure::MIN_FRAMES
        );
    }
    if !(0.0..50.0).contains(&args.detail) {
        bail!(
            "--detail {} is out of range: give a girth change in per cent, 0 to 50",
            args.detail
        );
    }
    if args.detail > 0.0 && args.garment.is_some() {
        bail!(
            "--detail with --garment is not supported: the garment is settled on the slider body, \
             not on the detailed one; give one of them"
        );
    }
    let model = s.body.load()?;
    let detail = if args.detail > 0.0 {
        Some(std::sync::Arc::new(
            Detailer::new(&model, args.detail / 100.0)
                .context("cannot segment the body model for --detail")?,
        ))
    } else {
        None
    };
    let prior = ShapePrior::shipped()?;
    let all = survey(&s.data)?;
    let pool = held_out(&all);
    let subjects = sample(&pool, s.subjects.unwrap_or(200), s.seed);
    let (women, men) = (
        chart("en13402-female-seed002.ron")?,
        chart("en13402-male-seed002.ron")?,
    );
    let garment = match &args.garment {
        None => None,
        Some(path) => Some(std::sync::Arc::new(
            fitroom_garment::GarmentSource::load(path)
                .with_context(|| format!("cannot read the garment '{}'", path.display()))?,
        )),
    };
    let progress = bar(subjects.len(), "subjects measured");
    let report = evaluate(
        &model,
        &subjects,
        &prior,
        (&women, &men),
        &FitSettings {
            outside_weight: args.outside_weight,
            ..FitSettings::default()
        },
        &EvalOptions {
            pose: match args.pose {
                PoseArg::Tracker => PoseSource::Tracker,
                PoseArg::Truth => PoseSource::Truth,
                PoseArg::TrackerPixels => PoseSource::TrackerPixels,
            },
            frames: args.frames,
            turn_deg: args.turn,
            seed: s.seed,
            threads: s.threads,
            garment,
            detail,
        },
        &|_, _| progress.inc(1),
    );
    progress.finish_and_clear();
    let json = serde_json::to_string_pretty(&report)?;
    if let Some(path) = &args.report {
        std::fs::write(path, &json)
            .with_context(|| format!("cannot write '{}'", path.display()))?;
    }
    if let Some(path) = &args.plot {
        crate::cli::measure_plot::plot_errors(&report, path)?;
    }
    let md = markdown(&report);
    if let Some(path) = &args.summary {
        std::fs::write(path, &md).with_context(|| format!("cannot write '{}'", path.display()))?;
    }
    if args.json {
        println!("{json}");
    } else {
        print!("{md}");
    }
    Ok(())
}

/// The report's summary as Markdown.
pub fn markdown(r: &MeasureReport) -> String {
    let mut md = String::new();
    let _ = writeln!(
        md,
        "{} ANSUR II subjects (held out from the prior; seed {}){}{}, {} calibration frames {}, pose from {}; {} failed.\n",
        r.subjects,
        r.seed,
        if r.detail > 0.0 {
            format!(
                " with detail (segment girths scaled by up to ±{:.0} %)",
                r.detail * 100.0
            )
        } else {
            String::new()
        },
        r.garment
            .as_ref()
            .map_or(String::new(), |g| format!(" wearing the {g} in their size")),
        r.frames,
        if r.turn_deg == 0.0 {
            "facing the camera".to_string()
        } else {
            format!(
                "facing the camera and {} more turned {:.0}°",
                r.frames, r.turn_deg
            )
        },
        r.pose,
        r.failed
    );
    let _ = writeln!(
        md,
        "| measure | ours: mean abs | bias | p95 | max | seed's method: mean abs | bias | p95 | seed, depth map alone: mean abs | bias |"
    );
    let _ = writeln!(
        md,
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |"
    );
    for m in &r.ours {
        let find = |v: &[fitroom_measure::eval::MeasureStats]| {
            v.iter()
                .find(|s| s.measure == m.measure)
                .map_or(" | ".to_string(), |s| {
                    format!("{:.2} cm | {:+.2}", s.mean_abs_cm, s.bias_cm)
                })
        };
        let p95 = r
            .seed_method
            .iter()
            .find(|s| s.measure == m.measure)
            .map_or(String::new(), |s| format!("{:.2}", s.p95_abs_cm));
        let _ = writeln!(
            md,
            "| {} | {:.2} cm | {:+.2} | {:.2} | {:.2} | {} | {} | {} |",
            m.measure,
            m.mean_abs_cm,
            m.bias_cm,
            m.p95_abs_cm,
            m.max_abs_cm,
            find(&r.seed_method),
            p95,
            find(&r.seed_map_only)
        );
    }
    let _ = writeln!(
        md,
        "\nStature, mean absolute error: ours {:.2} %, the seed's {:.2} % (its depth map alone {:.2} %). Recommended size (EN 13402, the subject's gender) equal to the true one: {:.1} %. Gender found: {:.1} %. Fit time (averaged frames to measured body, one core per subject): mean {:.0} ms, max {:.0} ms.",
        r.stature_percent_ours,
        r.stature_percent_seed,
        r.stature_percent_seed_map,
        r.size_agreement * 100.0,
        r.gender_agreement * 100.0,
        r.mean_fit_ms,
        r.max_fit_ms
    );
    md
}
