//! `fitroom sensor`: sensor tools. Recording depth (the synthetic camera with its ground
//! truth, or a Kinect), inspecting a recording and a contact sheet of it, and a BVH clip's
//! facts.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use anyhow::{Context, Result, bail};
use clap::{Args, Subcommand};
use fitroom_body::plugin::{AvatarMeasurements, AvatarShape};
use fitroom_depth::DepthCamera;
use fitroom_depth::fakenect::{Recording, RecordingWriter};
use fitroom_depth::plugin::DepthFeed;
use fitroom_depth::truth::{BODY_FILE, TruthWriter};
use fitroom_freenect::{KinectOptions, KinectSource, SourceStatus};
use serde::Serialize;

use super::OutputArgs;
use super::app::Inputs;
use crate::kiosk::actions::TryOn;
use crate::{Mode, headless, sensors::SensorSpec};
use bevy::time::TimeUpdateStrategy;

#[derive(Subcommand)]
pub enum SensorCommand {
    /// A recording's facts (frames, rate, valid pixels, depth range, ground truth), or a BVH
    /// clip's (frame count, rate, duration, joints, skeleton kind).
    Inspect {
        /// A fakenect folder (with `INDEX.txt`) or a `.bvh` clip.
        path: PathBuf,
        #[command(flatten)]
        output: OutputArgs,
    },
    /// Record depth into a fakenect folder: the synthetic Kinect v1 seeing the avatar (with
    /// ground truth beside the dump), or a Kinect.
    Record(RecordArgs),
    /// A contact sheet of a recording's depth frames, colour-mapped (near warm, far cool,
    /// black: no reading).
    View {
        /// The fakenect folder.
        dir: PathBuf,
        /// The PNG to write.
        #[arg(long)]
        png: PathBuf,
        /// Frames on the sheet, spread evenly over the recording.
        #[arg(long, default_value_t = 12)]
        frames: usize,
        /// Frames per row.
        #[arg(long, default_value_t = 4)]
        columns: usize,
    },
}

#[derive(Args)]
pub struct RecordArgs {
    /// The synthetic Kinect v1 seeing the avatar (driven by `--motion`, shaped by `--shape`,
    /// wearing `--garment`), in a room.
    #[arg(long, conflicts_with = "kinect", required_unless_present = "kinect")]
    pub synthetic: bool,
    /// A Kinect v1 through libfreenect.
    #[arg(long)]
    pub kinect: bool,
    /// The avatar's distance from the sensor at the start, metres.
    #[arg(long, default_value_t = 2.5)]
    pub distance_m: f32,
    /// Depth frames to record (30 per second).
    #[arg(long, default_value_t = 90)]
    pub frames: usize,
    /// The folder to write (created; it must not hold a recording).
    #[arg(long)]
    pub out: PathBuf,
    #[command(flatten)]
    pub inputs: Inputs,
}

pub fn run(command: SensorCommand) -> Result<()> {
    match command {
        SensorCommand::Inspect { path, output } => inspect(&path, &output),
        SensorCommand::Record(args) => {
            let report = if args.kinect {
                record_kinect(&args)?
            } else {
                record_synthetic(&args)?
            };
            println!("{}", serde_json::to_string_pretty(&report)?);
            Ok(())
        }
        SensorCommand::View {
            dir,
            png,
            frames,
            columns,
        } => view(&dir, &png, frames, columns),
    }
}

fn inspect(path: &Path, output: &OutputArgs) -> Result<()> {
    if path.is_dir() {
        let summary = fitroom_depth::summary::summarise(path, DepthCamera::default())?;
        return output.print(&summary, |s| {
            println!(
                "{}: {} depth frames at {:.1} fps ({:.2} s), {:.0} % of pixels with a reading, \
                 depth {}, ground truth: {}",
                s.folder,
                s.depth_frames,
                s.fps,
                s.duration_s,
                s.valid_share * 100.0,
                s.depth_range_mm
                    .map_or("none".into(), |(a, b)| format!("{a}-{b} mm")),
                match s.ground_truth_lines {
                    Some(n) => format!("{n} lines"),
                    None => "none".into(),
                }
            );
        });
    }
    let info = fitroom_sensor::bvh_source::inspect(path)?;
    output.print_compact(&info, |info| {
        println!(
            "{}: {} frames at {:.1} fps ({:.2} s), {} joints, skeleton {}",
            path.display(),
            info.frames,
            info.fps,
            info.duration_s,
            info.joints,
            info.skeleton
        );
    })
}

