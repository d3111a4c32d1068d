//! Seeing the person in the depth stream, without a proprietary SDK (libfreenect gives depth
//! only): [`floor`] finds the floor plane, [`segment`] the person's pixels (the user map the
//! Kinect SDK gave seed 000). The skeleton tracker will build on them.

#![forbid(unsafe_code)]

pub mod floor;
pub mod segment;

pub use floor::Plane;
pub use segment::{SegmentSettings, Segmentation, Segmenter};
