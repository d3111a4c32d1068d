//! The evaluation over ANSUR II subjects and its report.

use std::collections::BTreeMap;
use std::time::Instant;

use fitroom_body::ansur::AnsurSubject;
use fitroom_body::{BodyModel, FitOptions, FitRequest, Measure, Measurements, SizeChart, fit};
use fitroom_math::stats::percentile;
use serde::Serialize;

use super::record::{Stance, record};
use crate::fit::FitSettings;
use crate::person::measure_person;
use crate::posed::Placement;
use crate::prior::ShapePrior;
use crate::seed;
use crate::tracked::{calibration_frame, tracked_pose};
use crate::view::{AveragedView, CalibrationFrame};
use fitroom_depth::synthetic::NoiseSettings;
use fitroom_math::parallel_map;
use fitroom_tracker::{TrackBody, Tracker, TrackerSettings};

/// The measurements the evaluation reports (the list; both waists).
pub const EVALUATED: [Measure; 10] = [
    Measure::Stature,
    Measure::ShoulderWidth,
    Measure::Bust,
    Measure::Waist,
    Measure::NavelWaist,
    Measure::Hip,
    Measure::InsideLeg,
    Measure::ArmLength,
    Measure::Neck,
    Measure::Thigh,
];

/// The subjects the shape prior may learn from: every other one of each survey file
/// (even positions). The evaluation uses the others ([`held_out`]).
pub fn training(subjects: &[AnsurSubject]) -> Vec<AnsurSubject> {
    subjects.iter().step_by(2).cloned().collect()
}

/// The subjects the prior never saw (odd positions).
pub fn held_out(subjects: &[AnsurSubject]) -> Vec<AnsurSubject> {
    subjects.iter().skip(1).step_by(2).cloned().collect()
}

/// Where the fit's pose and the person's pixels come from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum PoseSource {
    /// The filmed pose and the renderer's body pixels (the measurement alone).
    Truth,
    /// Our tracker's pose, pixels and skeleton over the same frames (the product's chain).
    Tracker,
}

/// One subject measured.
#[derive(Clone, Debug, Serialize)]
pub struct SubjectResult {
    pub id: String,
    pub female: bool,
    pub stance: Stance,
    /// The filmed body's own measurements, cm.
    pub truth: BTreeMap<Measure, f32>,
    /// Ours, cm.
    pub ours: BTreeMap<Measure, f32>,
    /// The seed's height and shoulder width, cm.
    pub seed_stature_cm: f32,
    pub seed_shoulder_width_cm: f32,
    /// The same read off the depth map alone (before Eq. 6.7's averaging with the
    /// proportions' estimates), cm.
    pub seed_stature_map_cm: f32,
    pub seed_shoulder_width_map_cm: f32,
    /// The gender whose prior explained the frames better.
    pub found_female: bool,
    /// The size of the subject's gender's chart for the true and for our measurements.
    pub size_truth: Option<String>,
    pub size_ours: Option<String>,
    /// From the averaged frames to the measured body, ms.
    pub fit_ms: f64,
    pub error: Option<String>,
}

/// The error distribution of one measurement, cm.
#[derive(Clone, Debug, Serialize)]
pub struct MeasureStats {
    pub measure: Measure,
    pub count: usize,
    pub mean_abs_cm: f64,
    /// Mean of measured minus true.
    pub bias_cm: f64,
    pub p95_abs_cm: f64,
    pub max_abs_cm: f64,
}

impl MeasureStats {
    fn of(measure: Measure, errors: &[f64]) -> Self {
        let mut abs: Vec<f64> = errors.iter().map(|e| e.abs()).collect();
        abs.sort_by(f64::total_cmp);
        let n = errors.len().max(1) as f64;
        Self {
            measure,
            count: errors.len(),
            mean_abs_cm: abs.iter().sum::<f64>() / n,
            bias_cm: errors.iter().sum::<f64>() / n,
            p95_abs_cm: if abs.is_empty() {
                0.0
            } else {
                percentile(&abs, 0.95)
            },
            max_abs_cm: abs.last().copied().unwrap_or(0.0),
        }
    }
}

