//! CPU time per stage of the frame, measured by marker systems placed around each
//! [`FitroomSystems`] stage (and Bevy's transform propagation). The stages run one after
//! another (they are chained), so the time between a stage's start and end markers is that
//! stage's cost in this frame.

use std::sync::Mutex;
use std::time::Instant;

use bevy::{prelude::*, transform::TransformSystems};
use fitroom_schedule::FitroomSystems;
use serde::Serialize;

/// What we time: a stage of the frame, the transform propagation between `Pose` and
/// `Measure`, or the whole frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Stage {
    Systems(FitroomSystems),
    TransformPropagate,
    /// A whole `App::update`, from `First` to `Last`.
    Frame,
}

/// Every stage timed, in the order they run.
const STAGES: [Stage; 10] = [
    Stage::Systems(FitroomSystems::Sensor),
    Stage::Systems(FitroomSystems::Track),
    Stage::Systems(FitroomSystems::Motion),
    Stage::Systems(FitroomSystems::Pose),
    Stage::TransformPropagate,
    Stage::Systems(FitroomSystems::Measure),
    Stage::Systems(FitroomSystems::Cloth),
    Stage::Systems(FitroomSystems::Gesture),
    Stage::Systems(FitroomSystems::Ui),
    Stage::Frame,
];

impl Stage {
    pub const ALL: [Stage; 10] = STAGES;

    pub fn name(self) -> &'static str {
        match self {
            Stage::Systems(s) => s.name(),
            Stage::TransformPropagate => "transform_propagate",
            Stage::Frame => "frame",
        }
    }

    fn index(self) -> usize {
        STAGES.iter().position(|s| *s == self).unwrap_or(0)
    }
}

/// Samples per stage, milliseconds. The markers share it read-only (the samples sit behind a
/// lock), so that timing adds no ordering constraint between the stages it measures.
#[derive(Resource, Default, Debug)]
pub struct StageTimings {
    inner: Mutex<Samples>,
}

#[derive(Default, Debug)]
struct Samples {
    started: [Option<Instant>; STAGES.len()],
    ms: [Vec<f64>; STAGES.len()],
}

/// Mean and 95th percentile of one stage.
#[derive(Debug, Clone, Copy, Serialize, PartialEq)]
pub struct StageSummary {
    pub mean_ms: f64,
    pub p95_ms: f64,
    pub samples: usize,
}

impl StageTimings {
    pub fn summary(&self, stage: Stage) -> StageSummary {
        let samples = self.inner.lock().unwrap_or_else(|e| e.into_inner());
        summarize(&samples.ms[stage.index()])
    }

    fn begin(&self, stage: Stage) {
        let mut samples = self.inner.lock().unwrap_or_else(|e| e.into_inner());
        samples.started[stage.index()] = Some(Instant::now());
    }

    fn end(&self, stage: Stage) {
        let mut samples = self.inner.lock().unwrap_or_else(|e| e.into_inner());
        let i = stage.index();
        if let Some(start) = samples.started[i].take() {
            samples.ms[i].push(start.elapsed().as_secs_f64() * 1e3);
        }
    }
}

/// Mean and 95th percentile ([`fitroom_math::stats::percentile`]'s rule).
pub fn summarize(samples: &[f64]) -> StageSummary {
    let s = fitroom_math::stats::Summary::of(samples);
    StageSummary {
        mean_ms: s.mean,
        p95_ms: s.p95,
        samples: s.samples,
    }
}

fn begin(stage: Stage) -> impl FnMut(Res<StageTimings>) {
    move |timings| timings.begin(stage)
}

fn end(stage: Stage) -> impl FnMut(Res<StageTimings>) {
    move |timings| timings.end(stage)
}

/// The frame's end marker, after everything else in `Last` that is part of the frame's work.
#[derive(SystemSet, Debug, Clone, PartialEq, Eq, Hash)]
pub struct FrameEnd;

/// Adds the marker systems: each stage's start marker runs after the previous stage, its end
/// marker before the next one.
pub struct TimingPlugin;

impl Plugin for TimingPlugin {
    fn build(&self, app: &mut App) {
        fitroom_schedule::ensure(app);
        app.init_resource::<StageTimings>()
            .add_systems(First, begin(Stage::Frame))
            .add_systems(Last, end(Stage::Frame).in_set(FrameEnd))
            .add_systems(
                PostUpdate,
                (
                    begin(Stage::TransformPropagate)
                        .after(FitroomSystems::Pose)
                        .before(TransformSystems::Propagate),
                    end(Stage::TransformPropagate)
                        .after(TransformSystems::Propagate)
                        .before(FitroomSystems::Measure),
                ),
            );
        for (k, stage) in FitroomSystems::ALL.into_iter().enumerate() {
            let mut start = begin(Stage::Systems(stage)).into_configs().before(stage);
            let mut stop = end(Stage::Systems(stage)).into_configs().after(stage);
            if let Some(&previous) = k.checked_sub(1).and_then(|p| FitroomSystems::ALL.get(p)) {
                start = start.after(previous);
            }
            if let Some(&next) = FitroomSystems::ALL.get(k + 1) {
                stop = stop.before(next);
            }
            app.add_systems(PostUpdate, (start, stop));
        }
    }
}
