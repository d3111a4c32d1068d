//! The Kinect SDK's joint filter: Holt double exponential smoothing with jitter removal,
//! prediction and a maximum-deviation clamp, exactly as the SDK's `NuiTransformSmooth` /
//! `NUI_TRANSFORM_SMOOTH_PARAMETERS` and its sample `FilterDoubleExponential`
//! (`KinectJointFilter.cpp`) implement it.
//!
//! Sources: M. Azimi, "Skeletal Joint Smoothing White Paper", Microsoft, 2013 (MSDN jj131429,
//! the seed's reference [73]); Kinect for Windows SDK 1.8 documentation, "Joint Filtering"
//! (MSDN jj131024) and "NUI_TRANSFORM_SMOOTH_PARAMETERS Structure" (MSDN hh855623), whose
//! example parameter sets are [`HoltParams::DEFAULT`], [`HoltParams::SMOOTH`] and
//! [`HoltParams::VERY_SMOOTH`]; C. C. Holt, "Forecasting seasonals and trends by exponentially
//! weighted moving averages", 1957, reprinted in Int. J. Forecasting 20(1), 2004.
//!
//! # The recurrences (per joint, 3-D vectors, `f32` as in the SDK)
//!
//! With raw position `x`, previous filtered position `f'`, previous trend `b'` and previous raw
//! `x'`, and the parameters smoothing `a`, correction `c`, prediction `p`, jitter radius `J`
//! (at least 0.0001 m, the SDK's guard against division by zero) and max deviation radius `M`:
//!
//! * An invalid joint (raw position exactly `(0, 0, 0)`, the SDK's `JointPositionIsValid`)
//!   resets the joint's history to frame 0.
//! * Frame 0 of a joint: `f = x`, `b = 0`.
//! * Frame 1: `f = (x + x') / 2`, `b = c (f - f') + (1 - c) b'`.
//! * Later frames: jitter filter `d = |x - f'|`; `x_j = x d/J + f' (1 - d/J)` if `d <= J`, else
//!   `x_j = x`; then `f = (1 - a) x_j + a (f' + b')` and `b = c (f - f') + (1 - c) b'`.
//! * Output: the prediction `y = f + p b`, pulled back to distance `M` from the raw position
//!   when farther: `y = y M/e + x (1 - M/e)` with `e = |y - x| > M`.
//! * The history keeps `x`, `f` and `b` (not the clamped output).
//! * An inferred joint ([`TrackingState::Inferred`]) uses `2 J` and `2 M` (the SDK sample: "if
//!   inferred, we smooth a bit more by using a bigger jitter radius"); tracked and not-tracked
//!   joints use `J` and `M` as given.
//!
//! The filter ignores timestamps (the SDK runs it once per 30 Hz skeleton frame).
//!
//! # Deviations from the SDK (robustness only)
//!
//! A raw position that is not finite (which the SDK never produces) leaves the joint's history
//! untouched and outputs the joint's last output. Everything else, including the SDK's quirk
//! that the frame after an invalid (zero) joint averages the new raw position with that zero,
//! is kept as is; [`super::gate::FrameGate`] rejects frames with zero joints before they get
//! here.

use fitroom_sensor::{KinectJoint, SensorFrame};
use glam::Vec3;
use serde::{Deserialize, Serialize};

use super::{JointFilter, TrackingState, frame_with_positions};

/// The five `NUI_TRANSFORM_SMOOTH_PARAMETERS`.
#[cfg_attr(feature = "plugin", derive(bevy::reflect::Reflect))]
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct HoltParams {
    /// `fSmoothing`, 0..1: weight of the previous estimate plus trend (0 returns raw data).
    pub smoothing: f32,
    /// `fCorrection`, 0..1: how fast the trend follows the filtered positions.
    pub correction: f32,
    /// `fPrediction`, frames to predict into the future (>= 0).
    pub prediction: f32,
    /// `fJitterRadius`, metres: raw changes within it are damped in proportion to their size.
    pub jitter_radius: f32,
    /// `fMaxDeviationRadius`, metres: the output is kept within it of the raw position.
    pub max_deviation_radius: f32,
}

impl HoltParams {
    /// "Some smoothing with little latency (defaults). Only filters out small jitters. Good for
    /// gesture recognition." `{0.5, 0.5, 0.5, 0.05, 0.04}`: the SDK's defaults (hh855623).
    pub const DEFAULT: HoltParams = HoltParams {
        smoothing: 0.5,
        correction: 0.5,
        prediction: 0.5,
        jitter_radius: 0.05,
        max_deviation_radius: 0.04,
    };

    /// "Smoothed with some latency. Filters out medium jitters. Good for a menu system that
    /// needs to be smooth but doesn't need the reduced latency as much as gesture recognition
    /// does." `{0.5, 0.1, 0.5, 0.1, 0.1}` (hh855623, jj131024).
    pub const SMOOTH: HoltParams = HoltParams {
        smoothing: 0.5,
        correction: 0.1,
        prediction: 0.5,
        jitter_radius: 0.1,
        max_deviation_radius: 0.1,
    };

