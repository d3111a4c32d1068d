//! The whole app without a window or a GPU: the MakeHuman avatar driven by the embedded CMU
//! walk (replayed as a 30 Hz Kinect v1 skeleton stream through the motion pipeline), stepped
//! with exact time, then read back from the `World`.
//!
//! `cargo run --release --example headless_avatar`

use bevy::prelude::*;
use fitroom::{AppOptions, Mode, headless};
use fitroom_body::plugin::AvatarJoint;
use fitroom_motion::plugin::AvatarMotion;

fn main() -> anyhow::Result<()> {
    let options = AppOptions::with_defaults(Mode::Headless { render: false })?;
    let mut app = headless::headless_app(&options)?;
    // Each update is 1/60 s of the recording.
    for _ in 0..120 {
        app.update();
    }
    let world = app.world_mut();
    let motion = world.resource::<AvatarMotion>();
    println!(
        "{} sensor frames posed the avatar, {} rejected by the gate",
        motion.frames_applied,
        motion.pipeline.gate.stats().rejected_total()
    );
    let skeleton = motion.pipeline.skeleton().clone();
    let mut joints = world.query::<(&AvatarJoint, &GlobalTransform)>();
    for (joint, global) in joints.iter(world) {
        let name = &skeleton.bones[joint.0].name;
        if ["pelvis", "head", "hand_l", "foot_r"].contains(&name.as_str()) {
            let p = global.translation();
            println!("{name:>8}: ({:+.2}, {:+.2}, {:+.2}) m", p.x, p.y, p.z);
        }
    }
    Ok(())
}
