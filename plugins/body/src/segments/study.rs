//! The roughness study of seed 002 (Uğur 2008, parametric bodies for virtual dressing) §7.1,
//! Figures 7.3-7.5: two neighbouring segments morphed separately and together towards a target, and
//! the roughness (eq. 7.2) of their region against the morph amount, for increasing propagation
//! depths and each decay.

use std::fmt::Write as _;

use glam::Vec3;
use serde::Serialize;

use super::{
    BodySegment, BodySegmentation, Decay, Propagation, SegmentEdit, SegmentError, SegmentTarget,
};
use crate::model::BodyModel;
use crate::modifiers::Shape;

/// What the two segments of a [`roughness_study`] morph towards.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum StudyTarget {
    /// The whole body shaped by MakeHuman modifiers (the seed's calibrated target model).
    Shape(Shape),
    /// Each segment's girth scaled about its own axis.
    RadialScale { factor: f32 },
}

/// The parameters of a [`roughness_study`].
#[derive(Clone, Debug, PartialEq)]
pub struct RoughnessStudyConfig {
    /// Two neighbouring segments (the seed: under-bust and waist).
    pub segments: [BodySegment; 2],
    pub target: StudyTarget,
    /// Propagation depths (hops) compared; 0 is the hard segment.
    pub depths: Vec<u32>,
    pub decays: Vec<Decay>,
    /// The amount goes from 0 to 1 in this many equal steps.
    pub amount_steps: u32,
}

impl Default for RoughnessStudyConfig {
    /// Waist and chest (the band that holds the under-bust), towards MakeHuman's heaviest body
    /// (`weight` 1), depths 0, 1, 2, 4, 8, every decay, amounts in tenths.
    fn default() -> Self {
        Self {
            segments: [BodySegment::Waist, BodySegment::Chest],
            target: StudyTarget::Shape(Shape {
                weight: 1.0,
                ..Shape::default()
            }),
            depths: vec![0, 1, 2, 4, 8],
            decays: Decay::ALL.to_vec(),
            amount_steps: 10,
        }
    }
}

/// Roughness against amount for one interpolation, decay and depth: one line of the seed's
/// Figures 7.3-7.5.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RoughnessCurve {
    /// The segments that morph (amount `u`); every other segment stays (amount 0).
    pub interpolated: Vec<BodySegment>,
    pub decay: Decay,
    /// Propagation depth (hops) of every segment; 0 is the hard segment.
    pub depth: u32,
    /// Roughness of the region (mean Laplacian distance, mm), one per
    /// [`RoughnessStudy::amounts`].
    pub roughness_mm: Vec<f32>,
}

/// The seed's Figures 7.3-7.5 as data: for two neighbouring segments interpolated separately
/// and together, the roughness of their region against the interpolation amount, for each
/// decay and propagation depth.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RoughnessStudy {
    pub segments: [BodySegment; 2],
    pub target: StudyTarget,
    /// The region measured: both cores and every vertex within `region_hops` hops of them
    /// (one more than the deepest propagation, so it holds every vertex that moves).
    pub region_hops: u32,
    pub region_vertex_count: usize,
    /// Interpolation amounts `u`, 0 to 1.
    pub amounts: Vec<f32>,
    pub depths: Vec<u32>,
    pub decays: Vec<Decay>,
    /// Roughness of the region on the source body (mm): every curve's value at `u = 0`.
    pub source_roughness_mm: f32,
    /// Roughness of the region on the target body (mm), for a [`StudyTarget::Shape`]: where a
    /// global morph ends.
    pub target_roughness_mm: Option<f32>,
    /// One curve per interpolation (first segment, second, both), decay and depth, in that
    /// nesting order.
    pub curves: Vec<RoughnessCurve>,
}

impl RoughnessStudy {
    /// The curve for these interpolated segments, decay and depth.
    pub fn curve(
        &self,
        interpolated: &[BodySegment],
        decay: Decay,
        depth: u32,
    ) -> Option<&RoughnessCurve> {
        self.curves
            .iter()
            .find(|c| c.interpolated == interpolated && c.decay == decay && c.depth == depth)
    }

    /// The study as text tables: one per interpolation and decay, a row per depth, a column
    /// per amount (mm).
    pub fn table(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(
            s,
            "Roughness (mean Laplacian distance, mm) of {} vertices: {} and {} cores and {} hops \
             around; source {:.4} mm{}",
            self.region_vertex_count,
            self.segments[0],
            self.segments[1],
            self.region_hops,
            self.source_roughness_mm,
            self.target_roughness_mm
                .map_or(String::new(), |t| format!(", target {t:.4} mm")),
        );
        let mut last: Option<(&[BodySegment], Decay)> = None;
        for c in &self.curves {
            if last != Some((&c.interpolated, c.decay)) {
                let names: Vec<&str> = c.interpolated.iter().map(|s| s.name()).collect();
                let _ = writeln!(
                    s,
                    "\ninterpolated: {} | decay: {}",
                    names.join(" + "),
                    c.decay
                );
                let _ = write!(s, "{:>6}", "depth");
                for u in &self.amounts {
                    let _ = write!(s, " {:>7}", format!("u={u:.1}"));
                }
                s.push('\n');
                last = Some((&c.interpolated, c.decay));
            }
            let _ = write!(s, "{:>6}", c.depth);
            for r in &c.roughness_mm {
                let _ = write!(s, " {r:>7.4}");
            }
            s.push('\n');
        }
        s
    }
}