/// What `fitroom sensor record` wrote.
#[derive(Debug, Serialize)]
pub struct RecordReport {
    pub out: String,
    pub source: String,
    pub depth_frames: usize,
    pub ground_truth: bool,
    pub seconds: f64,
    /// Mean share of pixels with a reading.
    pub valid_share: f64,
}

fn progress(frames: usize) -> indicatif::ProgressBar {
    let bar = indicatif::ProgressBar::new(frames as u64);
    if let Ok(style) =
        indicatif::ProgressStyle::with_template("{msg} {bar:40} {pos}/{len} frames ({eta})")
    {
        bar.set_style(style);
    }
    bar
}

/// The headless app with the synthetic sensor; every depth frame it renders is written with
/// its ground truth.
pub(super) fn record_synthetic(args: &RecordArgs) -> Result<RecordReport> {
    let start = Instant::now();
    let mut options = super::app::options(Mode::Headless { render: false }, &args.inputs)?;
    options.sensor = SensorSpec::Synthetic;
    options.distance_m = args.distance_m;
    let mut app = headless::headless_app(&options)?;
    // The person wears what `--garment` says, nothing without it (as `body.json` records):
    // the kiosk would dress a bare avatar in its carousel's first garment.
    if options.garment.is_none()
        && let Some(mut tryon) = app.world_mut().get_resource_mut::<TryOn>()
    {
        tryon.keep_bare = true;
    }
    // Every cloth step runs: a recording is made offline, and a step dropped because the
    // machine was busy would make two recordings of one seed differ.
    if let Some(mut cloth) = app
        .world_mut()
        .get_resource_mut::<fitroom_garment::plugin::ClothSettings>()
    {
        cloth.budget_ms = f32::INFINITY;
    }
    warm_up(&mut app, options.garment.is_some())?;
    let mut writer = RecordingWriter::create(&args.out)?;
    let mut truth = TruthWriter::create(&args.out)?;
    let bar = progress(args.frames);
    bar.set_message("synthetic Kinect");
    let (mut written, mut valid) = (0usize, 0.0f64);
    // A camera frame rendered before the garment was dressed shows the person bare: with a
    // garment, the recording starts at the next one.
    let mut seen = match options.garment {
        Some(_) => app.world().resource::<DepthFeed>().frames_received,
        None => 0,
    };
    // Two app frames (1/60 s each) per depth frame; the bound only stops a stalled run.
    for _ in 0..args.frames * 4 + 600 {
        if written == args.frames {
            break;
        }
        app.update();
        let feed = app.world().resource::<DepthFeed>();
        if feed.frames_received == seen {
            continue;
        }
        seen = feed.frames_received;
        let (Some(frame), Some(frame_truth)) = (&feed.latest, &feed.truth) else {
            continue;
        };
        let Some(raw) = &frame.raw else {
            bail!("the synthetic camera gave a frame without raw values");
        };
        writer.write_depth(frame.time_s, frame.timestamp, raw)?;
        let mut line = frame_truth.clone();
        line.frame = written;
        truth.write(&line)?;
        valid += frame.valid_share();
        written += 1;
        bar.inc(1);
    }
    bar.finish_and_clear();
    truth.finish()?;
    if written < args.frames {
        bail!(
            "the synthetic camera rendered {written} of {} frames: the avatar did not appear (is the body file readable?)",
            args.frames
        );
    }
    let world = app.world();
    let body = serde_json::json!({
        "shape": world.get_resource::<AvatarShape>().map(|s| &s.0),
        "measurements_cm": world.get_resource::<AvatarMeasurements>().and_then(|m| m.measurements.as_ref()),
        "motion": options.motion.display().to_string(),
        "garment": options.garment.as_ref().map(|g| g.display().to_string()),
        "size": options.garment_size,
        "distance_m": args.distance_m,
        "treadmill": options.treadmill,
        "seed": options.depth_seed,
    });
    let body_path = args.out.join(BODY_FILE);
    std::fs::write(&body_path, serde_json::to_string_pretty(&body)?)
        .with_context(|| format!("cannot write '{}'", body_path.display()))?;
    Ok(RecordReport {
        out: args.out.display().to_string(),
        source: "synthetic".into(),
        depth_frames: written,
        ground_truth: true,
        seconds: start.elapsed().as_secs_f64(),
        valid_share: valid / written.max(1) as f64,
    })
}

