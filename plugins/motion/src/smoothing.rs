//! Asymptotic rotation smoothing (seed 000 §4.4.2, second stage) and the fractional quaternion
//! smoothing of §4.5 (equations 4.5–4.6).
//!
//! # Asymptotic smoothing
//!
//! Each joint's output rotation moves a fraction `α` of the way towards the newest input every
//! frame, `q_out <- slerp(q_out, q_in, α)`: an exponential (first-order, "asymptotic") filter
//! on the rotation manifold, which turns a sudden gap in the estimated angles into a smooth
//! approach instead of a tremor-like jump. To be independent of the frame rate, `α` comes from a
//! time constant: `α = 1 - exp(-dt / τ)`, so two frames of `dt` move the output exactly as far as
//! one frame of `2 dt` (for a constant input), and a dropped sensor frame is made up for by the
//! longer `dt` of the next one. The step response reaches 63% after `τ`, 95% after `3 τ`.
//!
//! # Large gaps
//!
//! * **Time gaps**: after more than [`SmoothingOptions::reset_after_s`] without a frame (tracking
//!   lost, application paused) the old output is stale; the filter restarts from the input
//!   instead of sliding from an orientation the user left long ago.
//! * **Angle gaps**: the slerp always takes the shorter arc (the input's sign is flipped when
//!   `q_out . q_in < 0`), so a quaternion sign flip in the data is no gap at all. Optionally,
//!   [`SmoothingOptions::max_angular_speed`] caps how fast the output may turn (rad/s), which
//!   spreads a large single-frame jump (a flipped limb of a mis-tracked, occluded joint) over
//!   several frames even with a short `τ`; it is off by default because real kicks and arm
//!   swings reach 10–20 rad/s.
//! * Non-finite input keeps the previous output.
//!
//! # Fractional quaternion smoothing (eq. 4.5–4.6)
//!
//! [`fractional_rotation`]: `Q_d = Q_new * Q_old^-1`, written as axis and angle; the output is
//! `Quaternion(axis, angle / k) * Q_old`, i.e. the joint turns a fraction `1/k` of the way. The
//! foot-skate filter uses it (with a frame-rate independent fraction) to blend a leg whose
//! constraint just switched.

use glam::Quat;

use crate::retarget::{AvatarPose, AvatarSkeleton};

/// `α = 1 - exp(-dt / τ)`: the share of the remaining difference a first-order filter with time
/// constant `tau_s` covers in `dt_s`. `dt <= 0` (or NaN) gives 0; `τ <= 0` gives 1 (no smoothing).
pub fn smoothing_alpha(dt_s: f32, tau_s: f32) -> f32 {
    if dt_s.is_nan() || dt_s <= 0.0 {
        return 0.0;
    }
    if tau_s.is_nan() || tau_s <= 0.0 || dt_s.is_infinite() {
        return 1.0;
    }
    // An infinite time constant gives exp(-0) = 1: no motion.
    1.0 - (-dt_s / tau_s).exp()
}

/// Equations 4.5–4.6 of seed 000: turns `from` by the fraction `fraction` of the rotation that
/// takes it to `to` (shorter arc, about the axis of `Q_d = to * from^-1`). `fraction = 0` gives
/// `from`, `1` gives `to` (up to sign); values outside `[0, 1]` are clamped.
pub fn fractional_rotation(from: Quat, to: Quat, fraction: f32) -> Quat {
    let f = if fraction.is_nan() {
        0.0
    } else {
        fraction.clamp(0.0, 1.0)
    };
    let mut delta = (to * from.inverse()).normalize();
    if delta.w < 0.0 {
        delta = -delta;
    }
    let (axis, angle) = delta.to_axis_angle();
    if !angle.is_finite() || angle.abs() < 1e-7 || !axis.is_finite() {
        return if f >= 1.0 { to } else { from };
    }
    (Quat::from_axis_angle(axis, angle * f) * from).normalize()
}

/// One asymptotic smoothing step: `from` turned towards `to` by `α(dt, τ)`, with the turn
/// capped at `max_angular_speed * dt` radians.
pub fn smooth_toward(from: Quat, to: Quat, dt_s: f32, tau_s: f32, max_angular_speed: f32) -> Quat {
    let alpha = smoothing_alpha(dt_s, tau_s);
    let mut delta = (to * from.inverse()).normalize();
    if delta.w < 0.0 {
        delta = -delta;
    }
    let angle = 2.0 * delta.w.clamp(-1.0, 1.0).acos();
    let mut fraction = alpha;
    if max_angular_speed.is_finite() && max_angular_speed >= 0.0 && angle > 1e-7 {
        let cap = max_angular_speed * dt_s.max(0.0);
        fraction = fraction.min(cap / angle);
    }
    fractional_rotation(from, to, fraction)
}

/// Options of [`RotationSmoother`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SmoothingOptions {
    /// Time constant, seconds. The default 0.05 s gives `α = 0.49` at 30 Hz: it halves
    /// frame-to-frame jitter's step while lagging a steady motion by about `τ`.
    pub tau_s: f32,
    /// After a gap longer than this (seconds) the filter restarts from the input.
    pub reset_after_s: f32,
    /// Maximum turn rate of the output, rad/s (`f32::INFINITY`: no cap).
    pub max_angular_speed: f32,
}

impl Default for SmoothingOptions {
    fn default() -> Self {
        Self {
            tau_s: 0.05,
            reset_after_s: 0.5,
            max_angular_speed: f32::INFINITY,
        }
    }
}

