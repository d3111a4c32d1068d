//! `fitroom track`: seeing the person in depth recordings. `eval` measures the skeleton
//! tracker against ground truth (recordings, or a clip rendered on the fly); `run` tracks any
//! recording and prints every joint of every frame; `extrema` measures the tracker's starting
//! detector (segmentation, then geodesic extrema for head, hands and feet).

use std::path::{Path, PathBuf};
use std::sync::Arc;

use anyhow::{Context, Result, bail};
use clap::Subcommand;
use fitroom_body::BodyModel;
use fitroom_depth::DepthCamera;
use fitroom_depth::fakenect::Recording;
use fitroom_depth::truth::read_truth;
use fitroom_math::stats::Summary;
use fitroom_measure::ShapePrior;
use fitroom_measure::build::TrackedBuild;
use fitroom_sensor::KinectJoint;
use fitroom_tracker::eval::{EvalReport, Evaluation};
use fitroom_tracker::{
    Part, SegmentSettings, Segmenter, Tracker, TrackerSettings, geodesic_extrema,
};
use glam::Vec3;
use serde::Serialize;

use super::app::Inputs;
use super::sensor::{RecordArgs, record_synthetic};
use super::{BodyArg, OutputArgs};

#[derive(Subcommand)]
pub enum TrackCommand {
    /// The skeleton tracker against ground truth: per-joint mean and 95th-percentile 3D
    /// error, the share of frames with every joint tracked or inferred, restarts, time per
    /// frame. On recordings (`--dump`, repeat it: one report over all of them, and a line
    /// each), or on a clip rendered by the synthetic camera on the fly (`--motion`, with
    /// `--shape`, `--garment`, `--size`, `--seed`).
    Eval {
        /// A recording with ground truth (`fitroom sensor record --synthetic`).
        #[arg(long, conflicts_with = "motion")]
        dump: Vec<PathBuf>,
        /// Frames to render on the fly.
        #[arg(long, default_value_t = 150)]
        frames: usize,
        /// The avatar's distance from the sensor on the fly, metres.
        #[arg(long, default_value_t = 2.5)]
        distance_m: f32,
        /// A picture (PNG) of four frames of the first recording, side by side and cut to
        /// the person: depth, the person found, the ground-truth skeleton (magenta) and the
        /// tracked one (green: tracked, yellow: inferred).
        #[arg(long)]
        png: Option<PathBuf>,
        #[command(flatten)]
        inputs: Box<Inputs>,
        #[command(flatten)]
        output: OutputArgs,
    },
    /// Tracks any recording (ground truth or not): per frame, each joint's position (sensor
    /// space, metres), its pixel in the depth image and its confidence.
    Run {
        /// A fakenect recording.
        #[arg(long)]
        dump: PathBuf,
        /// The body the tracker fits (default: the shipped MakeHuman body).
        #[command(flatten)]
        body: BodyArg,
        #[command(flatten)]
        output: OutputArgs,
    },
    /// Head, hands and feet found as geodesic extrema in every frame of a synthetic
    /// recording, their joints estimated from the surface around each end, against the
    /// ground-truth joints: per part, the share of frames within 15 cm, the distance's mean
    /// and 95th percentile.
    Extrema {
        /// A recording with ground truth (`fitroom sensor record --synthetic`).
        #[arg(long)]
        dump: PathBuf,
        #[command(flatten)]
        output: OutputArgs,
    },
}

