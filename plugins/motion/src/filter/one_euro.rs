//! The One Euro filter: G. Casiez, N. Roussel, D. Vogel, "1€ Filter: A Simple Speed-based
//! Low-pass Filter for Noisy Input in Interactive Systems", CHI 2012, pp. 2527-2530
//! (doi:10.1145/2207676.2208639).
//!
//! Each coordinate of each joint is filtered on its own by a first-order low-pass filter whose
//! cutoff grows with speed, so that slow motion is smoothed hard (little jitter) and fast motion
//! lightly (little lag). With `Te` the time since the previous sample (from the frames'
//! timestamps: the rate may vary), the paper's Algorithm 1 is:
//!
//! * `alpha(fc) = 1 / (1 + tau / Te)`, `tau = 1 / (2 pi fc)`; a low-pass step is
//!   `y_i = alpha x_i + (1 - alpha) y_{i-1}` (the first sample passes through).
//! * The speed is estimated on the filtered signal: `dx_i = (x_i - x̂_{i-1}) / Te` (the new raw
//!   sample against the previous *filtered* value, the paper's `x - xfilt.hatxprev()`; the
//!   first sample has `dx = 0`), low-passed at the fixed cutoff `dcutoff` (1 Hz) into `dx̂_i`.
//!   (`x̂_i - x̂_{i-1}` cannot be used: `x̂_i` needs the cutoff that the speed sets. The
//!   authors' later C++ code differences the raw samples instead; we follow the paper.)
//! * The cutoff `fc = mincutoff + beta |dx̂_i|`, and `x̂_i = lowpass(x_i, alpha(fc))`.
//!
//! Units here: metres and seconds, so `mincutoff` and `dcutoff` are in Hz and `beta` in
//! Hz per (m/s).
//!
//! # Tuning
//!
//! The authors' procedure (§"Tuning" of the paper): set `beta = 0` and lower `mincutoff` until
//! the jitter at rest or in slow motion is acceptable; then raise `beta` until the lag in fast
//! motion is acceptable. [`tune_one_euro`] does exactly these two steps with numbers in place
//! of the eye, given a clean reference and its noisy version: "jitter" is the mean acceleration
//! magnitude ([`crate::metrics`]) on frames where the reference moves slowly, "acceptable" is at
//! most the reference's own jitter there plus [`OneEuroTuning::jitter_tolerance`]; "lag" is
//! [`crate::metrics::lag_ms`] (weighted by motion energy, so dominated by fast motion) and
//! "acceptable" at most [`OneEuroTuning::lag_target_ms`].
//!
//! The default lag target is strict, 5 ms, because fitroom judges the filter by position error
//! and the error of a lagging filter is speed times lag: at the limb speeds of the CMU clips
//! (1-3 m/s) every 5 ms costs 0.5-1.5 cm, as much as the sensor noise. With the 30-40 ms often
//! found acceptable for pointing, the tuned filter's RMSE on the clips is about twice the raw
//! stream's (59 mm against 26 mm with the test noise of `tests/filters.rs`).

use fitroom_sensor::{KinectJoint, SensorFrame};
use glam::Vec3;
use serde::{Deserialize, Serialize};

use super::{JointFilter, frame_with_positions};
use crate::metrics;

/// Parameters of the One Euro filter.
#[cfg_attr(feature = "plugin", derive(bevy::reflect::Reflect))]
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct OneEuroParams {
    /// Minimum cutoff frequency, Hz (the cutoff at rest).
    pub min_cutoff_hz: f64,
    /// Speed coefficient, Hz per m/s.
    pub beta: f64,
    /// Cutoff of the speed's low-pass filter, Hz (the paper uses 1 Hz).
    pub d_cutoff_hz: f64,
    /// Rate assumed when two timestamps do not increase (or are not finite), Hz.
    pub fallback_rate_hz: f64,
}

impl Default for OneEuroParams {
    /// fitroom's defaults: [`tune_one_euro`] with [`OneEuroTuning::default`] on the 15 CMU
    /// clips with the test noise (about 1.5 cm per axis, see `tests/filters.rs`), median over
    /// the clips (`mincutoff` 0.86 Hz, `beta` 50.5; the ignored test `tune_one_euro_defaults`).
    /// `dcutoff` is the paper's 1 Hz.
    fn default() -> Self {
        Self {
            min_cutoff_hz: 0.86,
            beta: 50.0,
            d_cutoff_hz: 1.0,
            fallback_rate_hz: 30.0,
        }
    }
}

