//! Hand-state training and evaluation on synthetic hands ([`crate::synth`]): examples
//! filmed from a range of seeds (the training seeds and the held-out test seeds never
//! overlap), the skeleton's joints disturbed as a tracker's are, both methods trained on one
//! range and scored per 0.5 m of distance on another.

use fitroom_body::{BodyModel, ShapeError};
use fitroom_depth::synthetic::{NoiseSettings, next_unit, splitmix64};
use fitroom_sensor::KinectJoint;
use glam::Vec3;

use crate::hand::classify::{Example, HandModel, MIN_PIXELS, inputs};
use crate::hand::region::{HandJoints, hand_region};
use crate::hand::seed::seed_score;
use crate::synth::{HandPose, HandShot, HandStudio};
use crate::{HandSide, HandState};

/// The first seed of the held-out test examples (training uses seeds below it).
pub const TEST_SEEDS: u64 = 1 << 32;

/// What to film.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Sampling {
    /// Examples filmed, from seed `first_seed` on.
    pub count: usize,
    pub first_seed: u64,
    /// Distances drawn uniformly in this range, metres.
    pub near_m: f32,
    pub far_m: f32,
    /// Each joint (hand, wrist, elbow) moved by a Gaussian of this deviation per axis,
    /// metres: the tracker's error (its hands are 4-7 cm off in 3D on the recordings).
    pub joint_error_m: f32,
}

impl Sampling {
    /// `count` examples from `first_seed`, 1-3.5 m, joints off by 2.5 cm per axis.
    pub fn new(count: usize, first_seed: u64) -> Self {
        Self {
            count,
            first_seed,
            near_m: 1.0,
            far_m: 3.5,
            joint_error_m: 0.025,
        }
    }
}

/// One filmed example, read by both methods.
#[derive(Clone, Copy, Debug)]
pub struct Sample {
    pub pose: HandPose,
    pub example: Example,
    /// Whether the region lay on something (ours then says unknown).
    pub touching: bool,
}

/// The skeleton joints of `side`'s hand in `joints`, each moved by `error_m` per axis
/// (Gaussian, from `state`).
pub fn hand_joints(
    joints: &[Vec3; KinectJoint::COUNT],
    side: HandSide,
    error_m: f32,
    state: &mut u64,
) -> HandJoints {
    let [h, w, e] = side.arm_joints();
    let mut gauss = || {
        // Box-Muller.
        let (a, b) = (next_unit(state).max(1e-7), next_unit(state));
        (-2.0 * a.ln()).sqrt() * (std::f32::consts::TAU * b).cos()
    };
    let mut off = || Vec3::new(gauss(), gauss(), gauss()) * error_m;
    HandJoints {
        hand: joints[h.index()] + off(),
        wrist: joints[w.index()] + off(),
        elbow: joints[e.index()] + off(),
        head_neck_m: joints[KinectJoint::Head.index()]
            .distance(joints[KinectJoint::ShoulderCenter.index()]),
    }
}

/// Both methods' inputs for one shot.
pub fn read_shot(shot: &HandShot, error_m: f32, seed: u64) -> Sample {
    let mut state = splitmix64(seed ^ 0x0a11_7e55);
    let joints = hand_joints(&shot.joints, shot.pose.side, error_m, &mut state);
    let region = hand_region(&shot.frame, &joints);
    let features = region.as_ref().map(|r| r.features(&shot.frame.camera));
    let touching = region.as_ref().is_some_and(|r| r.touching);
    let inputs = features
        .filter(|f| f.pixels >= MIN_PIXELS)
        .map(|f| inputs(&f, joints.hand_length_m()));
    Sample {
        pose: shot.pose,
        example: Example {
            inputs,
            seed_score: seed_score(&shot.frame, &joints),
            open: shot.pose.state == HandState::Open,
        },
        touching,
    }
}

