//! The `SensorSource` trait: anything that produces skeleton frames (a recorded BVH clip, a
//! fakenect dump, a live Kinect).

use crate::frame::SensorFrame;

/// Why a source produced no frame.
#[derive(Debug, thiserror::Error)]
pub enum SourceError {
    /// The device or file went away; the caller should hold the last good pose.
    #[error("sensor source '{source_name}' disconnected: {reason}")]
    Disconnected { source_name: String, reason: String },
}

/// A producer of Kinect v1-style skeleton frames.
pub trait SensorSource: Send + Sync {
    /// Short human-readable name, shown in the kiosk overlay ("bvh:07_01").
    fn name(&self) -> &str;
    /// Nominal frame rate of the emitted stream (30 for Kinect v1).
    fn fps(&self) -> f32;
    /// Advances the source's clock by `dt_s` seconds and returns every frame that became due,
    /// oldest first (none if the next frame is not due yet).
    fn advance(&mut self, dt_s: f64) -> Result<Vec<SensorFrame>, SourceError>;
}
