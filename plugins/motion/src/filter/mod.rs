//! Joint position filters for the Kinect v1 skeleton stream (seed 000 §4.4.1, "Position
//! Filtering").
//!
//! The seed smooths joint positions with the Kinect SDK's Holt double exponential filter
//! (Azimi, "Skeletal Joint Smoothing", Microsoft white paper, 2013, the seed's reference [73];
//! Holt 1957/2004, reference [74]). This module offers that filter exactly as the SDK sample
//! implements it, the One Euro filter of Casiez, Roussel and Vogel ("1€ Filter: A Simple
//! Speed-based Low-pass Filter for Noisy Input in Interactive Systems", CHI 2012), and fitroom's
//! own Kalman filter with a bone-length step, which beats both on position error (see
//! [`kalman`]). [`gate::FrameGate`] rejects bad frames before any of them.
//!
//! # Contract of every [`JointFilter`]
//!
//! * Positions are filtered per joint; `timestamp_s`, `sequence` and every joint's `confidence`
//!   are passed through unchanged (a non-finite confidence becomes 0).
//! * Orientations keep the [`JointSample::orientation`] contract (+Y from the parent joint to the
//!   joint): the raw orientation is swung by the shortest arc from its +Y axis (the raw bone
//!   direction, by that same contract) onto the filtered bone direction, which keeps the raw
//!   twist. `HipCenter`'s orientation (the pelvis) is passed through. See
//!   [`realign_orientations`].
//! * Filters must be fed gated frames ([`gate::FrameGate`]), but never return a non-finite
//!   value: a joint whose raw position is not finite keeps its last output position (the origin
//!   if it never had one) and the filter's state for it is left as it was.

pub mod gate;
pub mod holt;
pub mod kalman;
pub mod one_euro;

use std::fmt;
use std::str::FromStr;

use fitroom_sensor::frame::bone_reference_frame;
use fitroom_sensor::{JointSample, KinectJoint, SensorFrame};
use glam::{Quat, Vec3};
use serde::{Deserialize, Serialize};

pub use gate::{FrameGate, GateDecision, GateStats, RejectReason};
pub use holt::{HoltFilter, HoltParams};
pub use kalman::{KalmanFilter, KalmanParams};
pub use one_euro::{OneEuroFilter, OneEuroParams, OneEuroTuning, tune_one_euro};

/// A filter over a stream of skeleton frames. See the module docs for the contract.
pub trait JointFilter: Send + Sync {
    /// Short name for reports ("holt", "oneeuro", "kalman").
    fn name(&self) -> &str;
    /// Forgets all history: the next frame starts the filter afresh (a new user, a new clip).
    fn reset(&mut self);
    /// Filters one frame (frames must come in time order) and returns the filtered frame.
    fn filter(&mut self, frame: &SensorFrame) -> SensorFrame;
}

/// The three tracking states of the Kinect SDK, recovered from [`JointSample::confidence`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TrackingState {
    /// `confidence > 0.5` (1.0 from a source).
    Tracked,
    /// `0 < confidence <= 0.5` (0.5 from a source).
    Inferred,
    /// `confidence <= 0`, or not a number.
    NotTracked,
}

impl TrackingState {
    pub fn from_confidence(confidence: f32) -> Self {
        if confidence > 0.5 {
            TrackingState::Tracked
        } else if confidence > 0.0 {
            TrackingState::Inferred
        } else {
            TrackingState::NotTracked
        }
    }
}

/// Which filter to run; [`FilterKind::build`] makes it.
#[cfg_attr(feature = "plugin", derive(bevy::reflect::Reflect))]
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum FilterKind {
    /// Raw positions (only non-finite values are replaced by the last finite one).
    None,
    Holt(HoltParams),
    OneEuro(OneEuroParams),
    /// fitroom's own filter ([`kalman`]).
    Kalman(KalmanParams),
}

impl Default for FilterKind {
    /// fitroom's own filter with its default parameters.
    fn default() -> Self {
        FilterKind::Kalman(KalmanParams::default())
    }
}

impl FilterKind {
    /// The CLI names [`FilterKind::from_str`] accepts, with what each means.
    pub const NAMES: &'static [(&'static str, &'static str)] = &[
        ("none", "raw positions"),
        (
            "holt",
            "Kinect SDK Holt filter, default parameters {0.5, 0.5, 0.5, 0.05, 0.04}",
        ),
        (
            "holt-smooth",
            "Kinect SDK Holt filter, 'smoothed with some latency' {0.5, 0.1, 0.5, 0.1, 0.1}",
        ),
        (
            "holt-very-smooth",
            "Kinect SDK Holt filter, 'very smooth, but with a lot of latency' \
             {0.7, 0.3, 1.0, 1.0, 1.0}",
        ),
        (
            "oneeuro",
            "One Euro filter (Casiez et al. 2012), fitroom's tuned defaults",
        ),
        (
            "kalman",
            "fitroom's Kalman filter with bone-length step (alias: fitroom)",
        ),
    ];

    /// Makes a fresh filter.
    pub fn build(&self) -> Box<dyn JointFilter> {
        match *self {
            FilterKind::None => Box::new(PassThrough::default()),
            FilterKind::Holt(p) => Box::new(HoltFilter::new(p)),
            FilterKind::OneEuro(p) => Box::new(OneEuroFilter::new(p)),
            FilterKind::Kalman(p) => Box::new(KalmanFilter::new(p)),
        }
    }

    /// The CLI name of this kind (Holt parameters other than the three SDK sets are "holt").
    pub fn cli_name(&self) -> &'static str {
        match self {
            FilterKind::None => "none",
            FilterKind::Holt(p) if *p == HoltParams::SMOOTH => "holt-smooth",
            FilterKind::Holt(p) if *p == HoltParams::VERY_SMOOTH => "holt-very-smooth",
            FilterKind::Holt(_) => "holt",
            FilterKind::OneEuro(_) => "oneeuro",
            FilterKind::Kalman(_) => "kalman",
        }
    }
}

