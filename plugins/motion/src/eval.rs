//! Evaluation of the motion pipeline against clean motion capture (issue: "measured on real
//! motion capture"; seed 000 chapter 4 had no measurements).
//!
//! A clean CMU clip is replayed as a 30 Hz Kinect stream, corrupted by the seeded Kinect v1
//! noise model, then run through the pipeline the kiosk uses ([`MotionPipeline`], the same type):
//! bad-frame gate -> joint filter -> retargeting -> joint limits -> foot-skate correction ->
//! joint limits. Positions are compared
//! with the clean frame each noisy frame shows (`NoisyFrame::clean_index`), so the sensor's own
//! latency, the same for every filter, is not counted as filter lag.

use std::{path::Path, str::FromStr, time::Instant};

use fitroom_sensor::{
    KinectJoint, SensorFrame,
    bvh::BvhError,
    bvh_source::{BvhSource, BvhSourceOptions},
    noise::{KinectNoiseModel, corrupt_stream},
};
use serde::Serialize;

use crate::{
    AvatarPose, AvatarSkeleton, RetargetOptions, Retargeter,
    filter::{FilterKind, JointFilter, UnknownFilter},
    footskate::{FootSkateError, SkateCriteria, foot_skating},
    metrics::{self, FilterReport},
    pipeline::{AvatarPipeline, MotionPipeline, MotionStep, PipelineError},
};

/// Which filter to evaluate.
#[derive(Clone, Debug, PartialEq)]
pub enum FilterChoice {
    Kind(FilterKind),
    /// One Euro tuned on this clip with the authors' two-step procedure.
    OneEuroTuned,
}

impl FromStr for FilterChoice {
    type Err = UnknownFilter;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.to_ascii_lowercase().replace('_', "-").as_str() {
            "oneeuro-tuned" | "one-euro-tuned" => Ok(FilterChoice::OneEuroTuned),
            other => other.parse().map(FilterChoice::Kind),
        }
    }
}

impl FilterChoice {
    pub fn name(&self) -> String {
        match self {
            FilterChoice::Kind(kind) => kind.cli_name().to_string(),
            FilterChoice::OneEuroTuned => "oneeuro-tuned".into(),
        }
    }
}

/// What to evaluate.
#[derive(Clone, Debug)]
pub struct EvalOptions {
    pub filter: FilterChoice,
    /// `None`: the clean stream itself (no noise).
    pub noise: Option<KinectNoiseModel>,
    pub seed: u64,
    pub source: BvhSourceOptions,
}

impl Default for EvalOptions {
    fn default() -> Self {
        Self {
            filter: FilterChoice::Kind(FilterKind::default()),
            noise: Some(evaluation_noise()),
            seed: 1,
            source: BvhSourceOptions::default(),
        }
    }
}

/// The Kinect noise model used for evaluation: the defaults, with the field-of-view and range
/// limits off. The walking clips cover several metres towards the sensor, far more than a
/// Kinect tracks; self-occlusion, depth noise, jitter, bone-length noise, drops, duplicates and
/// latency stay on.
pub fn evaluation_noise() -> KinectNoiseModel {
    KinectNoiseModel {
        view_limits_enabled: false,
        ..KinectNoiseModel::default()
    }
}

