//! The Kinect v1 depth stream (seed 000 reads a 640x480 depth map at 30 Hz for the skeleton,
//! the body measurement of ch. 6 and the hand gestures of App. C):
//!
//! - [`camera`]: the depth camera's model, the 11-bit raw disparity scale and its conversion
//!   to metres, projection between pixels and sensor space;
//! - [`frame`]: [`DepthFrame`], the sensor's currency (depth in millimetres, the raw values,
//!   optional RGB, timestamp, camera), its images shared rather than copied;
//! - [`fakenect`]: libfreenect's record/replay folder format, read and written in pure Rust;
//! - [`colour`]: the depth colour map (Turbo, near red to far blue, no reading black) of the
//!   contact sheet and the kiosk's picture-in-picture view;
//! - [`sheet`]: a recording's contact sheet, its depth frames in a grid, as RGB8;
//! - [`summary`]: a recording in numbers (frames, rate, readings, ground truth), as JSON;
//! - [`player`]: a recording played as a live stream, at its pace, looping;
//! - [`truth`]: the ground truth written beside a synthetic recording;
//! - [`synthetic`]: the synthetic Kinect v1 with the published error model.
//!
//! The `plugin` feature adds [`plugin::DepthFeed`], the depth stream as a Bevy resource.

#![forbid(unsafe_code)]

pub mod camera;
pub mod colour;
pub mod fakenect;
pub mod frame;
pub mod noise;
pub mod player;
pub mod sheet;
pub mod summary;
pub mod synthetic;
pub mod truth;

#[cfg(feature = "plugin")]
pub mod plugin;

pub use camera::{DepthCamera, HEIGHT, PIXELS, RAW_NO_VALUE, WIDTH};
pub use frame::DepthFrame;