impl fmt::Display for FilterKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.cli_name())
    }
}

/// An unknown filter name.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error(
    "unknown filter '{0}'; expected one of: none, holt, holt-smooth, holt-very-smooth, oneeuro, \
     kalman (or fitroom)"
)]
pub struct UnknownFilter(pub String);

impl FromStr for FilterKind {
    type Err = UnknownFilter;

    /// Case-insensitive; `_` may stand for `-`, and "one-euro"/"1euro" for "oneeuro".
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let name = s.trim().to_ascii_lowercase().replace('_', "-");
        Ok(match name.as_str() {
            "none" | "raw" => FilterKind::None,
            "holt" | "holt-default" => FilterKind::Holt(HoltParams::DEFAULT),
            "holt-smooth" => FilterKind::Holt(HoltParams::SMOOTH),
            "holt-very-smooth" => FilterKind::Holt(HoltParams::VERY_SMOOTH),
            "oneeuro" | "one-euro" | "1euro" => FilterKind::OneEuro(OneEuroParams::default()),
            "kalman" | "fitroom" => FilterKind::Kalman(KalmanParams::default()),
            _ => return Err(UnknownFilter(s.to_string())),
        })
    }
}

/// No filtering: positions pass through, except that a non-finite position is replaced by the
/// joint's last finite one (the origin if none).
#[derive(Clone, Debug, Default)]
pub struct PassThrough {
    last: [Option<Vec3>; KinectJoint::COUNT],
}

impl JointFilter for PassThrough {
    fn name(&self) -> &str {
        "none"
    }

    fn reset(&mut self) {
        self.last = [None; KinectJoint::COUNT];
    }

    fn filter(&mut self, frame: &SensorFrame) -> SensorFrame {
        let mut positions = [Vec3::ZERO; KinectJoint::COUNT];
        for (k, out) in positions.iter_mut().enumerate() {
            let raw = frame.joints[k].position;
            *out = if raw.is_finite() {
                self.last[k] = Some(raw);
                raw
            } else {
                self.last[k].unwrap_or(Vec3::ZERO)
            };
        }
        frame_with_positions(frame, &positions)
    }
}

/// The filtered frame: `raw`'s timestamp, sequence and confidences with `positions` and the
/// orientations re-aligned to them ([`realign_orientations`]).
pub fn frame_with_positions(
    raw: &SensorFrame,
    positions: &[Vec3; KinectJoint::COUNT],
) -> SensorFrame {
    let orientations = realign_orientations(raw, positions);
    let mut joints = [JointSample::default(); KinectJoint::COUNT];
    for (k, joint) in joints.iter_mut().enumerate() {
        let confidence = raw.joints[k].confidence;
        *joint = JointSample {
            position: positions[k],
            orientation: orientations[k],
            confidence: if confidence.is_finite() {
                confidence
            } else {
                0.0
            },
        };
    }
    SensorFrame {
        timestamp_s: raw.timestamp_s,
        sequence: raw.sequence,
        joints,
    }
}

/// Orientations for filtered positions, keeping the [`JointSample::orientation`] contract.
///
/// For a joint with a parent: `arc(raw.orientation * Y -> filtered bone) * raw.orientation`,
/// where the filtered bone is `positions[joint] - positions[parent]`. By the contract the raw
/// +Y axis is the raw bone direction, so this is the shortest arc from the raw bone to the
/// filtered bone applied to the raw orientation; using the orientation's own axis also makes
/// the output satisfy the contract when a source's orientations and positions disagree. A
/// non-finite (or zero) raw orientation is replaced by [`bone_reference_frame`] of the
/// filtered bone; a zero-length filtered bone keeps the raw orientation. `HipCenter` keeps its
/// raw orientation (identity if not finite).
pub fn realign_orientations(
    raw: &SensorFrame,
    positions: &[Vec3; KinectJoint::COUNT],
) -> [Quat; KinectJoint::COUNT] {
    let mut out = [Quat::IDENTITY; KinectJoint::COUNT];
    for joint in KinectJoint::ALL {
        let k = joint.index();
        let q = raw.joints[k].orientation;
        let q = if q.is_finite() && q.length_squared() > 1e-12 {
            Some(q.normalize())
        } else {
            None
        };
        out[k] = match joint.parent() {
            None => q.unwrap_or(Quat::IDENTITY),
            Some(parent) => {
                let bone = positions[k] - positions[parent.index()];
                let bone = if bone.is_finite() {
                    bone.normalize_or_zero()
                } else {
                    Vec3::ZERO
                };
                match q {
                    Some(q) if bone != Vec3::ZERO => {
                        let along = (q * Vec3::Y).normalize_or_zero();
                        if along == Vec3::ZERO {
                            q
                        } else {
                            (Quat::from_rotation_arc(along, bone) * q).normalize()
                        }
                    }
                    Some(q) => q,
                    None => bone_reference_frame(bone),
                }
            }
        };
    }
    out
}
