//! Bevy adapter: the depth stream as a resource. A depth source (the synthetic camera, a
//! fakenect recording, a live Kinect) writes its newest frame into [`DepthFeed`] in the
//! app's `Sensor` stage; readers (the picture-in-picture view, later the tracker) take it
//! from there. Frames share their images ([`DepthFrame`]'s `Arc`s): nothing is copied.

use bevy::prelude::*;

use crate::frame::DepthFrame;
use crate::truth::FrameTruth;

/// The newest depth frame and the state of its source.
#[derive(Resource, Default, Debug)]
pub struct DepthFeed {
    /// The most recent frame (kept when the source stalls or fails).
    pub latest: Option<DepthFrame>,
    /// Its ground truth, where the source has it (the synthetic camera, a synthetic
    /// recording).
    pub truth: Option<FrameTruth>,
    /// Per pixel, what it sees (`synthetic::Label` as `u8`), where the source knows.
    pub labels: Option<std::sync::Arc<[u8]>>,
    pub frames_received: u64,
    /// Name of the source ("synthetic", "fakenect:DIR", "kinect").
    pub source_name: String,
    /// What is wrong with the source (disconnected, a bad frame), cleared when frames flow
    /// again.
    pub error: Option<String>,
}

impl DepthFeed {
    /// Publishes a new frame: it becomes the latest and any error is cleared.
    pub fn publish(&mut self, frame: DepthFrame, truth: Option<FrameTruth>) {
        self.latest = Some(frame);
        self.truth = truth;
        self.frames_received += 1;
        self.error = None;
    }
}
