//! Bevy adapter: turns the sensor feed into an [`AvatarPose`] and writes it to the avatar's
//! joint transforms.

use bevy::prelude::*;
use fitroom_body::plugin::AvatarJoint;
use fitroom_sensor::plugin::{SensorFeed, SensorSystems};

use crate::{AvatarPose, Retargeter};

/// Systems of the motion plugin, in order.
#[derive(SystemSet, Debug, Clone, PartialEq, Eq, Hash)]
pub enum MotionSystems {
    /// Sensor frames to an avatar pose.
    Retarget,
    /// The pose to joint transforms.
    ApplyPose,
}

/// The retargeter and its latest pose.
#[derive(Resource)]
pub struct AvatarMotion {
    pub retargeter: Retargeter,
    pub pose: AvatarPose,
    /// Sensor frames turned into poses so far.
    pub frames_applied: u64,
}

impl AvatarMotion {
    pub fn new(retargeter: Retargeter) -> Self {
        let pose = retargeter.rest_pose();
        Self {
            retargeter,
            pose,
            frames_applied: 0,
        }
    }
}

pub struct MotionPlugin;

impl Plugin for MotionPlugin {
    fn build(&self, app: &mut App) {
        app.configure_sets(
            Update,
            (MotionSystems::Retarget, MotionSystems::ApplyPose).chain(),
        )
        .add_systems(
            Update,
            (
                retarget.in_set(MotionSystems::Retarget),
                apply_pose.in_set(MotionSystems::ApplyPose),
            ),
        );
        // The sensor set runs in PreUpdate, so it is always before these.
        let _ = SensorSystems::Poll;
    }
}

fn retarget(feed: Res<SensorFeed>, motion: Option<ResMut<AvatarMotion>>) {
    let Some(mut motion) = motion else {
        return;
    };
    for frame in &feed.new_frames {
        motion.pose = motion.retargeter.update(frame);
        motion.frames_applied += 1;
    }
}

fn apply_pose(
    motion: Option<Res<AvatarMotion>>,
    mut joints: Query<(&AvatarJoint, &mut Transform)>,
) {
    let Some(motion) = motion else {
        return;
    };
    if !motion.is_changed() {
        return;
    }
    let bones = &motion.retargeter.skeleton().bones;
    let pose = &motion.pose;
    for (joint, mut transform) in &mut joints {
        let i = joint.0;
        let (Some(bone), Some(&local), Some(&head), Some(&global)) = (
            bones.get(i),
            pose.local_rotations.get(i),
            pose.heads.get(i),
            pose.rotations.get(i),
        ) else {
            continue;
        };
        if bone.parent.is_none() {
            transform.translation = head;
            transform.rotation = global;
        } else {
            transform.translation = bone.local_translation;
            transform.rotation = local;
        }
    }
}
