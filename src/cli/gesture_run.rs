//! `fitroom gesture run --dump DIR`: any depth recording through the tracker and the hand
//! reader; per frame, each hand's pixel, depth and state.

use std::path::Path;
use std::sync::Arc;

use anyhow::{Context, Result};
use fitroom_depth::DepthCamera;
use fitroom_depth::fakenect::Recording;
use fitroom_gesture::hand::classify::{HandModel, look};
use fitroom_gesture::hand::region::HandJoints;
use fitroom_gesture::hand::state::HandFilter;
use fitroom_gesture::{HandSide, HandState};
use fitroom_tracker::{Tracker, TrackerSettings};
use serde::Serialize;

use super::BodyArg;

/// The report.
#[derive(Debug, Serialize)]
pub struct GestureRunReport {
    pub dump: String,
    pub frames: Vec<GestureFrame>,
}

/// One frame: both hands (left, right); empty when nobody was tracked.
#[derive(Debug, Serialize)]
pub struct GestureFrame {
    pub frame: usize,
    pub time_s: f64,
    pub hands: Vec<HandOut>,
}

#[derive(Debug, Serialize)]
pub struct HandOut {
    pub hand: HandSide,
    /// The hand joint's pixel (column, row) and depth (metres).
    pub pixel: Option<[f32; 2]>,
    pub depth_m: Option<f32>,
    /// The state after the hysteresis, and this frame's probability of open.
    pub state: HandState,
    pub p_open: f32,
}

pub fn gesture_run(dump: &Path, body: &BodyArg) -> Result<GestureRunReport> {
    let model = Arc::new(body.load()?);
    let mut tracker = Tracker::estimating(model, TrackerSettings::default())
        .context("the body cannot be tracked (its rig lacks a bone the tracker needs)")?;
    let hands = HandModel::embedded()?;
    let recording = Recording::open(dump)?;
    let mut filters = [HandFilter::default(); 2];
    let mut frames = Vec::new();
    for (i, entry) in recording.depth_entries().enumerate() {
        let frame = recording
            .read_depth(entry, DepthCamera::default())
            .with_context(|| format!("{}: frame {i}", dump.display()))?;
        let mut out = Vec::new();
        if let Some(tracked) = tracker.track(&frame) {
            let skeleton = tracked.sensor_frame(frame.time_s, i as u64);
            for (k, side) in [HandSide::Left, HandSide::Right].into_iter().enumerate() {
                let joints = HandJoints::of_frame(&skeleton, side);
                let seen = look(&frame, &joints, &hands);
                let state = filters[k].update(&seen);
                let pixel = frame.camera.project(joints.hand).map(|p| [p.x, p.y]);
                out.push(HandOut {
                    hand: side,
                    pixel,
                    depth_m: joints.hand.z.is_finite().then_some(joints.hand.z),
                    state,
                    p_open: seen.p_open,
                });
            }
        }
        frames.push(GestureFrame {
            frame: i,
            time_s: frame.time_s,
            hands: out,
        });
    }
    Ok(GestureRunReport {
        dump: dump.display().to_string(),
        frames,
    })
}