pub fn run(command: TrackCommand) -> Result<()> {
    match command {
        TrackCommand::Eval {
            dump,
            frames,
            distance_m,
            png,
            inputs,
            output,
        } => {
            let report = if dump.is_empty() {
                eval_on_the_fly(*inputs, frames, distance_m, png.as_deref())?
            } else {
                eval(&dump, &inputs.body, png.as_deref())?
            };
            output.print(&report, print_eval)
        }
        TrackCommand::Run { dump, body, output } => {
            let report = track_run(&dump, &body)?;
            output.print_compact(&report, |r| {
                for f in &r.frames {
                    let tracked = f
                        .joints
                        .iter()
                        .filter(|j| j.confidence == fitroom_tracker::Confidence::Tracked)
                        .count();
                    println!(
                        "frame {:>4} {:>8.3} s: {}",
                        f.frame,
                        f.time_s,
                        if f.joints.is_empty() {
                            "no one".to_string()
                        } else {
                            format!("{tracked} of 20 joints tracked")
                        }
                    );
                }
            })
        }
        TrackCommand::Extrema { dump, output } => {
            let report = extrema(&dump)?;
            output.print(&report, |r| {
                println!(
                    "{}: {} frames, a person found in {}",
                    r.dump, r.frames, r.segmented
                );
                for p in &r.parts {
                    println!(
                        "  {:<10} within 15 cm in {:>5.1} % of frames; distance mean {:.0} mm, p95 {:.0} mm",
                        p.part, p.within_15cm_pct, p.mean_mm, p.p95_mm
                    );
                }
            })
        }
    }
}

/// One part's figures.
#[derive(Debug, Serialize)]
pub struct PartReport {
    pub part: String,
    /// Frames where the part was named and lay within 15 cm of its joint, %.
    pub within_15cm_pct: f64,
    /// Distance to its joint where named, mm.
    pub mean_mm: f64,
    pub p95_mm: f64,
    pub named_in: usize,
}

/// `fitroom track extrema`'s report.
#[derive(Debug, Serialize)]
pub struct ExtremaReport {
    pub dump: String,
    pub frames: usize,
    pub segmented: usize,
    pub parts: Vec<PartReport>,
}

/// The Kinect joint each part's estimated joint is compared with.
const PARTS: [(Part, KinectJoint); 5] = [
    (Part::Head, KinectJoint::Head),
    (Part::HandLeft, KinectJoint::HandLeft),
    (Part::HandRight, KinectJoint::HandRight),
    (Part::FootLeft, KinectJoint::FootLeft),
    (Part::FootRight, KinectJoint::FootRight),
];

fn extrema(dump: &Path) -> Result<ExtremaReport> {
    let recording = Recording::open(dump)?;
    let Some(truth) = read_truth(dump)? else {
        bail!(
            "'{}' has no ground truth (groundtruth.jsonl): record one with `fitroom sensor record --synthetic`",
            dump.display()
        );
    };
    let camera = DepthCamera::default();
    let mut segmenter = Segmenter::new(SegmentSettings::default());
    let mut distances: Vec<Vec<f64>> = vec![Vec::new(); PARTS.len()];
    let (mut frames, mut segmented) = (0, 0);
    for (entry, line) in recording.depth_entries().zip(&truth) {
        frames += 1;
        let frame = recording
            .read_depth(entry, camera)
            .with_context(|| format!("frame {}", line.frame))?;
        let Some(person) = segmenter.segment(&frame) else {
            continue;
        };
        segmented += 1;
        let ends = geodesic_extrema(&frame, &person);
        for (k, (part, joint)) in PARTS.iter().enumerate() {
            let Some(found) = ends.iter().find(|e| e.part == *part) else {
                continue;
            };
            let Some(&truth) = line.joints.get(joint.index()) else {
                continue;
            };
            distances[k].push(f64::from(found.joint.distance(Vec3::from_array(truth))));
        }
    }
    let parts = PARTS
        .iter()
        .zip(&distances)
        .map(|((part, _), d)| {
            let summary = Summary::of(d);
            PartReport {
                part: format!("{part:?}"),
                within_15cm_pct: 100.0 * d.iter().filter(|&&x| x < 0.15).count() as f64
                    / frames.max(1) as f64,
                mean_mm: summary.mean * 1000.0,
                p95_mm: summary.p95 * 1000.0,
                named_in: d.len(),
            }
        })
        .collect();
    Ok(ExtremaReport {
        dump: dump.display().to_string(),
        frames,
        segmented,
        parts,
    })
}

