//! `fitroom gesture run --dump DIR`: any depth recording through the tracker and the
//! gesture reader the kiosk runs; per frame, each hand's pixel, depth and state, and the
//! swipes and grips (cursor presses) it made, with their totals (false actions, on a
//! recording of someone who is not trying to click).

use std::path::Path;
use std::sync::Arc;

use anyhow::{Context, Result};
use fitroom_depth::DepthCamera;
use fitroom_depth::fakenect::Recording;
use fitroom_gesture::cursor::Click;
use fitroom_gesture::hand::classify::HandModel;
use fitroom_gesture::hand::region::HandJoints;
use fitroom_gesture::reader::GestureReader;
use fitroom_gesture::swipe::SwipeDirection;
use fitroom_gesture::{HandSide, HandState};
use serde::Serialize;

use super::BodyArg;

/// The report.
#[derive(Debug, Serialize)]
pub struct GestureRunReport {
    pub dump: String,
    pub seconds: f64,
    /// Swipes and presses over the recording (the kiosk's actions: next / previous, select).
    pub swipes: usize,
    pub presses: usize,
    pub frames: Vec<GestureFrame>,
}

/// One frame: both hands (left, right); empty when nobody was tracked.
#[derive(Debug, Serialize)]
pub struct GestureFrame {
    pub frame: usize,
    pub time_s: f64,
    pub hands: Vec<HandOut>,
    /// A swipe ended here, or the cursor's hand pressed (gripped) or released.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub swipe: Option<SwipeDirection>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub click: Option<Click>,
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
    let mut tracker = super::track::tracker(&model, &super::track::build_fit()?)?;
    let hands = HandModel::embedded()?;
    let recording = Recording::open(dump)?;
    let mut reader = GestureReader::new(Some(hands));
    let mut frames = Vec::new();
    let (mut swipes, mut presses, mut seconds) = (0, 0, 0.0);
    for (i, entry) in recording.depth_entries().enumerate() {
        let frame = recording
            .read_depth(entry, DepthCamera::default())
            .with_context(|| format!("{}: frame {i}", dump.display()))?;
        seconds = frame.time_s;
        let mut out = Vec::new();
        let (mut swipe, mut click) = (None, None);
        let tracked = tracker.track(&frame);
        if tracked.is_none() {
            // Nobody tracked: as in the kiosk, the reader gets a frame with no joint tracked
            // (the tracker plugin sends one), so a gesture under way is dropped.
            reader.step(&fitroom_sensor::SensorFrame::nobody(frame.time_s, i as u64));
        }
        if let Some(tracked) = tracked {
            let skeleton = tracked.sensor_frame(frame.time_s, i as u64);
            reader.read_hands(&skeleton, Some(&frame));
            for (k, side) in [HandSide::Left, HandSide::Right].into_iter().enumerate() {
                let joints = HandJoints::of_frame(&skeleton, side);
                let pixel = frame.camera.project(joints.hand).map(|p| [p.x, p.y]);
                out.push(HandOut {
                    hand: side,
                    pixel,
                    depth_m: joints.hand.z.is_finite().then_some(joints.hand.z),
                    state: reader.hands[k],
                    p_open: reader.p_open[k],
                });
            }
            let step = reader.step(&skeleton);
            swipe = step.swipe.map(|s| s.direction);
            click = step.click;
            swipes += usize::from(swipe.is_some());
            presses += usize::from(click == Some(Click::Press));
        }
        frames.push(GestureFrame {
            frame: i,
            time_s: frame.time_s,
            hands: out,
            swipe,
            click,
        });
    }
    Ok(GestureRunReport {
        dump: dump.display().to_string(),
        seconds,
        swipes,
        presses,
        frames,
    })
}
