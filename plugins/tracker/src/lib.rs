//! Seeing the person in the depth stream, without a proprietary SDK (libfreenect gives depth
//! only): [`floor`] finds the floor plane, [`segment`] the person's pixels (the user map the
//! Kinect SDK gave seed 000), [`extrema`] head, hands and feet without a prior pose (to
//! start and recover the tracker), [`bodyparts`] each pixel's body part from a forest grown on
//! synthetic images (joint proposals, opt-in); [`tracker`] fits the skeleton to each frame.
//!
//! The `plugin` feature adds [`plugin::TrackerPlugin`]: the user map of each new depth frame.

#![forbid(unsafe_code)]

pub mod bodyparts;
pub mod denoise;
pub mod draw;
pub mod eval;
pub mod extrema;
pub mod fit;
pub mod floor;
pub mod kinect;
pub mod model;
pub mod segment;
pub mod shape;
pub mod silhouette;
pub mod skirt;
pub mod sleeve;
pub mod surface;
pub mod tracker;

#[cfg(feature = "plugin")]
pub mod plugin;

pub use extrema::{Extremum, Part, geodesic_extrema};
pub use fit::{FitSettings, FitStats};
pub use floor::Plane;
pub use model::{ModelError, Pose, TrackBody};
pub use segment::{SegmentSettings, Segmentation, Segmenter};
pub use shape::{BuildFit, BuildFitted, Estimate, ShapeSettings, Snapshot};
pub use tracker::{Confidence, Tracked, TrackedJointOut, Tracker, TrackerSettings};
