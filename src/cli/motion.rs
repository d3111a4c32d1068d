//! `fitroom motion eval`: the motion pipeline on a noisy replay of a clean clip, with figures
//! and an optional plot of one joint angle (raw, filtered, clean), like seed 000 Figure 4.1.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, anyhow};
use clap::Subcommand;
use fitroom_motion::{
    eval::{
        ClipEvaluation, EvalOptions, FilterChoice, evaluate_clip, evaluation_noise, joint_angle_deg,
    },
    filter::FilterKind,
};
use fitroom_sensor::KinectJoint;
use plotters::prelude::*;

use super::{BodyArg, Noise, OutputArgs};

#[derive(Subcommand)]
pub enum MotionCommand {
    /// Replay a clean clip through the Kinect noise model and the motion pipeline; report RMSE,
    /// jitter, lag, bone-length spread, foot skating and joint-limit violations.
    Eval(EvalArgs),
}

/// `fitroom motion eval`.
#[derive(clap::Args)]
pub struct EvalArgs {
    /// The clean BVH clip.
    #[arg(long)]
    pub bvh: PathBuf,
    /// `kinect` (the Kinect v1 model, view limits off) or `none`.
    #[arg(long, value_enum, default_value_t = Noise::Kinect)]
    pub noise: Noise,
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// The joint filter.
    #[arg(long, value_enum, ignore_case = true, default_value_t = Filter::Kalman)]
    pub filter: Filter,
    /// Draw raw, filtered and clean curves of the right elbow angle (PNG).
    #[arg(long)]
    pub plot: Option<PathBuf>,
    #[command(flatten)]
    pub output: OutputArgs,
    #[command(flatten)]
    pub body: BodyArg,
}

/// `--filter`: the joint filters `fitroom_motion::eval` can evaluate.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Filter {
    /// Raw positions.
    #[value(alias = "raw")]
    None,
    /// Holt double exponential smoothing, the Kinect SDK's default parameters.
    #[value(alias = "holt-default")]
    Holt,
    /// Holt, the SDK's "smooth" parameters.
    #[value(alias = "holt_smooth")]
    HoltSmooth,
    /// Holt, the SDK's "very smooth" parameters.
    #[value(alias = "holt_very_smooth")]
    HoltVerySmooth,
    /// The One Euro filter, default parameters.
    #[value(aliases = ["one-euro", "1euro"])]
    Oneeuro,
    /// One Euro tuned on the clip (the authors' two-step procedure).
    #[value(aliases = ["one-euro-tuned", "oneeuro_tuned"])]
    OneeuroTuned,
    /// fitroom's own filter.
    #[value(alias = "fitroom")]
    Kalman,
}

impl Filter {
    /// The filter `fitroom_motion::eval` evaluates.
    pub fn choice(self) -> FilterChoice {
        use fitroom_motion::filter::{HoltParams, KalmanParams, OneEuroParams};
        match self {
            Filter::None => FilterChoice::Kind(FilterKind::None),
            Filter::Holt => FilterChoice::Kind(FilterKind::Holt(HoltParams::DEFAULT)),
            Filter::HoltSmooth => FilterChoice::Kind(FilterKind::Holt(HoltParams::SMOOTH)),
            Filter::HoltVerySmooth => FilterChoice::Kind(FilterKind::Holt(HoltParams::VERY_SMOOTH)),
            Filter::Oneeuro => FilterChoice::Kind(FilterKind::OneEuro(OneEuroParams::default())),
            Filter::OneeuroTuned => FilterChoice::OneEuroTuned,
            Filter::Kalman => FilterChoice::Kind(FilterKind::Kalman(KalmanParams::default())),
        }
    }
}

pub fn run(command: MotionCommand) -> Result<()> {
    match command {
        MotionCommand::Eval(args) => eval(&args),
    }
}

