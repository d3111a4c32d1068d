//! The parameters of the Kinect v1 skeleton noise model (sources and formulas in the
//! [module docs](super)): the position noise growing with depth (Nguyen, Izadi & Lovell,
//! 3DIMPVT 2012, scaled to Table 6.1 of seed 000, the 2013 Kinect fitting-room thesis),
//! bone-length and twist noise, hand spikes, self-occlusion, the field of view, dropped and
//! duplicated frames and latency; and the body volumes of the occlusion test.

use glam::Vec3;
use serde::{Deserialize, Serialize};

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

/// The parameters of the Kinect v1 skeleton noise model; see the [module docs](super) for the
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
}
