//! One limited bone (seed 000 §4.4.2): its angles against its anatomical neutral (flexion,
//! abduction and twist, from the swing-twist split), the quadrant-ellipse swing region and
//! the twist interval, and the clamp into them.

use glam::{Quat, Vec3};

use crate::retarget::swing_twist;

use super::{JointKind, Side};

/// Semi-axes of the swing region are at least this (radians) so the region never degenerates.
const MIN_SEMI_AXIS: f32 = 1e-3;

/// A joint's angles relative to its anatomical neutral, radians (signs per
/// [`JointKind::directions`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JointAngles {
    pub flexion: f32,
    pub abduction: f32,
    pub twist: f32,
}

/// One limited bone.
#[derive(Clone, Debug, PartialEq)]
pub struct JointLimit {
    pub bone: usize,
    pub name: String,
    pub kind: JointKind,
    pub side: Side,
    /// Anatomical neutral local rotation (relative to the parent bone).
    pub neutral: Quat,
    /// Local (neutral frame) swing axis of positive flexion; perpendicular to +Y.
    pub flexion_axis: Vec3,
    /// Local swing axis of positive abduction; `±(Y x flexion_axis)`.
    pub abduction_axis: Vec3,
    /// +1 if positive twist is a right-handed turn about the bone's +Y, else -1.
    pub twist_sign: f32,
    /// Ranges, radians.
    pub flexion: (f32, f32),
    pub abduction: (f32, f32),
    pub twist: (f32, f32),
}

/// Which part of a joint's limit is exceeded.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum LimitPart {
    /// The swing (flexion/abduction) lies outside its region.
    Swing,
    /// The twist lies outside its interval.
    Twist,
}

/// A limit exceeded by more than the tolerance.
#[derive(Clone, Debug, PartialEq)]
pub struct Violation {
    pub bone: usize,
    pub kind: JointKind,
    pub side: Side,
    pub part: LimitPart,
    /// How far outside, degrees: the distance of the swing point from the region (in the
    /// flexion/abduction chart), or of the twist from its interval.
    pub excess_deg: f32,
    /// The joint's angles, degrees.
    pub angles_deg: JointAngles,
}

/// `D = swing * twist`, `D.w >= 0`; returns (swing rotation vector, twist angle about +Y).
pub(super) fn decompose(d: Quat) -> (Vec3, f32) {
    let d = if d.w < 0.0 { -d } else { d };
    let (swing, twist) = swing_twist(d, Vec3::Y);
    let (swing, twist) = if swing.w < 0.0 {
        (-swing, -twist)
    } else {
        (swing, twist)
    };
    let twist_angle = {
        let a = 2.0 * twist.y.atan2(twist.w);
        // Wrap into (-pi, pi].
        if a > std::f32::consts::PI {
            a - std::f32::consts::TAU
        } else if a <= -std::f32::consts::PI {
            a + std::f32::consts::TAU
        } else {
            a
        }
    };
    let v = Vec3::new(swing.x, 0.0, swing.z);
    let s = v.length();
    let swing_vec = if s < 1e-9 {
        Vec3::ZERO
    } else {
        v / s * 2.0 * s.atan2(swing.w.max(0.0))
    };
    (swing_vec, twist_angle)
}

/// Nearest point of the quadrant ellipse `{(x/ex)^2 + (y/ey)^2 <= 1}` (semi-axes chosen by
/// the signs of the point) to `(x, y)`; the point itself if inside.
pub(super) fn project_quadrant_ellipse(
    x: f32,
    y: f32,
    xr: (f32, f32),
    yr: (f32, f32),
) -> (f32, f32) {
    let ex = if x >= 0.0 { xr.1 } else { -xr.0 }.max(MIN_SEMI_AXIS) as f64;
    let ey = if y >= 0.0 { yr.1 } else { -yr.0 }.max(MIN_SEMI_AXIS) as f64;
    let (px, py) = ((x as f64).abs(), (y as f64).abs());
    // Points on the boundary up to rounding count as inside, so a clamped rotation is a fixed
    // point of the clamp.
    if (px / ex).powi(2) + (py / ey).powi(2) <= 1.0 + 1e-5 {
        return (x, y);
    }
    // Nearest point: (e_i^2 p_i / (t + e_i^2)) with t > 0 the root of
    // F(t) = sum (e_i p_i / (t + e_i^2))^2 - 1, decreasing on t >= 0 (Eberly, "Distance from a
    // point to an ellipse"). Bisection in f64.
    let f = |t: f64| (ex * px / (t + ex * ex)).powi(2) + (ey * py / (t + ey * ey)).powi(2) - 1.0;
    let mut lo = 0.0f64;
    let mut hi = (std::f64::consts::SQRT_2 * (ex * px).max(ey * py)).max(1e-12);
    while f(hi) > 0.0 {
        hi *= 2.0;
    }
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if f(mid) > 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let t = hi;
    let qx = ex * ex * px / (t + ex * ex);
    let qy = ey * ey * py / (t + ey * ey);
    (
        (qx as f32).copysign(if x == 0.0 { 1.0 } else { x }),
        (qy as f32).copysign(if y == 0.0 { 1.0 } else { y }),
    )
}

