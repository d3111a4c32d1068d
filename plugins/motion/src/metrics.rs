//! Evaluation metrics for joint filters: pure functions over frame sequences aligned frame by
//! frame (output `k` is the filter's answer to input `k`, compared with clean frame `k`), or over
//! per-joint position series.
//!
//! * [`position_rmse_mm`]: root mean square of the 3-D position error, millimetres.
//! * [`jitter`]: mean magnitude of the acceleration (second difference over the sample
//!   intervals), m/s². Report it for the clean reference too: real motion has some.
//! * [`lag_ms`]: delay of the output behind the clean signal by cross-correlation of the
//!   velocities, per joint and axis, searched over 0..300 ms with sub-frame resolution by a
//!   parabola through the correlation peak, averaged with the clean motion energy as weight.
//! * [`bone_length_std`]: standard deviation of each bone's length over time, millimetres.
//! * [`foot_skate_ratio`]: share of frame transitions in which a foot near the floor slides.
//!
//! Sensor space is Y-up (metres), so "height" is `y` and "horizontal" is `(x, z)`. Frames with
//! non-finite values are skipped where a metric would otherwise become NaN.

use fitroom_sensor::{KinectJoint, SensorFrame};
use glam::Vec3;
use serde::{Deserialize, Serialize};

/// Default search range of [`lag_ms`], milliseconds.
pub const DEFAULT_MAX_LAG_MS: f64 = 300.0;

/// One joint's positions over a frame sequence.
pub fn joint_series(frames: &[SensorFrame], joint: KinectJoint) -> Vec<Vec3> {
    frames.iter().map(|f| f.joint(joint).position).collect()
}

/// The frames' timestamps.
pub fn timestamps(frames: &[SensorFrame]) -> Vec<f64> {
    frames.iter().map(|f| f.timestamp_s).collect()
}

/// Median interval between consecutive finite, increasing timestamps, seconds (`None` if
/// there is none).
pub fn median_interval_s(times: &[f64]) -> Option<f64> {
    let mut d: Vec<f64> = times
        .windows(2)
        .map(|w| w[1] - w[0])
        .filter(|d| d.is_finite() && *d > 0.0)
        .collect();
    if d.is_empty() {
        return None;
    }
    d.sort_by(f64::total_cmp);
    Some(d[d.len() / 2])
}

/// RMSE between two aligned position series (the shorter length), millimetres. Pairs with a
/// non-finite value are skipped; `None` if no pair is left.
pub fn rmse_mm_series(clean: &[Vec3], out: &[Vec3]) -> Option<f64> {
    let mut sum = 0.0;
    let mut n = 0usize;
    for (c, o) in clean.iter().zip(out) {
        if c.is_finite() && o.is_finite() {
            sum += f64::from((*o - *c).length_squared());
            n += 1;
        }
    }
    (n > 0).then(|| (sum / n as f64).sqrt() * 1000.0)
}

/// Position RMSE over all joints and aligned frames, millimetres.
pub fn position_rmse_mm(clean: &[SensorFrame], out: &[SensorFrame]) -> Option<f64> {
    let mut sum = 0.0;
    let mut n = 0usize;
    for (c, o) in clean.iter().zip(out) {
        for (cj, oj) in c.joints.iter().zip(&o.joints) {
            if cj.position.is_finite() && oj.position.is_finite() {
                sum += f64::from((oj.position - cj.position).length_squared());
                n += 1;
            }
        }
    }
    (n > 0).then(|| (sum / n as f64).sqrt() * 1000.0)
}

/// Accelerations of a position series at samples `1..n-1` (index `i` of the result is sample
/// `i + 1`), m/s²: `2 ((p[i+1]-p[i])/h1 - (p[i]-p[i-1])/h0) / (h0 + h1)` with the timestamp
/// intervals `h0`, `h1` (exact for a parabola, even for uneven intervals). `None` where a
/// value is not finite or an interval is not positive.
pub fn acceleration_series(positions: &[Vec3], times: &[f64]) -> Vec<Option<Vec3>> {
    let n = positions.len().min(times.len());
    if n < 3 {
        return Vec::new();
    }
    (1..n - 1)
        .map(|i| {
            let (h0, h1) = (times[i] - times[i - 1], times[i + 1] - times[i]);
            if !(h0.is_finite() && h1.is_finite() && h0 > 0.0 && h1 > 0.0) {
                return None;
            }
            let p0 = positions[i - 1].as_dvec3();
            let p1 = positions[i].as_dvec3();
            let p2 = positions[i + 1].as_dvec3();
            let a = ((p2 - p1) / h1 - (p1 - p0) / h0) * (2.0 / (h0 + h1));
            a.is_finite().then(|| a.as_vec3())
        })
        .collect()
}

