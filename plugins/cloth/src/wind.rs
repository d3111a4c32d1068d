//! Wind with seeded gusts, and per-triangle aerodynamic drag and lift.
//!
//! **Wind.** The air velocity is a mean wind plus gusts: each component of the gust is a
//! smooth value noise in time (a seeded table of 256 random values, smoothstep-interpolated,
//! one value per `gust_period_s`). The gusts travel with the mean wind (Taylor's frozen
//! turbulence): the noise is read at `t − (x·ŵ)/|w|`, so a gust sweeps across the garment
//! instead of hitting every point at once. The same seed gives the same wind.
//!
//! **Aerodynamics.** Each triangle of area `A` and unit normal `n` moving at `u` relative to
//! the air (the mean of its corners' velocities minus the wind at its centroid) feels, with
//! `n` oriented so that `cos = û·n ≥ 0` and air density `ρ`:
//!
//! - drag `F_D = −½ ρ |u|² A C_D cos · û` (along the relative flow),
//! - lift `F_L = −½ ρ |u|² A C_L cos · sin · l̂`, `l̂` the unit part of `n` perpendicular to
//!   `û`, `sin = √(1 − cos²)` (zero edge-on and face-on, largest at 45°),
//!
//! the flat-plate model used for cloth by Keckeisen et al. 2004 and in PhysX's cloth
//! (`PxClothFabric` drag/lift coefficients). A third of the force goes to each corner. The
//! forces are computed once per step from the velocities at the step start and held over the
//! substeps.

use glam::Vec3;
#[cfg(test)]
use glam::Vec3A;

use crate::simd::{Lanes, V3};

/// Number of noise samples per component (the gust pattern repeats after this many periods).
const TABLE: usize = 256;

/// A wind field: mean velocity plus seeded travelling gusts.
#[derive(Debug, Clone, PartialEq)]
pub struct Wind {
    mean: Vec3,
    gust_amplitude: f32,
    gust_period: f32,
    seed: u64,
    table: Vec<[f32; 3]>,
}

impl Wind {
    /// A wind blowing at `mean` m/s with gusts of about `gust_amplitude` m/s per component that
    /// change every `gust_period_s` seconds, drawn from `seed`.
    pub fn new(mean: Vec3, gust_amplitude: f32, gust_period_s: f32, seed: u64) -> Self {
        let mut state = seed;
        let mut next = || {
            // splitmix64
            state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = state;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            z ^= z >> 31;
            ((z >> 40) as f32 / (1u64 << 24) as f32) * 2.0 - 1.0
        };
        let table = (0..TABLE).map(|_| [next(), next(), next()]).collect();
        Self {
            mean: if mean.is_finite() { mean } else { Vec3::ZERO },
            gust_amplitude: if gust_amplitude.is_finite() {
                gust_amplitude.max(0.0)
            } else {
                0.0
            },
            gust_period: if gust_period_s.is_finite() && gust_period_s > 1e-3 {
                gust_period_s
            } else {
                1.0
            },
            seed,
            table,
        }
    }

    /// A steady wind with no gusts.
    pub fn steady(mean: Vec3) -> Self {
        Self::new(mean, 0.0, 1.0, 0)
    }

    /// The mean wind, m/s.
    pub fn mean(&self) -> Vec3 {
        self.mean
    }

    /// The seed the gusts were drawn from.
    pub fn seed(&self) -> u64 {
        self.seed
    }

    /// Air velocity at world point `x` (metres) and time `t` (seconds), m/s.
    pub fn velocity(&self, x: Vec3, t: f32) -> Vec3 {
        if self.gust_amplitude == 0.0 {
            return self.mean;
        }
        let speed2 = self.mean.length_squared();
        let tau = if speed2 > 1e-4 {
            t - x.dot(self.mean) / speed2
        } else {
            t
        };
        let s = tau / self.gust_period;
        let cell = s.floor();
        let f = s - cell;
        let f = f * f * (3.0 - 2.0 * f);
        let i = (cell as i64).rem_euclid(TABLE as i64) as usize;
        let (a, b) = (self.table[i], self.table[(i + 1) % TABLE]);
        let gust = Vec3::new(
            a[0] + (b[0] - a[0]) * f,
            a[1] + (b[1] - a[1]) * f,
            a[2] + (b[2] - a[2]) * f,
        );
        self.mean + self.gust_amplitude * gust
    }
}

/// Aerodynamic force on one triangle (see the module documentation): the reference the
/// solver's eight-lane [`triangle_force_lanes`] is tested against.
#[cfg(test)]
pub(crate) fn triangle_force(
    corners: [Vec3A; 3],
    relative_velocity: Vec3A,
    air_density: f32,
    drag: f32,
    lift: f32,
) -> Vec3A {
    let area_normal = (corners[1] - corners[0]).cross(corners[2] - corners[0]);
    let doubled_area = area_normal.length();
    let speed = relative_velocity.length();
    if doubled_area < 1e-12 || speed < 1e-6 || !speed.is_finite() {
        return Vec3A::ZERO;
    }
    let mut n = area_normal / doubled_area;
    let u = relative_velocity / speed;
    let mut cos = u.dot(n);
    if cos < 0.0 {
        n = -n;
        cos = -cos;
    }
    let pressure = 0.5 * air_density * speed * speed * (0.5 * doubled_area) * cos;
    let mut force = -pressure * drag * u;
    if lift > 0.0 {
        let across = n - cos * u;
        let len = across.length();
        if len > 1e-6 {
            let sin = (1.0 - cos * cos).max(0.0).sqrt();
            force -= pressure * lift * sin * (across / len);
        }
    }
    force
}