/// Runs the app until the avatar moves and wears what it was asked to, so that the
/// recording's first frame shows it. The garment is dressed when its file has loaded, which
/// takes wall-clock time: the clock stands still from the avatar's first pose until then, so
/// that the clip starts at the same moment, and a seed records the same frames, however long
/// the load took.
fn warm_up(app: &mut bevy::app::App, garment: bool) -> Result<()> {
    let step = app
        .world()
        .get_resource::<TimeUpdateStrategy>()
        .and_then(|s| match s {
            TimeUpdateStrategy::ManualDuration(d) => Some(*d),
            _ => None,
        })
        .context("the headless app steps its clock by hand")?;
    // Up to 10 s of simulated time for the avatar to move, then up to 30 s of wall time for
    // the garment's file.
    let mut updates = 0;
    let mut frozen_since: Option<Instant> = None;
    loop {
        app.update();
        let world = app.world_mut();
        let moving = world
            .get_resource::<fitroom_motion::plugin::AvatarMotion>()
            .is_some_and(|m| m.frames_applied > 0);
        let mut worn = world.query::<&fitroom_garment::plugin::WornGarment>();
        let dressed = worn.iter(world).any(|g| !g.surface().0.is_empty());
        if let Some(error) = world
            .get_resource::<fitroom_garment::plugin::GarmentStatus>()
            .and_then(|s| s.error.clone())
        {
            bail!("the garment cannot be worn: {error}");
        }
        if moving && (dressed || !garment) {
            app.insert_resource(TimeUpdateStrategy::ManualDuration(step));
            return Ok(());
        }
        match frozen_since {
            None if moving => {
                frozen_since = Some(Instant::now());
                app.insert_resource(TimeUpdateStrategy::ManualDuration(Duration::ZERO));
            }
            None => {
                updates += 1;
                if updates >= 600 {
                    bail!("the avatar did not start moving within 10 s of simulated time");
                }
            }
            Some(since) if since.elapsed() > Duration::from_secs(30) => {
                bail!(
                    "the avatar was not dressed within 30 s of its first pose (the garment's file did not load)"
                );
            }
            // The file loads on the asset threads.
            Some(_) => std::thread::sleep(Duration::from_millis(1)),
        }
    }
}

/// A Kinect's frames as they come; stops after `--frames` or when the device is gone for
/// five seconds.
fn record_kinect(args: &RecordArgs) -> Result<RecordReport> {
    let start = Instant::now();
    let mut kinect = KinectSource::open(KinectOptions::default())?;
    let mut writer = RecordingWriter::create(&args.out)?;
    let bar = progress(args.frames);
    bar.set_message(kinect.library().to_string());
    let (mut written, mut valid) = (0usize, 0.0f64);
    let mut quiet = Instant::now();
    while written < args.frames {
        match kinect.next_timeout(Duration::from_millis(200)) {
            Some(frame) => {
                let Some(raw) = &frame.raw else { continue };
                writer.write_depth(frame.time_s, frame.timestamp, raw)?;
                valid += frame.valid_share();
                written += 1;
                bar.inc(1);
                quiet = Instant::now();
            }
            None => match kinect.status() {
                SourceStatus::Ended => break,
                SourceStatus::Disconnected { reason } if quiet.elapsed().as_secs() >= 5 => {
                    bar.finish_and_clear();
                    bail!("no frames from the Kinect for 5 s: {reason}");
                }
                _ => {}
            },
        }
    }
    bar.finish_and_clear();
    Ok(RecordReport {
        out: args.out.display().to_string(),
        source: format!("kinect ({})", kinect.library()),
        depth_frames: written,
        ground_truth: false,
        seconds: start.elapsed().as_secs_f64(),
        valid_share: valid / written.max(1) as f64,
    })
}

fn view(dir: &Path, png: &Path, frames: usize, columns: usize) -> Result<()> {
    let recording = Recording::open(dir)?;
    let sheet = fitroom_depth::sheet::contact_sheet(
        &recording,
        DepthCamera::default(),
        columns.max(1),
        frames.max(1),
        2,
    )?;
    let image = image::RgbImage::from_raw(sheet.width, sheet.height, sheet.rgb)
        .context("the contact sheet has the wrong size for its image")?;
    image
        .save(png)
        .with_context(|| format!("cannot write '{}'", png.display()))?;
    println!(
        "{}: {} frames of {} ({}x{})",
        png.display(),
        sheet.frames.len(),
        dir.display(),
        sheet.width,
        sheet.height
    );
    Ok(())
}
