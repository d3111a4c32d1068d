//! Simulating in a frame that follows the body, with a chosen fraction of its inertia.
//!
//! Seed 000 §4.3 and §5.3 move the simulated dress with a "cloth handle" attached to the root
//! bone: the physics world sees the colliders and fixed vertices in the handle's frame, and the
//! handle's motion reaches the cloth only as inertia. PhysX exposes how much of that inertia
//! the cloth feels (linear, angular and centrifugal inertia scales). This module does the same.
//!
//! When the caller gives the body frame's pose each step ([`crate::ClothSolver::set_body_frame`]),
//! every position the solver takes and returns — particles, attachment targets, colliders,
//! planes — is in that frame's local coordinates; gravity and wind are given in world
//! coordinates and rotated into the frame. The frame's linear velocity `v`, acceleration `a`,
//! angular velocity `ω` and angular acceleration `α` are estimated by finite differences of the
//! poses, and every free particle at local position `x` with local velocity `ẋ` gets the
//! fictitious accelerations of a non-inertial frame, each scaled by a fraction in `[0, 1]`:
//!
//! ```text
//! ẍ += − s_lin · a                 (linear: the frame's acceleration)
//!      − s_ang · (α × x + 2 ω × ẋ) (angular: Euler and Coriolis)
//!      − s_cen · ω × (ω × x)       (centrifugal)
//! ```
//!
//! All fractions 1 is the same motion as simulating in world space (up to the finite
//! differences); all 0 carries the cloth rigidly with the body (no inertia at all), which is
//! what the kiosk wants when tracking noise would otherwise shake the skirt. Aerodynamic drag
//! uses the air velocity relative to the frame scaled the same way (`s_lin` for `v`, `s_ang`
//! for `ω × x`).

use glam::{Quat, Vec3};

pub use fitroom_math::RigidTransform;

/// Fractions of the body frame's inertia that the cloth feels (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrameInertia {
    /// Scale of the frame's linear acceleration.
    pub linear: f32,
    /// Scale of the Euler and Coriolis terms.
    pub angular: f32,
    /// Scale of the centrifugal term.
    pub centrifugal: f32,
}

impl FrameInertia {
    /// The full inertia: the same as simulating in world space.
    pub const FULL: Self = Self {
        linear: 1.0,
        angular: 1.0,
        centrifugal: 1.0,
    };
    /// No inertia: the cloth is carried rigidly with the frame.
    pub const NONE: Self = Self {
        linear: 0.0,
        angular: 0.0,
        centrifugal: 0.0,
    };
}

impl Default for FrameInertia {
    fn default() -> Self {
        Self::FULL
    }
}

/// Per-step motion of the body frame, expressed in the frame's local coordinates at the end of
/// the step.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct FrameMotion {
    pub velocity: Vec3,
    pub acceleration: Vec3,
    pub angular_velocity: Vec3,
    pub angular_acceleration: Vec3,
    /// World → local rotation at the end of the step.
    pub to_local: Quat,
    pub pose: RigidTransform,
}

/// The frame's pose history.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct FrameState {
    pub enabled: bool,
    previous: Option<RigidTransform>,
    next: Option<RigidTransform>,
    velocity: Vec3,
    angular_velocity: Vec3,
}

impl FrameState {
    pub fn set_next(&mut self, pose: RigidTransform) {
        self.enabled = true;
        self.next = Some(pose);
    }

    pub fn reset(&mut self, pose: RigidTransform) {
        self.enabled = true;
        self.previous = Some(pose);
        self.next = Some(pose);
        self.velocity = Vec3::ZERO;
        self.angular_velocity = Vec3::ZERO;
    }

    /// Advances by `dt` and returns the frame's motion over the step (world velocities
    /// rotated into the end pose's local frame).
    pub fn advance(&mut self, dt: f32) -> FrameMotion {
        let next = self.next.or(self.previous).unwrap_or_default();
        let previous = self.previous.unwrap_or(next);
        let velocity = (next.translation - previous.translation) / dt;
        let mut delta = next.rotation * previous.rotation.inverse();
        if delta.w < 0.0 {
            delta = -delta;
        }
        let angular_velocity = delta.to_scaled_axis() / dt;
        let acceleration = (velocity - self.velocity) / dt;
        let angular_acceleration = (angular_velocity - self.angular_velocity) / dt;
        self.velocity = velocity;
        self.angular_velocity = angular_velocity;
        self.previous = Some(next);
        let to_local = next.rotation.inverse();
        FrameMotion {
            velocity: to_local * velocity,
            acceleration: to_local * acceleration,
            angular_velocity: to_local * angular_velocity,
            angular_acceleration: to_local * angular_acceleration,
            to_local,
            pose: next,
        }
    }
}
