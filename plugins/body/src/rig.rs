//! The skeleton derived from a (possibly morphed) mesh: bone ends from the rig's placement
//! strategies, bone frames exactly as Blender builds them from head, tail and roll; morph
//! target application and vertex normals.
//!
//! MakeHuman rigs (MPFB2 `rig.*.json`) are authored in Blender, so a bone's frame is defined by
//! Blender's `vec_roll_to_mat3_normalized` (`blenkernel/intern/armature.cc`): the shortest-arc
//! rotation taking +Y onto the head->tail direction, then a rotation by `roll` about that
//! direction. That construction is not invariant under a change of axes (it has a singularity
//! at -Y), so it is evaluated in MakeHuman's Blender space (Z up, the body faces -Y) and the
//! result converted to model space by the fixed rotation between the two spaces
//! ([`MODEL_TO_BLENDER`]).

use glam::{Mat3, Quat, Vec3};

use crate::model::{BodyModel, RestPose};

/// Rotation taking model-space vectors (Y up, facing +Z) to MakeHuman's Blender space (Z up,
/// facing -Y): `(x, y, z) -> (x, -z, y)`, a quarter turn about +X.
pub const MODEL_TO_BLENDER: Quat = Quat::from_xyzw(
    core::f32::consts::FRAC_1_SQRT_2,
    0.0,
    0.0,
    core::f32::consts::FRAC_1_SQRT_2,
);

/// Converts a position from model space to MakeHuman's Blender space (both in metres).
pub fn model_to_blender(v: Vec3) -> Vec3 {
    Vec3::new(v.x, -v.z, v.y)
}

/// Converts a position from MakeHuman's Blender space (Z up, as in the rig's
/// `default_position`) to model space.
pub fn blender_to_model(v: Vec3) -> Vec3 {
    Vec3::new(v.x, v.z, -v.y)
}

/// Blender's `vec_roll_to_mat3_normalized`: the bone matrix (columns = bone X, Y, Z axes) of
/// a bone pointing along the unit vector `nor` with the given `roll`, in the space `nor` is
/// given in (Blender space for MakeHuman rigs).
///
/// Ported from the formula (thresholds included) so that bones pointing almost along -Y get
/// the same frame Blender gives them.
pub fn vec_roll_to_mat3_normalized(nor: Vec3, roll: f32) -> Mat3 {
    const SAFE_THRESHOLD: f32 = 6.1e-3;
    const CRITICAL_THRESHOLD: f32 = 2.5e-4;
    const THRESHOLD_SQUARED: f32 = CRITICAL_THRESHOLD * CRITICAL_THRESHOLD;
    let (x, y, z) = (nor.x, nor.y, nor.z);
    let mut theta = 1.0 + y;
    let theta_alt = x * x + z * z;
    let b = if theta > SAFE_THRESHOLD || theta_alt > THRESHOLD_SQUARED {
        if theta <= SAFE_THRESHOLD {
            theta = theta_alt * 0.5 + theta_alt * theta_alt * 0.125;
        }
        Mat3::from_cols(
            Vec3::new(1.0 - x * x / theta, -x, -x * z / theta),
            Vec3::new(x, y, z),
            Vec3::new(-x * z / theta, -z, 1.0 - z * z / theta),
        )
    } else {
        // Pointing along -Y: Blender uses the half turn about Z.
        Mat3::from_diagonal(Vec3::new(-1.0, -1.0, 1.0))
    };
    Mat3::from_axis_angle(nor, roll) * b
}

/// The model-space frame (+Y from head to tail, roll as Blender applies it) of a bone with the
/// given model-space head and tail and Blender roll. A zero-length bone gets the frame of a
/// bone pointing up (+Z in Blender space).
pub fn bone_frame(head: Vec3, tail: Vec3, roll: f32) -> Quat {
    let dir = model_to_blender(tail - head);
    let nor = dir.try_normalize().unwrap_or(Vec3::Z);
    let blender = Quat::from_mat3(&vec_roll_to_mat3_normalized(nor, roll));
    (MODEL_TO_BLENDER.inverse() * blender).normalize()
}

