//! Still poses for the garment designer: the avatar's rest pose (MakeHuman's, arms down and
//! away from the body: an A-pose) and a T-pose made from it by raising each upper arm to the
//! horizontal, the forearms and hands carried along.

use glam::{Quat, Vec3};

use crate::{AvatarPose, AvatarSkeleton};

/// A still pose to dress the avatar in.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum StillPose {
    /// The rest pose: arms down and away from the body.
    #[default]
    APose,
    /// Arms raised sideways to the horizontal.
    TPose,
}

/// The rest pose, on the floor where the skeleton stands at rest.
pub fn a_pose(skeleton: &AvatarSkeleton) -> AvatarPose {
    let bones = &skeleton.bones;
    AvatarPose {
        heads: bones.iter().map(|b| b.rest_head).collect(),
        rotations: bones.iter().map(|b| b.rest_rotation).collect(),
        local_rotations: bones.iter().map(|b| b.rest_local_rotation).collect(),
        timestamp_s: 0.0,
    }
}

/// The rest pose with both arms straight out sideways, horizontally: each upper arm, then each
/// forearm (`upperarm_*`, `lowerarm_*`), is turned about its head to point sideways; every
/// bone below turns with it, so the hands keep their rest orientation to the forearm.
pub fn t_pose(skeleton: &AvatarSkeleton) -> AvatarPose {
    let mut pose = a_pose(skeleton);
    for arm in ["upperarm_l", "lowerarm_l", "upperarm_r", "lowerarm_r"] {
        let Some(a) = skeleton.index_of(arm) else {
            continue;
        };
        // A bone's +Y runs along it; the arm is raised in its own vertical plane through the
        // shoulder, to the side it already points to.
        let along = pose.rotations[a] * Vec3::Y;
        let side = Vec3::new(along.x.signum(), 0.0, 0.0);
        let turn = Quat::from_rotation_arc(along.normalize(), side);
        let pivot = pose.heads[a];
        for b in 0..skeleton.bones.len() {
            if b == a || descends_from(skeleton, b, a) {
                pose.heads[b] = pivot + turn * (pose.heads[b] - pivot);
                pose.rotations[b] = (turn * pose.rotations[b]).normalize();
            }
        }
        let parent = skeleton.bones[a]
            .parent
            .map_or(Quat::IDENTITY, |p| pose.rotations[p]);
        pose.local_rotations[a] = (parent.inverse() * pose.rotations[a]).normalize();
    }
    pose
}

/// The pose of a [`StillPose`], standing on the floor at height `floor_y` (sensor space),
/// `distance_m` in front of the sensor (the rest pose stands where the model was made).
pub fn still_pose(
    skeleton: &AvatarSkeleton,
    pose: StillPose,
    floor_y: f32,
    distance_m: f32,
) -> AvatarPose {
    let mut out = match pose {
        StillPose::APose => a_pose(skeleton),
        StillPose::TPose => t_pose(skeleton),
    };
    let shift = Vec3::new(0.0, floor_y - skeleton.rest_floor_y, distance_m);
    for head in &mut out.heads {
        *head += shift;
    }
    out
}

fn descends_from(skeleton: &AvatarSkeleton, mut bone: usize, ancestor: usize) -> bool {
    while let Some(p) = skeleton.bones[bone].parent {
        if p == ancestor {
            return true;
        }
        bone = p;
    }
    false
}
