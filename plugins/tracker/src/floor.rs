//! The floor plane in a depth frame: RANSAC (Fischler & Bolles 1981) over points of the
//! image's lower part, planes allowed within 35° of level (the sensor stands roughly upright),
//! refined by least squares on the inliers. Deterministic: the same frame gives the same plane.
//! The same for the wall behind the person (the image's upper part, planes facing the sensor).

use fitroom_depth::{DepthFrame, HEIGHT, WIDTH};
use glam::{DMat3, DVec3, Vec3};
use serde::Serialize;

/// A plane `normal · p + d = 0` in sensor space, `normal` a unit vector on the side the plane
/// faces (up for a floor, towards the sensor for a wall), so that [`Plane::height`] is the
/// height above it (the distance in front of it).
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

    /// The plane through three points, its normal turned to `axis`'s side; `None` when they
    /// are (nearly) collinear.
    fn through(a: Vec3, b: Vec3, c: Vec3, axis: Vec3) -> Option<Self> {
        let n = (b - a).cross(c - a);
        let length = n.length();
        if length < 1e-6 {
            return None;
        }
        let n = if n.dot(axis) < 0.0 { -n } else { n } / length;
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

/// Points of the upper 45 % of the image at least `beyond_m` away (z), every 4th pixel each
/// way, sensor space, into `points` (cleared first); returns how many pixels there had a
/// reading at all (what a wall's support is counted against).
pub fn wall_samples_into(frame: &DepthFrame, beyond_m: f32, points: &mut Vec<Vec3>) -> usize {
    let camera = frame.camera;
    points.clear();
    let mut readings = 0;
    for j in (0..HEIGHT * 45 / 100).step_by(4) {
        for i in (0..WIDTH).step_by(4) {
            let mm = frame.depth_mm[j * WIDTH + i];
            if mm > 0 {
                readings += 1;
                let z = f32::from(mm) / 1000.0;
                if z >= beyond_m {
                    points.push(camera.unproject(i as f32, j as f32, z));
                }
            }
        }
    }
    readings
}

/// The best-supported level plane among `points`, refined; `None` when no plane holds
/// [`FloorSettings::min_support`] of them.
pub fn fit_floor(points: &[Vec3], settings: &FloorSettings) -> Option<(Plane, usize)> {
    fit_plane(points, settings, Vec3::Y)
}

/// The best-supported plane among `points` whose normal lies within
/// [`FloorSettings::max_tilt_deg`] of `axis` (a unit axis of sensor space: +Y for a floor,
/// -Z for a wall facing the sensor), its normal on `axis`'s side, refined; `None` when no
/// such plane holds [`FloorSettings::min_support`] of them.
pub fn fit_plane(points: &[Vec3], settings: &FloorSettings, axis: Vec3) -> Option<(Plane, usize)> {
    if points.len() < 30 {
        return None;
    }
    let min_along = settings.max_tilt_deg.to_radians().cos();
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
        let Some(plane) = Plane::through(points[pick()], points[pick()], points[pick()], axis)
        else {
            continue;
        };
        if plane.normal.dot(axis) < min_along {
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
    let refined = least_squares(&inliers, axis).unwrap_or(plane);
    Some((refined, support(&refined)))
}

/// The plane `w = a u + b v + c` nearest `points` along `w`, the coordinate `axis` points
/// along (y for a floor, z for a wall; `u`, `v` the other two), as a [`Plane`] with its
/// normal on `axis`'s side.
fn least_squares(points: &[Vec3], axis: Vec3) -> Option<Plane> {
    let a = axis.abs();
    let w = if a.y >= a.x && a.y >= a.z {
        1
    } else if a.z >= a.x {
        2
    } else {
        0
    };
    let (u, v) = match w {
        1 => (0, 2),
        2 => (0, 1),
        _ => (1, 2),
    };
    let (mut m, mut r) = (DMat3::ZERO, DVec3::ZERO);
    for p in points {
        let row = DVec3::new(f64::from(p[u]), f64::from(p[v]), 1.0);
        m += DMat3::from_cols(row * row.x, row * row.y, row * row.z);
        r += row * f64::from(p[w]);
    }
    if m.determinant().abs() < 1e-9 {
        return None;
    }
    let [a, b, c] = (m.inverse() * r).to_array();
    let mut n = DVec3::ZERO;
    (n[u], n[w], n[v]) = (-a, 1.0, -b);
    let length = n.length();
    let (mut n, mut d) = (n / length, -c / length);
    if n.dot(axis.as_dvec3()) < 0.0 {
        (n, d) = (-n, -d);
    }
    Some(Plane {
        normal: n.as_vec3(),
        d: d as f32,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Quat;

    /// A wall 3.6 m away turned 20° about the vertical and leaning 5° back, with a person's
    /// worth of points in front of it: found within a millimetre, its normal facing the
    /// sensor; no wall among points that are all level.
    #[test]
    fn a_turned_wall_is_found_and_faces_the_sensor() {
        let normal = (Quat::from_rotation_y(20f32.to_radians())
            * Quat::from_rotation_x(5f32.to_radians())
            * -Vec3::Z)
            .normalize();
        let truth = Plane { normal, d: 3.6 };
        let (u, v) = (normal.cross(Vec3::Y).normalize(), Vec3::Y);
        let v = (v - normal * v.dot(normal)).normalize();
        let origin = -normal * truth.d;
        let mut points = Vec::new();
        for i in 0..40 {
            for k in 0..20 {
                let p = origin + u * (i as f32 * 0.1 - 2.0) + v * (k as f32 * 0.1 - 1.0);
                points.push(p);
                if i % 4 == 0 {
                    points.push(p + normal * (0.5 + 0.02 * (k % 9) as f32));
                }
            }
        }
        let (found, _) = fit_plane(&points, &FloorSettings::default(), -Vec3::Z).expect("a wall");
        assert!(found.normal.angle_between(normal) < 1e-3, "{found:?}");
        assert!((found.d - truth.d).abs() < 1e-3, "{found:?}");
        // In front of the wall is positive: the sensor (the origin) is 3.6 m in front.
        assert!((found.height(Vec3::ZERO) - 3.6).abs() < 1e-3);
        let level: Vec<Vec3> = (0..900)
            .map(|k| Vec3::new((k % 30) as f32 * 0.1, -0.8, 2.0 + (k / 30) as f32 * 0.1))
            .collect();
        assert!(fit_plane(&level, &FloorSettings::default(), -Vec3::Z).is_none());
    }

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
