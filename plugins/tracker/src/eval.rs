//! The tracker against ground truth: per-joint 3D error (mean, 95th percentile), the share of
//! frames with every joint tracked or inferred, restarts, and time per frame. Bevy-free, so
//! `fitroom track eval` and the tests measure the same thing.

use std::time::Instant;

use fitroom_depth::DepthFrame;
use fitroom_math::stats::Summary;
use fitroom_sensor::KinectJoint;
use glam::Vec3;
use serde::Serialize;

use crate::tracker::{Confidence, Tracked, Tracker};

/// The trunk joints the acceptance holds to a tighter bound.
pub const TRUNK: [KinectJoint; 7] = [
    KinectJoint::HipCenter,
    KinectJoint::Spine,
    KinectJoint::ShoulderCenter,
    KinectJoint::ShoulderLeft,
    KinectJoint::ShoulderRight,
    KinectJoint::HipLeft,
    KinectJoint::HipRight,
];

/// One joint's figures.
#[derive(Clone, Debug, Serialize)]
pub struct JointReport {
    pub joint: &'static str,
    /// Distance to the truth over the frames where the joint was tracked or inferred, mm.
    pub mean_mm: f64,
    pub p95_mm: f64,
    /// Share of frames with a person where it was tracked / inferred, %.
    pub tracked_pct: f64,
    pub inferred_pct: f64,
}

/// A run of the tracker over frames with ground truth.
#[derive(Clone, Debug, Serialize)]
pub struct EvalReport {
    pub frames: usize,
    /// Frames in which a person was found and fitted.
    pub tracked_frames: usize,
    /// Over all joints and frames (tracked or inferred joints), mm.
    pub mean_mm: f64,
    pub p95_mm: f64,
    /// Over the trunk joints ([`TRUNK`]), mm.
    pub trunk_mean_mm: f64,
    /// Frames whose true joints all lie in the image and in range.
    pub in_view_frames: usize,
    /// Of those, the share with every joint tracked or inferred, %.
    pub all_joints_pct: f64,
    /// Frames with a person whose fit had lost them: every joint reported not tracked
    /// ([`crate::TrackerSettings::lost_inliers`]); their joints count in no error above.
    pub lost_frames: usize,
    /// Fits (re)started from the extrema.
    pub starts: usize,
    /// Time per frame (segmentation and fit), ms; without the searches for the person's
    /// build, which the app runs on a thread of its own (here they run in the frame that
    /// completes their snapshots): their count and mean time follow.
    pub time_mean_ms: f64,
    pub time_p95_ms: f64,
    pub shape_searches: usize,
    pub shape_search_mean_ms: f64,
    pub joints: Vec<JointReport>,
}

/// Gathers a run frame by frame.
#[derive(Default)]
pub struct Evaluation {
    frames: usize,
    tracked_frames: usize,
    in_view: usize,
    all_joints: usize,
    lost_frames: usize,
    errors: Vec<Vec<f64>>,
    tracked: Vec<usize>,
    inferred: Vec<usize>,
    times_ms: Vec<f64>,
    searches_ms: Vec<f64>,
    last_search_ms: Option<f64>,
}

impl Evaluation {
    pub fn new() -> Self {
        Self {
            errors: vec![Vec::new(); KinectJoint::COUNT],
            tracked: vec![0; KinectJoint::COUNT],
            inferred: vec![0; KinectJoint::COUNT],
            ..Self::default()
        }
    }

    /// Tracks `frame` (timed) and scores it against `truth` (20 joints, sensor space).
    pub fn step(
        &mut self,
        tracker: &mut Tracker,
        frame: &DepthFrame,
        truth: &[Vec3],
    ) -> Option<Tracked> {
        let start = Instant::now();
        let out = tracker.track(frame);
        let ms = start.elapsed().as_secs_f64() * 1000.0;
        let search = tracker.search_ms;
        self.record(
            frame,
            truth,
            out.as_ref(),
            ms - search.unwrap_or(0.0),
            search,
        );
        out
    }

    /// The time of the last frame recorded (without a search for the build), ms, and that
    /// search's, if one ran in it.
    pub fn last_time_ms(&self) -> (f64, Option<f64>) {
        (
            self.times_ms.last().copied().unwrap_or(0.0),
            self.last_search_ms,
        )
    }

    /// Scores a result already made (`tracked`, which took `ms`) against `truth`.
    pub fn record(
        &mut self,
        frame: &DepthFrame,
        truth: &[Vec3],
        tracked: Option<&Tracked>,
        ms: f64,
        search_ms: Option<f64>,
    ) {
        self.times_ms.push(ms);
        self.searches_ms.extend(search_ms);
        self.last_search_ms = search_ms;
        self.frames += 1;
        let camera = frame.camera;
        let in_view = truth.len() == KinectJoint::COUNT
            && truth.iter().all(|p| {
                camera.in_range(p.z)
                    && camera.project(*p).is_some_and(|px| {
                        (0.0..fitroom_depth::WIDTH as f32).contains(&px.x)
                            && (0.0..fitroom_depth::HEIGHT as f32).contains(&px.y)
                    })
            });
        if in_view {
            self.in_view += 1;
        }
        let Some(tracked) = tracked else {
            return;
        };
        self.tracked_frames += 1;
        if tracked
            .joints
            .iter()
            .all(|j| j.confidence == Confidence::NotTracked)
        {
            self.lost_frames += 1;
        }
        let mut all = true;
        for (k, j) in tracked.joints.iter().enumerate() {
            match j.confidence {
                Confidence::Tracked => self.tracked[k] += 1,
                Confidence::Inferred => self.inferred[k] += 1,
                Confidence::NotTracked => {
                    all = false;
                    continue;
                }
            }
            if let Some(t) = truth.get(k) {
                self.errors[k].push(f64::from(j.position.distance(*t)) * 1000.0);
            }
        }
        if all && in_view {
            self.all_joints += 1;
        }
    }

    pub fn report(&self, starts: usize) -> EvalReport {
        let all: Vec<f64> = self.errors.iter().flatten().copied().collect();
        let trunk: Vec<f64> = TRUNK
            .iter()
            .flat_map(|j| self.errors[j.index()].iter().copied())
            .collect();
        let per = |n: usize| 100.0 * n as f64 / self.tracked_frames.max(1) as f64;
        let time = Summary::of(&self.times_ms);
        EvalReport {
            frames: self.frames,
            tracked_frames: self.tracked_frames,
            mean_mm: Summary::of(&all).mean,
            p95_mm: Summary::of(&all).p95,
            trunk_mean_mm: Summary::of(&trunk).mean,
            in_view_frames: self.in_view,
            all_joints_pct: 100.0 * self.all_joints as f64 / self.in_view.max(1) as f64,
            lost_frames: self.lost_frames,
            starts,
            time_mean_ms: time.mean,
            time_p95_ms: time.p95,
            shape_searches: self.searches_ms.len(),
            shape_search_mean_ms: Summary::of(&self.searches_ms).mean,
            joints: KinectJoint::ALL
                .iter()
                .map(|j| {
                    let s = Summary::of(&self.errors[j.index()]);
                    JointReport {
                        joint: j.name(),
                        mean_mm: s.mean,
                        p95_mm: s.p95,
                        tracked_pct: per(self.tracked[j.index()]),
                        inferred_pct: per(self.inferred[j.index()]),
                    }
                })
                .collect(),
        }
    }
}