/// `fitroom track eval`'s report: over all recordings, and each one's.
#[derive(Debug, Serialize)]
pub struct TrackEvalReport {
    pub overall: EvalReport,
    pub recordings: Vec<RecordingEval>,
}

/// One recording's figures: its evaluation, and what the tracker found of the person.
#[derive(Debug, Serialize)]
pub struct RecordingEval {
    pub dump: String,
    #[serde(flatten)]
    pub report: EvalReport,
    /// The person's height as the tracker sized them in the last frame tracked, cm (the
    /// recording's own is in its `body.json`, `stature_cm`).
    pub stature_cm: Option<f64>,
    /// The clothing layer the person was found to wear (the build's search tries one on the
    /// trunk and upper arms), cm; `None`: no build found.
    pub clothing_cm: Option<f64>,
    /// The median inward step seen in the outline of the person's hanging upper arms, where a
    /// short sleeve ends, mm (`fitroom_tracker::sleeve`; `None`: too few hanging arms seen).
    pub sleeve_step_mm: Option<f64>,
    /// What went wrong in the last search for the person's build, if anything did (the body
    /// tracked before it is kept, or the clothed build worn without the body under it).
    pub build_error: Option<String>,
}

fn print_eval(r: &TrackEvalReport) {
    for d in &r.recordings {
        let e = &d.report;
        let height = d
            .stature_cm
            .map_or(String::new(), |h| format!(", sized {h:.1} cm tall"));
        let clothing = d
            .clothing_cm
            .map_or(String::new(), |c| format!(", clothing {c:.1} cm"));
        let sleeve = d
            .sleeve_step_mm
            .map_or(String::new(), |s| format!(" (sleeve step {s:.0} mm)"));
        println!(
            "{}: {} frames, mean {:.0} mm (trunk {:.0}), p95 {:.0} mm, every joint tracked or \
             inferred in {:.1} % of frames in view, {} lost, {} starts{height}{clothing}{sleeve}",
            d.dump,
            e.frames,
            e.mean_mm,
            e.trunk_mean_mm,
            e.p95_mm,
            e.all_joints_pct,
            e.lost_frames,
            e.starts
        );
        if let Some(e) = &d.build_error {
            println!("  the person's build: {e}");
        }
    }
    let o = &r.overall;
    println!(
        "overall: {} frames ({} tracked, {} wholly in view): mean {:.1} mm, trunk {:.1} mm, \
         p95 {:.0} mm; every joint tracked or inferred in {:.1} % ({} frames lost); {} starts; {:.2} ms per \
         frame (p95 {:.2}); {} searches for the person's build, {:.0} ms each (the app runs \
         them on a thread of their own)",
        o.frames,
        o.tracked_frames,
        o.in_view_frames,
        o.mean_mm,
        o.trunk_mean_mm,
        o.p95_mm,
        o.all_joints_pct,
        o.lost_frames,
        o.starts,
        o.time_mean_ms,
        o.time_p95_ms,
        o.shape_searches,
        o.shape_search_mean_ms
    );
    println!(
        "  {:<16} {:>8} {:>8} {:>9} {:>9}",
        "joint", "mean mm", "p95 mm", "tracked %", "inferred %"
    );
    for j in &o.joints {
        println!(
            "  {:<16} {:>8.0} {:>8.0} {:>9.1} {:>9.1}",
            j.joint, j.mean_mm, j.p95_mm, j.tracked_pct, j.inferred_pct
        );
    }
}

/// The body of `--body` (the shipped one by default), for trackers.
fn track_model(body: &BodyArg) -> Result<Arc<BodyModel>> {
    Ok(Arc::new(body.load()?))
}

/// The measurement's body fit as the tracker's estimate of each person's build, as the kiosk
/// has it (the shipped shape prior, read once for all the trackers made with it).
pub fn build_fit() -> Result<Arc<TrackedBuild>> {
    let prior = ShapePrior::shipped().context("the shipped shape prior cannot be read")?;
    Ok(Arc::new(TrackedBuild::new(Arc::new(prior))))
}

