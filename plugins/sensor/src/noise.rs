//! A seeded Kinect v1 skeleton noise model: turns a clean skeleton stream (for example a
//! [`BvhSource`](crate::BvhSource) replaying real mocap) into a stream with the errors of a
//! Kinect v1 skeleton tracker, reproducibly for a given `u64` seed.
//!
//! # What is modelled
//!
//! Per shown clean frame, in this order (symbols are the fields of [`KinectNoiseModel`]):
//!
//! 1. **Latency.** The noisy frame emitted when clean frame `k` arrives shows clean frame
//!    `k - L`, `L = round(latency_s * fps)`; it carries the timestamp of frame `k` (its arrival
//!    time). No frame is emitted for the first `L` arrivals. Default `latency_s = 0.1` s
//!    (3 frames at 30 Hz): an *assumption*. Livingston, Sebastian, Ai & Decker, "Performance
//!    measurements for the Microsoft Kinect skeleton", IEEE VR 2012, measured the SDK
//!    skeleton's latency; their figure was not at hand, so check it before relying on 0.1 s.
//! 2. **Bone-length noise.** Each bone (parent -> joint offset) is scaled by
//!    `s_j = 1 + bone_length_sigma * (sqrt(c) * g + sqrt(1 - c) * b_j)`, clamped to
//!    `[0.5, 1.5]`, with `c = bone_length_shared_fraction`, `g` one whole-skeleton unit
//!    Gauss-Markov process and `b_j` one per bone (correlation time
//!    `bone_length_correlation_time_s`). The skeleton is rebuilt root first,
//!    `p'_j = p'_parent + s_j * (p_j - p_parent)`, so a scaled bone moves its whole subtree.
//!    Kinect v1 skeletons have no fixed bone lengths (every joint is estimated separately), so
//!    their bone lengths vary from frame to frame (Wang, Kurillo, Ofli & Bajcsy, "Evaluation
//!    of pose tracking accuracy in the first and second generations of Microsoft Kinect",
//!    ICHI 2015, evaluate Kinect bone-length estimates against mocap); the default 1.5 % comes
//!    on top of the variation the independent joint noise already causes (an *assumption*;
//!    together they give a forearm-length standard deviation of about 4 % at 2.5 m).
//! 3. **Position noise**, per joint, anisotropic and growing quadratically with depth `z`
//!    (metres along the optical axis) like the Kinect v1 depth error:
//!
//!    ```text
//!    sigma_axial(z)   = k_j * (c0 + c2 * (z - z0)^2)       along the line of sight
//!    sigma_lateral(z) = lateral_sigma_ratio * sigma_axial(z)   across it (2 axes)
//!    ```
//!
//!    with `c0 = axial_sigma_c0_m = 0.00128 m`, `c2 = axial_sigma_c2_per_m = 0.00203 /m`,
//!    `z0 = axial_sigma_z0_m = 0.4 m`: the axial depth-noise model of Nguyen, Izadi & Lovell,
//!    "Modeling Kinect sensor noise for improved 3D reconstruction and tracking", 3DIMPVT 2012
//!    (`0.0012 + 0.0019 (z - 0.4)^2` m), scaled by 1.068 so that `sigma_axial(3 m) = 1.50 cm`,
//!    the Kinect error at 3 m of Table 6.1 of the seed thesis (0.5 / 1.5 / 4 cm at 1 / 3 / 5 m,
//!    after Khoshelham & Oude Elberink, "Accuracy and resolution of Kinect depth data for
//!    indoor mapping applications", Sensors 12(2), 2012, whose random depth error grows with
//!    `z^2`; the thesis text quotes them as "two centimeters" at 3 m, so 1.5 cm is the lower of
//!    the two). The model gives 0.2 / 1.5 / 4.4 cm at 1 / 3 / 5 m.
//!    `k_j = extremity_sigma_scale` (1.3) for wrists, hands, ankles and feet, 1 otherwise
//!    (*assumption*: extremities are the least reliable Kinect joints). The lateral ratio 0.5
//!    is an *assumption*: the per-pixel lateral noise of Nguyen et al. is only
//!    `0.8 px * z / f` (about 4 mm at 3 m with `f ≈ 585 px`), but a skeleton joint's lateral
//!    error is dominated by the body-part inference, not by the pixel noise. The line of sight
//!    is `a = p / |p|`; the lateral axes are `e1 = normalize(Y x a)` (horizontal) and
//!    `e2 = a x e1`. The noise is
//!    `n_j = sigma_lateral (v_1 e1 + v_2 e2) + sigma_axial v_3 a`, where each `v_i` is a
//!    unit-variance mix of a temporally correlated and a white part:
//!    `v = sqrt(1 - w) u + sqrt(w) eps`, `w = white_noise_fraction` (0.2), `eps ~ N(0, 1)` and
//!    `u` a first-order Gauss-Markov (AR(1)) process, `u_t = phi u_{t-1} + sqrt(1 - phi^2) eps'`,
//!    `phi = exp(-dt / noise_correlation_time_s)` with `dt` the time between shown frames
//!    (0.2 s: an *assumption*; Kinect skeleton jitter is visibly smooth over a few frames). At
//!    30 Hz the lag-1 autocorrelation of `v` is `(1 - w) phi = 0.68`.
//! 4. **Hand spikes.** Per arm, a spike starts with probability
//!    `1 - exp(-hand_spike_rate_hz * dt)` per frame (when none is running), lasts a uniform
//!    time in `[hand_spike_min_duration_s, hand_spike_max_duration_s]` and displaces the hand by
//!    a constant offset `~ N(0, hand_spike_sigma_m^2 I)` and the wrist by `wrist_spike_share`
//!    of it: the jumps of the Kinect's hand joints when the small hand blob is confused with
//!    the forearm or the body. Wang et al. (2015) model Kinect joint offsets as a Gaussian plus
//!    a uniform outlier component; these spikes play the outlier part (rate 0.3 /s,
//!    sigma 5 cm, 33-200 ms are *assumptions*).
//! 5. **Self-occlusion and the view limits** (geometric tests on the *clean* shown pose). The
//!    body is a set of capsules ([`BodyVolumes`]): the trunk (hip centre - shoulder centre),
//!    both trunk sides (shoulder - hip), the head (a sphere), upper arms, forearms, thighs and
//!    shanks. A joint (all but hip centre, spine and shoulder centre) is *occluded* when the
//!    line of sight from the sensor (the origin) to a point `occlusion_margin_m` (5 cm) in front
//!    of the joint passes within `radius - occlusion_inset_m` (inset 3 cm) of the axis of a
//!    capsule that neither ends at the joint nor contains it ([`occluded_joints`]). This is the
//!    depth-image test "the joint projects well inside the silhouette of a body part that is
//!    nearer to the sensor", done in 3D: it catches the far-side shoulder, hip and limbs of a
//!    person turned sideways, a hand behind the back or the head, a knee behind the other leg;
//!    the inset keeps a joint grazed by an edge (an elbow beside the trunk) tracked. A joint is
//!    also hidden when it is outside the depth camera's view
//!    ([`KinectNoiseModel::in_view`]: 57° x 43° field of view, 0.8-4.0 m depth range, the
//!    Kinect for Windows v1 specification), treated like occlusion (an *assumption* about the
//!    SDK; note that the clean walk clips, placed at 2.5 m, walk towards and past the sensor
//!    and so leave the view, see `BvhSourceOptions::start_distance_m`). A hidden
//!    joint is reported **inferred** (`confidence = inferred_confidence`, 0.5, always `<= 0.5`,
//!    i.e. rejected by a `> 0.5` gate) at a biased, late position: a held estimate `h` starts
//!    at the joint's last reported position and follows
//!    `h += (1 - exp(-dt / inferred_lag_s)) * (target - h)` with
//!    `target = noisy + (inferred_sigma_scale - 1) n_j + inferred_body_pull * (c - p_clean)`,
//!    `c` the nearest point of the clean trunk segment (the Kinect guesses hidden joints
//!    towards the body and late). After `not_tracked_after_s` (1 s) of continuous hiding the
//!    joint becomes **not tracked** (`confidence = 0`); its position stays the held estimate
//!    (meaningless, like the SDK's). The occluder radii, margin, inset, lag, pull and the 1 s
//!    are *assumptions* (rounded adult body dimensions; the seed thesis names self-occlusion,
//!    worst "in lateral views of the user", as the main cause of the unnatural movements its
//!    motion filters must handle).
//! 6. **Orientations**, per the contract of [`JointSample::orientation`]: with `Q` the clean
//!    orientation of the bone ending at `j` and `d` the noisy bone (noisy `p_j - p_parent`,
//!    after all the above), the orientation is `twist(d, theta_j) * arc(Q * Y -> d) * Q`, so
//!    its +Y points exactly along the noisy bone, with `theta_j = twist_sigma_deg * t_j` and
//!    `t_j` a unit Gauss-Markov process (correlation time `noise_correlation_time_s`; 3° is an
//!    *assumption*). The hip centre (pelvis) gets `arc(clean hip line -> noisy hip line) * Q`
//!    with the hip line `hip_left - hip_right`.
//! 7. **Dropped and duplicated frames.** Per emitted slot one uniform `u`: `u <
//!    drop_probability` drops the frame (nothing emitted; the noise processes still advance),
//!    `u < drop_probability + duplicate_probability` repeats the previously emitted frame's
//!    joints with the new timestamp and sequence number (USB / SDK hiccups; 1 % each is an
//!    *assumption*).
//!
//! The emitted `sequence` counts the noisy frames emitted (0, 1, 2, ...).
//!
//! # Determinism
//!
//! All randomness comes from ChaCha8 ([`rand_chacha::ChaCha8Rng`], a portable stream cipher)
//! seeded with `seed_from_u64(seed)`, one stream ([`ChaCha8Rng::set_stream`]) per effect
//! (position, bone length, twist, hand spikes, frame fate); every shown frame draws a fixed
//! count of numbers from each stream. So the same seed and the same input give a bit-identical
//! output, and changing one effect's parameters (or switching it off) leaves the random numbers
//! of the others unchanged.
//!
//! # Lining up noisy and clean frames
//!
//! [`corrupt_stream`] and [`NoisySource::advance_detailed`] return [`NoisyFrame`]s: the frame
//! plus `clean_index` (the index of the clean input frame whose pose it shows:
//! `arrival_index - L` for a fresh frame, the repeated frame's for a duplicate) and
//! `arrival_index` (the input frame at whose arrival it was emitted; its timestamp is that
//! frame's). An evaluator compares `frame` with `clean[clean_index]` for the noise and with
//! `clean[arrival_index]` for the total error including latency. Indices count the frames
//! passed in (for [`NoisySource`], the frames its inner source emitted since the wrap).

