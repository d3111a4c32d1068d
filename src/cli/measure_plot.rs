//! `fitroom measure eval --plot`: the error distribution of each measurement, ours beside the
//! seed's method, as one picture.

use std::path::Path;

use anyhow::{Context, Result, bail};
use fitroom_body::Measure;
use fitroom_math::stats::percentile;
use fitroom_measure::eval::{EVALUATED, MeasureReport, SubjectResult};

/// One row of the plot: a name and its errors (measured minus true), cm.
struct Row {
    name: String,
    errors: Vec<f64>,
}

fn rows_of(report: &MeasureReport) -> (Vec<Row>, Vec<Row>) {
    let ok: Vec<&SubjectResult> = report
        .results
        .iter()
        .filter(|r| r.error.is_none())
        .collect();
    let ours = EVALUATED
        .iter()
        .map(|&m| Row {
            name: m.name().to_owned(),
            errors: ok
                .iter()
                .map(|r| f64::from(r.ours[&m] - r.truth[&m]))
                .collect(),
        })
        .collect();
    let seed = |name: &str, m: Measure, f: fn(&SubjectResult) -> f32| Row {
        name: name.to_owned(),
        errors: ok.iter().map(|r| f64::from(f(r) - r.truth[&m])).collect(),
    };
    let theirs = vec![
        seed("stature (Eq. 6.7)", Measure::Stature, |r| r.seed_stature_cm),
        seed("stature (map)", Measure::Stature, |r| r.seed_stature_map_cm),
        seed("shoulder (Eq. 6.7)", Measure::ShoulderWidth, |r| {
            r.seed_shoulder_width_cm
        }),
        seed("shoulder (map)", Measure::ShoulderWidth, |r| {
            r.seed_shoulder_width_map_cm
        }),
    ];
    (ours, theirs)
}

/// Draws `report`'s errors to `path` (PNG): per measurement a box from the 25th to the 75th
/// percentile, whiskers to the 5th and 95th, the median, and the subjects beyond the whiskers
/// as dots; ours on the left, the seed's method on the right (its errors are ten times
/// larger: a scale of their own).
pub fn plot_errors(report: &MeasureReport, path: &Path) -> Result<()> {
    use plotters::prelude::*;
    let (ours, theirs) = rows_of(report);
    if ours.iter().all(|r| r.errors.is_empty()) {
        bail!("no subject was measured: nothing to plot");
    }
    crate::cli::plot_font()?;
    let draw = |e: DrawingAreaErrorKind<_>| anyhow::anyhow!("cannot draw the plot: {e:?}");
    let root = BitMapBackend::new(path, (1500, 620)).into_drawing_area();
    root.fill(&WHITE).map_err(draw)?;
    let (title, body) = root.split_vertically(44);
    title
        .titled(
            &format!(
                "Measured minus true, cm: {} ANSUR II subjects, pose from {}{}",
                report.subjects - report.failed,
                report.pose,
                report
                    .garment
                    .as_ref()
                    .map_or(String::new(), |g| format!(", wearing the {g}"))
            ),
            ("sans-serif", 20),
        )
        .map_err(draw)?;
    let (left, right) = body.split_horizontally(900);
    let panels = [
        (left, "ours", &ours, 5.0f64, RGBColor(40, 110, 200)),
        (
            right,
            "the seed's method",
            &theirs,
            40.0,
            RGBColor(200, 90, 40),
        ),
    ];
    for (panel, caption, rows, reach, color) in panels {
        let n = rows.len();
        let names: Vec<String> = rows.iter().map(|r| r.name.clone()).collect();
        let mut chart = ChartBuilder::on(&panel)
            .caption(
                format!("{caption} (clipped at ±{reach} cm)"),
                ("sans-serif", 18),
            )
            .margin(12)
            .x_label_area_size(36)
            .y_label_area_size(150)
            .build_cartesian_2d(-reach..reach, -0.5f64..(n as f64 - 0.5))
            .map_err(draw)?;
        chart
            .configure_mesh()
            .x_desc("error (cm)")
            .y_labels(n)
            .y_label_formatter(&|y| {
                let k = y.round();
                if (y - k).abs() > 0.01 || k < 0.0 {
                    return String::new();
                }
                names
                    .get(n.saturating_sub(1 + k as usize))
                    .cloned()
                    .unwrap_or_default()
            })
            .light_line_style(WHITE)
            .label_style(("sans-serif", 14))
            .draw()
            .map_err(draw)?;
        chart
            .draw_series(std::iter::once(PathElement::new(
                vec![(0.0, -0.5), (0.0, n as f64 - 0.5)],
                BLACK.mix(0.4),
            )))
            .map_err(draw)?;
        for (i, row) in rows.iter().enumerate() {
            if row.errors.is_empty() {
                continue;
            }
            // The first row at the top.
            let y = (n - 1 - i) as f64;
            let mut sorted = row.errors.clone();
            sorted.sort_by(f64::total_cmp);
            let clip = |v: f64| v.clamp(-reach, reach);
            let q = |p: f64| clip(percentile(&sorted, p));
            let (p5, p25, p50, p75, p95) = (q(0.05), q(0.25), q(0.5), q(0.75), q(0.95));
            chart
                .draw_series([
                    PathElement::new(vec![(p5, y), (p95, y)], color.stroke_width(2)),
                    PathElement::new(vec![(p5, y - 0.15), (p5, y + 0.15)], color.stroke_width(2)),
                    PathElement::new(
                        vec![(p95, y - 0.15), (p95, y + 0.15)],
                        color.stroke_width(2),
                    ),
                ])
                .map_err(draw)?;
            chart
                .draw_series(std::iter::once(Rectangle::new(
                    [(p25, y - 0.28), (p75, y + 0.28)],
                    color.mix(0.35).filled(),
                )))
                .map_err(draw)?;
            chart
                .draw_series(std::iter::once(PathElement::new(
                    vec![(p50, y - 0.3), (p50, y + 0.3)],
                    BLACK.stroke_width(3),
                )))
                .map_err(draw)?;
            let (lo, hi) = (percentile(&sorted, 0.05), percentile(&sorted, 0.95));
            chart
                .draw_series(
                    sorted
                        .iter()
                        .filter(|&&v| v < lo || v > hi)
                        .map(|&v| Circle::new((clip(v), y), 3, color.filled())),
                )
                .map_err(draw)?;
        }
    }
    root.present()
        .with_context(|| format!("cannot write the plot '{}'", path.display()))?;
    Ok(())
}
