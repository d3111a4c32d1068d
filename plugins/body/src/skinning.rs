//! CPU linear blend skinning (Magnenat-Thalmann et al. 1988; the "skeleton subspace
//! deformation" of Lewis et al. 2000) and forward kinematics over a rest pose.
//!
//! The product skins on the GPU (Bevy); this CPU version is the reference used by tests and by
//! measurements on posed bodies (seed 000 §4.4.3: the forearm twist cross-section).
//!
//! A bone's *global transform* maps bone-local coordinates to model space. In the rest pose it
//! is `(rest.rotations[i], rest.heads[i])`. A vertex is skinned as
//! `v' = sum_i w_i * G_i * R_i^-1 * v`, with `R_i` the rest and `G_i` the posed global transform.

use glam::{Affine3A, Mat3A, Quat, Vec3, Vec3A};

use crate::model::{BodyModel, Bone, RestPose};

pub use fitroom_math::RigidTransform;

impl RestPose {
    /// Rest global transform of every bone: its frame at its head.
    pub fn global_transforms(&self) -> Vec<RigidTransform> {
        self.rotations
            .iter()
            .zip(&self.heads)
            .map(|(&r, &h)| RigidTransform::new(r, h))
            .collect()
    }
}

/// Forward kinematics: global transforms of every bone given rotations relative to each bone's
/// rest frame (what a Blender pose bone's rotation holds) and a translation of the root bones
/// (model space, added to their rest heads). Bones must be parents-first; a bone whose parent
/// is missing or does not come before it is treated as a root. `local_rotations` shorter than
/// the skeleton leaves the remaining bones at rest.
///
/// `G_i = G_parent * (R_parent^-1 * R_i) * local_i`, and `G_root = T(root_offset) * R_root *
/// local_root`.
pub fn forward_kinematics(
    bones: &[Bone],
    rest: &RestPose,
    local_rotations: &[Quat],
    root_offset: Vec3,
) -> Vec<RigidTransform> {
    let rest_globals = rest.global_transforms();
    let mut out: Vec<RigidTransform> = Vec::with_capacity(rest_globals.len());
    for (i, rest_i) in rest_globals.iter().enumerate() {
        let local = RigidTransform::new(
            local_rotations.get(i).copied().unwrap_or(Quat::IDENTITY),
            Vec3::ZERO,
        );
        let parent = bones.get(i).and_then(|b| b.parent).filter(|&p| p < i);
        let global = match parent {
            Some(p) => {
                let offset = rest_globals[p].inverse() * *rest_i;
                out[p] * offset * local
            }
            None => {
                let mut g = *rest_i * local;
                g.translation += root_offset;
                g
            }
        };
        out.push(global);
    }
    out
}

/// Per-bone skinning matrices `G_i * R_i^-1` (model space to posed model space).
pub fn skinning_matrices(rest: &RestPose, posed: &[RigidTransform]) -> Vec<Affine3A> {
    rest.global_transforms()
        .iter()
        .zip(posed)
        .map(|(r, g)| (*g * r.inverse()).to_affine())
        .collect()
}

/// Linear blend skinning of `positions` with per-vertex joints and weights (parallel slices;
/// vertices past the shorter of them are returned unchanged). A vertex's weights are used as
/// stored (not renormalised). Joints naming no bone count as the identity.
pub fn skin_positions(
    positions: &[Vec3],
    joints: &[[u16; 4]],
    weights: &[[f32; 4]],
    rest: &RestPose,
    posed: &[RigidTransform],
) -> Vec<Vec3> {
    skin_with_matrices(positions, joints, weights, &skinning_matrices(rest, posed))
}

/// [`skin_positions`] with the skinning matrices already made (rest model space to the
/// space the pose is in, e.g. world space from the avatar's joint entities).
pub fn skin_with_matrices(
    positions: &[Vec3],
    joints: &[[u16; 4]],
    weights: &[[f32; 4]],
    matrices: &[Affine3A],
) -> Vec<Vec3> {
    positions
        .iter()
        .enumerate()
        .map(|(v, &p)| {
            let (Some(j), Some(w)) = (joints.get(v), weights.get(v)) else {
                return p;
            };
            blend(matrices, j, w).transform_point3(p)
        })
        .collect()
}