/// A tracker for `model`, estimating each person's build as it tracks them with `build`
/// (in the frame that completes its snapshots: the same recording gives the same figures).
pub fn tracker(model: &Arc<BodyModel>, build: &Arc<TrackedBuild>) -> Result<Tracker> {
    Ok(
        Tracker::estimating(model.clone(), TrackerSettings::default())
            .context("the body cannot be tracked (its rig lacks a bone the tracker needs)")?
            .with_build_fit(build.clone()),
    )
}

/// Frames of a picture, as shares of the recording.
const PICTURE_AT: [f64; 4] = [0.1, 0.35, 0.6, 0.85];

fn eval(dumps: &[PathBuf], body: &BodyArg, png: Option<&Path>) -> Result<TrackEvalReport> {
    let mut pictures: Vec<(Vec<u8>, Option<[u16; 4]>)> = Vec::new();
    let model = track_model(body)?;
    let build = build_fit()?;
    let camera = DepthCamera::default();
    let mut overall = Evaluation::new();
    let mut starts = 0;
    let mut recordings = Vec::new();
    for dump in dumps {
        let recording = Recording::open(dump)?;
        let Some(truth) = read_truth(dump)? else {
            bail!(
                "'{}' has no ground truth (groundtruth.jsonl): `fitroom track run` tracks it \
                 without; record one with ground truth with `fitroom sensor record --synthetic`",
                dump.display()
            );
        };
        // A tracker of its own: nothing of one recording (its floor, its person's build)
        // carries into the next, so each one's figures do not depend on the order (they did,
        // by 57 mm on a T-shirt recording the fit loses a limb in).
        let mut tracker = tracker(&model, &build)?;
        let mut one = Evaluation::new();
        let mut stature_cm = None;
        let count = recording.depth_count();
        let shown: Vec<usize> = PICTURE_AT
            .iter()
            .map(|s| (s * count as f64) as usize)
            .collect();
        for (i, (entry, line)) in recording.depth_entries().zip(&truth).enumerate() {
            let frame = recording
                .read_depth(entry, camera)
                .with_context(|| format!("{}: frame {}", dump.display(), line.frame))?;
            let joints: Vec<Vec3> = line.joints.iter().map(|j| Vec3::from_array(*j)).collect();
            // Time and score once; the overall figures take the same result.
            let out = one.step(&mut tracker, &frame, &joints);
            if let Some(t) = &out {
                stature_cm = Some(f64::from(tracker.body.height_m * t.pose.scale) * 100.0);
            }
            let (ms, search_ms) = one.last_time_ms();
            overall.record(&frame, &joints, out.as_ref(), ms, search_ms);
            if png.is_some() && recordings.is_empty() && shown.contains(&i) {
                let rgb = fitroom_tracker::draw::picture(&frame, out.as_ref(), &joints);
                pictures.push((rgb, out.as_ref().map(|t| t.person.bbox)));
            }
        }
        starts += tracker.starts;
        recordings.push(RecordingEval {
            dump: dump.display().to_string(),
            report: one.report(tracker.starts),
            stature_cm,
            clothing_cm: tracker
                .shape
                .as_ref()
                .map(|e| f64::from(e.clothing_m) * 100.0),
            sleeve_step_mm: tracker.sleeve_step_m().map(|s| f64::from(s) * 1000.0),
            build_error: tracker.shape_error.clone(),
        });
    }
    if let Some(png) = png {
        write_pictures(png, &pictures)?;
    }
    Ok(TrackEvalReport {
        overall: overall.report(starts),
        recordings,
    })
}

