//! The Kinect v1 depth camera: a 640x480 IR camera 7.5 cm from the IR projector whose speckle
//! pattern it sees. The device reports, per pixel, an 11-bit raw value proportional to the
//! pattern's disparity (about 1/8 pixel per raw step), 2047 where it has no reading.
//!
//! Raw to metres: the fit of Nicolas Burrus (2011, "Kinect calibration",
//! <https://nicolas.burrus.name/index.php/Research/KinectCalibration>) for a Kinect v1,
//! `z = 1 / (3.3309495161 - 0.0030711016 raw)` m, used here both ways. One raw step is then
//! `dz = 0.0030711016 z^2` m: 3.1 mm at 1 m, 12.3 mm at 2 m, 27.6 mm at 3 m. (libfreenect's
//! own registration uses the device's factory constants instead; without a device the
//! published fit is the one we can cite.) With the intrinsics below, one raw step is
//! `f b 0.00307 = 0.137` px of disparity, the 1/8 pixel of the hardware's sub-pixel matching.
//!
//! Pixels and sensor space: sensor space is the Kinect skeleton space of
//! [`fitroom_sensor`](../fitroom_sensor/index.html) (right-handed, +Y up, +Z from the sensor
//! towards the person, +X to the sensor's left). The image is not mirrored: column `u` grows
//! to the sensor's right (-X) and row `v` downwards (-Y):
//! `u = cx - fx x / z`, `v = cy - fy y / z`.
//!
//! The projector sits 7.5 cm to the sensor's right of the IR camera (the left lens seen from
//! the front): the band it cannot light beside a foreground edge, and so has no reading, lies
//! on the image's left of the edge.

use glam::{Vec2, Vec3};

/// Image width, pixels.
pub const WIDTH: usize = 640;
/// Image height, pixels.
pub const HEIGHT: usize = 480;
/// Pixels in a frame.
pub const PIXELS: usize = WIDTH * HEIGHT;
/// The raw value of a pixel without a reading (libfreenect's `FREENECT_DEPTH_RAW_NO_VALUE`).
pub const RAW_NO_VALUE: u16 = 2047;

/// `1/z = RAW_OFFSET - RAW_SCALE raw` (z in metres), Burrus's fit.
const RAW_OFFSET: f64 = 3.330_949_516_1;
const RAW_SCALE: f64 = 0.003_071_101_6;

/// The depth camera's model: pinhole intrinsics (Burrus's calibration of a Kinect v1's IR
/// camera), the projector baseline, and the range the device reports.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DepthCamera {
    /// Focal lengths, pixels.
    pub fx: f32,
    pub fy: f32,
    /// Principal point, pixels.
    pub cx: f32,
    pub cy: f32,
    /// IR projector to IR camera, metres (the projector on the sensor's right, -X).
    pub baseline_m: f32,
    /// Nearest and farthest depth with a reading, metres.
    pub min_m: f32,
    pub max_m: f32,
}

impl Default for DepthCamera {
    /// A Kinect v1 (Burrus's depth intrinsics; 0.8-4 m, the range of the default mode).
    fn default() -> Self {
        Self {
            fx: 594.21,
            fy: 591.04,
            cx: 339.31,
            cy: 242.74,
            baseline_m: 0.075,
            min_m: 0.8,
            max_m: 4.0,
        }
    }
}

impl DepthCamera {
    /// Where sensor-space `p` is seen, in continuous pixel coordinates (pixel `(i, j)`'s
    /// centre at `(i, j)`); `None` behind the camera.
    pub fn project(&self, p: Vec3) -> Option<Vec2> {
        (p.z > 1e-6)
            .then(|| Vec2::new(self.cx - self.fx * p.x / p.z, self.cy - self.fy * p.y / p.z))
    }

    /// The sensor-space point at depth `z` metres seen at pixel `(u, v)`.
    pub fn unproject(&self, u: f32, v: f32, z: f32) -> Vec3 {
        Vec3::new((self.cx - u) * z / self.fx, (self.cy - v) * z / self.fy, z)
    }

    /// Whether `z` metres is within the range the device reports.
    pub fn in_range(&self, z: f32) -> bool {
        (self.min_m..=self.max_m).contains(&z)
    }
}

/// Metres of a raw value; `None` for [`RAW_NO_VALUE`] and for values the fit puts behind the
/// camera or at infinity (raw ≥ 1085).
pub fn raw_to_metres(raw: u16) -> Option<f32> {
    if raw >= RAW_NO_VALUE {
        return None;
    }
    let inverse = RAW_OFFSET - RAW_SCALE * f64::from(raw);
    (inverse > 0.0).then(|| (1.0 / inverse) as f32)
}