use std::collections::VecDeque;

use glam::{Quat, Vec3};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};

use crate::frame::{JointSample, KinectJoint, SensorFrame};
use crate::source::{SensorSource, SourceError};

/// Radii of the capsules that stand for the body in the self-occlusion test, metres. The
/// defaults are rounded adult body dimensions (an *assumption*, not fitted to the performer):
/// the trunk is about 0.2 m deep and 0.35 m wide at the hips, a head about 0.2 m across.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct BodyVolumes {
    /// Capsule from the hip centre to the shoulder centre. Default 0.10 m.
    pub trunk_radius_m: f32,
    /// Capsules from each shoulder to the hip of the same side. Default 0.05 m.
    pub trunk_side_radius_m: f32,
    /// Sphere around the head joint. Default 0.10 m.
    pub head_radius_m: f32,
    /// Shoulder to elbow. Default 0.05 m.
    pub upper_arm_radius_m: f32,
    /// Elbow to wrist. Default 0.04 m.
    pub forearm_radius_m: f32,
    /// Hip to knee. Default 0.075 m.
    pub thigh_radius_m: f32,
    /// Knee to ankle. Default 0.055 m.
    pub shank_radius_m: f32,
}

impl Default for BodyVolumes {
    fn default() -> Self {
        Self {
            trunk_radius_m: 0.10,
            trunk_side_radius_m: 0.05,
            head_radius_m: 0.10,
            upper_arm_radius_m: 0.05,
            forearm_radius_m: 0.04,
            thigh_radius_m: 0.075,
            shank_radius_m: 0.055,
        }
    }
}

