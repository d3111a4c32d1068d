//! Kinematics helpers: forward kinematics of an [`AvatarPose`] and the analytic two-bone IK
//! that the foot-skate filter (seed 000 §4.5, Algorithm 4, step 2) uses for hip–knee–ankle.
//!
//! The seed solves the leg with the IKAN library (Tolani, Goswami & Badler, "Real-time inverse
//! kinematics techniques for anthropomorphic limbs", Graphical Models 62(5), 2000). For a
//! two-bone chain the solution is closed form: the law of cosines gives the knee angle, the
//! swivel of the knee about the hip–ankle line is a free parameter which IKAN also exposes,
//! and here it is fixed by a pole hint (the direction the knee points, normally the input
//! pose's own knee) so the knee stays in its plane.
//!
//! Conventions (as in [`crate::retarget`]): a bone frame's +Y runs from the bone's head to its
//! tail, and a child's head lies on its parent's +Y axis at the parent's length (true for the
//! MakeHuman `game_engine` thigh -> calf -> foot chain: `local_translation = (0, len, 0)`).

use glam::{Mat3, Quat, Vec3};

use crate::retarget::{AvatarPose, AvatarSkeleton};

/// Recomputes `pose.rotations` and `pose.heads` from `pose.local_rotations`.
///
/// Root bones (no parent) keep their head position; their global rotation is their local one.
/// Every other bone gets `rotation = parent_rotation * local` and
/// `head = parent_head + parent_rotation * local_translation`, the same rule
/// [`crate::Retargeter`] uses, so bone lengths are always the skeleton's own. Bones beyond the
/// pose's length (a pose of another skeleton) are left alone.
pub fn forward_kinematics(skeleton: &AvatarSkeleton, pose: &mut AvatarPose) {
    let n = skeleton
        .bones
        .len()
        .min(pose.heads.len())
        .min(pose.rotations.len())
        .min(pose.local_rotations.len());
    for i in 0..n {
        let bone = &skeleton.bones[i];
        match bone.parent {
            Some(p) if p < i => {
                let parent_rotation = pose.rotations[p];
                pose.rotations[i] = (parent_rotation * pose.local_rotations[i]).normalize();
                pose.heads[i] = pose.heads[p] + parent_rotation * bone.local_translation;
            }
            _ => {
                pose.rotations[i] = pose.local_rotations[i].normalize();
            }
        }
    }
}

/// Recomputes `pose.local_rotations` from the global `pose.rotations`.
pub fn local_from_global(skeleton: &AvatarSkeleton, pose: &mut AvatarPose) {
    let n = skeleton
        .bones
        .len()
        .min(pose.rotations.len())
        .min(pose.local_rotations.len());
    for i in 0..n {
        pose.local_rotations[i] = match skeleton.bones[i].parent {
            Some(p) if p < i => (pose.rotations[p].inverse() * pose.rotations[i]).normalize(),
            _ => pose.rotations[i],
        };
    }
}

/// The result of [`solve_two_bone`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TwoBoneSolution {
    /// New global frame of the upper bone (thigh).
    pub upper: Quat,
    /// New global frame of the lower bone (calf).
    pub lower: Quat,
    /// Position of the middle joint (knee).
    pub mid: Vec3,
    /// Position of the end (ankle) the new frames give.
    pub end: Vec3,
    /// Whether `end` is the target (within 1e-4 of the chain length); otherwise the chain is
    /// stretched straight towards the target (too far) or folded as far as the lengths allow
    /// (too close).
    pub reached: bool,
}

/// The rotation that takes `a_from` exactly onto `a_to` and `b_from` (made perpendicular to
/// `a_from`) onto `b_to` (made perpendicular to `a_to`). `None` if a pair is degenerate.
pub fn rotation_from_pairs(a_from: Vec3, b_from: Vec3, a_to: Vec3, b_to: Vec3) -> Option<Quat> {
    let basis = |a: Vec3, b: Vec3| -> Option<Mat3> {
        let a = a.try_normalize()?;
        let b = (b - a * a.dot(b)).try_normalize()?;
        Some(Mat3::from_cols(a, b, a.cross(b)))
    };
    let from = basis(a_from, b_from)?;
    let to = basis(a_to, b_to)?;
    Some(Quat::from_mat3(&(to * from.transpose())).normalize())
}

/// Any unit vector perpendicular to `v` (unit).
fn any_perpendicular(v: Vec3) -> Vec3 {
    let other = if v.x.abs() < 0.9 { Vec3::X } else { Vec3::Y };
    (other - v * v.dot(other)).normalize()
}

