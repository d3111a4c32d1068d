//! The evaluation over ANSUR II subjects and its report.

use std::collections::BTreeMap;
use std::time::Instant;

use fitroom_body::ansur::AnsurSubject;
pub use fitroom_body::ansur::MeasureStats;
use fitroom_body::{
    BodyModel, BodySegment, FitOptions, FitRequest, Measure, Measurements, SizeChart, fit,
};
use serde::{Deserialize, Serialize};

use super::detail::Detailer;
use super::dressed::{DressOptions, worn};
use super::record::{Filmed, Stance, TURN_DEG, record};
use crate::fit::FitSettings;
use crate::fit::ViewPose;
use crate::garment_size::garment_chart;
use crate::person::{PersonMeasurement, measure_person};
use crate::posed::Placement;
use crate::prior::ShapePrior;
use crate::seed;
use crate::tracked::{TrackedView, calibration_frame, tracked_placement, tracked_views};
use crate::view::{AveragedView, CalibrationFrame};
use fitroom_depth::synthetic::NoiseSettings;
use fitroom_garment::GarmentSource;
use fitroom_math::parallel_map;
use fitroom_tracker::{TrackBody, Tracker, TrackerSettings};
use std::sync::Arc;

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
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum PoseSource {
    /// The filmed pose and the renderer's body pixels (the measurement alone).
    Truth,
    /// Our tracker's pose, pixels and skeleton over the same frames (the product's chain).
    Tracker,
    /// Our tracker's pixels, skeleton and floor, the fit started from the filmed pose and
    /// placement: the tracker's pixels alone (the pose's share of the error is the
    /// difference to `Tracker`).
    TrackerPixels,
}

/// One subject measured.
#[derive(Clone, Debug, Serialize, Deserialize)]
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
    /// The size of the garment worn, if one was.
    pub garment_size: Option<String>,
    /// Each view's points' RMS at the end (clamped), mm; whether the turned view was left
    /// out ([`crate::person::TURNED_RMS_RATIO`]).
    #[serde(default)]
    pub view_rms_mm: Vec<f32>,
    #[serde(default)]
    pub turned_dropped: bool,
    /// Both genders' fits, the kept one first (what the choice between them saw).
    #[serde(default)]
    pub fits: Vec<GenderFit>,
    /// The radial scale of each segment given detail ([`EvalOptions::detail`]); empty: the
    /// slider body itself.
    #[serde(default)]
    pub detail: Vec<(BodySegment, f32)>,
    pub error: Option<String>,
}

/// One gender's fit of a subject.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct GenderFit {
    pub female: bool,
    /// The fit's cost, m²; `ln det` of its normal matrix; its evidence
    /// ([`crate::person::evidence`]), nats.
    pub cost: f64,
    pub log_det_h: f64,
    pub evidence: f64,
    pub view_rms_mm: Vec<f32>,
    /// Its measurements, cm, and the size they give (the subject's gender's chart).
    pub measured: BTreeMap<Measure, f32>,
    pub size: Option<String>,
}

/// The error summary's tolerance (`within_tolerance`: the share within it), cm: a quarter of
/// an EN 13402 size step (4 cm of bust).
pub const TOLERANCE_CM: f64 = 1.0;

/// The evaluation's figures.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct MeasureReport {
    pub subjects: usize,
    pub failed: usize,
    pub seed: u64,
    pub frames: usize,
    /// The second view's turn, degrees (0: the front view alone).
    pub turn_deg: f32,
    /// The garment the subjects wore, if any.
    pub garment: Option<String>,
    /// The largest relative change of a segment's girth in the bodies' detail (0: slider
    /// bodies, which the fit can match exactly; see [`EvalOptions::detail`]).
    #[serde(default)]
    pub detail: f32,
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

/// How the evaluation films and measures.
#[derive(Clone, Debug, Serialize)]
pub struct EvalOptions {
    /// The garment the subjects wear (each in the size its own table gives their true
    /// measurements), or none.
    #[serde(skip)]
    pub garment: Option<Arc<GarmentSource>>,
    pub pose: PoseSource,
    /// Calibration frames per view.
    pub frames: usize,
    /// The second view's turn from the first, degrees (the calibration's turn to the side);
    /// 0: the front view alone.
    pub turn_deg: f32,
    /// Draws the stances and the sensor's noise.
    pub seed: u64,
    /// Subjects measured at once.
    pub threads: usize,
    /// Detail the fit cannot express, added to each slider body before it is filmed (and
    /// measured for the truth); none: the slider bodies.
    #[serde(skip)]
    pub detail: Option<Arc<Detailer>>,
}

impl Default for EvalOptions {
    fn default() -> Self {
        Self {
            pose: PoseSource::Tracker,
            frames: 30,
            turn_deg: TURN_DEG,
            seed: 1,
            threads: 2,
            garment: None,
            detail: None,
        }
    }
}

