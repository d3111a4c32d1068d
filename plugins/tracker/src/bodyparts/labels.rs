//! The body parts: the skin around each of the 20 Kinect joints. A vertex belongs to the
//! nearest (at rest) of the joints at the two ends of the Kinect bone its dominant rig bone
//! lies in, so a part's pixels gather around its joint, as Shotton et al.'s parts do.

use fitroom_body::{BodyModel, RestPose, forward_kinematics};
use fitroom_sensor::KinectJoint;
use glam::Quat;

use crate::kinect::{JOINT_BONES, rig_joints};

/// Number of parts: one per Kinect joint, in [`KinectJoint::ALL`] order.
pub const PARTS: usize = KinectJoint::COUNT;

/// Each body vertex's part (a Kinect joint index), for the model's body vertices
/// (`positions`: the model's own or a shaped body's, with its `rest`).
pub fn vertex_parts(model: &BodyModel, positions: &[glam::Vec3], rest: &RestPose) -> Vec<u8> {
    let bones = &model.bones;
    let locals = vec![Quat::IDENTITY; bones.len()];
    let globals = forward_kinematics(bones, rest, &locals, glam::Vec3::ZERO);
    let joints = rig_joints(model, &globals);
    // The Kinect joint at each bone's head, if any.
    let mut joint_of_bone = vec![None; bones.len()];
    for (joint, name) in JOINT_BONES {
        if let Some(b) = model.bone_index(name) {
            joint_of_bone[b] = Some(joint.index());
        }
    }
    // The joint a bone's skin starts from: its own, or its nearest ancestor's.
    let owner = |mut b: usize| -> Option<usize> {
        loop {
            if let Some(j) = joint_of_bone[b] {
                return Some(j);
            }
            b = bones[b].parent?;
        }
    };
    // The Kinect joints one step down from each joint: those whose bone's parent chain
    // reaches that joint's bone first.
    let mut below = vec![Vec::new(); PARTS];
    for (b, joint) in joint_of_bone.iter().enumerate() {
        if let (Some(j), Some(parent)) = (joint, bones[b].parent)
            && let Some(up) = owner(parent)
        {
            below[up].push(*j);
        }
    }
    let n = (model.body_vertex_count as usize).min(positions.len());
    (0..n)
        .map(|v| {
            let (bones4, weights) = (model.skin_joints[v], model.skin_weights[v]);
            let dominant = (0..4)
                .max_by(|&a, &b| weights[a].total_cmp(&weights[b]))
                .map_or(0, |k| usize::from(bones4[k]));
            let Some(start) = owner(dominant.min(bones.len() - 1)) else {
                return KinectJoint::HipCenter.index() as u8;
            };
            let p = positions[v];
            std::iter::once(start)
                .chain(below[start].iter().copied())
                .min_by(|&a, &b| {
                    joints[a]
                        .distance_squared(p)
                        .total_cmp(&joints[b].distance_squared(p))
                })
                .unwrap_or(start) as u8
        })
        .collect()
}

/// The body's triangles grouped by part (a triangle goes with its first vertex).
pub fn part_triangles(triangles: &[[u32; 3]], parts: &[u8]) -> Vec<Vec<[u32; 3]>> {
    let mut out = vec![Vec::new(); PARTS];
    for t in triangles {
        if let Some(&p) = parts.get(t[0] as usize) {
            out[usize::from(p)].push(*t);
        }
    }
    out
}
