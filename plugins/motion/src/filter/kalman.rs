//! fitroom's joint filter: a per-joint Kalman filter with a depth-dependent measurement model
//! and a bone-length step.
//!
//! # Design
//!
//! **Motion model.** Each joint's x, y and z follow the same linear model, one Kalman filter
//! per joint and axis (the three axes share one covariance because their noise model is the
//! same): by default constant velocity driven by white-noise acceleration of power spectral
//! density `q` (m²/s³), `F = [[1, dt], [0, 1]]`, `Q = q [[dt³/3, dt²/2], [dt²/2, dt]]`
//! (Bar-Shalom, Li, Kirubarajan, "Estimation with Applications to Tracking and Navigation",
//! 2001, §6.2, the "continuous white noise acceleration" model); [`KalmanModel`] also offers
//! constant acceleration driven by white-noise jerk. `dt` comes from the frames' timestamps.
//! The torso joints (hip centre, spine, shoulder centre, head, shoulders, hips) move slower
//! than the limbs and get `q * torso_process_scale`; the limb ends (wrists, hands, ankles,
//! feet) get `q * distal_process_scale`.
//!
//! **Measurement model.** The raw joint position with noise standard deviation
//! `sigma(z) = max(sigma_min, sigma_at_3m (z / 3 m)²)` per axis: Kinect v1 depth noise grows
//! with the square of the distance and is about 1.5 cm at 3 m (Khoshelham and Oude Elberink,
//! "Accuracy and Resolution of Kinect Depth Data for Indoor Mapping Applications", Sensors
//! 12(2), 2012; the seed's reference [32] reports "up to 2 cm at 3 m"). Inferred joints
//! (confidence <= 0.5) have their variance multiplied by `inferred_variance_scale`; joints that
//! are not tracked (confidence 0) are not measured at all: the filter predicts them, with their
//! velocity decaying (`coast_decay_per_s`) so that a long occlusion ends in a hold rather than
//! a drift. A tracked measurement farther than `reacquire_distance_m` from the prediction (the
//! person jumped: a new user, a looped clip) restarts that joint at the measurement, as does a
//! gap between frames longer than `max_gap_s` for all joints.
//!
//! **Bone-length step.** After the per-joint updates, each bone (in parents-first order,
//! `bone_iterations` passes) is pulled towards its learned length: with `d` the filtered child
//! minus parent, `L` the learned length and `e = |d| - L`, the child moves by
//! `-s e w_c d/|d|` and the parent by `+s e w_p d/|d|`, with weights `w_c = P_c / (P_c + P_p)`,
//! `w_p = P_p / (P_c + P_p)` from the joints' position variances (the less certain end moves
//! more: an inferred hand moves, its tracked elbow barely; a limb end more than the torso) and
//! stiffness `s` (`bone_stiffness`). This is the projection of the estimate onto the linearised
//! length constraint weighted by the covariances (Simon and Chia, "Kalman filtering with state
//! equality constraints", IEEE TAES 38(1), 2002), softened because the Kinect "bones" are not
//! rigid (the spine segment spans several vertebrae). With `bone_feedback` the correction is fed
//! back into the state, velocity included (through the position-velocity covariance); the
//! covariance itself is left as it is. Each bone's length is the running median of its length
//! (from the per-joint estimates, before the step) over the frames in which both ends are
//! tracked: the step starts after `bone_learn_min_frames` such frames and the median stops
//! changing after `bone_learn_frames`; [`JointFilter::reset`] forgets it.
//!
//! **Lag.** The filter is causal and adds no fixed delay; its lag is that of the Kalman gain:
//! 4.7 ms on average over the 15 CMU clips by cross-correlation at 30 Hz (2-10 ms per clip),
//! against 8.4 ms for the Holt default and 4.9 ms for the tuned One Euro filter (see
//! `tests/filters.rs`). A fixed-lag (RTS) smoother over 1-2 frames was considered and left out:
//! it lowers the error of the *delayed* estimate, but the pipeline shows the current frame, for
//! which it would add 33-67 ms of delay and, at limb speeds of 1-3 m/s, more error than it
//! removes.
//!
//! **Defaults** ([`KalmanParams::default`]) were tuned on the 15 CMU clips with the test noise
//! of `tests/filters.rs` (white 1.0 cm plus AR(1) 1.1 cm per axis): the ignored test
//! `tune_kalman_grid` reproduces the search. With them the position RMSE is 21.3 mm against
//! 25.7 mm raw, 31.3 mm for the Holt default and 24.5 mm for the tuned One Euro filter; the
//! bone-length step is worth 2.9 mm of it (24.1 mm with `bone_stiffness` 0) and cuts
//! the bone-length standard deviation from 20 mm to 6 mm.