/// The weighted sum of the bones' skinning matrices for one vertex (linear blend).
fn blend(matrices: &[Affine3A], joints: &[u16; 4], weights: &[f32; 4]) -> Affine3A {
    let mut m3 = Mat3A::ZERO;
    let mut t = Vec3A::ZERO;
    let mut total = 0.0;
    for (&j, &w) in joints.iter().zip(weights) {
        if w == 0.0 {
            continue;
        }
        let m = matrices
            .get(j as usize)
            .copied()
            .unwrap_or(Affine3A::IDENTITY);
        m3 += m.matrix3 * w;
        t += m.translation * w;
        total += w;
    }
    if total == 0.0 {
        return Affine3A::IDENTITY;
    }
    Affine3A {
        matrix3: m3,
        translation: t,
    }
}

impl BodyModel {
    /// Skins `positions` (the whole mesh or its body part, possibly morphed, whose rest pose
    /// is `rest`) with the model's own skin weights (body, then helpers) to the posed bone
    /// global transforms.
    pub fn skin_positions(
        &self,
        positions: &[Vec3],
        rest: &RestPose,
        posed: &[RigidTransform],
    ) -> Vec<Vec3> {
        let body = (self.body_vertex_count as usize).min(positions.len());
        let mut out = skin_positions(
            &positions[..body],
            &self.skin_joints,
            &self.skin_weights,
            rest,
            posed,
        );
        out.extend(skin_positions(
            &positions[body..],
            &self.helper_skin_joints,
            &self.helper_skin_weights,
            rest,
            posed,
        ));
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::JointPlacement;

    fn chain() -> (Vec<Bone>, RestPose) {
        let bone = |name: &str, parent| Bone {
            name: name.into(),
            parent,
            head_placement: JointPlacement::Vertex(0),
            tail_placement: JointPlacement::Vertex(0),
            roll: 0.0,
        };
        let bones = vec![bone("a", None), bone("b", Some(0))];
        let rest = RestPose {
            heads: vec![Vec3::ZERO, Vec3::Y],
            tails: vec![Vec3::Y, Vec3::new(0.0, 2.0, 0.0)],
            rotations: vec![Quat::from_rotation_z(0.3), Quat::from_rotation_x(-0.4)],
        };
        (bones, rest)
    }

    #[test]
    fn identity_pose_reproduces_rest_globals() {
        let (bones, rest) = chain();
        let g = forward_kinematics(&bones, &rest, &[], Vec3::ZERO);
        for (a, b) in g.iter().zip(rest.global_transforms()) {
            assert!(a.rotation.abs_diff_eq(b.rotation, 1e-6));
            assert!(a.translation.abs_diff_eq(b.translation, 1e-6));
        }
    }

    #[test]
    fn child_rotates_about_its_own_head() {
        let (bones, rest) = chain();
        let g = forward_kinematics(
            &bones,
            &rest,
            &[Quat::IDENTITY, Quat::from_rotation_y(1.0)],
            Vec3::ZERO,
        );
        assert!(g[1].translation.abs_diff_eq(rest.heads[1], 1e-6));
        // Rotation about the bone's local Y is about its rest Y axis in model space.
        let axis = rest.rotations[1] * Vec3::Y;
        let expected = Quat::from_axis_angle(axis, 1.0) * rest.rotations[1];
        assert!(g[1].rotation.abs_diff_eq(expected, 1e-5));
    }

    #[test]
    fn half_blend_shrinks_by_cos_half_angle() {
        let (bones, rest) = chain();
        let axis = rest.rotations[1] * Vec3::Y;
        let angle = 1.2f32;
        let posed = forward_kinematics(
            &bones,
            &rest,
            &[Quat::IDENTITY, Quat::from_rotation_y(angle)],
            Vec3::ZERO,
        );
        // A point one unit off the child's axis, weighted half to each bone.
        let off = axis.any_orthonormal_vector();
        let p = rest.heads[1] + off;
        let out = skin_positions(
            &[p],
            &[[0, 1, 0, 0]],
            &[[0.5, 0.5, 0.0, 0.0]],
            &rest,
            &posed,
        );
        let r = (out[0] - rest.heads[1]).length();
        assert!((r - (angle / 2.0).cos()).abs() < 1e-5, "{r}");
    }
}