/// The evaluation's figures.
#[derive(Clone, Debug, Serialize)]
pub struct MeasureReport {
    pub subjects: usize,
    pub failed: usize,
    pub seed: u64,
    pub frames: usize,
    /// Where the pose came from ("truth": the filmed pose).
    pub pose: String,
    pub ours: Vec<MeasureStats>,
    /// The seed's method: stature and shoulder width (Eq. 6.7's averages).
    pub seed_method: Vec<MeasureStats>,
    /// The seed's stature and shoulder width read off the depth map alone.
    pub seed_map_only: Vec<MeasureStats>,
    /// Stature's mean absolute error in % of stature, ours and the seed's.
    pub stature_percent_ours: f64,
    pub stature_percent_seed: f64,
    pub stature_percent_seed_map: f64,
    /// Share of subjects whose recommended size (their gender's chart) equals the true one.
    pub size_agreement: f64,
    /// Share of subjects whose gender the fit found.
    pub gender_agreement: f64,
    pub mean_fit_ms: f64,
    pub max_fit_ms: f64,
    pub results: Vec<SubjectResult>,
}

/// Measures each subject: their body made from their ANSUR measurements, filmed in a
/// calibration stance drawn from `seed`, measured by both methods. `charts` are the
/// women's and the men's size charts. Subjects run on `threads` threads.
#[allow(clippy::too_many_arguments)]
pub fn evaluate(
    model: &BodyModel,
    subjects: &[AnsurSubject],
    prior: &ShapePrior,
    charts: (&SizeChart, &SizeChart),
    settings: &FitSettings,
    pose: PoseSource,
    frames: usize,
    seed: u64,
    threads: usize,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> MeasureReport {
    let done = std::sync::atomic::AtomicUsize::new(0);
    let indexed: Vec<(usize, &AnsurSubject)> = subjects.iter().enumerate().collect();
    let fit_settings = FitSettings {
        threads: 1,
        ..settings.clone()
    };
    let results = parallel_map(&indexed, threads, |&(k, s)| {
        let r = one(
            model,
            s,
            prior,
            charts,
            &fit_settings,
            pose,
            frames,
            seed ^ (k as u64) << 20,
        );
        progress(
            done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1,
            subjects.len(),
        );
        r
    });
    summarise(results, seed, frames, pose)
}

#[allow(clippy::too_many_arguments)]
fn one(
    model: &BodyModel,
    s: &AnsurSubject,
    prior: &ShapePrior,
    (women, men): (&SizeChart, &SizeChart),
    settings: &FitSettings,
    pose: PoseSource,
    frames: usize,
    seed: u64,
) -> SubjectResult {
    let stance = Stance::drawn(seed);
    let mut result = SubjectResult {
        id: s.id.clone(),
        female: s.female,
        stance,
        truth: BTreeMap::new(),
        ours: BTreeMap::new(),
        seed_stature_cm: f32::NAN,
        seed_shoulder_width_cm: f32::NAN,
        seed_stature_map_cm: f32::NAN,
        seed_shoulder_width_map_cm: f32::NAN,
        found_female: s.female,
        size_truth: None,
        size_ours: None,
        fit_ms: 0.0,
        error: None,
    };
    let request = FitRequest {
        gender: if s.female { 0.0 } else { 1.0 },
        age_years: None,
        targets: s.measurements.clone(),
    };
    let run =
        || -> Result<(Measurements, Measurements, seed::SeedMeasurement, bool, f64), String> {
            let shape = fit(model, &request, &FitOptions::default())
                .map_err(|e| e.to_string())?
                .shape;
            let rec = record(
                model,
                &shape,
                &stance,
                frames,
                NoiseSettings::default(),
                seed,
            )
            .map_err(|e| e.to_string())?;
            let truth = model
                .measure(&rec.body.positions)
                .map_err(|e| e.to_string())?;
            let (frames, locals, placement) = match pose {
                PoseSource::Truth => (rec.frames, rec.locals, rec.placement),
                PoseSource::Tracker => tracked(model, &rec.frames)?,
            };
            let began = Instant::now();
            let view = AveragedView::new(&frames).map_err(|e| e.to_string())?;
            let ours = measure_person(model, &view, &locals, placement, prior, settings)
                .map_err(|e| e.to_string())?;
            let ms = began.elapsed().as_secs_f64() * 1e3;
            let theirs = seed::measure(&frames).map_err(|e| e.to_string())?;
            Ok((truth, ours.estimate.measurements, theirs, ours.female, ms))
        };
    match run() {
        Ok((truth, ours, theirs, found_female, ms)) => {
            let chart = if s.female { women } else { men };
            result.truth = Measure::ALL.iter().map(|&m| (m, m.of(&truth))).collect();
            result.ours = Measure::ALL.iter().map(|&m| (m, m.of(&ours))).collect();
            result.seed_stature_cm = theirs.height_m * 100.0;
            result.seed_shoulder_width_cm = theirs.shoulder_width_m * 100.0;
            result.seed_stature_map_cm = theirs.height_map_m * 100.0;
            result.seed_shoulder_width_map_cm = theirs.shoulder_width_map_m * 100.0;
            result.found_female = found_female;
            result.size_truth = chart.recommend(&truth).size;
            result.size_ours = chart.recommend(&ours).size;
            result.fit_ms = ms;
        }
        Err(e) => result.error = Some(e),
    }
    result
}

/// The frames as our tracker sees them (from the default body, as in the kiosk), and the
/// pose it tracked in the last of them.
pub type Tracked = (Vec<CalibrationFrame>, Vec<glam::Quat>, Placement);

pub fn tracked(model: &BodyModel, frames: &[CalibrationFrame]) -> Result<Tracked, String> {
    let body = TrackBody::new(model, &model.positions).map_err(|e| e.to_string())?;
    let mut tracker = Tracker::new(body, TrackerSettings::default());
    let mut out = Vec::new();
    let mut pose = None;
    for f in frames {
        if let Some(t) = tracker.track(&f.depth) {
            out.push(calibration_frame(&f.depth, &t));
            pose = Some(tracked_pose(&t));
        }
    }
    let (locals, placement) = pose.ok_or("the tracker found nobody in the calibration")?;
    Ok((out, locals, placement))
}

fn summarise(
    results: Vec<SubjectResult>,
    seed: u64,
    frames: usize,
    pose: PoseSource,
) -> MeasureReport {
    let ok: Vec<&SubjectResult> = results.iter().filter(|r| r.error.is_none()).collect();
    let errors = |m: Measure| -> Vec<f64> {
        ok.iter()
            .map(|r| f64::from(r.ours[&m] - r.truth[&m]))
            .collect()
    };
    let ours = EVALUATED
        .iter()
        .map(|&m| MeasureStats::of(m, &errors(m)))
        .collect();
    let seed_errors = |f: fn(&SubjectResult) -> f32, m: Measure| -> Vec<f64> {
        ok.iter().map(|r| f64::from(f(r) - r.truth[&m])).collect()
    };
    let seed_method = vec![
        MeasureStats::of(
            Measure::Stature,
            &seed_errors(|r| r.seed_stature_cm, Measure::Stature),
        ),
        MeasureStats::of(
            Measure::ShoulderWidth,
            &seed_errors(|r| r.seed_shoulder_width_cm, Measure::ShoulderWidth),
        ),
    ];
    let seed_map_only = vec![
        MeasureStats::of(
            Measure::Stature,
            &seed_errors(|r| r.seed_stature_map_cm, Measure::Stature),
        ),
        MeasureStats::of(
            Measure::ShoulderWidth,
            &seed_errors(|r| r.seed_shoulder_width_map_cm, Measure::ShoulderWidth),
        ),
    ];
    let n = ok.len().max(1) as f64;
    let percent = |f: &dyn Fn(&SubjectResult) -> f32| {
        ok.iter()
            .map(|r| {
                f64::from(((f(r) - r.truth[&Measure::Stature]) / r.truth[&Measure::Stature]).abs())
            })
            .sum::<f64>()
            / n
            * 100.0
    };
    let times: Vec<f64> = ok.iter().map(|r| r.fit_ms).collect();
    MeasureReport {
        subjects: results.len(),
        failed: results.len() - ok.len(),
        seed,
        frames,
        pose: match pose {
            PoseSource::Truth => "filmed pose and body pixels (truth)".into(),
            PoseSource::Tracker => "our tracker (pose, pixels, skeleton)".into(),
        },
        ours,
        seed_method,
        seed_map_only,
        stature_percent_ours: percent(&|r| r.ours[&Measure::Stature]),
        stature_percent_seed: percent(&|r| r.seed_stature_cm),
        stature_percent_seed_map: percent(&|r| r.seed_stature_map_cm),
        size_agreement: ok.iter().filter(|r| r.size_truth == r.size_ours).count() as f64 / n,
        gender_agreement: ok.iter().filter(|r| r.found_female == r.female).count() as f64 / n,
        mean_fit_ms: times.iter().sum::<f64>() / n,
        max_fit_ms: times.iter().copied().fold(0.0, f64::max),
        results,
    }
}