use fitroom_sensor::{KinectJoint, SensorFrame};
use glam::Vec3;
use serde::{Deserialize, Serialize};

use super::{JointFilter, TrackingState, frame_with_positions};

/// The motion model of each joint axis.
#[cfg_attr(feature = "plugin", derive(bevy::reflect::Reflect))]
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum KalmanModel {
    /// State `[position, velocity]`, white-noise acceleration of PSD `q` (m²/s³).
    ConstantVelocity,
    /// State `[position, velocity, acceleration]`, white-noise jerk of PSD `q` (m²/s⁵).
    ConstantAcceleration,
}

impl KalmanModel {
    fn order(self) -> usize {
        match self {
            KalmanModel::ConstantVelocity => 2,
            KalmanModel::ConstantAcceleration => 3,
        }
    }
}

/// Parameters of [`KalmanFilter`]. See the module docs.
#[cfg_attr(feature = "plugin", derive(bevy::reflect::Reflect))]
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct KalmanParams {
    pub model: KalmanModel,
    /// Process noise PSD `q`: m²/s³ (constant velocity) or m²/s⁵ (constant acceleration).
    pub process_noise: f64,
    /// Measurement noise standard deviation per axis at 3 m depth, metres (grows as z²).
    pub sigma_at_3m: f64,
    /// Lower bound of the measurement noise standard deviation, metres.
    pub sigma_min: f64,
    /// Measurement variance multiplier for inferred joints.
    pub inferred_variance_scale: f64,
    /// Velocity (and acceleration) decay rate while a joint is not tracked, 1/s.
    pub coast_decay_per_s: f64,
    /// A tracked measurement this far from the prediction restarts the joint, metres.
    pub reacquire_distance_m: f64,
    /// A gap between frames longer than this restarts every joint, seconds.
    pub max_gap_s: f64,
    /// Interval assumed when timestamps do not increase, seconds.
    pub fallback_dt_s: f64,
    /// Stiffness `s` of the bone-length step, 0 (off) ..= 1 (full projection).
    pub bone_stiffness: f64,
    /// Whether the bone-length correction is fed back into the filter state.
    pub bone_feedback: bool,
    /// Each bone's length is the running median of its length in the frames where both ends
    /// are tracked, from this many frames on (no bone step before)...
    pub bone_learn_min_frames: usize,
    /// ...up to this many frames, after which it is kept.
    pub bone_learn_frames: usize,
    /// Initial velocity standard deviation of a (re)started joint, m/s.
    pub initial_velocity_sigma: f64,
    /// Process noise multiplier of the torso joints (hip centre, spine, shoulder centre, head,
    /// shoulders, hips), which move slower than the limbs.
    pub torso_process_scale: f64,
    /// Process noise multiplier of the limb ends (wrists, hands, ankles, feet).
    pub distal_process_scale: f64,
    /// Passes of the bone-length step per frame.
    pub bone_iterations: usize,
}

impl Default for KalmanParams {
    fn default() -> Self {
        Self {
            model: KalmanModel::ConstantVelocity,
            process_noise: 2.0,
            sigma_at_3m: 0.015,
            sigma_min: 0.005,
            inferred_variance_scale: 9.0,
            coast_decay_per_s: 5.0,
            reacquire_distance_m: 0.5,
            max_gap_s: 0.5,
            fallback_dt_s: 1.0 / 30.0,
            bone_stiffness: 0.7,
            bone_feedback: true,
            bone_learn_min_frames: 10,
            bone_learn_frames: 150,
            initial_velocity_sigma: 1.0,
            torso_process_scale: 0.3,
            distal_process_scale: 2.0,
            bone_iterations: 3,
        }
    }
}

