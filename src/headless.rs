//! Headless runs: step the full app a fixed number of frames with exact time, optionally render
//! one offscreen image, and report stage timings and the avatar's final joints.

use std::{
    collections::BTreeMap,
    path::Path,
    sync::{Arc, Mutex},
};

use anyhow::{Context, Result, bail};
use bevy::{
    prelude::*,
    render::view::screenshot::{Screenshot, ScreenshotCaptured},
};
use fitroom_body::plugin::AvatarJoint;
use fitroom_motion::plugin::AvatarMotion;
use fitroom_sensor::plugin::SensorFeed;
use serde::Serialize;

use crate::{
    AppOptions, Mode, OffscreenTarget, build_app, kiosk,
    timing::{Stage, StageSummary, StageTimings},
};

/// The JSON report of `fitroom run --headless`.
#[derive(Debug, Serialize)]
pub struct HeadlessReport {
    pub frames: u32,
    pub simulated_s: f64,
    pub sensor_source: String,
    pub sensor_frames: u64,
    /// Time to load the body asset, milliseconds.
    pub body_load_ms: f64,
    /// CPU time per pipeline stage.
    pub stages_ms: BTreeMap<String, StageSummary>,
    /// Path length of the avatar's pelvis over the run, metres.
    pub root_path_m: f32,
    /// Sensor frames the bad-frame gate kept from the avatar.
    pub rejected_frames: u64,
    /// Avatar leg length / performer leg length used to scale root motion.
    pub retarget_scale: Option<f32>,
    /// World positions of every avatar joint at the last frame, metres.
    pub joints: BTreeMap<String, [f32; 3]>,
    pub screenshot: Option<String>,
}

/// The avatar's root path, accumulated from each new pose.
#[derive(Resource, Default, Debug)]
pub struct RootPath {
    last: Option<Vec3>,
    pub length_m: f32,
}

fn track_root_path(motion: Option<Res<AvatarMotion>>, mut path: ResMut<RootPath>) {
    let Some(motion) = motion else { return };
    if !motion.is_changed() || motion.frames_applied == 0 {
        return;
    }
    let Some(pelvis) = motion.pipeline.skeleton().index_of("pelvis") else {
        return;
    };
    let Some(&head) = motion.pose.heads.get(pelvis) else {
        return;
    };
    if let Some(last) = path.last {
        path.length_m += last.distance(head);
    }
    path.last = Some(head);
}

/// Builds the app for a headless run (with offscreen rendering when `render`).
pub fn headless_app(options: &AppOptions) -> Result<App> {
    if !matches!(options.mode, Mode::Headless { .. }) {
        bail!("headless_app needs Mode::Headless");
    }
    let mut app = build_app(options)?;
    app.init_resource::<RootPath>().add_systems(
        PostUpdate,
        track_root_path
            .in_set(fitroom_schedule::FitroomSystems::Ui)
            .after(kiosk::KioskSystems::Flow),
    );
    app.finish();
    app.cleanup();
    Ok(app)
}

/// Renders one image of the current scene and returns it as RGBA8.
pub fn capture(app: &mut App) -> Result<image::RgbaImage> {
    let Some(target) = app.world().get_resource::<OffscreenTarget>().cloned() else {
        bail!("this app has no offscreen camera: build it with Mode::Headless {{ render: true }}");
    };
    kiosk::snap_camera(app.world_mut());
    let slot: Arc<Mutex<Option<Image>>> = Arc::default();
    let sink = slot.clone();
    app.world_mut().spawn(Screenshot::image(target.0)).observe(
        move |captured: On<ScreenshotCaptured>| {
            if let Ok(mut slot) = sink.lock() {
                *slot = Some(captured.image.clone());
            }
        },
    );
    for _ in 0..120 {
        app.update();
        let taken = slot.lock().ok().and_then(|mut s| s.take());
        if let Some(image) = taken {
            let dynamic = image.try_into_dynamic().map_err(|e| {
                anyhow::anyhow!("the captured image has an unexpected format: {e:?}")
            })?;
            return Ok(dynamic.to_rgba8());
        }
    }
    bail!(
        "the renderer produced no image within 120 frames (is a Vulkan driver installed? try `apt-get install mesa-vulkan-drivers`)"
    )
}

/// World positions of the avatar's joints by name.
pub fn joint_positions(app: &mut App) -> BTreeMap<String, [f32; 3]> {
    let world = app.world_mut();
    let mut query = world.query::<(&AvatarJoint, &Name, &GlobalTransform)>();
    query
        .iter(world)
        .map(|(_, name, transform)| {
            (
                name.as_str().to_string(),
                transform.translation().to_array(),
            )
        })
        .collect()
}

/// Runs `frames` updates and reports; saves a screenshot when asked.
pub fn run(options: &AppOptions, frames: u32, screenshot: Option<&Path>) -> Result<HeadlessReport> {
    let mut app = headless_app(options)?;
    for _ in 0..frames {
        app.update();
    }
    let screenshot = match screenshot {
        Some(path) => {
            let image = capture(&mut app)?;
            image
                .save(path)
                .with_context(|| format!("cannot write the screenshot '{}'", path.display()))?;
            Some(path.display().to_string())
        }
        None => None,
    };
    let world = app.world();
    let timings = world.resource::<StageTimings>();
    let stages_ms = Stage::ALL
        .iter()
        .map(|s| (s.name().to_string(), timings.summary(*s)))
        .collect();
    let feed = world.resource::<SensorFeed>();
    let motion = world.get_resource::<AvatarMotion>();
    let report = HeadlessReport {
        frames,
        simulated_s: f64::from(frames) / 60.0,
        sensor_source: feed.source_name.clone(),
        sensor_frames: feed.frames_received,
        body_load_ms: world.resource::<crate::LoadTimings>().body_load_ms,
        stages_ms,
        root_path_m: world.resource::<RootPath>().length_m,
        retarget_scale: motion
            .and_then(|m| m.pipeline.retargeter().calibration())
            .map(|c| c.scale),
        rejected_frames: motion.map_or(0, |m| m.pipeline.gate.stats().rejected_total()),
        joints: BTreeMap::new(),
        screenshot,
    };
    Ok(HeadlessReport {
        joints: joint_positions(&mut app),
        ..report
    })
}