/// Mean acceleration magnitude of a position series, m/s² (`None` under 3 usable samples).
pub fn jitter_series(positions: &[Vec3], times: &[f64]) -> Option<f64> {
    mean(acceleration_series(positions, times).into_iter().flatten())
}

fn mean(values: impl Iterator<Item = Vec3>) -> Option<f64> {
    let mut sum = 0.0;
    let mut n = 0usize;
    for a in values {
        sum += f64::from(a.length());
        n += 1;
    }
    (n > 0).then(|| sum / n as f64)
}

/// Jitter of a frame sequence: mean acceleration magnitude over all joints and frames, m/s².
pub fn jitter(frames: &[SensorFrame]) -> Option<f64> {
    let times = timestamps(frames);
    mean(KinectJoint::ALL.into_iter().flat_map(|joint| {
        acceleration_series(&joint_series(frames, joint), &times)
            .into_iter()
            .flatten()
    }))
}

/// Jitter of `out` on the samples where the aligned `clean` joint moves slower than
/// `slow_speed_m_s` (central difference of `clean`), m/s²: the jitter "at rest or in slow
/// motion" of the One Euro tuning procedure. `None` if no sample qualifies.
pub fn jitter_where_slow(
    out: &[SensorFrame],
    clean: &[SensorFrame],
    slow_speed_m_s: f64,
) -> Option<f64> {
    let n = out.len().min(clean.len());
    let times = timestamps(&clean[..n]);
    let mut sum = 0.0;
    let mut count = 0usize;
    for joint in KinectJoint::ALL {
        let c = joint_series(&clean[..n], joint);
        let acc = acceleration_series(&joint_series(&out[..n], joint), &times);
        for (i, a) in acc.into_iter().enumerate() {
            let (Some(a), s) = (a, i + 1) else { continue };
            let dt = times[s + 1] - times[s - 1];
            let speed = f64::from((c[s + 1] - c[s - 1]).length()) / dt;
            if speed.is_finite() && speed < slow_speed_m_s {
                sum += f64::from(a.length());
                count += 1;
            }
        }
    }
    (count > 0).then(|| sum / count as f64)
}

/// The correlation peak of [`lag_series`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LagPeak {
    /// Delay of `out` behind `clean`, in samples (fractional; may be slightly negative, down to
    /// -0.5, when the peak is at 0 and the parabola leans towards a lead).
    pub lag_samples: f64,
    /// Normalised correlation at the best integer shift.
    pub correlation: f64,
    /// Energy of `clean` (sum of squares): the weight of this series in [`lag_ms`].
    pub energy: f64,
}

/// Normalised cross-correlation of `out` delayed by `shift` samples against `clean`:
/// `sum clean[t - shift] out[t] / sqrt(sum clean[t - shift]^2 sum out[t]^2)` over the overlap.
fn correlation_at(clean: &[f64], out: &[f64], shift: isize) -> f64 {
    let n = clean.len().min(out.len()) as isize;
    let (mut sco, mut scc, mut soo) = (0.0, 0.0, 0.0);
    for t in 0..n {
        let s = t - shift;
        if s < 0 || s >= n {
            continue;
        }
        let (c, o) = (clean[s as usize], out[t as usize]);
        sco += c * o;
        scc += c * c;
        soo += o * o;
    }
    let d = (scc * soo).sqrt();
    if d > 0.0 && d.is_finite() {
        sco / d
    } else {
        0.0
    }
}

