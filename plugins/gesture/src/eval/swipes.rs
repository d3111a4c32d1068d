//! Swipes: recall on scripted swipes (a standing body whose hand rises, sweeps across and
//! drops, through the Kinect skeleton noise model), and false swipes on the shared CMU
//! clips (walks, a wave, jumps, kicks, a dance: nobody is swiping).

use std::path::Path;

use fitroom_body::{BodyModel, Shape, ShapeError};
use fitroom_depth::synthetic::{next_unit, splitmix64};
use fitroom_sensor::noise::{KinectNoiseModel, corrupt_stream};
use fitroom_sensor::{
    BvhError, BvhSource, BvhSourceOptions, JointSample, KinectJoint, SensorFrame,
};
use glam::{Quat, Vec3};

use crate::HandSide;
use crate::swipe::{SwipeDetector, SwipeDirection, SwipeSettings, body_frame};
use crate::synth::standing_joints;

/// A scripted swipe drawn from a seed.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct ScriptedSwipe {
    pub hand: HandSide,
    pub direction: SwipeDirection,
    /// The sweep's duration, seconds, and its sideways travel, shoulder widths.
    pub duration_s: f32,
    pub travel: f32,
    /// The sweep's height relative to the shoulder centre and its reach in front of the
    /// shoulders, shoulder widths.
    pub height: f32,
    pub reach: f32,
    pub distance_m: f32,
    pub yaw_deg: f32,
}

impl ScriptedSwipe {
    /// Either hand, either way, 0.25-0.7 s, 1.2-1.8 shoulder widths across, from the lower
    /// chest to above the shoulders, the hand 0.8-1.3 shoulder widths in front, the person
    /// 1.8-3 m away, turned up to ±15°.
    pub fn drawn(seed: u64) -> Self {
        let mut s = splitmix64(seed ^ 0x5_01ee_0000);
        let mut u = || next_unit(&mut s);
        Self {
            hand: if u() < 0.5 {
                HandSide::Left
            } else {
                HandSide::Right
            },
            direction: if u() < 0.5 {
                SwipeDirection::Left
            } else {
                SwipeDirection::Right
            },
            duration_s: 0.25 + 0.45 * u(),
            travel: 1.2 + 0.6 * u(),
            height: -1.0 + 1.3 * u(),
            reach: 0.8 + 0.5 * u(),
            distance_m: 1.8 + 1.2 * u(),
            yaw_deg: (u() - 0.5) * 30.0,
        }
    }
}

/// Minimum-jerk progress from 0 to 1 over `x` in [0, 1].
pub(crate) fn min_jerk(x: f32) -> f32 {
    let x = x.clamp(0.0, 1.0);
    x * x * x * (10.0 - 15.0 * x + 6.0 * x * x)
}

/// The clean 30 Hz skeleton stream of `script` on a body of `shape`: 0.6 s standing, the
/// hand rising from beside the hip to the stroke's start (0.7 s), held 0.2 s, the sweep,
/// held 0.2 s, dropping back (0.7 s), 0.6 s standing; the elbow and wrist placed between
/// the shoulder and hand.
pub fn scripted_stream(
    model: &BodyModel,
    shape: &Shape,
    script: &ScriptedSwipe,
) -> Result<Vec<SensorFrame>, ShapeError> {
    let rest = standing_joints(
        model,
        shape,
        Vec3::new(0.0, -0.1, script.distance_m),
        script.yaw_deg,
    )?;
    let frame_of = |joints: &[Vec3; KinectJoint::COUNT], t: f64, k: u64| SensorFrame {
        timestamp_s: t,
        sequence: k,
        joints: std::array::from_fn(|j| JointSample {
            position: joints[j],
            orientation: Quat::IDENTITY,
            confidence: 1.0,
        }),
    };
    let still = frame_of(&rest, 0.0, 0);
    let Some((centre, right, forward, width)) = body_frame(&still) else {
        return Ok(Vec::new());
    };
    let (hand_j, wrist_j, elbow_j, shoulder_j) = match script.hand {
        HandSide::Left => (
            KinectJoint::HandLeft,
            KinectJoint::WristLeft,
            KinectJoint::ElbowLeft,
            KinectJoint::ShoulderLeft,
        ),
        HandSide::Right => (
            KinectJoint::HandRight,
            KinectJoint::WristRight,
            KinectJoint::ElbowRight,
            KinectJoint::ShoulderRight,
        ),
    };
    // The stroke is centred on the hand's own side of the body.
    let side = match script.hand {
        HandSide::Left => -1.0,
        HandSide::Right => 1.0,
    };
    let sign = match script.direction {
        SwipeDirection::Right => 1.0,
        SwipeDirection::Left => -1.0,
    };
    let mid = side * 0.3;
    let at =
        |x: f32| centre + (right * x + Vec3::Y * script.height + forward * script.reach) * width;
    let start = at(mid - sign * script.travel * 0.5);
    let end = at(mid + sign * script.travel * 0.5);
    // The arm hangs at the side between swipes (the rig rests its arms lifted 45°): the hand
    // an arm's length (2.6 shoulder widths) below the shoulder, a little out.
    let shoulder = rest[shoulder_j.index()];
    let rest_hand = shoulder + (right * side * 0.2 - Vec3::Y * 2.6) * width;
    let phases = [
        (0.6, rest_hand, rest_hand),
        (0.7, rest_hand, start),
        (0.2, start, start),
        (script.duration_s, start, end),
        (0.2, end, end),
        (0.7, end, rest_hand),
        (0.6, rest_hand, rest_hand),
    ];
    let total: f32 = phases.iter().map(|p| p.0).sum();
    let count = (total * 30.0).ceil() as usize;
    let mut out = Vec::with_capacity(count);
    for k in 0..count {
        let t = k as f32 / 30.0;
        let mut t0 = 0.0;
        let mut hand = rest_hand;
        for &(d, a, b) in &phases {
            if t < t0 + d {
                hand = a.lerp(b, min_jerk((t - t0) / d));
                break;
            }
            t0 += d;
        }
        let mut joints = rest;
        let elbow = shoulder.lerp(hand, 0.5) - Vec3::Y * 0.12;
        joints[hand_j.index()] = hand;
        joints[elbow_j.index()] = elbow;
        joints[wrist_j.index()] = hand + (elbow - hand).normalize_or_zero() * 0.08;
        out.push(frame_of(&joints, f64::from(t), k as u64));
    }
    Ok(out)
}

