//! The Kinect v1's depth error, as published:
//!
//! - **Axial** (along the ray), Nguyen, Izadi & Lovell 2012, "Modeling Kinect Sensor Noise for
//!   Improved 3D Reconstruction and Tracking" (3DIMPVT), eq. 6:
//!   `σz(z, θ) = 1.2 mm + 1.9 mm (z - 0.4 m)² + 0.1 mm / √z · θ² / (π/2 - θ)²`, z in metres,
//!   θ the angle between the surface normal and the ray (the third term, for grazing
//!   surfaces, is the paper's fit for θ above about 60°).
//! - **Lateral** (across the image), the same paper, eq. 5:
//!   `σL(θ) = 0.8 px + 0.035 px · θ / (π/2 - θ)`, about 0.8 px facing the camera.
//! - **Quantisation**: the 11-bit raw disparity ([`crate::camera`]), about 1/8 px per step.
//!
//! Beyond about 80° from the normal the pattern is too stretched to match: no reading.

use std::f32::consts::FRAC_PI_2;

/// Surfaces seen more obliquely than this have no reading, radians (80°).
pub const GRAZING_LIMIT: f32 = 80.0 * std::f32::consts::PI / 180.0;

/// Axial standard deviation at depth `z` metres on a surface at `theta` radians from facing
/// the camera, metres (Nguyen et al. 2012, eq. 6).
pub fn axial_sigma_m(z: f32, theta: f32) -> f32 {
    axial_sigma_with_grazing_m(z, grazing_factor(theta))
}

/// The grazing factor `θ² / (π/2 - θ)²` of [`axial_sigma_m`] (0 facing the camera); a caller
/// with many pixels tabulates it.
pub fn grazing_factor(theta: f32) -> f32 {
    let theta = theta.clamp(0.0, GRAZING_LIMIT);
    let rest = FRAC_PI_2 - theta;
    theta * theta / (rest * rest)
}

/// [`axial_sigma_m`] from the grazing factor of the surface's angle.
#[inline]
pub fn axial_sigma_with_grazing_m(z: f32, grazing: f32) -> f32 {
    let d = z - 0.4;
    let sigma = 0.0012 + 0.0019 * d * d;
    // Nothing to add facing the camera (the common case; saves a square root per pixel).
    if grazing > 1e-6 {
        sigma + 0.0001 / z.max(1e-3).sqrt() * grazing
    } else {
        sigma
    }
}

/// Lateral standard deviation on a surface at `theta` radians from facing the camera, pixels
/// (Nguyen et al. 2012, eq. 5).
pub fn lateral_sigma_px(theta: f32) -> f32 {
    let theta = theta.clamp(0.0, GRAZING_LIMIT);
    0.8 + 0.035 * theta / (FRAC_PI_2 - theta)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The formula transcribed right: its values worked by hand (1.2 + 1.9 (z - 0.4)² mm:
    /// 1.88 mm at 1 m, 6.06 at 2 m, 14.04 at 3 m, 25.82 at 4 m facing the camera); the
    /// grazing term matters only past about 60°.
    #[test]
    fn axial_sigma_is_the_papers_formula() {
        for (z, mm) in [(1.0f32, 1.88f32), (2.0, 6.06), (3.0, 14.04), (4.0, 25.82)] {
            let got = axial_sigma_m(z, 0.0) * 1000.0;
            assert!((got - mm).abs() < 0.01, "{z} m: {got} mm");
        }
        let facing = axial_sigma_m(2.0, 0.0);
        assert!(axial_sigma_m(2.0, 30f32.to_radians()) < facing * 1.01);
        assert!(axial_sigma_m(2.0, 75f32.to_radians()) > facing * 1.1);
        assert!(lateral_sigma_px(0.0) == 0.8 && lateral_sigma_px(1.2) > 0.85);
    }
}