/// The parameters of the Kinect v1 skeleton noise model; see the [module docs](self) for the
/// formulas. Deserialising a partial object fills the missing fields with the defaults.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct KinectNoiseModel {
    // --- position noise -----------------------------------------------------------------
    /// Constant term `c0` of `sigma_axial(z) = c0 + c2 (z - z0)^2`, metres. Default 0.00128
    /// (Nguyen et al. 2012's 0.0012 m scaled to 1.5 cm at 3 m, seed thesis Table 6.1).
    pub axial_sigma_c0_m: f32,
    /// Quadratic coefficient `c2`, metres per square metre. Default 0.00203 (Nguyen et al.'s
    /// 0.0019 scaled likewise).
    pub axial_sigma_c2_per_m: f32,
    /// Depth `z0` of the minimum of the axial noise, metres. Default 0.4 (Nguyen et al.).
    pub axial_sigma_z0_m: f32,
    /// `sigma_lateral / sigma_axial`. Default 0.5 (assumption).
    pub lateral_sigma_ratio: f32,
    /// Noise multiplier for wrists, hands, ankles and feet. Default 1.3 (assumption).
    pub extremity_sigma_scale: f32,
    /// Correlation time of the Gauss-Markov part of the position noise and of the twist noise,
    /// seconds. Default 0.2 (assumption; lag-1 autocorrelation 0.68 at 30 Hz).
    pub noise_correlation_time_s: f32,
    /// Share of the position-noise variance that is white (frame-to-frame independent).
    /// Default 0.2 (assumption).
    pub white_noise_fraction: f32,

    // --- hand spikes --------------------------------------------------------------------
    /// Spikes per second per arm (Poisson rate). Default 0.3 (assumption).
    pub hand_spike_rate_hz: f32,
    /// Per-axis standard deviation of a spike's hand offset, metres. Default 0.05.
    pub hand_spike_sigma_m: f32,
    /// Shortest spike, seconds. Default 0.033 (one frame).
    pub hand_spike_min_duration_s: f32,
    /// Longest spike, seconds. Default 0.2.
    pub hand_spike_max_duration_s: f32,
    /// Share of the hand's spike offset applied to the wrist. Default 0.5.
    pub wrist_spike_share: f32,

    // --- self-occlusion -----------------------------------------------------------------
    /// Whether the self-occlusion test runs. Default true.
    pub occlusion_enabled: bool,
    /// The line of sight must pass a body capsule at least this far in front of the joint.
    /// Default 0.05 m.
    pub occlusion_margin_m: f32,
    /// How far inside an occluder's silhouette the joint must be: the line of sight must pass
    /// within `radius - occlusion_inset_m` of the capsule's axis, so that a joint grazed by
    /// the edge of a body part (an elbow beside the trunk) stays tracked. Default 0.03 m
    /// (about the radius of a limb: most of the joint's own body part is hidden).
    pub occlusion_inset_m: f32,
    /// The occluding body parts.
    pub body: BodyVolumes,
    /// Whether joints outside the sensor's view (field of view or depth range) are inferred
    /// like occluded ones. Default true.
    pub view_limits_enabled: bool,
    /// Horizontal and vertical field of view of the depth camera, degrees. Default
    /// `[57, 43]` (Kinect for Windows v1 specification).
    pub field_of_view_deg: [f32; 2],
    /// Nearest and farthest depth at which the skeleton is tracked, metres. Default
    /// `[0.8, 4.0]` (Kinect for Windows v1 default range specification).
    pub depth_range_m: [f32; 2],
    /// Confidence of an inferred joint; clamped to `[0, 0.5]`. Default 0.5 (the SDK's
    /// "inferred").
    pub inferred_confidence: f32,
    /// Time constant with which an inferred joint's estimate follows the (noisy, pulled)
    /// truth, seconds. Default 0.25 (assumption).
    pub inferred_lag_s: f32,
    /// Fraction of the way from the joint to the trunk segment an inferred joint is pulled.
    /// Default 0.15 (assumption).
    pub inferred_body_pull: f32,
    /// Position-noise multiplier while inferred. Default 2.0 (assumption).
    pub inferred_sigma_scale: f32,
    /// After this long continuously occluded, a joint is not tracked (confidence 0), seconds.
    /// Default 1.0 (assumption).
    pub not_tracked_after_s: f32,

    // --- bone lengths -------------------------------------------------------------------
    /// Relative standard deviation of a bone's length scale. Default 0.015 (assumption).
    pub bone_length_sigma: f32,
    /// Share of the bone-scale variance common to the whole skeleton. Default 0.5.
    pub bone_length_shared_fraction: f32,
    /// Correlation time of the bone-scale processes, seconds. Default 0.5 (assumption).
    pub bone_length_correlation_time_s: f32,

    // --- orientations -------------------------------------------------------------------
    /// Standard deviation of the twist noise about each bone, degrees. Default 3 (assumption).
    pub twist_sigma_deg: f32,

    // --- stream -------------------------------------------------------------------------
    /// Probability that a frame is dropped. Default 0.01 (assumption).
    pub drop_probability: f32,
    /// Probability that the previous frame is repeated instead of a new one. Default 0.01
    /// (assumption).
    pub duplicate_probability: f32,
    /// Delay between a pose and the frame that shows it, seconds (rounded to whole frames).
    /// Default 0.1 (assumption, see the module docs).
    pub latency_s: f32,
}

impl Default for KinectNoiseModel {
    fn default() -> Self {
        Self {
            axial_sigma_c0_m: 0.00128,
            axial_sigma_c2_per_m: 0.00203,
            axial_sigma_z0_m: 0.4,
            lateral_sigma_ratio: 0.5,
            extremity_sigma_scale: 1.3,
            noise_correlation_time_s: 0.2,
            white_noise_fraction: 0.2,
            hand_spike_rate_hz: 0.3,
            hand_spike_sigma_m: 0.05,
            hand_spike_min_duration_s: 0.033,
            hand_spike_max_duration_s: 0.2,
            wrist_spike_share: 0.5,
            occlusion_enabled: true,
            occlusion_margin_m: 0.05,
            occlusion_inset_m: 0.03,
            body: BodyVolumes::default(),
            view_limits_enabled: true,
            field_of_view_deg: [57.0, 43.0],
            depth_range_m: [0.8, 4.0],
            inferred_confidence: 0.5,
            inferred_lag_s: 0.25,
            inferred_body_pull: 0.15,
            inferred_sigma_scale: 2.0,
            not_tracked_after_s: 1.0,
            bone_length_sigma: 0.015,
            bone_length_shared_fraction: 0.5,
            bone_length_correlation_time_s: 0.5,
            twist_sigma_deg: 3.0,
            drop_probability: 0.01,
            duplicate_probability: 0.01,
            latency_s: 0.1,
        }
    }
}

/// A parameter of [`KinectNoiseModel`] outside its range.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("noise model parameter `{name}` = {value} is invalid: must be {expected}")]
pub struct NoiseModelError {
    pub name: &'static str,
    pub value: f32,
    pub expected: &'static str,
}

impl KinectNoiseModel {
    /// Every effect switched off and no latency: the output equals the input (bit for bit for
    /// positions and confidences).
    pub fn noiseless() -> Self {
        Self {
            axial_sigma_c0_m: 0.0,
            axial_sigma_c2_per_m: 0.0,
            hand_spike_rate_hz: 0.0,
            hand_spike_sigma_m: 0.0,
            occlusion_enabled: false,
            view_limits_enabled: false,
            bone_length_sigma: 0.0,
            twist_sigma_deg: 0.0,
            drop_probability: 0.0,
            duplicate_probability: 0.0,
            latency_s: 0.0,
            ..Self::default()
        }
    }

    /// Axial (line-of-sight) standard deviation of a non-extremity joint's position noise at
    /// depth `z_m`: `c0 + c2 (z - z0)^2`, metres.
    pub fn axial_sigma_m(&self, z_m: f32) -> f32 {
        let dz = z_m.max(0.0) - self.axial_sigma_z0_m;
        self.axial_sigma_c0_m + self.axial_sigma_c2_per_m * dz * dz
    }

