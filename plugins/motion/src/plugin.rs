//! Bevy adapter: runs the motion pipeline on the sensor feed (bad-frame gate -> joint filter ->
//! retargeting -> joint limits -> foot-skate correction) and writes the pose to the avatar's
//! joint transforms. A rejected frame never reaches the avatar: the last good pose stays and
//! the rejection is counted.

use bevy::prelude::*;
use fitroom_body::plugin::{AvatarBody, AvatarJoint, BodySystems, SensorPlacement};
use fitroom_schedule::FitroomSystems;
use fitroom_sensor::{SensorFrame, plugin::SensorFeed};

use crate::filter::FilterKind;
use crate::{AvatarPipeline, AvatarPose, MotionPipeline, MotionStep};

/// Systems of the motion plugin, in order.
#[derive(SystemSet, Debug, Clone, PartialEq, Eq, Hash)]
pub enum MotionSystems {
    /// Sensor frames to an avatar pose (stage `Motion`).
    Retarget,
    /// A reshaped body: the pipeline is rebuilt on its skeleton (stage `Pose`, after the
    /// body's reshape).
    FollowShape,
    /// The pose to joint transforms (stage `Pose`).
    ApplyPose,
}

/// The motion pipeline and its latest output.
#[derive(Resource)]
pub struct AvatarMotion {
    /// The same pipeline `fitroom motion eval` runs.
    pub pipeline: MotionPipeline,
    pub pose: AvatarPose,
    /// Sensor frames turned into poses so far.
    pub frames_applied: u64,
    /// The last accepted raw frame and its filtered version (for the debug overlay).
    pub last_raw: Option<SensorFrame>,
    pub last_filtered: Option<SensorFrame>,
}

impl AvatarMotion {
    pub fn new(pipeline: MotionPipeline) -> Self {
        let pose = pipeline.retargeter().rest_pose();
        Self {
            pipeline,
            pose,
            frames_applied: 0,
            last_raw: None,
            last_filtered: None,
        }
    }

    /// Runs one sensor frame through the pipeline; a rejected frame changes nothing.
    pub fn push(&mut self, frame: &SensorFrame) -> bool {
        let Some(MotionStep { filtered, pose }) = self.pipeline.push(frame) else {
            return false;
        };
        self.pose = pose;
        self.last_raw = Some(frame.clone());
        self.last_filtered = Some(filtered);
        self.frames_applied += 1;
        true
    }

    /// A new avatar skeleton (the body was reshaped): the pose stays until the next frame.
    pub fn replace_pipeline(&mut self, avatar: AvatarPipeline) {
        self.pipeline.replace_avatar(avatar);
    }

    /// A new user: calibrate again and restart the filter.
    pub fn reset(&mut self) {
        self.pipeline.reset();
    }
}

/// The joint filter the avatar's pipeline runs (live-editable: a change replaces the filter,
/// which starts afresh on the next frame).
#[derive(Resource, Debug, Clone, Copy, Default, PartialEq, Reflect)]
#[reflect(Resource)]
pub struct FilterSettings {
    pub filter: FilterKind,
}

pub struct MotionPlugin;

impl Plugin for MotionPlugin {
    fn build(&self, app: &mut App) {
        fitroom_schedule::ensure(app);
        // The sensor and body plugins own these; initialised here too so that the plugin
        // works alone (an app without them sees no frames and the default placement).
        app.init_resource::<SensorFeed>()
            .init_resource::<SensorPlacement>()
            .init_resource::<FilterSettings>()
            .register_type::<FilterSettings>()
            .configure_sets(
                PostUpdate,
                (
                    MotionSystems::Retarget.in_set(FitroomSystems::Motion),
                    (MotionSystems::FollowShape, MotionSystems::ApplyPose)
                        .chain()
                        .in_set(FitroomSystems::Pose)
                        .after(BodySystems::Reshape),
                ),
            )
            .add_systems(
                PostUpdate,
                (
                    (apply_filter_settings, retarget)
                        .chain()
                        .in_set(MotionSystems::Retarget),
                    follow_body_shape.in_set(MotionSystems::FollowShape),
                    apply_pose.in_set(MotionSystems::ApplyPose),
                ),
            );
    }
}

/// A changed [`FilterSettings`] replaces the running filter (its state is not carried over:
/// another filter's state has another meaning).
fn apply_filter_settings(settings: Res<FilterSettings>, motion: Option<ResMut<AvatarMotion>>) {
    let Some(mut motion) = motion else {
        return;
    };
    if settings.is_changed() && !settings.is_added() {
        motion.pipeline.filter = settings.filter.build();
    }
}

fn retarget(feed: Res<SensorFeed>, motion: Option<ResMut<AvatarMotion>>) {
    let Some(mut motion) = motion else {
        return;
    };
    for frame in &feed.new_frames {
        motion.push(frame);
    }
}

/// A reshaped body has other bone lengths: the motion pipeline is rebuilt on the new
/// skeleton (the filter keeps its state; the retargeter calibrates again).
fn follow_body_shape(
    body: Option<Res<AvatarBody>>,
    placement: Res<SensorPlacement>,
    motion: Option<ResMut<AvatarMotion>>,
) {
    let (Some(body), Some(mut motion)) = (body, motion) else {
        return;
    };
    if !body.is_changed() || body.is_added() {
        return;
    }
    let pipeline = crate::avatar_skeleton(&body.model, &body.rest)
        .map_err(|e| e.to_string())
        .and_then(|skeleton| {
            AvatarPipeline::new(&skeleton, -placement.sensor_height_m).map_err(|e| e.to_string())
        });
    match pipeline {
        Ok(pipeline) => motion.replace_pipeline(pipeline),
        Err(e) => error!("the motion keeps the old skeleton: {e}"),
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
    let bones = &motion.pipeline.skeleton().bones;
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
