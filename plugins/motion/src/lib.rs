//! Motion pipeline of fitroom: Kinect v1 skeleton frames to avatar poses (seed 000 chapter 4).
//!
//! - [`retarget`]: Algorithm 1 (bone orientations relative to their initial orientation,
//!   confidence gate, root translation) onto the avatar's own skeleton, with the split
//!   forearm of §4.4.3.
//!
//! The core modules use no Bevy types; the `plugin` feature adds [`plugin::MotionPlugin`].

#![forbid(unsafe_code)]

pub mod eval;
pub mod filter;
pub mod footskate;
pub mod ik;
pub mod limits;
pub mod metrics;
pub mod pipeline;
pub mod retarget;
pub mod smoothing;
pub mod still_pose;
pub mod walk;

#[cfg(feature = "plugin")]
pub mod plugin;

pub use pipeline::{AvatarPipeline, MotionPipeline, MotionStep, PipelineError};
pub use retarget::{
    AvatarPose, AvatarSkeleton, Calibration, RetargetError, RetargetOptions, Retargeter,
};

/// Builds the avatar skeleton of a body model from its rest pose.
pub fn avatar_skeleton(
    model: &fitroom_body::BodyModel,
    rest: &fitroom_body::RestPose,
) -> Result<AvatarSkeleton, RetargetError> {
    let names: Vec<String> = model.bones.iter().map(|b| b.name.clone()).collect();
    let parents: Vec<Option<usize>> = model.bones.iter().map(|b| b.parent).collect();
    let n = model.body_vertex_count as usize;
    let floor_y = model.positions[..n]
        .iter()
        .map(|p| p.y)
        .fold(f32::INFINITY, f32::min);
    AvatarSkeleton::from_model_rest(&names, &parents, &rest.heads, &rest.rotations, floor_y)
}
