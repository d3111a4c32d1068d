//! The commands that build an App: `fitroom kiosk` (the default), `fitroom design` and
//! `fitroom run --headless`.

use std::path::PathBuf;

use anyhow::{Context, Result};
use bevy::{
    prelude::*,
    render::view::screenshot::{Screenshot, save_to_disk},
};

use super::{BodyArg, Noise};
use crate::{AppOptions, Mode, build_app, headless, sensors::SensorSpec};

/// What the app loads: configuration, body, motion, shape, garment.
#[derive(clap::Args, Clone)]
pub struct Inputs {
    /// The kiosk configuration (RON; default: assets/kiosk.ron): sensor, timings, garments,
    /// display. Edits are followed while the app runs.
    #[arg(long)]
    pub config: Option<PathBuf>,
    #[command(flatten)]
    pub body: BodyArg,
    /// Where frames come from: `bvh:FILE` (a recorded clip), `synthetic` (the synthetic
    /// Kinect v1 seeing the avatar, which the clip drives), `performer` or `performer:FILE`
    /// (the synthetic Kinect v1 filming a performer who plays the clip, or FILE: a clip or a
    /// gesture script such as assets/motions/gestures.ron, in which the person swipes and
    /// grips; our tracker drives the avatar), `fakenect:DIR` (a depth recording), `kinect` (a
    /// Kinect v1 through libfreenect). Default: the configuration's (`performer`).
    #[arg(long)]
    pub sensor: Option<String>,
    /// With the synthetic sensor: a box (0.5 x 1 x 0.5 m) standing at sensor-space X,Z metres
    /// (e.g. `0.9,2.4`: to the sensor's left, 2.4 m away).
    #[arg(long, value_name = "X,Z", value_parser = parse_xz, allow_hyphen_values = true)]
    pub synthetic_box: Option<[f32; 2]>,
    /// With the synthetic sensor: a second person standing still at X,Z (e.g. `-1.0,3.3`).
    #[arg(long, value_name = "X,Z", value_parser = parse_xz, allow_hyphen_values = true)]
    pub synthetic_person: Option<[f32; 2]>,
    /// Play a `fakenect:DIR` recording this many times as fast as it was recorded.
    #[arg(long, default_value_t = 1.0)]
    pub replay_speed: f64,
    /// Play a `fakenect:DIR` recording once instead of looping it.
    #[arg(long)]
    pub replay_once: bool,
    /// BVH clip that drives the avatar (default: the embedded assets/motions/walk.bvh), or
    /// with the `performer` sensor a gesture script (`.ron`).
    #[arg(long)]
    pub motion: Option<PathBuf>,
    /// Replay the clip on a treadmill: the performer's hip centre stays where it is at the
    /// clip's first frame (horizontally; the feet slide), so a walk stays in the sensor's
    /// view and range. Default: the configuration's `treadmill`.
    #[arg(long, conflicts_with = "no_treadmill")]
    pub treadmill: bool,
    /// Replay the clip as recorded (the performer travels), whatever the configuration says.
    #[arg(long)]
    pub no_treadmill: bool,
    /// `kinect`: replay the clip through the Kinect v1 noise model (to see the filters work);
    /// `none`: the clean recording.
    #[arg(long, value_enum, default_value_t = Noise::None)]
    pub noise: Noise,
    /// Seed of the noise models (the skeleton noise of `--noise kinect`, the synthetic depth
    /// camera).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// The avatar's body shape (RON, e.g. from `fitroom body fit --out`); the body panel (B)
    /// saves to this file too.
    #[arg(long)]
    pub shape: Option<PathBuf>,
    /// Open the body panel at start.
    #[arg(long)]
    pub body_panel: bool,
    /// A garment for the avatar (pattern .ron, e.g. assets/garments/sundress.ron).
    #[arg(long)]
    pub garment: Option<PathBuf>,
    /// The garment's size (a label of its size chart; default: its middle size).
    #[arg(long)]
    pub size: Option<String>,
    /// Colour the garment by strain (the fit map).
    #[arg(long)]
    pub fit_map: bool,
}

