//! `fitroom track`: seeing the person in depth recordings. `extrema` measures the tracker's
//! starting detector (segmentation, then geodesic extrema for head, hands and feet) against a
//! recording's ground truth.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use clap::Subcommand;
use fitroom_depth::DepthCamera;
use fitroom_depth::fakenect::Recording;
use fitroom_depth::truth::read_truth;
use fitroom_math::stats::Summary;
use fitroom_sensor::KinectJoint;
use fitroom_tracker::{Part, SegmentSettings, Segmenter, geodesic_extrema};
use glam::Vec3;
use serde::Serialize;

use super::OutputArgs;

#[derive(Subcommand)]
pub enum TrackCommand {
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