    /// "Very smooth, but with a lot of latency. Filters out large jitters. Good for situations
    /// where smooth data is absolutely required and latency is not an issue."
    /// `{0.7, 0.3, 1.0, 1.0, 1.0}` (hh855623, jj131024).
    pub const VERY_SMOOTH: HoltParams = HoltParams {
        smoothing: 0.7,
        correction: 0.3,
        prediction: 1.0,
        jitter_radius: 1.0,
        max_deviation_radius: 1.0,
    };
}

impl Default for HoltParams {
    fn default() -> Self {
        HoltParams::DEFAULT
    }
}

/// Per-joint history of the SDK filter (`m_pHistory[JointID]`).
#[derive(Clone, Copy, Debug, Default)]
struct History {
    raw: Vec3,
    filtered: Vec3,
    trend: Vec3,
    frame_count: u32,
}

/// The Kinect SDK joint filter. See the module docs.
#[derive(Clone, Debug)]
pub struct HoltFilter {
    params: HoltParams,
    history: [History; KinectJoint::COUNT],
    last_output: [Option<Vec3>; KinectJoint::COUNT],
}

impl HoltFilter {
    pub fn new(params: HoltParams) -> Self {
        Self {
            params,
            history: [History::default(); KinectJoint::COUNT],
            last_output: [None; KinectJoint::COUNT],
        }
    }

    pub fn params(&self) -> &HoltParams {
        &self.params
    }

    /// One joint's update (`FilterDoubleExponential::Update(joints, JointID, params)`), with
    /// the per-frame parameters already adjusted for the tracking state. Returns the output.
    fn update_joint(history: &mut History, raw: Vec3, p: &HoltParams) -> Vec3 {
        let jitter_radius = p.jitter_radius;
        let max_deviation = p.max_deviation_radius;
        let prev_filtered = history.filtered;
        let prev_trend = history.trend;
        let prev_raw = history.raw;

        if raw == Vec3::ZERO {
            history.frame_count = 0;
        }

        let (filtered, trend) = if history.frame_count == 0 {
            history.frame_count += 1;
            (raw, Vec3::ZERO)
        } else if history.frame_count == 1 {
            let filtered = (raw + prev_raw) * 0.5;
            let diff = filtered - prev_filtered;
            let trend = diff * p.correction + prev_trend * (1.0 - p.correction);
            history.frame_count += 1;
            (filtered, trend)
        } else {
            // Jitter filter.
            let d = (raw - prev_filtered).length().abs();
            let jittered = if d <= jitter_radius {
                raw * (d / jitter_radius) + prev_filtered * (1.0 - d / jitter_radius)
            } else {
                raw
            };
            // Double exponential smoothing.
            let filtered =
                jittered * (1.0 - p.smoothing) + (prev_filtered + prev_trend) * p.smoothing;
            let diff = filtered - prev_filtered;
            let trend = diff * p.correction + prev_trend * (1.0 - p.correction);
            (filtered, trend)
        };

        // Prediction, then the max-deviation clamp.
        let mut predicted = filtered + trend * p.prediction;
        let e = (predicted - raw).length().abs();
        if e > max_deviation {
            predicted = predicted * (max_deviation / e) + raw * (1.0 - max_deviation / e);
        }

        history.raw = raw;
        history.filtered = filtered;
        history.trend = trend;
        predicted
    }
}

impl Default for HoltFilter {
    fn default() -> Self {
        Self::new(HoltParams::DEFAULT)
    }
}

impl JointFilter for HoltFilter {
    fn name(&self) -> &str {
        "holt"
    }

    fn reset(&mut self) {
        self.history = [History::default(); KinectJoint::COUNT];
        self.last_output = [None; KinectJoint::COUNT];
    }

    fn filter(&mut self, frame: &SensorFrame) -> SensorFrame {
        // The SDK's guard: a jitter radius of at least a tenth of a millimetre.
        let mut base = self.params;
        base.jitter_radius = base.jitter_radius.max(0.0001);
        let mut positions = [Vec3::ZERO; KinectJoint::COUNT];
        for (k, out) in positions.iter_mut().enumerate() {
            let sample = &frame.joints[k];
            if !sample.position.is_finite() {
                *out = self.last_output[k].unwrap_or(Vec3::ZERO);
                continue;
            }
            let mut p = base;
            if TrackingState::from_confidence(sample.confidence) == TrackingState::Inferred {
                p.jitter_radius *= 2.0;
                p.max_deviation_radius *= 2.0;
            }
            let y = Self::update_joint(&mut self.history[k], sample.position, &p);
            // Non-finite parameters could still produce NaN: fall back to the raw position.
            *out = if y.is_finite() { y } else { sample.position };
            self.last_output[k] = Some(*out);
        }
        frame_with_positions(frame, &positions)
    }
}