/// `fitroom kiosk`.
#[derive(clap::Args)]
pub struct KioskArgs {
    /// A window instead of full screen.
    #[arg(long)]
    pub windowed: bool,
    /// Save a screenshot of the window after `--frames` frames, then quit.
    #[arg(long)]
    pub screenshot: Option<PathBuf>,
    /// Frames to run before the screenshot.
    #[arg(long, default_value_t = 180)]
    pub frames: u32,
    /// Start with the raw and filtered sensor skeletons drawn (the D key toggles them).
    #[arg(long)]
    pub skeletons: bool,
    /// Kiosk actions performed once the avatar wears its first garment in Try on (e.g.
    /// `compare` for two sizes side by side, `next,select`, `toggle-fit-map`).
    #[arg(long, value_enum, value_delimiter = ',')]
    pub actions: Vec<crate::kiosk::actions::KioskAction>,
    #[command(flatten)]
    pub inputs: Inputs,
}

/// `fitroom design`.
#[derive(clap::Args)]
pub struct DesignArgs {
    /// The garment file (pattern .ron, .obj, .glb). (Not named `garment`: the flattened
    /// inputs have a `--garment`, and clap needs unique argument names.)
    #[arg(value_name = "GARMENT")]
    pub file: PathBuf,
    /// Save a screenshot of the window after `--frames` frames, then quit.
    #[arg(long)]
    pub screenshot: Option<PathBuf>,
    /// Frames to run before the screenshot.
    #[arg(long, default_value_t = 180)]
    pub frames: u32,
    /// The designer's starting pose.
    #[arg(long, value_enum, default_value_t = DesignPose::APose)]
    pub pose: DesignPose,
    #[command(flatten)]
    pub inputs: Inputs,
}

/// The designer's poses.
#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub enum DesignPose {
    /// The avatar's rest pose: arms down and away from the body.
    APose,
    /// Arms raised sideways.
    TPose,
    /// The configured clip, looped.
    Walk,
}

/// `fitroom run`.
#[derive(clap::Args)]
pub struct RunArgs {
    /// Required: no window (the only mode of `run`).
    #[arg(long)]
    pub headless: bool,
    /// Frames to run (1/60 s of the recording each).
    #[arg(long, default_value_t = 120)]
    pub frames: u32,
    /// Render the last frame offscreen (any Vulkan adapter, Mesa lavapipe included).
    #[arg(long)]
    pub screenshot: Option<PathBuf>,
    /// Write the JSON report here (it is printed to stdout as well).
    #[arg(long)]
    pub report: Option<PathBuf>,
    #[command(flatten)]
    pub inputs: Inputs,
}

/// `X,Z` in metres, both finite.
fn parse_xz(text: &str) -> Result<[f32; 2], String> {
    let parse = |s: &str| s.trim().parse::<f32>().ok().filter(|v| v.is_finite());
    match text.split_once(',') {
        Some((x, z)) => match (parse(x), parse(z)) {
            (Some(x), Some(z)) => Ok([x, z]),
            _ => Err(format!(
                "\"{text}\": give two numbers in metres, X,Z (e.g. 0.9,2.4)"
            )),
        },
        None => Err(format!("\"{text}\": give X,Z in metres (e.g. 0.9,2.4)")),
    }
}

