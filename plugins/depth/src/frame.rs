//! [`DepthFrame`]: one frame of the depth stream. The images are reference-counted: a stage
//! that passes a frame on (source -> tracker -> measurement -> screen) shares them, and only a
//! stage that changes an image makes its own copy.

use std::sync::Arc;

use crate::camera::{self, DepthCamera, PIXELS, RAW_NO_VALUE};

/// One depth frame, 640x480, row-major from the top-left pixel.
#[derive(Clone, Debug)]
pub struct DepthFrame {
    /// Depth along the optical axis, millimetres; 0 where there is no reading.
    pub depth_mm: Arc<[u16]>,
    /// The device's 11-bit raw values ([`RAW_NO_VALUE`] where there is no reading), where the
    /// source has them.
    pub raw: Option<Arc<[u16]>>,
    /// 640x480 RGB, 8 bits per channel, where the source has it.
    pub rgb: Option<Arc<[u8]>>,
    /// Seconds since the stream's start.
    pub time_s: f64,
    /// The device's 32-bit timestamp (libfreenect's; 60 MHz ticks on a Kinect v1), or the
    /// frame's index for a source without one.
    pub timestamp: u32,
    pub camera: DepthCamera,
}

impl DepthFrame {
    /// A frame from raw values (depth in millimetres derived through [`camera::raw_to_mm`]).
    /// `raw` must hold [`PIXELS`] values; values above 2047 count as no reading.
    pub fn from_raw(raw: Vec<u16>, time_s: f64, timestamp: u32, camera: DepthCamera) -> Self {
        debug_assert_eq!(raw.len(), PIXELS);
        let raw: Vec<u16> = raw.into_iter().map(|r| r.min(RAW_NO_VALUE)).collect();
        let mm = camera::raw_mm_table();
        let depth_mm: Vec<u16> = raw.iter().map(|&r| mm[usize::from(r)]).collect();
        Self {
            depth_mm: depth_mm.into(),
            raw: Some(raw.into()),
            rgb: None,
            time_s,
            timestamp,
            camera,
        }
    }

    /// The share of pixels with a reading, 0-1.
    pub fn valid_share(&self) -> f64 {
        let valid = self.depth_mm.iter().filter(|&&d| d > 0).count();
        valid as f64 / self.depth_mm.len().max(1) as f64
    }

    /// Nearest and farthest reading, millimetres (`None` for a frame without readings).
    pub fn depth_range_mm(&self) -> Option<(u16, u16)> {
        let mut valid = self.depth_mm.iter().copied().filter(|&d| d > 0);
        let first = valid.next()?;
        Some(valid.fold((first, first), |(lo, hi), d| (lo.min(d), hi.max(d))))
    }
}
