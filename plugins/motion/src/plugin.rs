//! Bevy adapter: runs the motion pipeline on the sensor feed (bad-frame gate -> joint filter ->
//! retargeting -> joint limits -> foot-skate correction) and writes the pose to the avatar's
//! joint transforms. A rejected frame never reaches the avatar: the last good pose stays and
//! the rejection is counted.

use bevy::prelude::*;
use fitroom_body::plugin::AvatarJoint;
use fitroom_sensor::{SensorFrame, plugin::SensorFeed};

use crate::{
    AvatarPose,
    eval::AvatarPipeline,
    filter::{
        JointFilter,
        gate::{FrameGate, GateDecision},
    },
};

/// Systems of the motion plugin, in order.
#[derive(SystemSet, Debug, Clone, PartialEq, Eq, Hash)]
pub enum MotionSystems {
    /// Sensor frames to an avatar pose.
    Retarget,
    /// The pose to joint transforms.
    ApplyPose,
}

/// The motion pipeline and its latest output.
#[derive(Resource)]
pub struct AvatarMotion {
    pub pipeline: AvatarPipeline,
    pub gate: FrameGate,
    pub filter: Box<dyn JointFilter>,
    pub pose: AvatarPose,
    /// Sensor frames turned into poses so far.
    pub frames_applied: u64,
    /// The last accepted raw frame and its filtered version (for the debug overlay).
    pub last_raw: Option<SensorFrame>,
    pub last_filtered: Option<SensorFrame>,
    last_timestamp: Option<f64>,
}

impl AvatarMotion {
    pub fn new(pipeline: AvatarPipeline, filter: Box<dyn JointFilter>) -> Self {
        let pose = pipeline.retargeter().rest_pose();
        Self {
            pipeline,
            gate: FrameGate::new(),
            filter,
            pose,
            frames_applied: 0,
            last_raw: None,
            last_filtered: None,
            last_timestamp: None,
        }
    }

    /// Runs one sensor frame through the pipeline; a rejected frame changes nothing.
    pub fn push(&mut self, frame: &SensorFrame) -> bool {
        if !matches!(self.gate.check(frame), GateDecision::Accept) {
            return false;
        }
        let filtered = self.filter.filter(frame);
        let dt = self
            .last_timestamp
            .map_or(1.0 / 30.0, |t| (frame.timestamp_s - t).max(1e-3)) as f32;
        self.last_timestamp = Some(frame.timestamp_s);
        self.pose = self.pipeline.pose(&filtered, dt);
        self.last_raw = Some(frame.clone());
        self.last_filtered = Some(filtered);
        self.frames_applied += 1;
        true
    }

    /// A new avatar skeleton (the body was reshaped): the pose stays until the next frame.
    pub fn replace_pipeline(&mut self, pipeline: AvatarPipeline) {
        self.pipeline = pipeline;
        self.last_timestamp = None;
    }

    /// A new user: calibrate again and restart the filter.
    pub fn reset(&mut self) {
        self.pipeline.reset();
        self.gate.reset();
        self.filter.reset();
        self.last_timestamp = None;
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