/// The app's options from the command line's inputs (the configuration's defaults for what
/// they leave out).
pub fn options(mode: Mode, inputs: &Inputs) -> Result<AppOptions> {
    let defaults = match &inputs.config {
        Some(config) => AppOptions::with_config(mode.clone(), config)?,
        None => AppOptions::with_defaults(mode.clone())?,
    };
    let body = inputs.body.body.clone().unwrap_or(defaults.body);
    if !(inputs.replay_speed.is_finite() && inputs.replay_speed > 0.0) {
        anyhow::bail!(
            "--replay-speed is {}; give a positive factor (1 = the recorded pace)",
            inputs.replay_speed
        );
    }
    let sensor = match &inputs.sensor {
        Some(spec) => spec
            .parse::<SensorSpec>()
            .context("--sensor is not a sensor")?,
        None => defaults.sensor,
    };
    let motion = match (&inputs.motion, &sensor) {
        (Some(motion), _) => motion.clone(),
        (None, SensorSpec::Bvh(clip) | SensorSpec::Performer(Some(clip))) => clip.clone(),
        (None, _) => defaults.motion,
    };
    let sensor = sensor.with_clip(&motion);
    let noise_seed = match inputs.noise {
        Noise::None => None,
        Noise::Kinect => Some(inputs.seed),
    };
    let shape = match &inputs.shape {
        Some(path) if path.exists() => Some(super::body::load_shape(Some(path))?),
        Some(path) => {
            eprintln!(
                "note: the shape file '{}' does not exist yet: the default body; the body \
                 panel (B) saves there",
                path.display()
            );
            None
        }
        None => None,
    };
    Ok(AppOptions {
        mode,
        body,
        sensor,
        motion,
        depth_seed: inputs.seed,
        distance_m: defaults.distance_m,
        treadmill: (inputs.treadmill || defaults.treadmill) && !inputs.no_treadmill,
        extras: crate::depth_scene::Extras {
            box_at: inputs.synthetic_box,
            person_at: inputs.synthetic_person,
        },
        replay: crate::sensors::Replay {
            speed: inputs.replay_speed,
            looping: !inputs.replay_once,
        },
        image_size: UVec2::new(960, 720),
        noise_seed,
        shape,
        shape_path: inputs
            .shape
            .clone()
            .unwrap_or_else(|| PathBuf::from("shape.ron")),
        body_panel: inputs.body_panel,
        garment: inputs.garment.clone(),
        garment_size: inputs.size.clone(),
        fit_map: inputs.fit_map,
        config: defaults.config,
        config_path: defaults.config_path,
    })
}

/// `fitroom kiosk`: the mirror in a window.
pub fn kiosk(args: KioskArgs) -> Result<()> {
    let mode = Mode::Kiosk {
        windowed: args.windowed,
    };
    let mut app = build_app(&options(mode, &args.inputs)?)?;
    app.insert_resource(crate::kiosk::DebugSkeletons(args.skeletons));
    app.insert_resource(crate::kiosk::actions::StartActions(args.actions));
    if let Some(path) = args.screenshot {
        app.add_systems(Update, screenshot_then_quit(path, args.frames));
    }
    app.run();
    Ok(())
}

/// `fitroom design`: the garment designer in a window.
pub fn design(args: DesignArgs) -> Result<()> {
    let DesignArgs {
        file: garment,
        screenshot,
        frames,
        pose,
        mut inputs,
    } = args;
    inputs.garment = Some(garment);
    let motion = match pose {
        DesignPose::APose => {
            crate::design::DesignMotion::Still(fitroom_motion::still_pose::StillPose::APose)
        }
        DesignPose::TPose => {
            crate::design::DesignMotion::Still(fitroom_motion::still_pose::StillPose::TPose)
        }
        DesignPose::Walk => crate::design::DesignMotion::Clip,
    };
    let mut app = build_app(&options(Mode::Design, &inputs)?)?;
    app.world_mut()
        .resource_mut::<crate::design::Designer>()
        .motion = motion;
    if let Some(path) = screenshot {
        app.add_systems(Update, screenshot_then_quit(path, frames));
    }
    app.run();
    Ok(())
}

/// `fitroom run --headless`: the pipeline without a window; prints (and writes) the report.
pub fn run_headless(args: RunArgs) -> Result<()> {
    if !args.headless {
        anyhow::bail!(
            "`fitroom run` runs without a window: pass --headless (for the kiosk window, run `fitroom kiosk`)"
        );
    }
    let render = args.screenshot.is_some();
    let result = headless::run(
        &options(Mode::Headless { render }, &args.inputs)?,
        args.frames,
        args.screenshot.as_deref(),
    )?;
    let json = serde_json::to_string_pretty(&result)?;
    if let Some(path) = args.report {
        std::fs::write(&path, &json)
            .with_context(|| format!("cannot write the report '{}'", path.display()))?;
    }
    println!("{json}");
    Ok(())
}

/// After `frames` frames, saves a screenshot of the primary window and quits.
pub fn screenshot_then_quit(
    path: PathBuf,
    frames: u32,
) -> impl FnMut(Commands, MessageWriter<AppExit>, Local<u32>) {
    move |mut commands, mut exit, mut count| {
        *count += 1;
        if *count == frames {
            commands
                .spawn(Screenshot::primary_window())
                .observe(save_to_disk(path.clone()));
        }
        // The capture is written a few frames later.
        if *count == frames + 30 {
            exit.write(AppExit::Success);
        }
    }
}