/// Measures each subject: their body made from their ANSUR measurements, filmed in a
/// calibration stance drawn from `options.seed` (and turned, for the second view), measured
/// by both methods. `charts` are the women's and the men's size charts.
pub fn evaluate(
    model: &BodyModel,
    subjects: &[AnsurSubject],
    prior: &ShapePrior,
    charts: (&SizeChart, &SizeChart),
    settings: &FitSettings,
    options: &EvalOptions,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> MeasureReport {
    let done = std::sync::atomic::AtomicUsize::new(0);
    let indexed: Vec<(usize, &AnsurSubject)> = subjects.iter().enumerate().collect();
    let fit_settings = FitSettings {
        threads: 1,
        ..settings.clone()
    };
    let results = parallel_map(&indexed, options.threads, |&(k, s)| {
        let r = one(
            model,
            s,
            prior,
            charts,
            &fit_settings,
            options,
            options.seed ^ (k as u64) << 20,
        );
        progress(
            done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1,
            subjects.len(),
        );
        r
    });
    summarise(results, options)
}

fn one(
    model: &BodyModel,
    s: &AnsurSubject,
    prior: &ShapePrior,
    (women, men): (&SizeChart, &SizeChart),
    settings: &FitSettings,
    options: &EvalOptions,
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
        garment_size: None,
        view_rms_mm: Vec::new(),
        turned_dropped: false,
        fits: Vec::new(),
        detail: Vec::new(),
        error: None,
    };
    let request = FitRequest {
        gender: if s.female { 0.0 } else { 1.0 },
        age_years: None,
        targets: s.measurements.clone(),
    };
    let mut garment_size: Option<String> = None;
    let mut views_seen: (Vec<f32>, bool) = (Vec::new(), false);
    let mut detail = Vec::new();
    let mut run =
        || -> Result<(Measurements, PersonMeasurement, seed::SeedMeasurement, f64), String> {
            let shape = fit(model, &request, &FitOptions::default())
                .map_err(|e| e.to_string())?
                .shape;
            let detailed = match &options.detail {
                None => None,
                Some(detailer) => {
                    let rest = model.shaped(&shape).map_err(|e| e.to_string())?.positions;
                    let detailed = detailer.detailed(&rest, seed).map_err(|e| e.to_string())?;
                    detail = detailed.factors;
                    Some(detailed.positions)
                }
            };
            // Dressed: the garment in the subject's size, settled once on the body in the
            // calibration pose; it turns with the body.
            let worn = match &options.garment {
                None => None,
                Some(source) => {
                    let at_rest = model.shaped(&shape).map_err(|e| e.to_string())?;
                    let measured = model
                        .measure(&at_rest.positions)
                        .map_err(|e| e.to_string())?;
                    let size = garment_chart(source)
                        .ok()
                        .and_then(|c| c.recommend(&measured).size);
                    let (worn, dressed) = worn(
                        model,
                        &shape,
                        &stance,
                        source,
                        size.as_deref(),
                        &DressOptions::default(),
                    )
                    .map_err(|e| e.to_string())?;
                    garment_size = Some(dressed.size);
                    Some(worn)
                }
            };
            let mut stances = vec![stance];
            if options.turn_deg != 0.0 {
                stances.push(stance.turned(options.turn_deg));
            }
            let mut truth = None;
            let mut filmed = Vec::with_capacity(stances.len());
            for (i, st) in stances.iter().enumerate() {
                let rec = record(
                    model,
                    Filmed {
                        shape: &shape,
                        detailed: detailed.as_deref(),
                    },
                    st,
                    options.frames,
                    NoiseSettings::default(),
                    seed ^ (i as u64) << 40,
                    worn.as_ref(),
                )
                .map_err(|e| e.to_string())?;
                if truth.is_none() {
                    truth = Some(
                        model
                            .measure(&rec.body.positions)
                            .map_err(|e| e.to_string())?,
                    );
                }
                filmed.push(rec);
            }
            let truth = truth.ok_or("nothing was filmed")?;
            // The frames the fit gets, and the front view's for the seed's method.
            let (seen, front): (Vec<TrackedView>, Vec<CalibrationFrame>) = match options.pose {
                PoseSource::Truth => {
                    let front = filmed[0].frames.clone();
                    let seen = filmed
                        .into_iter()
                        .map(|rec| {
                            Ok(TrackedView {
                                view: AveragedView::new(&rec.frames).map_err(|e| e.to_string())?,
                                locals: rec.locals,
                                placement: rec.placement,
                            })
                        })
                        .collect::<Result<_, String>>()?;
                    (seen, front)
                }
                PoseSource::Tracker | PoseSource::TrackerPixels => {
                    let tracked = filmed
                        .iter()
                        .map(|rec| tracked(model, &rec.frames))
                        .collect::<Result<Vec<_>, _>>()?;
                    let front = tracked[0].0.clone();
                    let mut seen = tracked_views(model, &tracked).map_err(|e| e.to_string())?;
                    // The fit's start from the filmed pose: what the tracker's pose
                    // costs, apart from its pixels.
                    if options.pose == PoseSource::TrackerPixels {
                        for (v, rec) in seen.iter_mut().zip(&filmed) {
                            v.locals.clone_from(&rec.locals);
                            v.placement = rec.placement;
                        }
                    }
                    (seen, front)
                }
            };
            let began = Instant::now();
            let views: Vec<ViewPose> = seen.iter().map(|v| v.as_view_pose()).collect();
            let ours = measure_person(model, &views, prior, settings).map_err(|e| e.to_string())?;
            let ms = began.elapsed().as_secs_f64() * 1e3;
            // The seed measures the front view.
            let theirs = seed::measure(&front).map_err(|e| e.to_string())?;
            views_seen = (
                ours.estimate.view_rms_m.iter().map(|r| r * 1e3).collect(),
                ours.turned_dropped,
            );
            Ok((truth, ours, theirs, ms))
        };
    match run() {
        Ok((truth, person, theirs, ms)) => {
            let chart = if s.female { women } else { men };
            let found_female = person.female;
            let fit_of = |e: &crate::BodyEstimate, female: bool| GenderFit {
                female,
                cost: e.cost,
                log_det_h: e.log_det_h,
                evidence: person.evidence[usize::from(!female)],
                view_rms_mm: e.view_rms_m.iter().map(|r| r * 1e3).collect(),
                measured: Measure::ALL
                    .iter()
                    .map(|&m| (m, m.of(&e.measurements)))
                    .collect(),
                size: chart.recommend(&e.measurements).size,
            };
            result.fits = std::iter::once(fit_of(&person.estimate, found_female))
                .chain(person.other.iter().map(|o| fit_of(o, !found_female)))
                .collect();
            let ours = person.estimate.measurements;
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
    result.garment_size = garment_size;
    result.detail = detail;
    (result.view_rms_mm, result.turned_dropped) = views_seen;
    result
}

/// The frames as our tracker sees them (from the default body, as in the kiosk), and where
/// it saw the body stand in the last of them.
pub type Tracked = (Vec<CalibrationFrame>, Placement);

pub fn tracked(model: &BodyModel, frames: &[CalibrationFrame]) -> Result<Tracked, String> {
    let body = TrackBody::new(model, &model.positions).map_err(|e| e.to_string())?;
    let mut tracker = Tracker::new(body, TrackerSettings::default());
    let mut out = Vec::new();
    let mut pose = None;
    for f in frames {
        if let Some(t) = tracker.track(&f.depth) {
            out.push(calibration_frame(&f.depth, &t));
            pose = Some(tracked_placement(&t));
        }
    }
    let placement = pose.ok_or("the tracker found nobody in the calibration")?;
    Ok((out, placement))
}

fn summarise(results: Vec<SubjectResult>, options: &EvalOptions) -> MeasureReport {
    let ok: Vec<&SubjectResult> = results.iter().filter(|r| r.error.is_none()).collect();
    let errors = |m: Measure| -> Vec<f64> {
        ok.iter()
            .map(|r| f64::from(r.ours[&m] - r.truth[&m]))
            .collect()
    };
    let ours = EVALUATED
        .iter()
        .map(|&m| MeasureStats::of(m, &errors(m), TOLERANCE_CM))
        .collect();
    let seed_errors = |f: fn(&SubjectResult) -> f32, m: Measure| -> Vec<f64> {
        ok.iter().map(|r| f64::from(f(r) - r.truth[&m])).collect()
    };
    let seed_method = vec![
        MeasureStats::of(
            Measure::Stature,
            &seed_errors(|r| r.seed_stature_cm, Measure::Stature),
            TOLERANCE_CM,
        ),
        MeasureStats::of(
            Measure::ShoulderWidth,
            &seed_errors(|r| r.seed_shoulder_width_cm, Measure::ShoulderWidth),
            TOLERANCE_CM,
        ),
    ];
    let seed_map_only = vec![
        MeasureStats::of(
            Measure::Stature,
            &seed_errors(|r| r.seed_stature_map_cm, Measure::Stature),
            TOLERANCE_CM,
        ),
        MeasureStats::of(
            Measure::ShoulderWidth,
            &seed_errors(|r| r.seed_shoulder_width_map_cm, Measure::ShoulderWidth),
            TOLERANCE_CM,
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
        seed: options.seed,
        frames: options.frames,
        turn_deg: options.turn_deg,
        garment: options.garment.as_ref().map(|g| g.name()),
        detail: options.detail.as_ref().map_or(0.0, |d| d.spread()),
        pose: match options.pose {
            PoseSource::Truth => "filmed pose and body pixels (truth)".into(),
            PoseSource::Tracker => "our tracker (pose, pixels, skeleton)".into(),
            PoseSource::TrackerPixels => {
                "our tracker's pixels, skeleton and floor; the filmed pose as the fit's start"
                    .into()
            }
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