impl BodyModel {
    /// The rest pose of the skeleton on a mesh with these vertex positions (the model's own,
    /// or morphed ones from [`BodyModel::apply_targets`]).
    ///
    /// # Panics
    /// If `positions` has fewer vertices than the model (placements use helper vertices).
    pub fn rest_pose(&self, positions: &[Vec3]) -> RestPose {
        assert!(
            positions.len() >= self.positions.len(),
            "rest_pose needs all {} vertices (helpers included), got {}",
            self.positions.len(),
            positions.len()
        );
        let heads: Vec<Vec3> = self
            .bones
            .iter()
            .map(|b| b.head_placement.resolve(positions))
            .collect();
        let tails: Vec<Vec3> = self
            .bones
            .iter()
            .map(|b| b.tail_placement.resolve(positions))
            .collect();
        let rotations = self
            .bones
            .iter()
            .zip(heads.iter().zip(&tails))
            .map(|(b, (&h, &t))| bone_frame(h, t, b.roll))
            .collect();
        RestPose {
            heads,
            tails,
            rotations,
        }
    }

    /// Vertex positions (whole mesh) with morph targets added: `weights` holds
    /// `(target index, weight)` pairs; unknown indices are ignored.
    pub fn apply_targets(&self, weights: &[(usize, f32)]) -> Vec<Vec3> {
        let mut out = self.positions.clone();
        self.add_targets(&mut out, weights);
        out
    }

    /// Adds morph targets to `positions` (the whole mesh, possibly morphed already):
    /// `(target index, weight)` pairs; unknown indices are ignored. Targets are linear, so
    /// a change of weights can be applied to a morphed mesh as the difference.
    pub fn add_targets(&self, positions: &mut [Vec3], weights: &[(usize, f32)]) {
        for &(index, weight) in weights {
            let Some(target) = self.targets.get(index) else {
                continue;
            };
            if weight == 0.0 {
                continue;
            }
            let s = target.scale_m * weight;
            for (&i, d) in target.indices.iter().zip(&target.deltas) {
                if let Some(p) = positions.get_mut(i as usize) {
                    *p += Vec3::new(d[0] as f32, d[1] as f32, d[2] as f32) * s;
                }
            }
        }
    }

    /// Area-weighted normals of the body vertices (`body_vertex_count` of them) for the given
    /// positions of the whole mesh.
    pub fn body_normals(&self, positions: &[Vec3]) -> Vec<Vec3> {
        let n = (self.body_vertex_count as usize).min(positions.len());
        compute_normals(&positions[..n], &self.triangles)
    }
}

/// Area-weighted vertex normals: each triangle adds its (unnormalised) cross product, whose
/// length is twice its area, to its three corners. One normal per position; vertices in no
/// triangle (or only degenerate ones) get zero. Triangles indexing past `positions` are skipped.
pub fn compute_normals(positions: &[Vec3], triangles: &[[u32; 3]]) -> Vec<Vec3> {
    let mut normals = Vec::new();
    compute_normals_into(positions, triangles, &mut normals);
    normals
}