/// The roughness study of `config` on the base mesh of `model` (segments it first).
pub fn roughness_study(
    model: &BodyModel,
    config: &RoughnessStudyConfig,
) -> Result<RoughnessStudy, SegmentError> {
    roughness_study_with(model, &BodySegmentation::new(model)?, config)
}

/// [`roughness_study`] with an existing segmentation of `model`.
///
/// The source is the base mesh. For each decay and depth every segment is propagated alike;
/// the segments of an interpolation morph by `u` (eq. 4.6, the others at 0), and the region's
/// roughness is measured at each amount. Eq. 4.6 is linear in `u` when the morphing segments
/// share it, so the body at `u` is the source plus `u` times the displacement at `u = 1`.
pub fn roughness_study_with(
    model: &BodyModel,
    segmentation: &BodySegmentation,
    config: &RoughnessStudyConfig,
) -> Result<RoughnessStudy, SegmentError> {
    let [first, second] = config.segments;
    if first == second {
        return Err(SegmentError::StudyConfig(format!(
            "segments are both `{first}`; give two different (neighbouring) segments"
        )));
    }
    if config.depths.is_empty() || config.decays.is_empty() {
        return Err(SegmentError::StudyConfig(
            "depths and decays must not be empty; e.g. depths 0, 1, 2, 4, 8 and every decay".into(),
        ));
    }
    const MAX_DEPTH: u32 = 64;
    if let Some(d) = config.depths.iter().find(|&&d| d > MAX_DEPTH) {
        return Err(SegmentError::StudyConfig(format!(
            "depth {d} is past the largest accepted depth {MAX_DEPTH}; the body is about 100 \
             hops from head to toe"
        )));
    }
    if !(1..=1000).contains(&config.amount_steps) {
        return Err(SegmentError::StudyConfig(format!(
            "amount_steps is {}; give 1 to 1000 steps from 0 to 1",
            config.amount_steps
        )));
    }
    let source = &model.positions;
    let graph = segmentation.graph();
    let body = graph.vertex_count();
    let (target, target_positions) = match &config.target {
        StudyTarget::Shape(shape) => {
            let t = model.shaped(shape)?.positions;
            (SegmentTarget::Positions(t.clone()), Some(t))
        }
        &StudyTarget::RadialScale { factor } => (SegmentTarget::RadialScale { factor }, None),
    };

    let mut cores = segmentation.core(first);
    cores.extend(segmentation.core(second));
    let max_depth = config.depths.iter().copied().max().unwrap_or(0);
    let region_hops = max_depth + 1;
    let region: Vec<u32> = graph
        .hops_from(&cores, region_hops)?
        .into_iter()
        .map(|r| r.0)
        .collect();
    let mm = |p: &[Vec3]| graph.roughness_m(p, &region).map(|r| r * 1000.0);
    let source_roughness_mm = mm(source)?;
    let target_roughness_mm = target_positions.as_deref().map(mm).transpose()?;

    let amounts: Vec<f32> = (0..=config.amount_steps)
        .map(|i| i as f32 / config.amount_steps as f32)
        .collect();
    let cases = [vec![first], vec![second], vec![first, second]];
    let mut curves = Vec::new();
    for case in &cases {
        for &decay in &config.decays {
            for &depth in &config.depths {
                let blend = segmentation.blend(Propagation::new(depth, decay))?;
                let edits: Vec<SegmentEdit> = case
                    .iter()
                    .map(|&segment| SegmentEdit {
                        segment,
                        target: target.clone(),
                        amount: 1.0,
                    })
                    .collect();
                let full = segmentation.morph(&blend, source, &edits)?;
                let displacement: Vec<Vec3> = (0..body).map(|k| full[k] - source[k]).collect();
                let mut at = source.clone();
                let roughness_mm = amounts
                    .iter()
                    .map(|&u| {
                        for k in 0..body {
                            at[k] = source[k] + displacement[k] * u;
                        }
                        mm(&at)
                    })
                    .collect::<Result<Vec<f32>, _>>()?;
                curves.push(RoughnessCurve {
                    interpolated: case.clone(),
                    decay,
                    depth,
                    roughness_mm,
                });
            }
        }
    }
    Ok(RoughnessStudy {
        segments: config.segments,
        target: config.target.clone(),
        region_hops,
        region_vertex_count: region.len(),
        amounts,
        depths: config.depths.clone(),
        decays: config.decays.clone(),
        source_roughness_mm,
        target_roughness_mm,
        curves,
    })
}