/// The raw value nearest to depth `z` metres (the device's quantisation); `None` when `z` is
/// not a positive finite depth the 11-bit scale can hold.
pub fn metres_to_raw(z: f32) -> Option<u16> {
    if !(z.is_finite() && z > 0.0) {
        return None;
    }
    // Rounded by a cast (`f64::round` is a library call on baseline x86-64; this runs per
    // pixel); negative values fail the range test first.
    let raw = (RAW_OFFSET - 1.0 / f64::from(z)) * (1.0 / RAW_SCALE) + 0.5;
    (0.0..f64::from(RAW_NO_VALUE))
        .contains(&raw)
        .then_some(raw as u16)
}

/// The continuous raw value of inverse depth `inverse_z` (1/m): raw values are linear in
/// inverse depth, so a per-pixel caller needs no division.
#[inline]
pub fn inverse_metres_to_raw_f32(inverse_z: f32) -> f32 {
    const C0: f32 = (RAW_OFFSET / RAW_SCALE) as f32;
    const C1: f32 = (1.0 / RAW_SCALE) as f32;
    C0 - C1 * inverse_z
}

/// Metres of a continuous raw value; `None` where the fit puts it at or behind infinity.
pub fn raw_f32_to_metres(raw: f32) -> Option<f32> {
    let inverse = RAW_OFFSET as f32 - RAW_SCALE as f32 * raw;
    (inverse > 0.0).then(|| 1.0 / inverse)
}

/// Millimetres of a raw value, 0 for no reading (libfreenect's `FREENECT_DEPTH_MM` encoding).
pub fn raw_to_mm(raw: u16) -> u16 {
    raw_to_metres(raw).map_or(0, |z| (z * 1000.0).round().min(f32::from(u16::MAX)) as u16)
}

/// [`raw_to_mm`] of every raw value (0 to 2047), computed once.
pub fn raw_mm_table() -> &'static [u16] {
    static TABLE: std::sync::OnceLock<Vec<u16>> = std::sync::OnceLock::new();
    TABLE.get_or_init(|| (0..=RAW_NO_VALUE).map(raw_to_mm).collect())
}

/// The depth difference of one raw step at `z` metres (the quantisation step), metres.
pub fn raw_step_m(z: f32) -> f32 {
    (RAW_SCALE * f64::from(z) * f64::from(z)) as f32
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The figures for one raw step (3 mm at 1 m, 12 mm at 2 m, 28 mm at 3 m), from
    /// neighbouring raw values rather than the derivative.
    #[test]
    fn one_raw_step_is_about_0_003_z_squared() {
        for (z, step_mm) in [(1.0f32, 3.1f32), (2.0, 12.3), (3.0, 27.6)] {
            let raw = metres_to_raw(z).expect("in range");
            let a = raw_to_metres(raw).expect("valid");
            let b = raw_to_metres(raw + 1).expect("valid");
            let measured = (b - a) * 1000.0;
            assert!(
                (measured - step_mm).abs() < 0.05 * step_mm,
                "{z} m: {measured} mm"
            );
            assert!((raw_step_m(z) * 1000.0 - step_mm).abs() < 0.05 * step_mm);
        }
    }

    #[test]
    fn raw_round_trips_and_no_value_is_none() {
        for raw in 0..1080u16 {
            let z = raw_to_metres(raw).expect("valid");
            assert_eq!(metres_to_raw(z), Some(raw), "raw {raw} -> {z} m");
        }
        assert_eq!(raw_to_metres(RAW_NO_VALUE), None);
        assert_eq!(raw_to_mm(RAW_NO_VALUE), 0);
        assert_eq!(metres_to_raw(f32::NAN), None);
        assert_eq!(metres_to_raw(-1.0), None);
        // The range the device reports is well inside the scale.
        assert!(metres_to_raw(0.8).is_some() && metres_to_raw(4.0).is_some());
    }

    /// One raw step is about 1/8 pixel of disparity (`d = f b / z`).
    #[test]
    fn a_raw_step_is_an_eighth_of_a_pixel_of_disparity() {
        let camera = DepthCamera::default();
        for z in [1.0f32, 2.0, 3.0] {
            let raw = metres_to_raw(z).expect("in range");
            let (a, b) = (
                raw_to_metres(raw).expect("valid"),
                raw_to_metres(raw + 1).expect("valid"),
            );
            let disparity = camera.fx * camera.baseline_m * (1.0 / a - 1.0 / b);
            assert!((disparity - 0.125).abs() < 0.02, "{z} m: {disparity} px");
        }
    }

    #[test]
    fn projection_inverts_and_follows_sensor_space() {
        let camera = DepthCamera::default();
        let p = Vec3::new(0.3, -0.2, 2.0);
        let uv = camera.project(p).expect("in front");
        assert!(camera.unproject(uv.x, uv.y, p.z).distance(p) < 1e-5);
        // +X is the sensor's left: the image's left (smaller u); +Y up: smaller v.
        assert!(uv.x < camera.cx && uv.y > camera.cy);
        assert_eq!(camera.project(Vec3::new(0.0, 0.0, -1.0)), None);
    }
}