/// `alpha(fc) = 1 / (1 + tau / Te)` with `tau = 1 / (2 pi fc)`.
pub fn smoothing_factor(cutoff_hz: f64, te_s: f64) -> f64 {
    let tau = 1.0 / (2.0 * std::f64::consts::PI * cutoff_hz);
    1.0 / (1.0 + tau / te_s)
}

/// One coordinate's state.
#[derive(Clone, Copy, Debug, Default)]
struct Coord {
    x_hat: f64,
    dx_hat: f64,
}

#[derive(Clone, Copy, Debug, Default)]
struct JointState {
    coords: [Coord; 3],
    last_t: f64,
    started: bool,
}

/// The One Euro filter on every coordinate of every joint. See the module docs.
#[derive(Clone, Debug)]
pub struct OneEuroFilter {
    params: OneEuroParams,
    joints: [JointState; KinectJoint::COUNT],
    last_output: [Option<Vec3>; KinectJoint::COUNT],
}

impl OneEuroFilter {
    pub fn new(params: OneEuroParams) -> Self {
        Self {
            params,
            joints: [JointState::default(); KinectJoint::COUNT],
            last_output: [None; KinectJoint::COUNT],
        }
    }

    pub fn params(&self) -> &OneEuroParams {
        &self.params
    }

    fn sample_period(&self, last_t: f64, t: f64) -> f64 {
        let te = t - last_t;
        if te.is_finite() && te > 0.0 {
            te
        } else {
            1.0 / self.params.fallback_rate_hz.max(1e-3)
        }
    }
}

impl Default for OneEuroFilter {
    fn default() -> Self {
        Self::new(OneEuroParams::default())
    }
}

impl JointFilter for OneEuroFilter {
    fn name(&self) -> &str {
        "oneeuro"
    }

    fn reset(&mut self) {
        self.joints = [JointState::default(); KinectJoint::COUNT];
        self.last_output = [None; KinectJoint::COUNT];
    }

    fn filter(&mut self, frame: &SensorFrame) -> SensorFrame {
        let p = self.params;
        let t = frame.timestamp_s;
        let mut positions = [Vec3::ZERO; KinectJoint::COUNT];
        for (k, out) in positions.iter_mut().enumerate() {
            let raw = frame.joints[k].position;
            if !raw.is_finite() {
                *out = self.last_output[k].unwrap_or(Vec3::ZERO);
                continue;
            }
            let raw = [f64::from(raw.x), f64::from(raw.y), f64::from(raw.z)];
            let state = self.joints[k];
            let mut next = state;
            if !state.started {
                for (c, &x) in next.coords.iter_mut().zip(&raw) {
                    *c = Coord {
                        x_hat: x,
                        dx_hat: 0.0,
                    };
                }
                next.started = true;
            } else {
                let te = self.sample_period(state.last_t, t);
                let a_d = smoothing_factor(p.d_cutoff_hz, te);
                for (c, &x) in next.coords.iter_mut().zip(&raw) {
                    let dx = (x - c.x_hat) / te;
                    let dx_hat = a_d * dx + (1.0 - a_d) * c.dx_hat;
                    let cutoff = p.min_cutoff_hz + p.beta * dx_hat.abs();
                    let a = smoothing_factor(cutoff, te);
                    *c = Coord {
                        x_hat: a * x + (1.0 - a) * c.x_hat,
                        dx_hat,
                    };
                }
            }
            next.last_t = if t.is_finite() { t } else { state.last_t };
            let y = Vec3::new(
                next.coords[0].x_hat as f32,
                next.coords[1].x_hat as f32,
                next.coords[2].x_hat as f32,
            );
            if y.is_finite() && next.coords.iter().all(|c| c.dx_hat.is_finite()) {
                self.joints[k] = next;
                *out = y;
            } else {
                // Unusable parameters: keep the state, pass the raw position through.
                *out = frame.joints[k].position;
            }
            self.last_output[k] = Some(*out);
        }
        frame_with_positions(frame, &positions)
    }
}

