//! The evaluation: ANSUR II subjects made into bodies, filmed in the calibration pose by the
//! synthetic Kinect v1, measured by both methods, against the filmed body's own measurements.

pub mod detail;
pub mod dressed;
pub mod record;

pub use detail::Detailer;
pub use record::{Filmed, Recording, Stance, TURN_DEG, Worn, calibration_pose, record};

mod report;

pub use report::{
    EVALUATED, EvalOptions, MeasureReport, MeasureStats, PoseSource, SubjectResult, evaluate,
    held_out, tracked, training,
};