/// One joint's filter: per-axis states sharing one covariance.
#[derive(Clone, Copy, Debug, Default)]
struct JointKf {
    /// `x[axis][k]`: position, velocity, acceleration.
    x: [[f64; 3]; 3],
    p: [[f64; 3]; 3],
    started: bool,
}

impl JointKf {
    fn start(&mut self, z: [f64; 3], r: f64, params: &KalmanParams) {
        self.x = [[z[0], 0.0, 0.0], [z[1], 0.0, 0.0], [z[2], 0.0, 0.0]];
        let v = params.initial_velocity_sigma * params.initial_velocity_sigma;
        let a = if params.model.order() == 3 {
            25.0 * v
        } else {
            0.0
        };
        self.p = [[r, 0.0, 0.0], [0.0, v, 0.0], [0.0, 0.0, a]];
        self.started = true;
    }

    fn position(&self) -> Vec3 {
        Vec3::new(
            self.x[0][0] as f32,
            self.x[1][0] as f32,
            self.x[2][0] as f32,
        )
    }

    /// `x = F x`, `P = F P F' + Q`, with the velocity decay when coasting. Rows and columns
    /// from `n` on stay zero.
    fn predict(&mut self, n: usize, dt: f64, q: f64, decay: f64) {
        let f = transition(n, dt);
        for axis in &mut self.x {
            let old = *axis;
            *axis = std::array::from_fn(|i| {
                let v: f64 = f[i].iter().zip(&old).map(|(a, b)| a * b).sum();
                if i == 0 { v } else { v * decay }
            });
        }
        let p = self.p;
        let fp: [[f64; 3]; 3] = std::array::from_fn(|i| {
            std::array::from_fn(|j| (0..3).map(|k| f[i][k] * p[k][j]).sum())
        });
        self.p = std::array::from_fn(|i| {
            std::array::from_fn(|j| {
                if i < n && j < n {
                    (0..3).map(|k| fp[i][k] * f[j][k]).sum::<f64>() + q * q_entry(n, i, j, dt)
                } else {
                    0.0
                }
            })
        });
    }

    /// Scalar position update on every axis with variance `r`.
    fn update(&mut self, z: [f64; 3], r: f64) {
        let s = self.p[0][0] + r;
        if !(s > 0.0 && s.is_finite()) {
            return;
        }
        let gain: [f64; 3] = std::array::from_fn(|i| self.p[i][0] / s);
        for (axis, &zi) in self.x.iter_mut().zip(&z) {
            let innovation = zi - axis[0];
            for (v, g) in axis.iter_mut().zip(&gain) {
                *v += g * innovation;
            }
        }
        let p = self.p;
        // P = P - K P[0,:], symmetrised.
        self.p = std::array::from_fn(|i| {
            std::array::from_fn(|j| {
                0.5 * ((p[i][j] - gain[i] * p[0][j]) + (p[j][i] - gain[j] * p[0][i]))
            })
        });
    }

    /// Moves the position by `delta` and the higher states through their covariance with the
    /// position.
    fn shift(&mut self, delta: Vec3) {
        let p00 = self.p[0][0];
        if !(p00.is_finite() && p00 > 0.0) {
            return;
        }
        let gains: [f64; 3] = std::array::from_fn(|i| self.p[i][0] / p00);
        for (axis, d) in self.x.iter_mut().zip(delta.to_array()) {
            for (v, g) in axis.iter_mut().zip(&gains) {
                *v += g * f64::from(d);
            }
        }
    }

    fn is_finite(&self) -> bool {
        self.x
            .iter()
            .flatten()
            .chain(self.p.iter().flatten())
            .all(|v| v.is_finite())
    }
}

/// The process noise multiplier of joint `k`.
fn process_scale(params: &KalmanParams, k: usize) -> f64 {
    use KinectJoint::*;
    match KinectJoint::ALL[k] {
        HipCenter | Spine | ShoulderCenter | Head | ShoulderLeft | ShoulderRight | HipLeft
        | HipRight => params.torso_process_scale,
        ElbowLeft | ElbowRight | KneeLeft | KneeRight => 1.0,
        WristLeft | HandLeft | WristRight | HandRight | AnkleLeft | FootLeft | AnkleRight
        | FootRight => params.distal_process_scale,
    }
}