/// Delay of a uniformly sampled signal `out` behind `clean` by cross-correlation: the integer
/// shift in `0..=max_shift` with the highest normalised correlation, refined by a parabola
/// through it and its neighbours (shift -1 is evaluated for the neighbour of 0). `None` if the
/// series are too short, not finite or `clean` is flat. Pass velocities (or other zero-mean
/// signals): the correlation is not mean-removed.
pub fn lag_series(clean: &[f64], out: &[f64], max_shift: usize) -> Option<LagPeak> {
    let n = clean.len().min(out.len());
    if n < 3 || max_shift + 2 >= n {
        return None;
    }
    let (clean, out) = (&clean[..n], &out[..n]);
    if !clean.iter().chain(out).all(|v| v.is_finite()) {
        return None;
    }
    let energy: f64 = clean.iter().map(|v| v * v).sum();
    if energy <= 0.0 {
        return None;
    }
    let r: Vec<f64> = (-1..=max_shift as isize + 1)
        .map(|s| correlation_at(clean, out, s))
        .collect();
    // r[k] is shift k - 1.
    let (best_k, &best) = r[1..=max_shift + 1]
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.total_cmp(b.1))
        .map(|(i, v)| (i + 1, v))?;
    let (ym, y0, yp) = (r[best_k - 1], best, r[best_k + 1]);
    let denom = ym - 2.0 * y0 + yp;
    let delta = if denom < 0.0 {
        (0.5 * (ym - yp) / denom).clamp(-0.5, 0.5)
    } else {
        0.0
    };
    Some(LagPeak {
        lag_samples: (best_k as f64 - 1.0) + delta,
        correlation: best,
        energy,
    })
}

/// Lag of `out` behind `clean`, milliseconds: [`lag_series`] on the velocities (first
/// differences) of every joint's x, y and z over the aligned frames, shifts up to
/// `max_lag_ms`, averaged with each series' clean motion energy as weight. The sample interval
/// is the median timestamp interval of `clean`. `None` without motion or timestamps.
pub fn lag_ms(clean: &[SensorFrame], out: &[SensorFrame], max_lag_ms: f64) -> Option<f64> {
    let n = clean.len().min(out.len());
    let dt = median_interval_s(&timestamps(&clean[..n]))?;
    let max_shift = (max_lag_ms / 1000.0 / dt).round().max(1.0) as usize;
    let mut sum = 0.0;
    let mut weight = 0.0;
    for joint in KinectJoint::ALL {
        let c = joint_series(&clean[..n], joint);
        let o = joint_series(&out[..n], joint);
        for axis in 0..3 {
            let vel = |p: &[Vec3]| -> Vec<f64> {
                p.windows(2)
                    .map(|w| f64::from(w[1][axis]) - f64::from(w[0][axis]))
                    .collect()
            };
            if let Some(peak) = lag_series(&vel(&c), &vel(&o), max_shift) {
                sum += peak.lag_samples * peak.energy;
                weight += peak.energy;
            }
        }
    }
    (weight > 0.0).then(|| sum / weight * dt * 1000.0)
}

/// Bone-length variability of a frame sequence.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BoneLengthStats {
    /// Per bone (named by the joint it ends at, in [`KinectJoint::ALL`] order without the
    /// root): standard deviation of its length over the frames, mm.
    pub per_bone_std_mm: Vec<(KinectJoint, f64)>,
    /// Mean of the per-bone standard deviations, mm.
    pub mean_std_mm: f64,
}

/// Standard deviation (population) of each bone's length over the frames, millimetres; frames
/// with a non-finite end are skipped for that bone.
pub fn bone_length_std(frames: &[SensorFrame]) -> BoneLengthStats {
    let mut per_bone = Vec::with_capacity(KinectJoint::COUNT - 1);
    for joint in KinectJoint::ALL {
        let Some(parent) = joint.parent() else {
            continue;
        };
        let lengths: Vec<f64> = frames
            .iter()
            .map(|f| f64::from(f.joint(joint).position.distance(f.joint(parent).position)))
            .filter(|l| l.is_finite())
            .collect();
        per_bone.push((joint, std_dev(&lengths) * 1000.0));
    }
    let mean_std_mm = if per_bone.is_empty() {
        0.0
    } else {
        per_bone.iter().map(|(_, s)| s).sum::<f64>() / per_bone.len() as f64
    };
    BoneLengthStats {
        per_bone_std_mm: per_bone,
        mean_std_mm,
    }
}

