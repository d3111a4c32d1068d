//! The body walking a motion clip as the cloth sees it: the motion pipeline's 30 Hz poses of
//! the clip's clean stream, interpolated to the 120 Hz cloth steps, as skinning transforms
//! (rest model space -> sensor space). The garment tools, tests and benches drive garments
//! with it.

use std::path::{Path, PathBuf};

use fitroom_body::{
    BodyModel, RestPose, ShapedBody,
    skinning::{RigidTransform, skinning_matrices},
};
use fitroom_sensor::{
    SensorFrame,
    bvh::BvhError,
    bvh_source::{BvhSource, BvhSourceOptions},
};
use glam::{Affine3A, Quat, Vec3};

use crate::{AvatarPipeline, PipelineError, RetargetError, eval::clean_stream};

/// The cloth rate: steps per second.
pub const STEP_HZ: f32 = 120.0;

/// The motion's frame interval as the walk plays it, s.
pub const FRAME_S: f32 = 1.0 / 30.0;

/// Why a walk cannot start.
#[derive(Debug, thiserror::Error)]
pub enum WalkError {
    #[error("cannot load the motion '{}'", path.display())]
    Motion {
        path: PathBuf,
        #[source]
        source: BvhError,
    },
    #[error("'{}' has no frames", .0.display())]
    NoFrames(PathBuf),
    #[error(transparent)]
    Skeleton(#[from] RetargetError),
    #[error(transparent)]
    Pipeline(#[from] PipelineError),
}

/// Skinning transforms (rest model space -> sensor space) of an avatar pose.
pub fn skinning_of(rest: &RestPose, rotations: &[Quat], heads: &[Vec3]) -> Vec<Affine3A> {
    let posed: Vec<RigidTransform> = rotations
        .iter()
        .zip(heads)
        .map(|(&r, &h)| RigidTransform::new(r, h))
        .collect();
    skinning_matrices(rest, &posed)
}

/// The body walking a motion as the cloth sees it: the motion pipeline's 30 Hz poses,
/// interpolated to the 120 Hz cloth steps, as skinning transforms. Frames past the clip's end
/// wrap to its start.
pub struct Walk<'a> {
    /// The floor's height in the motion's space.
    pub floor_y: f32,
    /// The skinning at the first frame.
    pub first: Vec<Affine3A>,
    rest: &'a RestPose,
    pipeline: AvatarPipeline,
    stream: Vec<SensorFrame>,
    next: usize,
    last: (Vec<Quat>, Vec<Vec3>),
    /// Play the clip back and forth instead of jumping from its end to its start.
    ping_pong: bool,
}

impl<'a> Walk<'a> {
    /// The body `shaped` walking the BVH clip `motion`.
    pub fn new(
        model: &BodyModel,
        shaped: &'a ShapedBody,
        motion: &Path,
    ) -> Result<Self, WalkError> {
        let source = BvhSource::load(motion, BvhSourceOptions::default()).map_err(|source| {
            WalkError::Motion {
                path: motion.to_owned(),
                source,
            }
        })?;
        let floor_y = -source.options().sensor_height_m;
        let skeleton = crate::avatar_skeleton(model, &shaped.rest_pose)?;
        let mut pipeline = AvatarPipeline::new(&skeleton, floor_y)?;
        let stream = clean_stream(&source);
        let Some(frame) = stream.first() else {
            return Err(WalkError::NoFrames(motion.to_owned()));
        };
        let pose = pipeline.pose(frame, FRAME_S);
        let last = (pose.rotations.clone(), pose.heads.clone());
        Ok(Self {
            floor_y,
            first: skinning_of(&shaped.rest_pose, &last.0, &last.1),
            rest: &shaped.rest_pose,
            pipeline,
            stream,
            next: 1,
            last,
            ping_pong: false,
        })
    }

    /// The same walk played forwards, then backwards, and so on: no jump back to the start
    /// (which the garment crosses as a teleport).
    pub fn ping_pong(mut self) -> Self {
        self.ping_pong = true;
        self
    }

    /// The clip's frames (30 Hz); past the last, [`Self::next_frame`] wraps to the first, or
    /// turns back ([`Self::ping_pong`]).
    pub fn frames(&self) -> usize {
        self.stream.len()
    }

    /// The skinning of each 120 Hz step of the next frame.
    pub fn next_frame(&mut self) -> Vec<Vec<Affine3A>> {
        let len = self.stream.len();
        let index = if self.ping_pong && len > 1 {
            let period = 2 * (len - 1);
            let k = self.next % period;
            if k < len { k } else { period - k }
        } else {
            self.next % len
        };
        let frame = &self.stream[index];
        self.next += 1;
        let pose = self.pipeline.pose(frame, FRAME_S);
        let now = (pose.rotations.clone(), pose.heads.clone());
        let (r0, h0) = std::mem::replace(&mut self.last, now);
        let now = &self.last;
        let per_frame = (STEP_HZ * FRAME_S).round() as usize;
        (1..=per_frame)
            .map(|k| {
                let t = k as f32 / per_frame as f32;
                let rot: Vec<Quat> = r0.iter().zip(&now.0).map(|(a, b)| a.slerp(*b, t)).collect();
                let head: Vec<Vec3> = h0.iter().zip(&now.1).map(|(a, b)| a.lerp(*b, t)).collect();
                skinning_of(self.rest, &rot, &head)
            })
            .collect()
    }
}
