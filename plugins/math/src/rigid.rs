//! The rigid transform (rotation then translation, no scale) used for bone frames, the body
//! frame the cloth simulates in, and poses in general.

use glam::{Affine3A, Quat, Vec3};
use serde::{Deserialize, Serialize};

/// A rotation followed by a translation (no scale): `p -> rotation * p + translation`, i.e.
/// local -> parent (or world) coordinates.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct RigidTransform {
    /// Orientation of the frame.
    pub rotation: Quat,
    /// Origin of the frame in the parent's coordinates, metres.
    pub translation: Vec3,
}

impl Default for RigidTransform {
    fn default() -> Self {
        Self::IDENTITY
    }
}

impl RigidTransform {
    /// The identity (the parent's own frame).
    pub const IDENTITY: Self = Self {
        rotation: Quat::IDENTITY,
        translation: Vec3::ZERO,
    };

    pub fn new(rotation: Quat, translation: Vec3) -> Self {
        Self {
            rotation,
            translation,
        }
    }

    /// Local -> parent.
    pub fn transform_point(&self, p: Vec3) -> Vec3 {
        self.rotation * p + self.translation
    }

    /// Parent -> local.
    pub fn inverse_transform_point(&self, p: Vec3) -> Vec3 {
        self.rotation.inverse() * (p - self.translation)
    }

    /// A direction, local -> parent (rotation only).
    pub fn transform_vector(&self, v: Vec3) -> Vec3 {
        self.rotation * v
    }

    /// `self * other`: apply `other` first. The rotation is renormalised, so that long
    /// chains (a skeleton's forward kinematics) do not drift from unit length.
    pub fn mul_transform(&self, other: &Self) -> Self {
        Self {
            rotation: (self.rotation * other.rotation).normalize(),
            translation: self.transform_point(other.translation),
        }
    }

    pub fn inverse(&self) -> Self {
        let r = self.rotation.inverse();
        Self {
            rotation: r,
            translation: -(r * self.translation),
        }
    }

    pub fn to_affine(&self) -> Affine3A {
        Affine3A::from_rotation_translation(self.rotation, self.translation)
    }

    /// Every component finite and the rotation far from zero length (a quaternion of length
    /// below 0.5 is not a rotation that renormalising can be trusted to recover).
    pub fn is_finite(&self) -> bool {
        self.rotation.is_finite() && self.translation.is_finite() && self.rotation.length() > 0.5
    }
}

impl core::ops::Mul for RigidTransform {
    type Output = RigidTransform;
    fn mul(self, rhs: Self) -> Self {
        self.mul_transform(&rhs)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Against glam's general affine transforms, an independent implementation.
    #[test]
    fn composition_and_inverse_agree_with_affine_matrices() {
        let a = RigidTransform::new(
            Quat::from_euler(glam::EulerRot::YXZ, 0.3, -1.1, 0.7),
            Vec3::new(0.2, 1.5, -0.4),
        );
        let b = RigidTransform::new(Quat::from_rotation_z(2.0), Vec3::new(-1.0, 0.1, 0.3));
        let p = Vec3::new(0.5, -0.25, 2.0);
        let ab = (a * b).to_affine();
        let expected = a.to_affine() * b.to_affine();
        assert!(
            ab.transform_point3(p)
                .distance(expected.transform_point3(p))
                < 1e-5
        );
        assert!(a.inverse_transform_point(a.transform_point(p)).distance(p) < 1e-5);
        assert!(
            a.inverse()
                .transform_point(p)
                .distance(a.to_affine().inverse().transform_point3(p))
                < 1e-5
        );
        assert!(a.is_finite());
        assert!(!RigidTransform::new(Quat::from_xyzw(0.0, 0.0, 0.0, 0.1), Vec3::ZERO).is_finite());
        assert!(!RigidTransform::new(Quat::IDENTITY, Vec3::NAN).is_finite());
    }
}