/// Asymptotic smoothing of a set of rotations (for example every bone's local rotation).
#[derive(Clone, Debug, PartialEq)]
pub struct RotationSmoother {
    pub options: SmoothingOptions,
    state: Vec<Option<Quat>>,
}

impl RotationSmoother {
    pub fn new(count: usize, options: SmoothingOptions) -> Self {
        Self {
            options,
            state: vec![None; count],
        }
    }

    /// Forgets the filter state: the next input passes through unchanged.
    pub fn reset(&mut self) {
        self.state.iter_mut().for_each(|s| *s = None);
    }

    /// The current output of rotation `index`, if it has one.
    pub fn output(&self, index: usize) -> Option<Quat> {
        self.state.get(index).copied().flatten()
    }

    /// Feeds rotation `index` with `input` after `dt_s` seconds and returns the new output.
    pub fn smooth(&mut self, index: usize, input: Quat, dt_s: f32) -> Quat {
        if index >= self.state.len() {
            self.state.resize(index + 1, None);
        }
        let o = self.options;
        let usable = input.is_finite() && input.length_squared() > 1e-12;
        let out = match (self.state[index], usable) {
            (None, true) => input.normalize(),
            (None, false) => return input,
            (Some(prev), false) => prev,
            (Some(_), true) if dt_s.is_nan() || dt_s > o.reset_after_s => input.normalize(),
            (Some(prev), true) => {
                smooth_toward(prev, input.normalize(), dt_s, o.tau_s, o.max_angular_speed)
            }
        };
        self.state[index] = Some(out);
        out
    }

    /// Smooths every rotation of the slice in place (index = position).
    pub fn smooth_all(&mut self, rotations: &mut [Quat], dt_s: f32) {
        for (i, q) in rotations.iter_mut().enumerate() {
            *q = self.smooth(i, *q, dt_s);
        }
    }

    /// Smooths the pose's local rotations (each joint relative to its parent, as the seed
    /// smooths joint angles) and recomputes its global rotations and heads; the roots keep
    /// their heads (the root translation is not smoothed here: positions have their own filter,
    /// seed §4.4.1).
    pub fn smooth_pose(&mut self, skeleton: &AvatarSkeleton, pose: &mut AvatarPose, dt_s: f32) {
        self.smooth_all(&mut pose.local_rotations, dt_s);
        crate::ik::forward_kinematics(skeleton, pose);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn angle(a: Quat, b: Quat) -> f32 {
        a.angle_between(b)
    }

    #[test]
    fn alpha_is_frame_rate_independent() {
        let (from, to) = (Quat::IDENTITY, Quat::from_rotation_z(1.0));
        let tau = 0.1;
        // Two steps of dt equal one step of 2 dt (constant input).
        let two = smooth_toward(
            smooth_toward(from, to, 1.0 / 60.0, tau, f32::INFINITY),
            to,
            1.0 / 60.0,
            tau,
            f32::INFINITY,
        );
        let one = smooth_toward(from, to, 1.0 / 30.0, tau, f32::INFINITY);
        assert!(angle(one, two) < 1e-5, "{}", angle(one, two));
        // And the remaining angle decays as exp(-t / tau).
        let remaining = angle(one, to);
        assert!((remaining - (-1.0f32 / 30.0 / tau).exp()).abs() < 1e-4);
        assert_eq!(smoothing_alpha(0.0, tau), 0.0);
        assert_eq!(smoothing_alpha(0.1, 0.0), 1.0);
    }

    #[test]
    fn fractional_rotation_follows_eq_4_6() {
        let from = Quat::from_rotation_x(0.3);
        let to = Quat::from_axis_angle(Vec3::new(1.0, 2.0, -1.0).normalize(), 1.2) * from;
        let half = fractional_rotation(from, to, 0.25);
        let expected = Quat::from_axis_angle(Vec3::new(1.0, 2.0, -1.0).normalize(), 0.3) * from;
        assert!(angle(half, expected) < 1e-5);
        // Shorter arc even if `to` has the other sign.
        let flipped = fractional_rotation(from, -to, 0.25);
        assert!(angle(flipped, expected) < 1e-5);
        assert!(angle(fractional_rotation(from, to, 1.0), to) < 1e-5);
    }

    #[test]
    fn smoother_handles_gaps() {
        let mut s = RotationSmoother::new(1, SmoothingOptions::default());
        let a = Quat::IDENTITY;
        let b = Quat::from_rotation_y(2.0);
        assert_eq!(s.smooth(0, a, 1.0 / 30.0), a);
        let step = s.smooth(0, b, 1.0 / 30.0);
        assert!(angle(step, a) > 0.5 && angle(step, b) > 0.5);
        // NaN keeps the output.
        let kept = s.smooth(0, Quat::from_xyzw(f32::NAN, 0.0, 0.0, 1.0), 1.0 / 30.0);
        assert_eq!(kept, step);
        // A long pause restarts from the input.
        assert!(angle(s.smooth(0, b, 2.0), b) < 1e-6);
        // The speed cap spreads a jump.
        let mut capped = RotationSmoother::new(
            1,
            SmoothingOptions {
                tau_s: 0.0,
                max_angular_speed: 3.0,
                ..Default::default()
            },
        );
        capped.smooth(0, a, 0.1);
        let out = capped.smooth(0, b, 0.1);
        assert!((angle(out, a) - 0.3).abs() < 1e-4);
    }
}