/// Analytic two-bone IK.
///
/// The chain starts at `root` (hip) with bones of `upper_len` (thigh) and `lower_len` (calf)
/// along their frames' +Y; `upper_rotation` and `lower_rotation` are their current global
/// frames (the input pose), `target` the wanted end (ankle) position and `pole` a direction
/// the middle joint (knee) should bend towards: the knee ends up in the half-plane spanned by
/// the root->target line and `pole`. Pass the input's own knee offset (`knee - hip`) to keep
/// the knee in its input plane.
///
/// The new frames are the input frames turned by the rotation that maps each bone's input
/// direction onto its new direction *and* the input bend-plane normal onto the new one, so
/// both bones share one hinge axis change: the knee's local rotation changes only about that
/// hinge, and the twist of each bone about its axis is kept relative to the bend plane.
///
/// A target farther than `upper_len + lower_len` gives the straight chain pointing at the
/// target; one closer than `|upper_len - lower_len|` gives the fully folded chain pointing at
/// it. If `pole` is parallel to the root->target line (or zero), the input bend plane is used,
/// and if that is degenerate too (a straight input chain along the target line), an arbitrary
/// perpendicular. Non-finite inputs return the input frames unchanged (`reached = false`).
#[allow(clippy::too_many_arguments)]
pub fn solve_two_bone(
    root: Vec3,
    upper_len: f32,
    lower_len: f32,
    target: Vec3,
    pole: Vec3,
    upper_rotation: Quat,
    lower_rotation: Quat,
) -> TwoBoneSolution {
    let upper_in = upper_rotation * Vec3::Y;
    let lower_in = lower_rotation * Vec3::Y;
    let input_mid = root + upper_in * upper_len;
    let unchanged = TwoBoneSolution {
        upper: upper_rotation,
        lower: lower_rotation,
        mid: input_mid,
        end: input_mid + lower_in * lower_len,
        reached: false,
    };
    if !(root.is_finite()
        && target.is_finite()
        && pole.is_finite()
        && upper_rotation.is_finite()
        && lower_rotation.is_finite()
        && upper_len.is_finite()
        && lower_len.is_finite()
        && upper_len > 0.0
        && lower_len > 0.0)
    {
        return unchanged;
    }

    // The input chain's own root->end axis and bend side.
    let input_axis = (upper_in * upper_len + lower_in * lower_len)
        .try_normalize()
        .unwrap_or(upper_in);
    let input_bend = {
        let b = upper_in - input_axis * input_axis.dot(upper_in);
        b.try_normalize()
    };

    let to_target = target - root;
    let distance = to_target.length();
    let u = to_target.try_normalize().unwrap_or(input_axis);
    // The bend side: the pole's component across the line, else the input's bend side
    // transported onto the new line, else any perpendicular.
    let across = |v: Vec3| (v - u * u.dot(v)).try_normalize();
    let v = across(pole)
        .or_else(|| input_bend.and_then(across))
        .or_else(|| across(upper_in))
        .unwrap_or_else(|| any_perpendicular(u));

    let max_reach = upper_len + lower_len;
    let min_reach = (upper_len - lower_len).abs();
    let tolerance = 1e-4 * max_reach;
    let reached = distance <= max_reach + tolerance && distance >= min_reach - tolerance;
    let d = distance.clamp(min_reach, max_reach);
    // Law of cosines: the knee's projection on the root->target line and its offset from it.
    let (along, height) = if d > 1e-9 {
        let along = (upper_len * upper_len - lower_len * lower_len + d * d) / (2.0 * d);
        let height = (upper_len * upper_len - along * along).max(0.0).sqrt();
        (along, height)
    } else {
        // Equal lengths folded onto themselves: the knee sticks out sideways.
        (0.0, upper_len)
    };
    let mid = root + u * along + v * height;
    let end = if reached { target } else { root + u * d };
    let upper_dir = (mid - root) / upper_len;
    let lower_dir = (end - mid) / lower_len;

    // Hinge axis of the input and of the solution (same handedness: bend x line).
    let input_normal = match input_bend {
        Some(b) => b.cross(input_axis),
        None => {
            let b = (v - input_axis * input_axis.dot(v))
                .try_normalize()
                .unwrap_or_else(|| any_perpendicular(input_axis));
            b.cross(input_axis)
        }
    };
    let new_normal = v.cross(u);
    let turn = |from_dir: Vec3, to_dir: Vec3| {
        rotation_from_pairs(from_dir, input_normal, to_dir, new_normal)
            .unwrap_or_else(|| Quat::from_rotation_arc(from_dir, to_dir))
    };
    let upper = (turn(upper_in, upper_dir) * upper_rotation).normalize();
    let lower = (turn(lower_in, lower_dir) * lower_rotation).normalize();
    // Exactness: the new frames' +Y are the solved directions (up to float rounding).
    let mid_fk = root + upper * Vec3::Y * upper_len;
    let end_fk = mid_fk + lower * Vec3::Y * lower_len;
    TwoBoneSolution {
        upper,
        lower,
        mid: mid_fk,
        end: end_fk,
        reached,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rotation_from_pairs_maps_both_vectors() {
        let q = Quat::from_euler(glam::EulerRot::XYZ, 0.3, -1.2, 2.0);
        let a = Vec3::new(0.2, 0.9, -0.1).normalize();
        let b = Vec3::new(1.0, 0.0, 0.3);
        let r = rotation_from_pairs(a, b, q * a, q * b).expect("pairs");
        assert!(r.abs_diff_eq(q, 1e-5) || r.abs_diff_eq(-q, 1e-5));
        assert!(rotation_from_pairs(a, a, Vec3::X, Vec3::Y).is_none());
    }

    #[test]
    fn the_solution_keeps_the_hinge() {
        // A bent input leg; move the target: the knee's local rotation changes only about the
        // input hinge axis.
        let thigh = Quat::from_rotation_x(2.9);
        let calf = thigh * Quat::from_rotation_x(-0.6);
        let hip = Vec3::new(0.1, 0.9, 0.0);
        let knee = hip + thigh * Vec3::Y * 0.42;
        let s = solve_two_bone(
            hip,
            0.42,
            0.38,
            Vec3::new(0.15, 0.25, -0.1),
            knee - hip,
            thigh,
            calf,
        );
        assert!(s.reached);
        let local_before = thigh.inverse() * calf;
        let local_after = s.upper.inverse() * s.lower;
        let delta = local_before.inverse() * local_after;
        let (axis, angle) = delta.to_axis_angle();
        assert!(
            angle.abs() < 1e-4 || axis.x.abs() > 0.9999,
            "{axis:?} {angle}"
        );
    }
}