/// Settings of [`tune_one_euro`]. See the module docs.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct OneEuroTuning {
    /// A joint moves "slowly" at a frame when the clean reference's speed there is below this,
    /// m/s. Step 1 judges jitter on those frames only.
    pub slow_speed_m_s: f64,
    /// Acceptable jitter: the clean reference's jitter on the slow frames plus this, m/s².
    pub jitter_tolerance: f64,
    /// Acceptable lag, ms ([`metrics::lag_ms`]).
    pub lag_target_ms: f64,
    /// Step 1 starts at this `mincutoff`, Hz...
    pub min_cutoff_start_hz: f64,
    /// ...and does not go below this one, Hz.
    pub min_cutoff_floor_hz: f64,
    /// Step 2 tries `beta = 0`, then `beta_start * step_ratio^k` up to `beta_max`.
    pub beta_start: f64,
    pub beta_max: f64,
    /// Ratio between successive values tried (> 1).
    pub step_ratio: f64,
    /// `dcutoff`, Hz (kept fixed, as the paper advises).
    pub d_cutoff_hz: f64,
}

impl Default for OneEuroTuning {
    fn default() -> Self {
        Self {
            slow_speed_m_s: 0.25,
            jitter_tolerance: 1.5,
            lag_target_ms: 5.0,
            min_cutoff_start_hz: 10.0,
            min_cutoff_floor_hz: 0.05,
            beta_start: 0.05,
            beta_max: 200.0,
            step_ratio: 1.25,
            d_cutoff_hz: 1.0,
        }
    }
}

fn run_one_euro(params: OneEuroParams, noisy: &[SensorFrame]) -> Vec<SensorFrame> {
    let mut f = OneEuroFilter::new(params);
    noisy.iter().map(|frame| f.filter(frame)).collect()
}

/// Tunes the One Euro filter by the authors' two-step procedure (module docs) on a clean
/// reference and its noisy version (aligned frame by frame).
///
/// Step 1: `beta = 0`; `mincutoff` goes down from `min_cutoff_start_hz` by `step_ratio` until
/// the jitter on slow frames is acceptable (or the floor is reached). Step 2: with that
/// `mincutoff`, `beta` goes up from 0 until the lag is acceptable; if no value reaches the
/// target, the one with the smallest lag is kept. Sequences shorter than 4 frames return the
/// parameters of step 1's start.
pub fn tune_one_euro(
    clean: &[SensorFrame],
    noisy: &[SensorFrame],
    tuning: &OneEuroTuning,
) -> OneEuroParams {
    let n = clean.len().min(noisy.len());
    let (clean, noisy) = (&clean[..n], &noisy[..n]);
    let ratio = if tuning.step_ratio.is_finite() && tuning.step_ratio > 1.0 {
        tuning.step_ratio
    } else {
        1.25
    };
    let mut params = OneEuroParams {
        min_cutoff_hz: tuning.min_cutoff_start_hz,
        beta: 0.0,
        d_cutoff_hz: tuning.d_cutoff_hz,
        ..OneEuroParams::default()
    };
    if n < 4 {
        return params;
    }

    // Step 1: beta = 0, lower mincutoff until the jitter at rest / slow motion is acceptable.
    let reference = metrics::jitter_where_slow(clean, clean, tuning.slow_speed_m_s);
    let acceptable = reference.unwrap_or(0.0) + tuning.jitter_tolerance;
    loop {
        let out = run_one_euro(params, noisy);
        let jitter = metrics::jitter_where_slow(&out, clean, tuning.slow_speed_m_s);
        if jitter.is_none_or(|j| j <= acceptable) {
            break;
        }
        let next = params.min_cutoff_hz / ratio;
        if next < tuning.min_cutoff_floor_hz {
            break;
        }
        params.min_cutoff_hz = next;
    }

    // Step 2: raise beta until the lag (dominated by fast motion) is acceptable.
    let mut best: Option<(f64, f64)> = None;
    let mut beta = 0.0;
    loop {
        params.beta = beta;
        let out = run_one_euro(params, noisy);
        let lag = metrics::lag_ms(clean, &out, metrics::DEFAULT_MAX_LAG_MS);
        if let Some(lag) = lag {
            if lag <= tuning.lag_target_ms {
                return params;
            }
            if best.is_none_or(|(_, l)| lag < l) {
                best = Some((beta, lag));
            }
        } else {
            // No motion to measure a lag on: nothing to gain from beta.
            params.beta = 0.0;
            return params;
        }
        beta = if beta == 0.0 {
            tuning.beta_start
        } else {
            beta * ratio
        };
        if beta > tuning.beta_max {
            break;
        }
    }
    params.beta = best.map_or(0.0, |(b, _)| b);
    params
}