/// Why a clip could not be evaluated.
#[derive(Debug, thiserror::Error)]
pub enum EvalError {
    #[error(transparent)]
    Bvh(#[from] BvhError),
    #[error(transparent)]
    Pipeline(#[from] PipelineError),
    #[error(transparent)]
    Retarget(#[from] crate::RetargetError),
    #[error(transparent)]
    FootSkate(#[from] FootSkateError),
    #[error("{0}: the clip is too short to evaluate ({1} frames at 30 Hz)")]
    TooShort(String, usize),
}

/// The figures of one evaluation (`fitroom motion eval --json`).
#[derive(Clone, Debug, Serialize)]
pub struct EvalReport {
    pub clip: String,
    pub filter: String,
    pub seed: u64,
    pub frames: usize,
    /// The filter's output against the clean clip.
    pub output: FilterReport,
    /// The noisy input against the clean clip.
    pub input: FilterReport,
    /// Foot-skating ratio of the avatar driven by the noisy input (retargeted, no filter, no
    /// correction) and of the full pipeline's output, measured on the avatar's soles.
    pub avatar_foot_skate_input: f32,
    pub avatar_foot_skate_output: f32,
    /// How far the foot-skate correction moves the feet: mean and largest horizontal distance
    /// (mm) of the output's ankles from the uncorrected (filtered, retargeted, limited) pose's.
    pub foot_correction_mean_mm: f32,
    pub foot_correction_max_mm: f32,
    /// Joint-limit violations (> 0.5°) in the output poses, summed over frames.
    pub joint_limit_violations: usize,
    /// Frames the gate rejected.
    pub rejected_frames: u64,
    /// Mean CPU time of gate, filter, retargeting, limits and foot-skate per frame, µs.
    pub pipeline_us_per_frame: f64,
}

/// Everything an evaluation produced, for plots.
#[derive(Clone, Debug)]
pub struct ClipEvaluation {
    pub report: EvalReport,
    /// Aligned series: the clean frame each output frame shows, the noisy input, the output.
    pub clean: Vec<SensorFrame>,
    pub noisy: Vec<SensorFrame>,
    pub filtered: Vec<SensorFrame>,
    pub poses: Vec<AvatarPose>,
}

/// The clean 30 Hz stream of a whole clip (one loop).
pub fn clean_stream(source: &BvhSource) -> Vec<SensorFrame> {
    let fps = source.options().fps.max(1.0);
    let count = (source.clip_duration_s() * fps).floor() as usize + 1;
    (0..count)
        .map(|i| {
            let mut frame = source.frame_at(i as f64 / fps);
            frame.sequence = i as u64;
            frame
        })
        .collect()
}

/// Runs the whole evaluation of one clip.
pub fn evaluate_clip(
    path: &Path,
    skeleton: &AvatarSkeleton,
    options: &EvalOptions,
) -> Result<ClipEvaluation, EvalError> {
    let source = BvhSource::load(path, options.source)?;
    let clip_name = Path::new(source.clip().file_name())
        .file_name()
        .map_or_else(
            || source.clip().file_name().to_string(),
            |n| n.to_string_lossy().into(),
        );
    let clean_all = clean_stream(&source);
    if clean_all.len() < 8 {
        return Err(EvalError::TooShort(clip_name, clean_all.len()));
    }
    let floor_y = -options.source.sensor_height_m;
    let (noisy, shows): (Vec<SensorFrame>, Vec<usize>) = match &options.noise {
        Some(model) => corrupt_stream(&clean_all, model, options.seed)
            .into_iter()
            .map(|n| (n.frame, n.clean_index.min(clean_all.len() - 1)))
            .unzip(),
        None => (clean_all.clone(), (0..clean_all.len()).collect()),
    };

    let filter: Box<dyn JointFilter> = match &options.filter {
        FilterChoice::Kind(kind) => kind.build(),
        FilterChoice::OneEuroTuned => {
            let clean_shown: Vec<SensorFrame> =
                shows.iter().map(|&i| clean_all[i].clone()).collect();
            let params = crate::filter::one_euro::tune_one_euro(
                &clean_shown,
                &noisy,
                &crate::filter::one_euro::OneEuroTuning::default(),
            );
            FilterKind::OneEuro(params).build()
        }
    };
    let mut pipeline = MotionPipeline::new(AvatarPipeline::new(skeleton, floor_y)?, filter);
    let mut raw_pipeline = Retargeter::new(
        skeleton.clone(),
        RetargetOptions {
            floor_y,
            ..RetargetOptions::default()
        },
    )?;
    let (mut correction_sum, mut correction_max, mut correction_count) = (0.0f64, 0.0f32, 0usize);

    let mut clean = Vec::with_capacity(noisy.len());
    let mut kept_noisy = Vec::with_capacity(noisy.len());
    let mut filtered = Vec::with_capacity(noisy.len());
    let mut poses = Vec::with_capacity(noisy.len());
    let mut raw_poses = Vec::with_capacity(noisy.len());
    let mut busy_s = 0.0;
    for (frame, &shown) in noisy.iter().zip(&shows) {
        let start = Instant::now();
        let step = pipeline.push(frame);
        busy_s += start.elapsed().as_secs_f64();
        // Bad frames never reach the avatar: the last output stays.
        let Some(MotionStep {
            filtered: out,
            pose,
        }) = step
        else {
            continue;
        };
        raw_poses.push(raw_pipeline.update(frame));
        for d in pipeline.avatar.last_foot_correction_m {
            if d.is_finite() {
                correction_sum += f64::from(d);
                correction_max = correction_max.max(d);
                correction_count += 1;
            }
        }
        clean.push(clean_all[shown].clone());
        kept_noisy.push(frame.clone());
        filtered.push(out);
        poses.push(pose);
    }

    let criteria = SkateCriteria::default();
    let skate_in = foot_skating(skeleton, &raw_poses, floor_y, criteria)?.ratio();
    let skate_out = foot_skating(skeleton, &poses, floor_y, criteria)?.ratio();
    let violations = poses
        .iter()
        .map(|p| pipeline.avatar.limits().violations(p).len())
        .sum();
    let report = EvalReport {
        clip: clip_name,
        filter: options.filter.name(),
        seed: options.seed,
        frames: filtered.len(),
        output: metrics::evaluate(&clean, &filtered, floor_y),
        input: metrics::evaluate(&clean, &kept_noisy, floor_y),
        avatar_foot_skate_input: skate_in,
        avatar_foot_skate_output: skate_out,
        foot_correction_mean_mm: (1000.0 * correction_sum / correction_count.max(1) as f64) as f32,
        foot_correction_max_mm: 1000.0 * correction_max,
        joint_limit_violations: violations,
        rejected_frames: pipeline.gate.stats().rejected_total(),
        pipeline_us_per_frame: busy_s * 1e6 / noisy.len().max(1) as f64,
    };
    Ok(ClipEvaluation {
        report,
        clean,
        noisy: kept_noisy,
        filtered,
        poses,
    })
}

/// The angle at `joint` between the bones to its parent and to `child`, degrees (e.g. the
/// elbow's flexion: 180° when straight). `None` where a bone has no length.
pub fn joint_angle_deg(frame: &SensorFrame, joint: KinectJoint, child: KinectJoint) -> Option<f32> {
    let parent = joint.parent()?;
    let at = frame.joint(joint).position;
    let a = frame.joint(parent).position - at;
    let b = frame.joint(child).position - at;
    (a.length() > 1e-6 && b.length() > 1e-6).then(|| a.angle_between(b).to_degrees())
}