/// [`triangle_force`] for eight triangles at once (one per lane).
#[inline(always)]
pub(crate) fn triangle_force_lanes<L: Lanes>(
    corners: [V3<L>; 3],
    relative_velocity: V3<L>,
    air_density: f32,
    drag: f32,
    lift: f32,
) -> V3<L> {
    let area_normal = (corners[1] - corners[0]).cross(corners[2] - corners[0]);
    let doubled_area = area_normal.dot(area_normal).sqrt();
    let speed = relative_velocity.dot(relative_velocity).sqrt();
    let zero = L::splat(0.0);
    let valid = doubled_area
        .not_lt(L::splat(1e-12))
        .and(speed.not_lt(L::splat(1e-6)))
        .and(L::splat(f32::INFINITY).gt(speed));
    let one = L::splat(1.0);
    let n = area_normal.scale(one.div(doubled_area));
    let u = relative_velocity.scale(one.div(speed));
    let cos = u.dot(n);
    // Orient n so that cos ≥ 0.
    let sign = L::select(zero.gt(cos), L::splat(-1.0), one);
    let n = n.scale(sign);
    let cos = cos * sign;
    let pressure =
        L::splat(0.5 * air_density) * speed * speed * (L::splat(0.5) * doubled_area) * cos;
    let mut force = u.scale(-(pressure * L::splat(drag)));
    if lift > 0.0 {
        let across = n - u.scale(cos);
        let len = across.dot(across).sqrt();
        let sin2 = one - cos * cos;
        let sin = L::select(sin2.gt(zero), sin2, zero).sqrt();
        let amount = (pressure * L::splat(lift) * sin)
            .div(len)
            .and(len.gt(L::splat(1e-6)));
        force = force - across.scale(amount);
    }
    force.and(valid)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::simd::Baseline8;

    #[test]
    fn gusts_are_seeded_and_bounded() {
        let a = Wind::new(Vec3::new(3.0, 0.0, 0.0), 1.5, 0.5, 7);
        let b = Wind::new(Vec3::new(3.0, 0.0, 0.0), 1.5, 0.5, 7);
        let c = Wind::new(Vec3::new(3.0, 0.0, 0.0), 1.5, 0.5, 8);
        let mut differs = false;
        for k in 0..200 {
            let t = k as f32 * 0.037;
            let x = Vec3::new(0.3, 1.0, -0.2);
            assert_eq!(a.velocity(x, t), b.velocity(x, t));
            differs |= a.velocity(x, t) != c.velocity(x, t);
            assert!((a.velocity(x, t) - a.mean()).abs().max_element() <= 1.5 + 1e-5);
        }
        assert!(differs);
    }

    #[test]
    fn eight_lanes_agree_with_one() {
        let corners = [
            [Vec3A::ZERO, Vec3A::X, Vec3A::Y],
            [
                Vec3A::ZERO,
                Vec3A::new(0.1, 0.0, 0.02),
                Vec3A::new(0.0, 0.1, 0.05),
            ],
            [Vec3A::ZERO, Vec3A::X, 2.0 * Vec3A::X],
            [
                Vec3A::Z,
                Vec3A::new(0.3, 0.2, 0.1),
                Vec3A::new(-0.2, 0.4, 0.0),
            ],
        ];
        let velocity = [
            Vec3A::new(0.0, 0.0, 2.0),
            Vec3A::new(1.0, -0.5, 0.3),
            Vec3A::new(0.0, 0.0, 1.0),
            Vec3A::new(0.0, 1e-7, 0.0),
        ];
        // Eight lanes: the four triangles twice.
        let lane = |v: [Vec3A; 4]| -> V3<Baseline8> {
            let at = |c: fn(Vec3A) -> f32| Baseline8::load(&std::array::from_fn(|l| c(v[l % 4])));
            V3 {
                x: at(|v| v.x),
                y: at(|v| v.y),
                z: at(|v| v.z),
            }
        };
        let corner = |k: usize| lane(std::array::from_fn(|t| corners[t][k]));
        let f = triangle_force_lanes(
            [corner(0), corner(1), corner(2)],
            lane(velocity),
            1.2,
            1.0,
            0.4,
        );
        let (fx, fy, fz) = (f.x.to_array(), f.y.to_array(), f.z.to_array());
        for l in 0..8 {
            let t = l % 4;
            let f = Vec3A::new(fx[l], fy[l], fz[l]);
            let one = triangle_force(corners[t], velocity[t], 1.2, 1.0, 0.4);
            assert!(
                (f - one).length() <= 1e-6 * (1.0 + one.length()),
                "{t}: {f} vs {one}"
            );
        }
    }

    #[test]
    fn a_plate_face_on_feels_full_drag_and_no_lift() {
        let corners = [Vec3A::ZERO, Vec3A::X, Vec3A::Y];
        let f = triangle_force(corners, Vec3A::new(0.0, 0.0, 2.0), 1.2, 1.0, 0.5);
        // ½ · 1.2 · 4 · 0.5 m² · 1 = 1.2 N against the motion.
        assert!((f - Vec3A::new(0.0, 0.0, -1.2)).length() < 1e-5, "{f}");
        let edge_on = triangle_force(corners, Vec3A::new(2.0, 0.0, 0.0), 1.2, 1.0, 0.5);
        assert!(edge_on.length() < 1e-6);
    }
}