/// Recall on scripted swipes.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct SwipeRecall {
    pub scripted: usize,
    /// Swipes detected in the scripted direction (at least one per script).
    pub found: usize,
    /// Scripts with a swipe the other way, or more than one swipe.
    pub wrong_way: usize,
    pub extra: usize,
    pub missed: Vec<ScriptedSwipe>,
}

impl SwipeRecall {
    pub fn recall(&self) -> f32 {
        self.found as f32 / self.scripted.max(1) as f32
    }
}

/// Runs `count` scripted swipes (seeds from `first_seed`; the body's gender, height and
/// weight drawn from the seed too) through the Kinect skeleton noise model and `settings`.
pub fn swipe_recall(
    model: &BodyModel,
    settings: SwipeSettings,
    count: usize,
    first_seed: u64,
) -> Result<SwipeRecall, ShapeError> {
    let noise = KinectNoiseModel::default();
    let mut recall = SwipeRecall {
        scripted: count,
        found: 0,
        wrong_way: 0,
        extra: 0,
        missed: Vec::new(),
    };
    for k in 0..count as u64 {
        let seed = first_seed + k;
        let script = ScriptedSwipe::drawn(seed);
        let mut s = splitmix64(seed ^ 0xb0d1);
        let shape = Shape {
            gender: next_unit(&mut s),
            height: 0.2 + 0.6 * next_unit(&mut s),
            weight: 0.2 + 0.6 * next_unit(&mut s),
            ..Shape::default()
        };
        let clean = scripted_stream(model, &shape, &script)?;
        let mut detector = SwipeDetector::new(settings);
        let swipes: Vec<_> = corrupt_stream(&clean, &noise, seed)
            .iter()
            .filter_map(|n| detector.update(&n.frame))
            .collect();
        let right = swipes
            .iter()
            .filter(|s| s.direction == script.direction)
            .count();
        if right >= 1 {
            recall.found += 1;
        } else {
            recall.missed.push(script);
        }
        if right < swipes.len() {
            recall.wrong_way += 1;
        }
        recall.extra += swipes.len().saturating_sub(1);
    }
    Ok(recall)
}

/// False swipes on one clip.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct ClipFalseSwipes {
    pub clip: String,
    /// Seconds of motion played (every repeat).
    pub seconds: f64,
    pub swipes: usize,
}

/// Plays the clip at `path` `repeats` times (each repeat its own noise seed; every second
/// one mirrored, left and right swapped) through the Kinect skeleton noise model and
/// `settings`; counts the swipes.
pub fn false_swipes(
    path: &Path,
    settings: SwipeSettings,
    repeats: usize,
    seed: u64,
) -> Result<ClipFalseSwipes, BvhError> {
    let source = BvhSource::load(path, BvhSourceOptions::default())?;
    let fps = source.options().fps.max(1.0);
    let count = (source.clip_duration_s() * fps).floor() as usize + 1;
    let clean: Vec<SensorFrame> = (0..count)
        .map(|i| {
            let mut frame = source.frame_at(i as f64 / fps);
            frame.sequence = i as u64;
            frame
        })
        .collect();
    let noise = KinectNoiseModel::default();
    let mut swipes = 0;
    for r in 0..repeats {
        let played: Vec<SensorFrame> = if r % 2 == 1 {
            clean.iter().map(SensorFrame::mirrored).collect()
        } else {
            clean.clone()
        };
        let mut detector = SwipeDetector::new(settings);
        swipes += corrupt_stream(&played, &noise, seed + r as u64)
            .iter()
            .filter(|n| detector.update(&n.frame).is_some())
            .count();
    }
    let name = path.file_name().map_or_else(
        || path.display().to_string(),
        |n| n.to_string_lossy().into(),
    );
    Ok(ClipFalseSwipes {
        clip: name,
        seconds: count as f64 / fps * repeats as f64,
        swipes,
    })
}
