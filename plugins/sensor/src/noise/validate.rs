//! The ranges of the Kinect v1 noise model's parameters (the model of the [module
//! docs](super), after seed 000, the 2013 Kinect fitting-room thesis, and the sources cited
//! there): [`KinectNoiseModel::validate`] reports the first one outside its range,
//! [`KinectNoiseModel::sanitized`] clamps them all (what the generator runs with).

use super::{BodyVolumes, KinectNoiseModel, NoiseModelError};

impl KinectNoiseModel {
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