/// `fitroom motion eval`.
pub fn eval(args: &EvalArgs) -> Result<()> {
    let noise = match args.noise {
        Noise::Kinect => Some(evaluation_noise()),
        Noise::None => None,
    };
    let model = args.body.load()?;
    let rest = model.rest_pose(&model.positions);
    let skeleton = fitroom_motion::avatar_skeleton(&model, &rest)?;
    let options = EvalOptions {
        filter: args.filter.choice(),
        noise,
        seed: args.seed,
        ..EvalOptions::default()
    };
    let evaluation = evaluate_clip(&args.bvh, &skeleton, &options)?;
    if let Some(plot) = &args.plot {
        plot_joint_angle(&evaluation, plot)?;
    }
    args.output.print(&evaluation.report, |r| {
        println!(
            "{} with {} (seed {}), {} frames\n\
             position RMSE {:.1} mm (raw {:.1}); jitter {:.1} m/s² (raw {:.1}, clean {:.1}); lag {:.0} ms\n\
             bone-length std {:.1} mm (raw {:.1}); avatar foot skating {:.1}% -> {:.1}% of frame pairs\n\
             the correction moves the ankles {:.1} mm on average (at most {:.1} mm)\n\
             joint-limit violations {}; frames rejected {}; pipeline {:.1} µs per frame",
            r.clip,
            r.filter,
            r.seed,
            r.frames,
            r.output.rmse_mm,
            r.input.rmse_mm,
            r.output.jitter_m_s2,
            r.input.jitter_m_s2,
            r.output.clean_jitter_m_s2,
            r.output.lag_ms,
            r.output.bone_std_mm,
            r.input.bone_std_mm,
            100.0 * r.avatar_foot_skate_input,
            100.0 * r.avatar_foot_skate_output,
            r.foot_correction_mean_mm,
            r.foot_correction_max_mm,
            r.joint_limit_violations,
            r.rejected_frames,
            r.pipeline_us_per_frame
        );
    })
}

/// The joint angle the plot shows: the right elbow (180° straight).
pub const PLOT_JOINT: (KinectJoint, KinectJoint) =
    (KinectJoint::ElbowRight, KinectJoint::WristRight);

/// Draws raw, filtered and clean curves of the right elbow angle over time.
pub fn plot_joint_angle(evaluation: &ClipEvaluation, path: &Path) -> Result<()> {
    crate::cli::plot_font()?;
    let (joint, child) = PLOT_JOINT;
    let series = |frames: &[fitroom_sensor::SensorFrame]| -> Vec<(f64, f64)> {
        let t0 = frames.first().map_or(0.0, |f| f.timestamp_s);
        frames
            .iter()
            .filter_map(|f| {
                joint_angle_deg(f, joint, child).map(|a| (f.timestamp_s - t0, f64::from(a)))
            })
            .collect()
    };
    let clean = series(&evaluation.clean);
    let raw = series(&evaluation.noisy);
    let filtered = series(&evaluation.filtered);
    let all = clean.iter().chain(&raw).chain(&filtered);
    let (mut lo, mut hi, mut t_max) = (f64::MAX, f64::MIN, 0.0f64);
    for (t, a) in all {
        lo = lo.min(*a);
        hi = hi.max(*a);
        t_max = t_max.max(*t);
    }
    if clean.is_empty() || lo > hi {
        return Err(anyhow!("no elbow angle to plot"));
    }
    let pad = ((hi - lo) * 0.08).max(2.0);

    let root = BitMapBackend::new(path, (1100, 520)).into_drawing_area();
    let draw = |e: DrawingAreaErrorKind<_>| anyhow!("cannot draw the plot: {e:?}");
    root.fill(&WHITE).map_err(draw)?;
    let report = &evaluation.report;
    let caption = format!(
        "{}: right elbow angle, {} vs raw (Kinect noise, seed {})",
        report.clip, report.filter, report.seed
    );
    let mut chart = ChartBuilder::on(&root)
        .caption(caption, ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(56)
        .build_cartesian_2d(0.0..t_max.max(0.1), (lo - pad)..(hi + pad))
        .map_err(draw)?;
    chart
        .configure_mesh()
        .x_desc("time (s)")
        .y_desc("elbow angle (°)")
        .label_style(("sans-serif", 15))
        .draw()
        .map_err(draw)?;
    let lines = [
        (raw, RGBColor(220, 70, 60), "raw (noisy input)"),
        (clean, RGBColor(40, 40, 40), "clean motion capture"),
        (filtered, RGBColor(30, 140, 70), "filtered"),
    ];
    for (points, color, label) in lines {
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
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 15))
        .draw()
        .map_err(draw)?;
    root.present()
        .with_context(|| format!("cannot write the plot '{}'", path.display()))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use clap::ValueEnum;

    use super::*;

    #[test]
    fn every_filter_spelling_means_what_the_motion_crate_parses() {
        for filter in Filter::value_variants() {
            let value = filter.to_possible_value().expect("a value");
            for name in value.get_name_and_aliases() {
                let parsed: FilterChoice = name.parse().expect("the motion crate knows it");
                assert_eq!(parsed, filter.choice(), "--filter {name}");
            }
        }
    }
}
