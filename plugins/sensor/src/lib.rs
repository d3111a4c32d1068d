//! Sensor sources for fitroom: the Kinect v1 skeleton frame model, the [`SensorSource`] trait
//! and a BVH motion-capture source that replays real CMU clips as a 30 Hz Kinect stream.
//!
//! Core modules (no Bevy types):
//! - [`frame`]: the Kinect v1 skeleton frame model (sensor space: metres, +Y up, +Z from the
//!   sensor towards the person, +X to the sensor's left).
//! - [`source`]: the [`SensorSource`] trait.
//! - [`bvh`]: a BVH parser with line-numbered errors and forward kinematics (file units,
//!   degrees).
//! - [`bvh_skeleton`]: detection of the two CMU skeleton variants and their mapping onto the
//!   Kinect joints, with the metre scale derived from the leg length.
//! - [`bvh_source`]: [`BvhSource`], a clip replayed as a looping 30 Hz Kinect stream, and
//!   [`inspect`].
//!
//! The `plugin` feature adds [`plugin::SensorPlugin`].

#![forbid(unsafe_code)]

pub mod bvh;
pub mod bvh_skeleton;
pub mod bvh_source;
pub mod frame;
pub mod noise;
pub mod source;

#[cfg(feature = "plugin")]
pub mod plugin;

pub use bvh::{BvhClip, BvhError, BvhJoint, BvhPoint, BvhPose, Channel};
pub use bvh_skeleton::{BvhSkeletonKind, KinectMapping, REFERENCE_LEG_LENGTH_M};
pub use bvh_source::{BvhInfo, BvhSource, BvhSourceOptions, Placement, inspect};
pub use frame::{JointSample, KinectJoint, SensorFrame};
pub use source::{SensorSource, SourceError};