impl JointLimit {
    /// The joint's angles for a local rotation.
    pub fn angles(&self, local: Quat) -> JointAngles {
        let (s, t) = decompose(self.neutral.inverse() * local);
        JointAngles {
            flexion: s.dot(self.flexion_axis),
            abduction: s.dot(self.abduction_axis),
            twist: t * self.twist_sign,
        }
    }

    /// The local rotation with these angles.
    pub fn rotation(&self, angles: JointAngles) -> Quat {
        let s = self.flexion_axis * angles.flexion + self.abduction_axis * angles.abduction;
        let swing = Quat::from_scaled_axis(s);
        let twist = Quat::from_rotation_y(angles.twist * self.twist_sign);
        (self.neutral * swing * twist).normalize()
    }

    /// (swing excess, twist excess), radians, and the clamped angles.
    pub(super) fn excess(&self, angles: JointAngles) -> (f32, f32, JointAngles) {
        let (f, a) = project_quadrant_ellipse(
            angles.flexion,
            angles.abduction,
            self.flexion,
            self.abduction,
        );
        let t = angles.twist.clamp(self.twist.0, self.twist.1);
        let swing_excess = ((f - angles.flexion).powi(2) + (a - angles.abduction).powi(2)).sqrt();
        (
            swing_excess,
            (t - angles.twist).abs(),
            JointAngles {
                flexion: f,
                abduction: a,
                twist: t,
            },
        )
    }

    /// The nearest allowed local rotation (the input itself if allowed).
    pub fn clamp(&self, local: Quat) -> Quat {
        if !local.is_finite() {
            return self.neutral;
        }
        let angles = self.angles(local);
        let (swing_excess, twist_excess, clamped) = self.excess(angles);
        if swing_excess == 0.0 && twist_excess == 0.0 {
            local
        } else {
            self.rotation(clamped)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ellipse_projection_is_nearest_and_idempotent() {
        let xr = (-0.2, 1.0);
        let yr = (-0.5, 0.3);
        for &(x, y) in &[
            (2.0, 1.0),
            (-1.0, -1.0),
            (0.0, 3.0),
            (3.0, 0.0),
            (0.5, -2.0),
        ] {
            let (px, py) = project_quadrant_ellipse(x, y, xr, yr);
            // On the boundary.
            let ex = if px >= 0.0 { xr.1 } else { -xr.0 };
            let ey = if py >= 0.0 { yr.1 } else { -yr.0 };
            let r = (px / ex).powi(2) + (py / ey).powi(2);
            assert!((r - 1.0).abs() < 1e-4, "{x},{y} -> {px},{py}: {r}");
            assert_eq!(
                project_quadrant_ellipse(px * 0.999, py * 0.999, xr, yr),
                (px * 0.999, py * 0.999)
            );
            // No boundary sample is nearer.
            let d = ((px - x).powi(2) + (py - y).powi(2)).sqrt();
            for k in 0..2000 {
                let t = k as f32 / 2000.0 * std::f32::consts::TAU;
                let (c, s) = (t.cos(), t.sin());
                let bx = c * if c >= 0.0 { xr.1 } else { -xr.0 };
                let by = s * if s >= 0.0 { yr.1 } else { -yr.0 };
                let db = ((bx - x).powi(2) + (by - y).powi(2)).sqrt();
                assert!(db >= d - 1e-4, "{x},{y}: {d} > {db}");
            }
        }
    }

    #[test]
    fn decompose_recomposes() {
        let q = Quat::from_euler(glam::EulerRot::YXZ, 0.7, 0.5, -0.9);
        let (s, t) = decompose(q);
        let r = Quat::from_scaled_axis(s) * Quat::from_rotation_y(t);
        assert!(r.abs_diff_eq(q, 1e-5) || r.abs_diff_eq(-q, 1e-5));
    }
}
