//! CPU time per pipeline stage, measured by marker systems placed around each stage's
//! system set. The stages run one after another (their sets are chained), so the time between a
//! stage's start and end markers is that stage's cost in this frame.

use std::time::Instant;

use bevy::{prelude::*, transform::TransformSystems};
use fitroom_motion::plugin::MotionSystems;
use fitroom_sensor::plugin::SensorSystems;
use serde::Serialize;

/// The pipeline stages we time.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Stage {
    Sensor,
    Motion,
    Pose,
    TransformPropagate,
    /// A whole `App::update`, from `First` to `Last`.
    Frame,
}

impl Stage {
    pub const ALL: [Stage; 5] = [
        Stage::Sensor,
        Stage::Motion,
        Stage::Pose,
        Stage::TransformPropagate,
        Stage::Frame,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Stage::Sensor => "sensor",
            Stage::Motion => "motion",
            Stage::Pose => "pose",
            Stage::TransformPropagate => "transform_propagate",
            Stage::Frame => "frame",
        }
    }
}

/// Samples per stage, milliseconds.
#[derive(Resource, Default, Debug)]
pub struct StageTimings {
    started: [Option<Instant>; 5],
    pub samples_ms: [Vec<f64>; 5],
}

/// Mean and 95th percentile of one stage.
#[derive(Debug, Clone, Copy, Serialize, PartialEq)]
pub struct StageSummary {
    pub mean_ms: f64,
    pub p95_ms: f64,
    pub samples: usize,
}

impl StageTimings {
    fn index(stage: Stage) -> usize {
        Stage::ALL.iter().position(|s| *s == stage).unwrap_or(0)
    }

    pub fn summary(&self, stage: Stage) -> StageSummary {
        summarize(&self.samples_ms[Self::index(stage)])
    }
}

/// Mean and nearest-rank 95th percentile.
pub fn summarize(samples: &[f64]) -> StageSummary {
    if samples.is_empty() {
        return StageSummary {
            mean_ms: 0.0,
            p95_ms: 0.0,
            samples: 0,
        };
    }
    let mut sorted = samples.to_vec();
    sorted.sort_by(f64::total_cmp);
    let rank = ((0.95 * sorted.len() as f64).ceil() as usize).clamp(1, sorted.len());
    StageSummary {
        mean_ms: sorted.iter().sum::<f64>() / sorted.len() as f64,
        p95_ms: sorted[rank - 1],
        samples: sorted.len(),
    }
}

fn begin(stage: Stage) -> impl FnMut(ResMut<StageTimings>) {
    move |mut timings| timings.started[StageTimings::index(stage)] = Some(Instant::now())
}

fn end(stage: Stage) -> impl FnMut(ResMut<StageTimings>) {
    move |mut timings| {
        let i = StageTimings::index(stage);
        if let Some(start) = timings.started[i].take() {
            timings.samples_ms[i].push(start.elapsed().as_secs_f64() * 1e3);
        }
    }
}

/// Adds the marker systems.
pub struct TimingPlugin;

impl Plugin for TimingPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<StageTimings>()
            .add_systems(First, begin(Stage::Frame))
            .add_systems(Last, end(Stage::Frame))
            .add_systems(PreUpdate, begin(Stage::Sensor).before(SensorSystems::Poll))
            .add_systems(PreUpdate, end(Stage::Sensor).after(SensorSystems::Poll))
            .add_systems(Update, begin(Stage::Motion).before(MotionSystems::Retarget))
            .add_systems(
                Update,
                end(Stage::Motion)
                    .after(MotionSystems::Retarget)
                    .before(MotionSystems::ApplyPose),
            )
            .add_systems(
                Update,
                begin(Stage::Pose)
                    .after(MotionSystems::Retarget)
                    .before(MotionSystems::ApplyPose),
            )
            .add_systems(Update, end(Stage::Pose).after(MotionSystems::ApplyPose))
            .add_systems(
                PostUpdate,
                begin(Stage::TransformPropagate).before(TransformSystems::Propagate),
            )
            .add_systems(
                PostUpdate,
                end(Stage::TransformPropagate).after(TransformSystems::Propagate),
            );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percentile_is_nearest_rank() {
        let samples: Vec<f64> = (1..=100).map(f64::from).collect();
        let s = summarize(&samples);
        assert_eq!(s.p95_ms, 95.0);
        assert!((s.mean_ms - 50.5).abs() < 1e-12);
        assert_eq!(summarize(&[3.0]).p95_ms, 3.0);
    }
}