/// `F[i][j] = dt^(j-i) / (j-i)!` for `i <= j < n`, zero elsewhere.
fn transition(n: usize, dt: f64) -> [[f64; 3]; 3] {
    std::array::from_fn(|i| {
        std::array::from_fn(|j| match j.checked_sub(i) {
            _ if j >= n => 0.0,
            Some(0) => 1.0,
            Some(1) => dt,
            Some(_) => 0.5 * dt * dt,
            None => 0.0,
        })
    })
}

/// Entry of the discretised continuous white-noise process covariance (per unit PSD) of an
/// `n`-th order integrator chain: `dt^(2n-1-i-j) / ((n-1-i)! (n-1-j)! (2n-1-i-j))`.
fn q_entry(n: usize, i: usize, j: usize, dt: f64) -> f64 {
    let fact = |k: usize| -> f64 { (1..=k).map(|v| v as f64).product() };
    let e = 2 * n - 1 - i - j;
    dt.powi(e as i32) / (fact(n - 1 - i) * fact(n - 1 - j) * e as f64)
}

/// fitroom's filter. See the module docs.
#[derive(Clone, Debug)]
pub struct KalmanFilter {
    params: KalmanParams,
    joints: [JointKf; KinectJoint::COUNT],
    last_t: Option<f64>,
    last_output: [Option<Vec3>; KinectJoint::COUNT],
    /// Learned bone lengths, indexed by the bone's end joint.
    bone_length: [Option<f32>; KinectJoint::COUNT],
    /// Length samples while learning.
    bone_samples: Vec<Vec<f32>>,
}

impl KalmanFilter {
    pub fn new(params: KalmanParams) -> Self {
        Self {
            params,
            joints: [JointKf::default(); KinectJoint::COUNT],
            last_t: None,
            last_output: [None; KinectJoint::COUNT],
            bone_length: [None; KinectJoint::COUNT],
            bone_samples: vec![Vec::new(); KinectJoint::COUNT],
        }
    }

    pub fn params(&self) -> &KalmanParams {
        &self.params
    }

    /// The learned length of the bone ending at `joint`, metres (`None` while learning).
    pub fn bone_length(&self, joint: KinectJoint) -> Option<f32> {
        self.bone_length[joint.index()]
    }

    /// Measurement variance of a joint at depth `z`, tracking state aside.
    fn measurement_variance(&self, z: f64) -> f64 {
        let p = &self.params;
        let depth = (z / 3.0).powi(2);
        let sigma = (p.sigma_at_3m * depth).max(p.sigma_min);
        sigma * sigma
    }

    /// Learns the bone lengths (from the per-joint estimates, before any projection) and runs
    /// the bone-length step; records the outputs.
    fn learn_and_constrain(&mut self, states: &[TrackingState; KinectJoint::COUNT]) {
        let params = self.params;
        let mut positions: [Vec3; KinectJoint::COUNT] =
            std::array::from_fn(|k| self.joints[k].position());
        let (min_samples, max_samples) = (
            params.bone_learn_min_frames.max(1),
            params
                .bone_learn_frames
                .max(params.bone_learn_min_frames.max(1)),
        );
        for joint in KinectJoint::ALL {
            let Some(parent) = joint.parent() else {
                continue;
            };
            let (c, p) = (joint.index(), parent.index());
            let samples = &mut self.bone_samples[c];
            if samples.len() >= max_samples
                || !(self.joints[c].started && self.joints[p].started)
                || states[c] != TrackingState::Tracked
                || states[p] != TrackingState::Tracked
            {
                continue;
            }
            let length = positions[c].distance(positions[p]);
            if length.is_finite() && length > 1e-4 {
                let at = samples.partition_point(|&v| v < length);
                samples.insert(at, length);
                if samples.len() >= min_samples {
                    self.bone_length[c] = Some(samples[samples.len() / 2]);
                }
            }
        }

        let stiffness = params.bone_stiffness.clamp(0.0, 1.0) as f32;
        if stiffness > 0.0 {
            for _ in 0..params.bone_iterations {
                for joint in KinectJoint::ALL {
                    let (Some(parent), Some(target)) =
                        (joint.parent(), self.bone_length[joint.index()])
                    else {
                        continue;
                    };
                    let (c, p) = (joint.index(), parent.index());
                    if !(self.joints[c].started && self.joints[p].started) {
                        continue;
                    }
                    let d = positions[c] - positions[p];
                    let length = d.length();
                    let (vc, vp) = (self.joints[c].p[0][0], self.joints[p].p[0][0]);
                    let total = vc + vp;
                    if !(length > 1e-4 && length.is_finite() && total > 0.0 && total.is_finite()) {
                        continue;
                    }
                    let u = d / length;
                    let e = (length - target) * stiffness;
                    let dc = -u * (e * (vc / total) as f32);
                    let dp = u * (e * (vp / total) as f32);
                    positions[c] += dc;
                    positions[p] += dp;
                    if params.bone_feedback {
                        self.joints[c].shift(dc);
                        self.joints[p].shift(dp);
                    }
                }
            }
        }
        for (k, out) in positions.iter().enumerate() {
            if self.joints[k].started && out.is_finite() {
                self.last_output[k] = Some(*out);
            }
        }
    }
}