/// [`compute_normals`] into `normals` (cleared first), to reuse its storage frame after frame.
pub fn compute_normals_into(positions: &[Vec3], triangles: &[[u32; 3]], normals: &mut Vec<Vec3>) {
    normals.clear();
    normals.resize(positions.len(), Vec3::ZERO);
    for t in triangles {
        let [a, b, c] = t.map(|i| i as usize);
        let (Some(&pa), Some(&pb), Some(&pc)) =
            (positions.get(a), positions.get(b), positions.get(c))
        else {
            continue;
        };
        let n = (pb - pa).cross(pc - pa);
        normals[a] += n;
        normals[b] += n;
        normals[c] += n;
    }
    for n in normals.iter_mut() {
        *n = n.normalize_or_zero();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn approx_mat(a: Mat3, b: Mat3, eps: f32) -> bool {
        a.abs_diff_eq(b, eps)
    }

    #[test]
    fn model_blender_conversion_is_the_quarter_turn() {
        let v = Vec3::new(0.1, 0.2, 0.3);
        assert!((MODEL_TO_BLENDER * v).abs_diff_eq(model_to_blender(v), 1e-6));
        assert!(blender_to_model(model_to_blender(v)).abs_diff_eq(v, 1e-7));
        // Model up (+Y) is Blender up (+Z); model front (+Z) is Blender front (-Y).
        assert_eq!(model_to_blender(Vec3::Y), Vec3::Z);
        assert_eq!(model_to_blender(Vec3::Z), -Vec3::Y);
    }

    #[test]
    fn blender_frame_is_shortest_arc_then_roll() {
        let dirs = [
            Vec3::new(0.3, 0.5, -0.8),
            Vec3::new(-0.9, 0.1, 0.2),
            Vec3::new(0.0, 0.0, 1.0),
            Vec3::new(0.2, -0.7, 0.4),
            Vec3::X,
        ];
        for d in dirs {
            let nor = d.normalize();
            for roll in [0.0f32, 0.7, -2.3] {
                let m = vec_roll_to_mat3_normalized(nor, roll);
                let expected = Mat3::from_quat(
                    Quat::from_axis_angle(nor, roll) * Quat::from_rotation_arc(Vec3::Y, nor),
                );
                assert!(
                    approx_mat(m, expected, 1e-5),
                    "{nor} {roll}: {m} vs {expected}"
                );
                assert!((m.determinant() - 1.0).abs() < 1e-5);
                assert!(m.y_axis.abs_diff_eq(nor, 1e-6));
            }
        }
    }

    #[test]
    fn blender_frame_for_up_bone_has_z_to_the_front() {
        // A bone pointing up (Blender +Z) with roll 0: X stays +X, Z points to Blender -Y.
        let m = vec_roll_to_mat3_normalized(Vec3::Z, 0.0);
        assert!(m.x_axis.abs_diff_eq(Vec3::X, 1e-6));
        assert!(m.z_axis.abs_diff_eq(-Vec3::Y, 1e-6));
        // In model space that bone's Z axis faces the front (+Z).
        let q = bone_frame(Vec3::ZERO, Vec3::Y, 0.0);
        assert!((q * Vec3::Y).abs_diff_eq(Vec3::Y, 1e-6));
        assert!((q * Vec3::Z).abs_diff_eq(Vec3::Z, 1e-6));
        assert!((q * Vec3::X).abs_diff_eq(Vec3::X, 1e-6));
    }

    #[test]
    fn blender_frame_along_negative_y_is_the_half_turn_about_z() {
        let m = vec_roll_to_mat3_normalized(-Vec3::Y, 0.0);
        assert!(approx_mat(
            m,
            Mat3::from_diagonal(Vec3::new(-1.0, -1.0, 1.0)),
            1e-6
        ));
        // Close to -Y the series expansion keeps the frame continuous and orthonormal.
        let nor = Vec3::new(1e-3, -1.0, 5e-4).normalize();
        let m = vec_roll_to_mat3_normalized(nor, 0.0);
        assert!(m.y_axis.abs_diff_eq(nor, 1e-5));
        assert!((m.determinant() - 1.0).abs() < 1e-3);
        assert!((m.x_axis.dot(m.y_axis)).abs() < 1e-3);
    }

    #[test]
    fn bone_frame_points_y_along_the_bone_in_model_space() {
        let head = Vec3::new(0.31, 0.35, 0.01);
        let tail = Vec3::new(0.43, 0.25, 0.18);
        for roll in [0.0f32, 2.3, -1.0] {
            let q = bone_frame(head, tail, roll);
            assert!((q * Vec3::Y).abs_diff_eq((tail - head).normalize(), 1e-6));
            // Same frame as Blender's, rotated into model space.
            let m_blender =
                vec_roll_to_mat3_normalized(model_to_blender(tail - head).normalize(), roll);
            for (axis, col) in [
                (Vec3::X, m_blender.x_axis),
                (Vec3::Y, m_blender.y_axis),
                (Vec3::Z, m_blender.z_axis),
            ] {
                assert!(model_to_blender(q * axis).abs_diff_eq(col, 1e-5));
            }
        }
    }

    #[test]
    fn normals_of_a_ccw_triangle_point_out_of_it() {
        let p = [Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::new(5.0, 5.0, 5.0)];
        let n = compute_normals(&p, &[[0, 1, 2]]);
        assert_eq!(n[0], Vec3::Z);
        assert_eq!(n[3], Vec3::ZERO);
    }
}
