//! `fitroom motion eval`: the motion pipeline on a noisy replay of a clean clip, with figures
//! and an optional plot of one joint angle (raw, filtered, clean), like seed 000 Figure 4.1.

use std::path::Path;

use anyhow::{Context, Result, anyhow};
use fitroom_motion::eval::{ClipEvaluation, joint_angle_deg};
use fitroom_sensor::KinectJoint;
use plotters::prelude::*;

/// The joint angle the plot shows: the right elbow (180° straight).
pub const PLOT_JOINT: (KinectJoint, KinectJoint) =
    (KinectJoint::ElbowRight, KinectJoint::WristRight);

/// Draws raw, filtered and clean curves of the right elbow angle over time.
pub fn plot_joint_angle(evaluation: &ClipEvaluation, path: &Path) -> Result<()> {
    plotters::style::register_font(
        "sans-serif",
        FontStyle::Normal,
        epaint_default_fonts::UBUNTU_LIGHT,
    )
    .map_err(|_| anyhow!("cannot load the plot font"))?;
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