impl Default for KalmanFilter {
    fn default() -> Self {
        Self::new(KalmanParams::default())
    }
}

impl JointFilter for KalmanFilter {
    fn name(&self) -> &str {
        "kalman"
    }

    fn reset(&mut self) {
        *self = Self::new(self.params);
    }

    fn filter(&mut self, frame: &SensorFrame) -> SensorFrame {
        let params = self.params;
        let n = params.model.order();
        let t = frame.timestamp_s;
        let mut dt = match self.last_t {
            Some(last) if (t - last).is_finite() && t > last => t - last,
            _ => params.fallback_dt_s,
        };
        if dt > params.max_gap_s {
            for joint in &mut self.joints {
                joint.started = false;
            }
            dt = params.fallback_dt_s;
        }
        if t.is_finite() {
            self.last_t = Some(t);
        }
        let coast = (-params.coast_decay_per_s.max(0.0) * dt).exp();

        let mut states = [TrackingState::NotTracked; KinectJoint::COUNT];
        for (k, state) in states.iter_mut().enumerate() {
            let sample = &frame.joints[k];
            let raw = sample.position;
            let finite = raw.is_finite();
            *state = if finite {
                TrackingState::from_confidence(sample.confidence)
            } else {
                TrackingState::NotTracked
            };
            let z = [f64::from(raw.x), f64::from(raw.y), f64::from(raw.z)];
            let mut r = self.measurement_variance_of(raw.z);
            let joint = &mut self.joints[k];
            if *state == TrackingState::Inferred {
                r *= params.inferred_variance_scale.max(1.0);
            }
            if !joint.started {
                // Start on the first finite position, whatever its confidence.
                if finite {
                    joint.start(z, r, &params);
                }
                continue;
            }
            let backup = *joint;
            let decay = if *state == TrackingState::NotTracked {
                coast
            } else {
                1.0
            };
            joint.predict(
                n,
                dt,
                params.process_noise * process_scale(&params, k),
                decay,
            );
            if *state != TrackingState::NotTracked {
                let predicted = joint.position();
                if *state == TrackingState::Tracked
                    && f64::from(predicted.distance(raw)) > params.reacquire_distance_m
                {
                    joint.start(z, r, &params);
                } else {
                    joint.update(z, r);
                }
            }
            if !joint.is_finite() {
                *joint = backup;
            }
        }
        self.learn_and_constrain(&states);

        let positions: [Vec3; KinectJoint::COUNT] = std::array::from_fn(|k| {
            self.last_output[k]
                .or_else(|| {
                    let raw = frame.joints[k].position;
                    raw.is_finite().then_some(raw)
                })
                .unwrap_or(Vec3::ZERO)
        });
        frame_with_positions(frame, &positions)
    }
}

impl KalmanFilter {
    fn measurement_variance_of(&self, z: f32) -> f64 {
        let z = f64::from(z);
        if z.is_finite() {
            self.measurement_variance(z)
        } else {
            let s = self.params.sigma_at_3m.max(self.params.sigma_min);
            s * s
        }
    }
}