fn std_dev(values: &[f64]) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    let n = values.len() as f64;
    let m = values.iter().sum::<f64>() / n;
    (values.iter().map(|v| (v - m) * (v - m)).sum::<f64>() / n).sqrt()
}

/// Thresholds of [`foot_skate_ratio`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct FootSkateParams {
    /// A foot point is on the floor when it is less than this above the floor, metres.
    pub contact_height_m: f32,
    /// It skates when it moves more than this horizontally between consecutive frames, metres.
    pub slide_m: f32,
}

impl Default for FootSkateParams {
    fn default() -> Self {
        Self {
            contact_height_m: 0.05,
            slide_m: 0.025,
        }
    }
}

/// Foot-skating ratio: the share of consecutive-frame transitions `i-1 -> i` in which some
/// foot point is below `contact_height_m` above the floor at both frames and moves more than
/// `slide_m` horizontally. `feet` holds one position series per foot point (sensor space,
/// Y-up: Kinect ankles and feet, or an avatar's feet); all series are read over their common
/// length. Transitions with a non-finite position do not count for that point. 0 for fewer
/// than two frames.
pub fn foot_skate_ratio(feet: &[&[Vec3]], floor_y: f32, params: &FootSkateParams) -> f64 {
    let n = feet.iter().map(|s| s.len()).min().unwrap_or(0);
    if n < 2 {
        return 0.0;
    }
    let skating = (1..n)
        .filter(|&i| {
            feet.iter().any(|series| {
                let (a, b) = (series[i - 1], series[i]);
                if !(a.is_finite() && b.is_finite()) {
                    return false;
                }
                let low = a.y - floor_y < params.contact_height_m
                    && b.y - floor_y < params.contact_height_m;
                let slide = Vec3::new(b.x - a.x, 0.0, b.z - a.z).length();
                low && slide > params.slide_m
            })
        })
        .count();
    skating as f64 / (n - 1) as f64
}

/// [`foot_skate_ratio`] of the Kinect foot points (both ankles and feet) of a frame sequence.
pub fn foot_skate_ratio_frames(
    frames: &[SensorFrame],
    floor_y: f32,
    params: &FootSkateParams,
) -> f64 {
    use KinectJoint::*;
    let series: Vec<Vec<Vec3>> = [AnkleLeft, FootLeft, AnkleRight, FootRight]
        .into_iter()
        .map(|j| joint_series(frames, j))
        .collect();
    let refs: Vec<&[Vec3]> = series.iter().map(Vec::as_slice).collect();
    foot_skate_ratio(&refs, floor_y, params)
}

/// All metrics of one filter output against the clean reference.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FilterReport {
    pub rmse_mm: f64,
    /// Jitter of the output, m/s².
    pub jitter_m_s2: f64,
    /// Jitter of the clean reference, m/s², for comparison.
    pub clean_jitter_m_s2: f64,
    pub lag_ms: f64,
    /// Mean per-bone length standard deviation, mm.
    pub bone_std_mm: f64,
    pub foot_skate_ratio: f64,
}

/// Evaluates `out` against `clean` (aligned): every metric above, NaN where undefined.
pub fn evaluate(clean: &[SensorFrame], out: &[SensorFrame], floor_y: f32) -> FilterReport {
    let n = clean.len().min(out.len());
    let (clean, out) = (&clean[..n], &out[..n]);
    FilterReport {
        rmse_mm: position_rmse_mm(clean, out).unwrap_or(f64::NAN),
        jitter_m_s2: jitter(out).unwrap_or(f64::NAN),
        clean_jitter_m_s2: jitter(clean).unwrap_or(f64::NAN),
        lag_ms: lag_ms(clean, out, DEFAULT_MAX_LAG_MS).unwrap_or(f64::NAN),
        bone_std_mm: bone_length_std(out).mean_std_mm,
        foot_skate_ratio: foot_skate_ratio_frames(out, floor_y, &FootSkateParams::default()),
    }
}