/// Films and reads `sampling`'s examples on `threads` threads; `progress` is called with
/// the number done.
pub fn film_samples(
    model: &BodyModel,
    sampling: &Sampling,
    threads: usize,
    progress: &(dyn Fn(usize) + Sync),
) -> Result<Vec<Sample>, ShapeError> {
    let studio = HandStudio::new(model, NoiseSettings::default());
    let done = std::sync::atomic::AtomicUsize::new(0);
    let threads = threads.max(1);
    let chunks: Vec<Result<Vec<(usize, Sample)>, ShapeError>> = std::thread::scope(|scope| {
        let handles: Vec<_> = (0..threads)
            .map(|t| {
                let (studio, done) = (&studio, &done);
                scope.spawn(move || {
                    let mut out = Vec::new();
                    for k in (t..sampling.count).step_by(threads) {
                        let seed = sampling.first_seed + k as u64;
                        let mut s = splitmix64(seed ^ 0xd15_7a9ce);
                        let d = sampling.near_m
                            + (sampling.far_m - sampling.near_m) * next_unit(&mut s);
                        let pose = HandPose::drawn(seed, d);
                        let shot = studio.film(&pose, seed)?;
                        out.push((k, read_shot(&shot, sampling.joint_error_m, seed)));
                        progress(done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1);
                    }
                    Ok(out)
                })
            })
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().unwrap_or_else(|e| std::panic::resume_unwind(e)))
            .collect()
    });
    let mut all = Vec::with_capacity(sampling.count);
    for chunk in chunks {
        all.extend(chunk?);
    }
    all.sort_by_key(|(k, _)| *k);
    Ok(all.into_iter().map(|(_, s)| s).collect())
}

/// One distance band's scores.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct BandScore {
    pub near_m: f32,
    pub far_m: f32,
    pub examples: usize,
    /// Share of examples called right (an unknown counts as wrong), ours and the seed's.
    pub ours: f32,
    pub seed: f32,
    /// Share ours called unknown.
    pub ours_unknown: f32,
}

/// Scores of `model` on `samples` per distance band `[edges[k], edges[k+1])`.
pub fn score(model: &HandModel, samples: &[Sample], edges: &[f32]) -> Vec<BandScore> {
    edges
        .windows(2)
        .map(|w| {
            let within: Vec<&Sample> = samples
                .iter()
                .filter(|s| s.pose.distance_m >= w[0] && s.pose.distance_m < w[1])
                .collect();
            let n = within.len().max(1) as f32;
            let ours = within
                .iter()
                .filter(|s| {
                    s.example
                        .inputs
                        .is_some_and(|x| (model.p_open(&x) >= 0.5) == s.example.open)
                })
                .count() as f32;
            let unknown = within.iter().filter(|s| s.example.inputs.is_none()).count() as f32;
            let seed = within
                .iter()
                .filter(|s| {
                    s.example
                        .seed_score
                        .is_some_and(|x| (x > model.seed_threshold) == s.example.open)
                })
                .count() as f32;
            BandScore {
                near_m: w[0],
                far_m: w[1],
                examples: within.len(),
                ours: ours / n,
                seed: seed / n,
                ours_unknown: unknown / n,
            }
        })
        .collect()
}

/// The share called right over all bands from `near_m` to `far_m` (weighted by examples).
pub fn pooled(bands: &[BandScore], near_m: f32, far_m: f32) -> (f32, f32) {
    let inside: Vec<&BandScore> = bands
        .iter()
        .filter(|b| b.near_m >= near_m - 1e-4 && b.far_m <= far_m + 1e-4)
        .collect();
    let n: usize = inside.iter().map(|b| b.examples).sum();
    let n = n.max(1) as f32;
    (
        inside
            .iter()
            .map(|b| b.ours * b.examples as f32)
            .sum::<f32>()
            / n,
        inside
            .iter()
            .map(|b| b.seed * b.examples as f32)
            .sum::<f32>()
            / n,
    )
}
