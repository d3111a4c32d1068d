//! `fitroom body roughness`: segment-local morphing, roughness against interpolation.

use std::path::Path;

use anyhow::{Context, Result, bail};
use fitroom_body::{
    BodyModel,
    segments::{BodySegment, Decay, RoughnessStudy, RoughnessStudyConfig},
};

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
    crate::cli::plot_font()?;
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