    /// Lateral standard deviation (per axis) of a non-extremity joint at depth `z_m`, metres.
    pub fn lateral_sigma_m(&self, z_m: f32) -> f32 {
        self.lateral_sigma_ratio * self.axial_sigma_m(z_m)
    }

    /// Whether a sensor-space point is inside the depth camera's view: depth within
    /// `depth_range_m` and `|x| / z`, `|y| / z` within the half field of view.
    pub fn in_view(&self, p: Vec3) -> bool {
        let [near, far] = self.depth_range_m;
        let [h, v] = self
            .field_of_view_deg
            .map(|deg| (deg.to_radians() * 0.5).tan());
        p.is_finite() && p.z >= near && p.z <= far && p.x.abs() <= h * p.z && p.y.abs() <= v * p.z
    }

    /// Checks every parameter's range (the noise functions clamp instead of failing).
    pub fn validate(&self) -> Result<(), NoiseModelError> {
        let b = &self.body;
        let non_negative: [(&'static str, f32); 23] = [
            ("axial_sigma_c0_m", self.axial_sigma_c0_m),
            ("axial_sigma_c2_per_m", self.axial_sigma_c2_per_m),
            ("lateral_sigma_ratio", self.lateral_sigma_ratio),
            ("extremity_sigma_scale", self.extremity_sigma_scale),
            ("noise_correlation_time_s", self.noise_correlation_time_s),
            ("hand_spike_rate_hz", self.hand_spike_rate_hz),
            ("hand_spike_sigma_m", self.hand_spike_sigma_m),
            ("hand_spike_min_duration_s", self.hand_spike_min_duration_s),
            ("occlusion_margin_m", self.occlusion_margin_m),
            ("occlusion_inset_m", self.occlusion_inset_m),
            ("inferred_lag_s", self.inferred_lag_s),
            ("inferred_sigma_scale", self.inferred_sigma_scale),
            ("not_tracked_after_s", self.not_tracked_after_s),
            (
                "bone_length_correlation_time_s",
                self.bone_length_correlation_time_s,
            ),
            ("twist_sigma_deg", self.twist_sigma_deg),
            ("latency_s", self.latency_s),
            ("body.trunk_radius_m", b.trunk_radius_m),
            ("body.trunk_side_radius_m", b.trunk_side_radius_m),
            ("body.head_radius_m", b.head_radius_m),
            ("body.upper_arm_radius_m", b.upper_arm_radius_m),
            ("body.forearm_radius_m", b.forearm_radius_m),
            ("body.thigh_radius_m", b.thigh_radius_m),
            ("body.shank_radius_m", b.shank_radius_m),
        ];
        for (name, value) in non_negative {
            if !(value.is_finite() && value >= 0.0) {
                return Err(NoiseModelError {
                    name,
                    value,
                    expected: "a finite number >= 0",
                });
            }
        }
        let fractions: [(&'static str, f32); 7] = [
            ("white_noise_fraction", self.white_noise_fraction),
            ("wrist_spike_share", self.wrist_spike_share),
            ("inferred_body_pull", self.inferred_body_pull),
            (
                "bone_length_shared_fraction",
                self.bone_length_shared_fraction,
            ),
            ("drop_probability", self.drop_probability),
            ("duplicate_probability", self.duplicate_probability),
            ("bone_length_sigma", self.bone_length_sigma),
        ];
        for (name, value) in fractions {
            if !(value.is_finite() && (0.0..=1.0).contains(&value)) {
                return Err(NoiseModelError {
                    name,
                    value,
                    expected: "in [0, 1]",
                });
            }
        }
        let [h, v] = self.field_of_view_deg;
        let [near, far] = self.depth_range_m;
        let checks: [(&'static str, f32, bool, &'static str); 8] = [
            (
                "field_of_view_deg[0]",
                h,
                h > 0.0 && h < 180.0,
                "in (0, 180)",
            ),
            (
                "field_of_view_deg[1]",
                v,
                v > 0.0 && v < 180.0,
                "in (0, 180)",
            ),
            (
                "depth_range_m[0]",
                near,
                near.is_finite() && near >= 0.0,
                "a finite number >= 0",
            ),
            (
                "depth_range_m[1]",
                far,
                far.is_finite() && far > near,
                "finite and > depth_range_m[0]",
            ),
            (
                "axial_sigma_z0_m",
                self.axial_sigma_z0_m,
                self.axial_sigma_z0_m.is_finite(),
                "finite",
            ),
            (
                "hand_spike_max_duration_s",
                self.hand_spike_max_duration_s,
                self.hand_spike_max_duration_s.is_finite()
                    && self.hand_spike_max_duration_s >= self.hand_spike_min_duration_s,
                "finite and >= hand_spike_min_duration_s",
            ),
            (
                "inferred_confidence",
                self.inferred_confidence,
                (0.0..=0.5).contains(&self.inferred_confidence),
                "in [0, 0.5]",
            ),
            (
                "duplicate_probability",
                self.duplicate_probability,
                self.drop_probability + self.duplicate_probability <= 1.0,
                "such that drop_probability + duplicate_probability <= 1",
            ),
        ];
        for (name, value, ok, expected) in checks {
            if !ok {
                return Err(NoiseModelError {
                    name,
                    value,
                    expected,
                });
            }
        }
        Ok(())
    }

    /// A copy with every parameter forced into its range (non-finite values take the default).
    pub fn sanitized(&self) -> Self {
        let d = Self::default();
        let non_neg = |v: f32, default: f32| if v.is_finite() { v.max(0.0) } else { default };
        let unit = |v: f32, default: f32| {
            if v.is_finite() {
                v.clamp(0.0, 1.0)
            } else {
                default
            }
        };
        let db = BodyVolumes::default();
        let b = &self.body;
        let min_duration = non_neg(self.hand_spike_min_duration_s, d.hand_spike_min_duration_s);
        let drop_probability = unit(self.drop_probability, d.drop_probability);
        Self {
            axial_sigma_c0_m: non_neg(self.axial_sigma_c0_m, d.axial_sigma_c0_m),
            axial_sigma_c2_per_m: non_neg(self.axial_sigma_c2_per_m, d.axial_sigma_c2_per_m),
            axial_sigma_z0_m: if self.axial_sigma_z0_m.is_finite() {
                self.axial_sigma_z0_m
            } else {
                d.axial_sigma_z0_m
            },
            lateral_sigma_ratio: non_neg(self.lateral_sigma_ratio, d.lateral_sigma_ratio),
            extremity_sigma_scale: non_neg(self.extremity_sigma_scale, d.extremity_sigma_scale),
            noise_correlation_time_s: non_neg(
                self.noise_correlation_time_s,
                d.noise_correlation_time_s,
            ),
            white_noise_fraction: unit(self.white_noise_fraction, d.white_noise_fraction),
            hand_spike_rate_hz: non_neg(self.hand_spike_rate_hz, d.hand_spike_rate_hz),
            hand_spike_sigma_m: non_neg(self.hand_spike_sigma_m, d.hand_spike_sigma_m),
            hand_spike_min_duration_s: min_duration,
            hand_spike_max_duration_s: non_neg(
                self.hand_spike_max_duration_s,
                d.hand_spike_max_duration_s,
            )
            .max(min_duration),
            wrist_spike_share: unit(self.wrist_spike_share, d.wrist_spike_share),
            occlusion_enabled: self.occlusion_enabled,
            occlusion_margin_m: non_neg(self.occlusion_margin_m, d.occlusion_margin_m),
            occlusion_inset_m: non_neg(self.occlusion_inset_m, d.occlusion_inset_m),
            view_limits_enabled: self.view_limits_enabled,
            field_of_view_deg: {
                let [h, v] = self.field_of_view_deg;
                let angle = |a: f32, default: f32| {
                    if a.is_finite() {
                        a.clamp(1.0, 179.0)
                    } else {
                        default
                    }
                };
                [
                    angle(h, d.field_of_view_deg[0]),
                    angle(v, d.field_of_view_deg[1]),
                ]
            },
            depth_range_m: {
                let near = non_neg(self.depth_range_m[0], d.depth_range_m[0]);
                let far = non_neg(self.depth_range_m[1], d.depth_range_m[1]);
                [near, far.max(near)]
            },
            body: BodyVolumes {
                trunk_radius_m: non_neg(b.trunk_radius_m, db.trunk_radius_m),
                trunk_side_radius_m: non_neg(b.trunk_side_radius_m, db.trunk_side_radius_m),
                head_radius_m: non_neg(b.head_radius_m, db.head_radius_m),
                upper_arm_radius_m: non_neg(b.upper_arm_radius_m, db.upper_arm_radius_m),
                forearm_radius_m: non_neg(b.forearm_radius_m, db.forearm_radius_m),
                thigh_radius_m: non_neg(b.thigh_radius_m, db.thigh_radius_m),
                shank_radius_m: non_neg(b.shank_radius_m, db.shank_radius_m),
            },
            inferred_confidence: if self.inferred_confidence.is_finite() {
                self.inferred_confidence.clamp(0.0, 0.5)
            } else {
                d.inferred_confidence
            },
            inferred_lag_s: non_neg(self.inferred_lag_s, d.inferred_lag_s),
            inferred_body_pull: unit(self.inferred_body_pull, d.inferred_body_pull),
            inferred_sigma_scale: non_neg(self.inferred_sigma_scale, d.inferred_sigma_scale),
            not_tracked_after_s: non_neg(self.not_tracked_after_s, d.not_tracked_after_s),
            bone_length_sigma: unit(self.bone_length_sigma, d.bone_length_sigma),
            bone_length_shared_fraction: unit(
                self.bone_length_shared_fraction,
                d.bone_length_shared_fraction,
            ),
            bone_length_correlation_time_s: non_neg(
                self.bone_length_correlation_time_s,
                d.bone_length_correlation_time_s,
            ),
            twist_sigma_deg: non_neg(self.twist_sigma_deg, d.twist_sigma_deg),
            drop_probability,
            duplicate_probability: unit(self.duplicate_probability, d.duplicate_probability)
                .min(1.0 - drop_probability),
            latency_s: non_neg(self.latency_s, d.latency_s),
        }
    }
}

/// One frame of a noisy stream, with the bookkeeping needed to line it up with the clean
/// input (see the module docs).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct NoisyFrame {
    /// The noisy frame. Its timestamp is the arrival frame's, its `sequence` counts the noisy
    /// frames emitted.
    pub frame: SensorFrame,
    /// Index (in the clean input) of the frame whose pose this frame shows.
    pub clean_index: usize,
    /// Index (in the clean input) of the frame at whose arrival this frame was emitted;
    /// `arrival_index - clean_index` is the latency in frames (more for a duplicate).
    pub arrival_index: usize,
    /// Whether the frame repeats the previously emitted one (same joints, new timestamp).
    pub duplicate: bool,
}

/// Streams of the ChaCha8 generator, one per effect.
const STREAM_POSITION: u64 = 1;
const STREAM_BONE: u64 = 2;
const STREAM_TWIST: u64 = 3;
const STREAM_SPIKE: u64 = 4;
const STREAM_FRAME: u64 = 5;

/// Joints never reported as occluded (they are inside the trunk).
const TRUNK_JOINTS: [KinectJoint; 3] = [
    KinectJoint::HipCenter,
    KinectJoint::Spine,
    KinectJoint::ShoulderCenter,
];

/// `(hand, wrist)` per arm.
const ARMS: [(KinectJoint, KinectJoint); 2] = [
    (KinectJoint::HandLeft, KinectJoint::WristLeft),
    (KinectJoint::HandRight, KinectJoint::WristRight),
];

fn is_extremity(joint: KinectJoint) -> bool {
    use KinectJoint::*;
    matches!(
        joint,
        WristLeft
            | HandLeft
            | WristRight
            | HandRight
            | AnkleLeft
            | FootLeft
            | AnkleRight
            | FootRight
    )
}

fn rng_for(seed: u64, stream: u64) -> ChaCha8Rng {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(stream);
    rng
}

fn normal(rng: &mut ChaCha8Rng) -> f32 {
    StandardNormal.sample(rng)
}

/// AR(1) coefficient `exp(-dt / tau)`; 0 (a fresh draw) for the first frame or `tau = 0`.
fn ar_coefficient(dt_s: Option<f64>, tau_s: f32) -> f32 {
    match dt_s {
        Some(dt) if tau_s > 0.0 => (-(dt as f32) / tau_s).exp(),
        _ => 0.0,
    }
}

/// One unit-variance Gauss-Markov step.
fn ar_step(state: f32, phi: f32, innovation: f32) -> f32 {
    phi * state + (1.0 - phi * phi).max(0.0).sqrt() * innovation
}

/// A running hand spike of one arm.
#[derive(Clone, Copy, Debug, Default)]
struct Spike {
    remaining_s: f32,
    offset: Vec3,
}

/// Occlusion bookkeeping of one joint.
#[derive(Clone, Copy, Debug, Default)]
struct JointTrack {
    /// Seconds continuously occluded (0 when visible).
    occluded_s: f32,
    /// The last reported position.
    last_reported: Option<Vec3>,
}

/// The streaming noise engine behind [`NoisySource`] and [`corrupt_stream`]: push clean frames
/// in order, get noisy frames out. Deterministic for a given model, seed and frame rate.
#[derive(Clone, Debug)]
pub struct KinectNoiser {
    model: KinectNoiseModel,
    seed: u64,
    latency_frames: usize,
    rng_position: ChaCha8Rng,
    rng_bone: ChaCha8Rng,
    rng_twist: ChaCha8Rng,
    rng_spike: ChaCha8Rng,
    rng_frame: ChaCha8Rng,
    /// Clean frames that arrived and are not shown yet (at most `latency_frames + 1`).
    pending: VecDeque<SensorFrame>,
    /// Clean frames pushed so far.
    arrivals: usize,
    /// Timestamp of the last shown clean frame.
    last_shown_s: Option<f64>,
    position_state: [[f32; 3]; KinectJoint::COUNT],
    bone_state: [f32; KinectJoint::COUNT],
    bone_shared_state: f32,
    twist_state: [f32; KinectJoint::COUNT],
    spikes: [Spike; 2],
    tracks: [JointTrack; KinectJoint::COUNT],
    last_emitted: Option<NoisyFrame>,
    emitted: u64,
}

impl KinectNoiser {
    /// A noiser for a stream of nominal rate `fps` (used only to turn `latency_s` into whole
    /// frames; a non-positive or non-finite rate counts as 30). The model is
    /// [sanitized](KinectNoiseModel::sanitized).
    pub fn new(model: &KinectNoiseModel, seed: u64, fps: f64) -> Self {
        let model = model.sanitized();
        let fps = if fps.is_finite() && fps > 0.0 {
            fps
        } else {
            30.0
        };
        let latency_frames = (f64::from(model.latency_s) * fps).round().clamp(0.0, 1e6) as usize;
        Self {
            model,
            seed,
            latency_frames,
            rng_position: rng_for(seed, STREAM_POSITION),
            rng_bone: rng_for(seed, STREAM_BONE),
            rng_twist: rng_for(seed, STREAM_TWIST),
            rng_spike: rng_for(seed, STREAM_SPIKE),
            rng_frame: rng_for(seed, STREAM_FRAME),
            pending: VecDeque::new(),
            arrivals: 0,
            last_shown_s: None,
            position_state: [[0.0; 3]; KinectJoint::COUNT],
            bone_state: [0.0; KinectJoint::COUNT],
            bone_shared_state: 0.0,
            twist_state: [0.0; KinectJoint::COUNT],
            spikes: [Spike::default(); 2],
            tracks: [JointTrack::default(); KinectJoint::COUNT],
            last_emitted: None,
            emitted: 0,
        }
    }