/// Up to four 640x480 pictures side by side, each cut to the person (their box in the
/// image, if found, and a margin; the same size for all), as a PNG.
fn write_pictures(png: &Path, pictures: &[(Vec<u8>, Option<[u16; 4]>)]) -> Result<()> {
    use fitroom_depth::{HEIGHT, WIDTH};
    let (w, h) = (WIDTH as u32, HEIGHT as u32);
    const MARGIN: u32 = 40;
    // One tile size: the widest and tallest box with its margin.
    let boxes: Vec<[u32; 4]> = pictures
        .iter()
        .map(|(_, b)| b.map_or([0, 0, w - 1, h - 1], |b| b.map(u32::from)))
        .collect();
    let tw = boxes
        .iter()
        .map(|b| b[2] - b[0] + 1 + 2 * MARGIN)
        .max()
        .unwrap_or(w)
        .min(w);
    let th = boxes
        .iter()
        .map(|b| b[3] - b[1] + 1 + 2 * MARGIN)
        .max()
        .unwrap_or(h)
        .min(h);
    let shown = pictures.len().min(4) as u32;
    let mut strip = image::RgbImage::new(tw * shown.max(1), th);
    for (n, ((rgb, _), b)) in pictures.iter().zip(&boxes).take(4).enumerate() {
        let Some(full) = image::RgbImage::from_raw(w, h, rgb.clone()) else {
            continue;
        };
        // The tile centred on the box, kept inside the image.
        let cx = (b[0] + b[2]) / 2;
        let cy = (b[1] + b[3]) / 2;
        let x0 = cx.saturating_sub(tw / 2).min(w - tw);
        let y0 = cy.saturating_sub(th / 2).min(h - th);
        let tile = image::imageops::crop_imm(&full, x0, y0, tw, th).to_image();
        image::imageops::replace(&mut strip, &tile, i64::from(n as u32 * tw), 0);
    }
    strip
        .save(png)
        .with_context(|| format!("cannot write the picture '{}'", png.display()))
}

/// Renders the clip with the synthetic camera into a scratch recording, then evaluates it.
fn eval_on_the_fly(
    inputs: Inputs,
    frames: usize,
    distance_m: f32,
    png: Option<&Path>,
) -> Result<TrackEvalReport> {
    let out = std::env::temp_dir().join(format!("fitroom-track-eval-{}", std::process::id()));
    if out.exists() {
        std::fs::remove_dir_all(&out)
            .with_context(|| format!("cannot clear the scratch folder '{}'", out.display()))?;
    }
    let body = inputs.body.clone();
    let args = RecordArgs {
        synthetic: true,
        kinect: false,
        distance_m,
        frames,
        out: out.clone(),
        inputs,
    };
    let result = record_synthetic(&args).and_then(|_| eval(std::slice::from_ref(&out), &body, png));
    // The scratch recording goes whatever happened.
    let _ = std::fs::remove_dir_all(&out);
    result
}

/// `fitroom track run`'s report.
#[derive(Debug, Serialize)]
pub struct RunReport {
    pub dump: String,
    pub frames: Vec<RunFrame>,
}

/// One frame: the joints in Kinect order (empty when no one was found).
#[derive(Debug, Serialize)]
pub struct RunFrame {
    pub frame: usize,
    pub time_s: f64,
    pub joints: Vec<fitroom_tracker::TrackedJointOut>,
    /// Whether the fit (re)started from the extrema in this frame.
    pub started: bool,
    /// How many times the tracker has changed its body's build or size so far.
    pub body_changes: u32,
}

fn track_run(dump: &Path, body: &BodyArg) -> Result<RunReport> {
    let mut tracker = tracker(&track_model(body)?, &build_fit()?)?;
    let recording = Recording::open(dump)?;
    let mut frames = Vec::new();
    for (i, entry) in recording.depth_entries().enumerate() {
        let frame = recording
            .read_depth(entry, DepthCamera::default())
            .with_context(|| format!("{}: frame {i}", dump.display()))?;
        let tracked = tracker.track(&frame);
        frames.push(RunFrame {
            frame: i,
            time_s: frame.time_s,
            joints: tracked
                .as_ref()
                .map(|t| t.joints.to_vec())
                .unwrap_or_default(),
            started: tracked.as_ref().is_some_and(|t| t.started),
            body_changes: tracked.as_ref().map_or(0, |t| t.body_changes),
        });
    }
    Ok(RunReport {
        dump: dump.display().to_string(),
        frames,
    })
}
