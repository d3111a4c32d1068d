//! The floor plane in a depth frame: RANSAC (Fischler & Bolles 1981) over points of the
//! image's lower part, planes allowed within 35° of level (the sensor stands roughly upright),
//! refined by least squares on the inliers. Deterministic: the same frame gives the same plane.

use fitroom_depth::{DepthFrame, HEIGHT, WIDTH};
use glam::{DMat3, DVec3, Vec3};
use serde::Serialize;

/// A plane `normal · p + d = 0` in sensor space, `normal` a unit vector pointing up (+Y side),
/// so that [`Plane::height`] is the height above it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Plane {
    pub normal: Vec3,
    pub d: f32,
}

impl Plane {
    /// Signed height of `p` above the plane, metres.
    pub fn height(&self, p: Vec3) -> f32 {
        self.normal.dot(p) + self.d
    }

    /// The plane through three points, its normal turned up; `None` when they are (nearly)
    /// collinear.
    fn through(a: Vec3, b: Vec3, c: Vec3) -> Option<Self> {
        let n = (b - a).cross(c - a);
        let length = n.length();
        if length < 1e-6 {
            return None;
        }
        let n = if n.y < 0.0 { -n } else { n } / length;
        Some(Self {
            normal: n,
            d: -n.dot(a),
        })
    }
}

/// How the floor is found.
#[derive(Clone, Copy, Debug)]
pub struct FloorSettings {
    /// Points within this of a candidate plane support it, metres.
    pub inlier_m: f32,
    /// Largest tilt of the floor from the sensor's horizontal, degrees.
    pub max_tilt_deg: f32,
    /// RANSAC candidates tried.
    pub candidates: usize,
    /// Least share of the sampled points a floor must hold.
    pub min_support: f32,
}

impl Default for FloorSettings {
    fn default() -> Self {
        Self {
            inlier_m: 0.03,
            max_tilt_deg: 35.0,
            candidates: 120,
            min_support: 0.12,
        }
    }
}

/// Points of the lower 45 % of the image, every 4th pixel each way, sensor space.
pub fn floor_samples(frame: &DepthFrame) -> Vec<Vec3> {
    let mut points = Vec::new();
    floor_samples_into(frame, &mut points);
    points
}

/// [`floor_samples`] into `points` (cleared first), for a caller that keeps the buffer.
pub fn floor_samples_into(frame: &DepthFrame, points: &mut Vec<Vec3>) {
    let camera = frame.camera;
    points.clear();
    for j in ((HEIGHT * 55 / 100)..HEIGHT).step_by(4) {
        for i in (0..WIDTH).step_by(4) {
            let mm = frame.depth_mm[j * WIDTH + i];
            if mm > 0 {
                points.push(camera.unproject(i as f32, j as f32, f32::from(mm) / 1000.0));
            }
        }
    }
}

/// The best-supported level plane among `points`, refined; `None` when no plane holds
/// [`FloorSettings::min_support`] of them.
pub fn fit_floor(points: &[Vec3], settings: &FloorSettings) -> Option<(Plane, usize)> {
    if points.len() < 30 {
        return None;
    }
    let min_up = settings.max_tilt_deg.to_radians().cos();
    let mut state = 0x9e37_79b9_7f4a_7c15_u64 ^ points.len() as u64;
    let mut pick = || {
        // xorshift64*: a deterministic stream of indices.
        state ^= state >> 12;
        state ^= state << 25;
        state ^= state >> 27;
        (state.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 33) as usize % points.len()
    };
    let support = |plane: &Plane| {
        points
            .iter()
            .filter(|&&p| plane.height(p).abs() < settings.inlier_m)
            .count()
    };
    let mut best: Option<(Plane, usize)> = None;
    for _ in 0..settings.candidates {
        let Some(plane) = Plane::through(points[pick()], points[pick()], points[pick()]) else {
            continue;
        };
        if plane.normal.y < min_up {
            continue;
        }
        let count = support(&plane);
        if best.is_none_or(|(_, c)| count > c) {
            best = Some((plane, count));
        }
    }
    let (plane, count) = best?;
    if (count as f32) < settings.min_support * points.len() as f32 {
        return None;
    }
    let inliers: Vec<Vec3> = points
        .iter()
        .copied()
        .filter(|&p| plane.height(p).abs() < settings.inlier_m)
        .collect();
    let refined = least_squares(&inliers).unwrap_or(plane);
    Some((refined, support(&refined)))
}

/// The plane `y = a x + b z + c` nearest `points` in y (the floor is near level), as a
/// [`Plane`].
fn least_squares(points: &[Vec3]) -> Option<Plane> {
    let (mut m, mut r) = (DMat3::ZERO, DVec3::ZERO);
    for p in points {
        let row = DVec3::new(f64::from(p.x), f64::from(p.z), 1.0);
        m += DMat3::from_cols(row * row.x, row * row.y, row * row.z);
        r += row * f64::from(p.y);
    }
    if m.determinant().abs() < 1e-9 {
        return None;
    }
    let [a, b, c] = (m.inverse() * r).to_array();
    let n = DVec3::new(-a, 1.0, -b);
    let length = n.length();
    Some(Plane {
        normal: (n / length).as_vec3(),
        d: (-c / length) as f32,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A tilted floor with outliers above it: found within a millimetre and a tenth of a
    /// degree.
    #[test]
    fn a_tilted_floor_is_found_among_outliers() {
        let tilt = 8f32.to_radians();
        let normal = Vec3::new(0.0, tilt.cos(), tilt.sin());
        let truth = Plane { normal, d: 0.8 };
        // Two axes in the plane, and its point nearest the sensor.
        let (u, v) = (Vec3::X, normal.cross(Vec3::X));
        let origin = -normal * truth.d;
        let mut points = Vec::new();
        for i in 0..40 {
            for k in 0..40 {
                let p = origin + u * (i as f32 * 0.1 - 2.0) + v * (k as f32 * 0.1 - 4.0);
                points.push(p);
                if (i + k) % 3 == 0 {
                    points.push(p + normal * (0.2 + 0.01 * (i % 17) as f32));
                }
            }
        }
        let (plane, support) = fit_floor(&points, &FloorSettings::default()).expect("a floor");
        assert!(support >= 1600, "{support}");
        assert!(plane.normal.angle_between(normal).to_degrees() < 0.1);
        assert!((plane.d - truth.d).abs() < 0.001, "{}", plane.d);
    }
}