    /// The (sanitized) model in use.
    pub fn model(&self) -> &KinectNoiseModel {
        &self.model
    }

    pub fn seed(&self) -> u64 {
        self.seed
    }

    /// The latency in whole frames, `round(latency_s * fps)`.
    pub fn latency_frames(&self) -> usize {
        self.latency_frames
    }

    /// Clean frames pushed so far.
    pub fn arrivals(&self) -> usize {
        self.arrivals
    }

    /// Feeds the next clean frame; returns the noisy frame emitted at its arrival, if any (none
    /// during the first `latency_frames` arrivals and for a dropped frame).
    pub fn push(&mut self, clean: &SensorFrame) -> Option<NoisyFrame> {
        let arrival_index = self.arrivals;
        self.arrivals += 1;
        let arrival_s = clean.timestamp_s;
        self.pending.push_back(clean.clone());
        if self.pending.len() <= self.latency_frames {
            return None;
        }
        let shown = self.pending.pop_front()?;
        let clean_index = arrival_index - self.latency_frames;
        let dt_s = self.last_shown_s.map(|last| {
            let dt = shown.timestamp_s - last;
            if dt.is_finite() {
                dt.clamp(0.0, 60.0)
            } else {
                0.0
            }
        });
        self.last_shown_s = Some(shown.timestamp_s);

        let joints = self.corrupt_pose(&shown, dt_s);

        let fate: f32 = self.rng_frame.random();
        let model = &self.model;
        if fate < model.drop_probability {
            return None;
        }
        let repeat = fate < model.drop_probability + model.duplicate_probability;
        let out = match (&self.last_emitted, repeat) {
            (Some(previous), true) => NoisyFrame {
                frame: SensorFrame {
                    timestamp_s: arrival_s,
                    sequence: self.emitted,
                    joints: previous.frame.joints,
                },
                clean_index: previous.clean_index,
                arrival_index,
                duplicate: true,
            },
            _ => NoisyFrame {
                frame: SensorFrame {
                    timestamp_s: arrival_s,
                    sequence: self.emitted,
                    joints,
                },
                clean_index,
                arrival_index,
                duplicate: false,
            },
        };
        self.emitted += 1;
        self.last_emitted = Some(out.clone());
        Some(out)
    }

