//! The motion pipeline, one type for every user: the kiosk's [`crate::plugin::AvatarMotion`]
//! and `fitroom motion eval` ([`crate::eval::evaluate_clip`]) both push sensor frames through a
//! [`MotionPipeline`]: bad-frame gate -> joint filter -> retargeting (seed 000 Algorithm 1) ->
//! joint limits -> foot-skate correction -> joint limits.

use fitroom_sensor::SensorFrame;
use glam::Vec3;

use crate::{
    AvatarPose, AvatarSkeleton, RetargetOptions, Retargeter,
    filter::{
        JointFilter,
        gate::{FrameGate, GateDecision},
    },
    footskate::{FootSkateCorrector, FootSkateError, FootSkateOptions},
    limits::{JointLimits, LimitOptions},
};

/// Why the pipeline cannot be built for a skeleton.
#[derive(Debug, thiserror::Error)]
pub enum PipelineError {
    #[error(transparent)]
    Retarget(#[from] crate::RetargetError),
    #[error(transparent)]
    FootSkate(#[from] FootSkateError),
}

/// The whole pipeline: a sensor frame in, the avatar's pose out.
pub struct MotionPipeline {
    pub gate: FrameGate,
    pub filter: Box<dyn JointFilter>,
    /// Everything after the filter.
    pub avatar: AvatarPipeline,
    last_timestamp: Option<f64>,
}

/// What one accepted frame gave.
pub struct MotionStep {
    /// The frame after the joint filter.
    pub filtered: SensorFrame,
    pub pose: AvatarPose,
}

impl MotionPipeline {
    pub fn new(avatar: AvatarPipeline, filter: Box<dyn JointFilter>) -> Self {
        Self {
            gate: FrameGate::new(),
            filter,
            avatar,
            last_timestamp: None,
        }
    }

    /// Runs one sensor frame through the pipeline. `None`: the gate rejected it, and nothing
    /// changed (the avatar keeps its last good pose).
    pub fn push(&mut self, frame: &SensorFrame) -> Option<MotionStep> {
        if !matches!(self.gate.check(frame), GateDecision::Accept) {
            return None;
        }
        let filtered = self.filter.filter(frame);
        let dt = self
            .last_timestamp
            .map_or(1.0 / 30.0, |t| (frame.timestamp_s - t).max(1e-3)) as f32;
        self.last_timestamp = Some(frame.timestamp_s);
        let pose = self.avatar.pose(&filtered, dt);
        Some(MotionStep { filtered, pose })
    }

    /// A new avatar skeleton (the body was reshaped); the filter keeps its state.
    pub fn replace_avatar(&mut self, avatar: AvatarPipeline) {
        self.avatar = avatar;
        self.last_timestamp = None;
    }

    /// A new user: calibrate again and restart the gate and the filter.
    pub fn reset(&mut self) {
        self.avatar.reset();
        self.gate.reset();
        self.filter.reset();
        self.last_timestamp = None;
    }

    pub fn skeleton(&self) -> &AvatarSkeleton {
        self.avatar.skeleton()
    }

    pub fn retargeter(&self) -> &Retargeter {
        self.avatar.retargeter()
    }
}

/// The pipeline after the filter: retargeting, limits, foot-skate correction, limits.
pub struct AvatarPipeline {
    retargeter: Retargeter,
    limits: JointLimits,
    footskate: FootSkateCorrector,
    floor_y: f32,
    feet: [Option<usize>; 2],
    /// Horizontal distance (m) by which the foot-skate correction moved each ankle (left,
    /// right) in the last [`AvatarPipeline::pose`].
    pub last_foot_correction_m: [f32; 2],
}

impl AvatarPipeline {
    pub fn new(skeleton: &AvatarSkeleton, floor_y: f32) -> Result<Self, PipelineError> {
        let options = RetargetOptions {
            floor_y,
            ..RetargetOptions::default()
        };
        Ok(Self {
            retargeter: Retargeter::new(skeleton.clone(), options)?,
            limits: JointLimits::new(skeleton, LimitOptions::default()),
            footskate: FootSkateCorrector::new(skeleton.clone(), FootSkateOptions::default())?,
            floor_y,
            feet: [skeleton.index_of("foot_l"), skeleton.index_of("foot_r")],
            last_foot_correction_m: [0.0; 2],
        })
    }

    /// One filtered frame to a corrected pose.
    pub fn pose(&mut self, frame: &SensorFrame, dt: f32) -> AvatarPose {
        let mut pose = self.retargeter.update(frame);
        let skeleton = self.retargeter.skeleton();
        self.limits.clamp_pose(skeleton, &mut pose);
        let before = self
            .feet
            .map(|f| f.and_then(|i| pose.heads.get(i).copied()));
        self.footskate.correct(&mut pose, self.floor_y, dt);
        self.limits.clamp_pose(skeleton, &mut pose);
        for (k, (foot, was)) in self.feet.iter().zip(before).enumerate() {
            self.last_foot_correction_m[k] = match (foot.and_then(|i| pose.heads.get(i)), was) {
                (Some(now), Some(was)) => Vec3::new(now.x - was.x, 0.0, now.z - was.z).length(),
                _ => 0.0,
            };
        }
        pose
    }

    pub fn limits(&self) -> &JointLimits {
        &self.limits
    }

    pub fn skeleton(&self) -> &AvatarSkeleton {
        self.retargeter.skeleton()
    }

    pub fn retargeter(&self) -> &Retargeter {
        &self.retargeter
    }

    /// A new user: calibrate again, forget planted feet.
    pub fn reset(&mut self) {
        self.retargeter.reset();
        self.footskate.reset();
    }
}
