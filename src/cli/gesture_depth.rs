//! `fitroom gesture depth-actions`: false actions through the whole chain. Each clip (nobody in
//! it is trying to click) drives the avatar that the synthetic Kinect films (with its noise,
//! on a treadmill); the recording goes through the tracker and the kiosk's gesture reader;
//! every swipe and every grip (cursor press) it makes is a false action. The skeleton-only
//! count (`fitroom gesture eval`) leaves out what the tracker and the hand reader add.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use fitroom_sensor::bvh::BvhClip;
use serde::Serialize;

use super::BodyArg;
use super::app::Inputs;
use super::gesture_run::gesture_run;
use super::sensor::{RecordArgs, record_synthetic};

/// One clip's false actions.
#[derive(Debug, Serialize)]
pub struct ClipActions {
    pub clip: String,
    pub seconds: f64,
    pub swipes: usize,
    pub presses: usize,
}

/// The report.
#[derive(Debug, Serialize)]
pub struct DepthActionsReport {
    pub clips: Vec<ClipActions>,
    pub seconds: f64,
    pub swipes: usize,
    pub presses: usize,
    pub per_10_min: f64,
}

/// Films each of `clips` (through `inputs`: the body, the configuration) and reads it.
pub fn depth_actions(
    clips: &[PathBuf],
    inputs: &Inputs,
    body: &BodyArg,
    distance_m: f32,
) -> Result<DepthActionsReport> {
    let scratch =
        std::env::temp_dir().join(format!("fitroom-depth-actions-{}", std::process::id()));
    let mut out = Vec::new();
    for (k, clip) in clips.iter().enumerate() {
        let result = one_clip(clip, inputs, body, distance_m, &scratch);
        // The scratch recording goes whatever happened.
        let _ = std::fs::remove_dir_all(&scratch);
        let clip_actions = result?;
        eprintln!(
            "[{}/{}] {}: {:.1} s, {} swipes, {} presses",
            k + 1,
            clips.len(),
            clip_actions.clip,
            clip_actions.seconds,
            clip_actions.swipes,
            clip_actions.presses
        );
        out.push(clip_actions);
    }
    let seconds: f64 = out.iter().map(|c| c.seconds).sum();
    let swipes = out.iter().map(|c| c.swipes).sum();
    let presses = out.iter().map(|c| c.presses).sum();
    Ok(DepthActionsReport {
        per_10_min: (swipes + presses) as f64 / seconds.max(1e-9) * 600.0,
        clips: out,
        seconds,
        swipes,
        presses,
    })
}

fn one_clip(
    clip: &Path,
    inputs: &Inputs,
    body: &BodyArg,
    distance_m: f32,
    scratch: &Path,
) -> Result<ClipActions> {
    let duration = BvhClip::load(clip)
        .with_context(|| format!("cannot read the clip '{}'", clip.display()))?
        .duration_s();
    let mut inputs = inputs.clone();
    inputs.motion = Some(clip.to_owned());
    let args = RecordArgs {
        synthetic: true,
        kinect: false,
        distance_m,
        frames: (duration * 30.0).floor().max(1.0) as usize,
        out: scratch.to_owned(),
        inputs,
    };
    record_synthetic(&args)
        .with_context(|| format!("cannot film the clip '{}'", clip.display()))?;
    let run = gesture_run(scratch, body)?;
    let name = clip.file_name().map_or_else(
        || clip.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    );
    Ok(ClipActions {
        clip: name,
        seconds: run.seconds,
        swipes: run.swipes,
        presses: run.presses,
    })
}