    /// Advances every random process by one shown frame and returns the corrupted joints.
    fn corrupt_pose(
        &mut self,
        clean: &SensorFrame,
        dt_s: Option<f64>,
    ) -> [JointSample; KinectJoint::COUNT] {
        let m = self.model.clone();
        let dt = dt_s.unwrap_or(0.0) as f32;

        // Random processes: a fixed count of draws per stream and frame.
        let phi = ar_coefficient(dt_s, m.noise_correlation_time_s);
        let (w_ar, w_white) = (
            (1.0 - m.white_noise_fraction).sqrt(),
            m.white_noise_fraction.sqrt(),
        );
        let mut unit_noise = [Vec3::ZERO; KinectJoint::COUNT];
        for (state, out) in self.position_state.iter_mut().zip(unit_noise.iter_mut()) {
            let mut v = [0.0f32; 3];
            for (axis, value) in state.iter_mut().zip(v.iter_mut()) {
                let innovation = normal(&mut self.rng_position);
                let white = normal(&mut self.rng_position);
                *axis = ar_step(*axis, phi, innovation);
                *value = w_ar * *axis + w_white * white;
            }
            *out = Vec3::from_array(v);
        }
        let phi_bone = ar_coefficient(dt_s, m.bone_length_correlation_time_s);
        self.bone_shared_state =
            ar_step(self.bone_shared_state, phi_bone, normal(&mut self.rng_bone));
        for state in self.bone_state.iter_mut() {
            *state = ar_step(*state, phi_bone, normal(&mut self.rng_bone));
        }
        for state in self.twist_state.iter_mut() {
            *state = ar_step(*state, phi, normal(&mut self.rng_twist));
        }
        let start_probability = 1.0 - (-m.hand_spike_rate_hz * dt).exp();
        for spike in self.spikes.iter_mut() {
            let start: f32 = self.rng_spike.random();
            let offset = Vec3::new(
                normal(&mut self.rng_spike),
                normal(&mut self.rng_spike),
                normal(&mut self.rng_spike),
            );
            let length: f32 = self.rng_spike.random();
            spike.remaining_s = (spike.remaining_s - dt).max(0.0);
            if spike.remaining_s <= 0.0 && dt_s.is_some() && start < start_probability {
                spike.remaining_s = m.hand_spike_min_duration_s
                    + length * (m.hand_spike_max_duration_s - m.hand_spike_min_duration_s);
                spike.offset = offset * m.hand_spike_sigma_m;
            }
        }

        let clean_pos = clean.joints.map(|s| s.position);
        let usable = clean
            .joints
            .map(|s| s.position.is_finite() && s.orientation.is_finite());

        // Bone lengths.
        let mut pos = clean_pos;
        if m.bone_length_sigma > 0.0 {
            let (shared, own) = (
                m.bone_length_shared_fraction.sqrt(),
                (1.0 - m.bone_length_shared_fraction).sqrt(),
            );
            for joint in KinectJoint::ALL {
                let j = joint.index();
                if let Some(parent) = joint.parent() {
                    let p = parent.index();
                    if usable[j] && usable[p] {
                        let scale = (1.0
                            + m.bone_length_sigma
                                * (shared * self.bone_shared_state + own * self.bone_state[j]))
                            .clamp(0.5, 1.5);
                        pos[j] = pos[p] + scale * (clean_pos[j] - clean_pos[p]);
                    }
                }
            }
        }

        // Depth-dependent anisotropic position noise.
        let mut noise = [Vec3::ZERO; KinectJoint::COUNT];
        for joint in KinectJoint::ALL {
            let j = joint.index();
            if !usable[j] {
                continue;
            }
            let scale = if is_extremity(joint) {
                m.extremity_sigma_scale
            } else {
                1.0
            };
            // Capped at 1 m (z > 22 m) so that absurd inputs cannot overflow to infinity.
            let axial = (scale * m.axial_sigma_m(clean_pos[j].z)).min(1.0);
            let lateral = m.lateral_sigma_ratio * axial;
            let (e1, e2, a) = sight_basis(clean_pos[j]);
            let v = unit_noise[j];
            noise[j] = e1 * (lateral * v.x) + e2 * (lateral * v.y) + a * (axial * v.z);
            pos[j] += noise[j];
        }

        // Hand spikes.
        for ((hand, wrist), spike) in ARMS.iter().zip(self.spikes.iter()) {
            if spike.remaining_s > 0.0 {
                if usable[hand.index()] {
                    pos[hand.index()] += spike.offset;
                }
                if usable[wrist.index()] {
                    pos[wrist.index()] += spike.offset * m.wrist_spike_share;
                }
            }
        }

        // Self-occlusion on the clean pose.
        let occluded = if m.occlusion_enabled {
            occluded_joints(
                &clean_pos,
                &usable,
                &m.body,
                m.occlusion_margin_m,
                m.occlusion_inset_m,
            )
        } else {
            [false; KinectJoint::COUNT]
        };
        let hidden: [bool; KinectJoint::COUNT] = std::array::from_fn(|j| {
            occluded[j] || (m.view_limits_enabled && usable[j] && !m.in_view(clean_pos[j]))
        });
        let trunk = (
            clean_pos[KinectJoint::HipCenter.index()],
            clean_pos[KinectJoint::ShoulderCenter.index()],
        );
        let follow = if m.inferred_lag_s > 0.0 {
            1.0 - (-dt / m.inferred_lag_s).exp()
        } else {
            1.0
        };
        let mut confidence = [1.0f32; KinectJoint::COUNT];
        for joint in KinectJoint::ALL {
            let j = joint.index();
            let track = &mut self.tracks[j];
            if !usable[j] {
                pos[j] = track.last_reported.unwrap_or(Vec3::ZERO);
                confidence[j] = 0.0;
                continue;
            }
            if hidden[j] {
                track.occluded_s += dt;
                let toward_body = closest_on_segment(clean_pos[j], trunk.0, trunk.1) - clean_pos[j];
                let target = pos[j]
                    + noise[j] * (m.inferred_sigma_scale - 1.0)
                    + toward_body * m.inferred_body_pull;
                let held = match track.last_reported {
                    Some(last) if dt_s.is_some() => last + (target - last) * follow,
                    _ => target,
                };
                pos[j] = if held.is_finite() { held } else { target };
                confidence[j] = if track.occluded_s > m.not_tracked_after_s {
                    0.0
                } else {
                    m.inferred_confidence
                };
            } else {
                track.occluded_s = 0.0;
            }
            track.last_reported = Some(pos[j]);
        }

        // Orientations from the noisy bones.
        let twist_sigma = m.twist_sigma_deg.to_radians();
        let mut joints = [JointSample::default(); KinectJoint::COUNT];
        for joint in KinectJoint::ALL {
            let j = joint.index();
            let clean_q = clean.joints[j].orientation;
            let orientation = if !usable[j] {
                Quat::IDENTITY
            } else {
                match joint.parent() {
                    Some(parent) => {
                        let bone = pos[j] - pos[parent.index()];
                        let swung = swing_to(clean_q, clean_q * Vec3::Y, bone);
                        let axis = bone.normalize_or_zero();
                        if axis == Vec3::ZERO || twist_sigma == 0.0 {
                            swung
                        } else {
                            (Quat::from_axis_angle(axis, twist_sigma * self.twist_state[j]) * swung)
                                .normalize()
                        }
                    }
                    None => {
                        let (l, r) = (KinectJoint::HipLeft.index(), KinectJoint::HipRight.index());
                        swing_to(clean_q, clean_pos[l] - clean_pos[r], pos[l] - pos[r])
                    }
                }
            };
            joints[j] = JointSample {
                position: pos[j],
                orientation,
                confidence: confidence[j],
            };
        }
        joints
    }
}

/// `arc(from -> to) * q`; `q` itself when either direction is degenerate or they agree.
fn swing_to(q: Quat, from: Vec3, to: Vec3) -> Quat {
    let (from, to) = (from.normalize_or_zero(), to.normalize_or_zero());
    if from == Vec3::ZERO || to == Vec3::ZERO || from == to {
        return q;
    }
    let swung = (Quat::from_rotation_arc(from, to) * q).normalize();
    if swung.is_finite() { swung } else { q }
}

/// `(e1, e2, a)`: `a` the line of sight to `p`, `e1` horizontal across it, `e2 = a x e1`.
fn sight_basis(p: Vec3) -> (Vec3, Vec3, Vec3) {
    let a = p.normalize_or(Vec3::Z);
    let e1 = Vec3::Y.cross(a).normalize_or(Vec3::X);
    let e2 = a.cross(e1).normalize_or(Vec3::Y);
    (e1, e2, a)
}

/// The point of segment `[a, b]` nearest to `p`.
fn closest_on_segment(p: Vec3, a: Vec3, b: Vec3) -> Vec3 {
    let ab = b - a;
    let len2 = ab.length_squared();
    if len2 <= f32::EPSILON {
        return a;
    }
    a + ab * ((p - a).dot(ab) / len2).clamp(0.0, 1.0)
}

/// Distance between segments `[p1, q1]` and `[p2, q2]` (Ericson, *Real-Time Collision
/// Detection*, 5.1.9).
fn segment_distance(p1: Vec3, q1: Vec3, p2: Vec3, q2: Vec3) -> f32 {
    let (d1, d2, r) = (q1 - p1, q2 - p2, p1 - p2);
    let (a, e, f) = (d1.dot(d1), d2.dot(d2), d2.dot(r));
    const EPS: f32 = 1e-12;
    let (s, t) = if a <= EPS && e <= EPS {
        (0.0, 0.0)
    } else if a <= EPS {
        (0.0, (f / e).clamp(0.0, 1.0))
    } else {
        let c = d1.dot(r);
        if e <= EPS {
            ((-c / a).clamp(0.0, 1.0), 0.0)
        } else {
            let b = d1.dot(d2);
            let denom = a * e - b * b;
            let mut s = if denom > 1e-9 * a * e {
                ((b * f - c * e) / denom).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let mut t = (b * s + f) / e;
            if t < 0.0 {
                t = 0.0;
                s = (-c / a).clamp(0.0, 1.0);
            } else if t > 1.0 {
                t = 1.0;
                s = ((b - c) / a).clamp(0.0, 1.0);
            }
            (s, t)
        }
    };
    ((p1 + d1 * s) - (p2 + d2 * t)).length()
}

/// The body capsules `(start, end, radius)` of the occlusion test.
fn body_capsules(body: &BodyVolumes) -> [(KinectJoint, KinectJoint, f32); 12] {
    use KinectJoint::*;
    [
        (HipCenter, ShoulderCenter, body.trunk_radius_m),
        (ShoulderLeft, HipLeft, body.trunk_side_radius_m),
        (ShoulderRight, HipRight, body.trunk_side_radius_m),
        (Head, Head, body.head_radius_m),
        (ShoulderLeft, ElbowLeft, body.upper_arm_radius_m),
        (ShoulderRight, ElbowRight, body.upper_arm_radius_m),
        (ElbowLeft, WristLeft, body.forearm_radius_m),
        (ElbowRight, WristRight, body.forearm_radius_m),
        (HipLeft, KneeLeft, body.thigh_radius_m),
        (HipRight, KneeRight, body.thigh_radius_m),
        (KneeLeft, AnkleLeft, body.shank_radius_m),
        (KneeRight, AnkleRight, body.shank_radius_m),
    ]
}

/// Which joints of a pose are hidden from the sensor (at the origin) by a body capsule; see
/// the module docs. Public so that evaluators and visualisations can show the same test.
pub fn occluded_joints(
    positions: &[Vec3; KinectJoint::COUNT],
    usable: &[bool; KinectJoint::COUNT],
    body: &BodyVolumes,
    margin_m: f32,
    inset_m: f32,
) -> [bool; KinectJoint::COUNT] {
    let capsules = body_capsules(body);
    let mut out = [false; KinectJoint::COUNT];
    for joint in KinectJoint::ALL {
        let j = joint.index();
        if TRUNK_JOINTS.contains(&joint) || !usable[j] {
            continue;
        }
        let p = positions[j];
        let range = p.length();
        if range <= margin_m + 1e-3 {
            continue;
        }
        let sight_end = p * (1.0 - margin_m / range);
        out[j] = capsules.iter().any(|&(a, b, radius)| {
            if a == joint || b == joint || !usable[a.index()] || !usable[b.index()] {
                return false;
            }
            let (pa, pb) = (positions[a.index()], positions[b.index()]);
            closest_on_segment(p, pa, pb).distance(p) > radius
                && segment_distance(Vec3::ZERO, sight_end, pa, pb) < radius - inset_m
        });
    }
    out
}

/// Corrupts a whole clean stream (frames in order, e.g. 30 Hz) with `model` and `seed`; the
/// pure-function form of [`NoisySource`] for evaluation. The frame rate used to turn the
/// latency into frames is `1 / median(frame interval)` of `clean` (30 Hz for fewer than two
/// frames). Same inputs, same output, bit for bit; the output equals what a [`NoisySource`]
/// with the same rate emits for the same frames.
pub fn corrupt_stream(
    clean: &[SensorFrame],
    model: &KinectNoiseModel,
    seed: u64,
) -> Vec<NoisyFrame> {
    let mut intervals: Vec<f64> = clean
        .windows(2)
        .map(|w| w[1].timestamp_s - w[0].timestamp_s)
        .filter(|dt| dt.is_finite() && *dt > 0.0)
        .collect();
    intervals.sort_by(f64::total_cmp);
    let fps = intervals
        .get(intervals.len() / 2)
        .map_or(30.0, |median| 1.0 / median);
    let mut noiser = KinectNoiser::new(model, seed, fps);
    clean
        .iter()
        .filter_map(|frame| noiser.push(frame))
        .collect()
}

/// A [`SensorSource`] wrapper that passes every frame of `inner` through a [`KinectNoiser`].
/// Deterministic given the seed: the same seed and the same inner frames give a bit-identical
/// stream.
#[derive(Clone, Debug)]
pub struct NoisySource<S> {
    inner: S,
    noiser: KinectNoiser,
    name: String,
}

impl<S: SensorSource> NoisySource<S> {
    /// Wraps `inner`; the latency is rounded to whole frames of `inner.fps()`. The name is
    /// `"noisy:<inner name>"`.
    pub fn new(inner: S, model: &KinectNoiseModel, seed: u64) -> Self {
        let noiser = KinectNoiser::new(model, seed, f64::from(inner.fps()));
        let name = format!("noisy:{}", inner.name());
        Self {
            inner,
            noiser,
            name,
        }
    }

    pub fn inner(&self) -> &S {
        &self.inner
    }

    pub fn into_inner(self) -> S {
        self.inner
    }

    pub fn noiser(&self) -> &KinectNoiser {
        &self.noiser
    }

    /// Like [`SensorSource::advance`] but with the [`NoisyFrame`] bookkeeping; `clean_index`
    /// and `arrival_index` count the frames `inner` emitted since the wrap.
    pub fn advance_detailed(&mut self, dt_s: f64) -> Result<Vec<NoisyFrame>, SourceError> {
        let clean = self.inner.advance(dt_s)?;
        Ok(clean.iter().filter_map(|f| self.noiser.push(f)).collect())
    }
}

impl<S: SensorSource> SensorSource for NoisySource<S> {
    fn name(&self) -> &str {
        &self.name
    }

    fn fps(&self) -> f32 {
        self.inner.fps()
    }

    fn advance(&mut self, dt_s: f64) -> Result<Vec<SensorFrame>, SourceError> {
        Ok(self
            .advance_detailed(dt_s)?
            .into_iter()
            .map(|f| f.frame)
            .collect())
    }
}
