//! Bevy adapter: measuring the person while the kiosk calibrates. While [`Calibration`] is
//! active, each tracked depth frame is checked (one person, whole in view, standing still);
//! a second of good frames is averaged and fitted on a thread of its own (the kiosk's
//! frames never wait for it); the result is [`BodyMeasurements`], and the avatar takes the
//! measured shape ([`AvatarShape`]). A frame that fails a check restarts the collection and
//! says why ([`CalibrationStatus::Collecting`]'s hint); no measurement comes from bad frames.
//!
//! The plugin also gives the tracker its fitter of the person's build ([`TrackerBuildFit`]:
//! the same body fit on frames of the person moving, [`crate::build`]).

use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::Instant;

use bevy::prelude::*;
use fitroom_body::plugin::{AvatarBody, AvatarShape};
use fitroom_body::{Measure, Measurements, Shape};
use fitroom_depth::plugin::DepthFeed;
use fitroom_schedule::FitroomSystems;
use fitroom_tracker::plugin::{TrackedSkeleton, TrackerBuildFit, UserMap};

use crate::MeasureError;
use crate::build::TrackedBuild;
use crate::calibration::{Collecting, Collector, Progress};
use crate::fit::{FitSettings, ViewPose};
use crate::person::{PersonMeasurement, measure_person};
use crate::prior::ShapePrior;
use crate::tracked::tracked_views;

/// Systems of the measurement plugin.
#[derive(SystemSet, Debug, Clone, PartialEq, Eq, Hash)]
pub enum MeasureSystems {
    Collect,
    Finish,
}

/// Where the calibration is.
#[derive(Clone, Debug, PartialEq, Default)]
pub enum CalibrationStatus {
    /// Not measuring (nobody to measure, or the kiosk is not calibrating).
    #[default]
    Idle,
    /// Collecting good frames, and what the person should do when the last was not good.
    Collecting(Collecting),
    /// The body is being fitted (off the main schedule).
    Fitting,
    /// Measured: [`BodyMeasurements`] holds the result.
    Done,
}

/// The person's measurements, as measured from depth.
#[derive(Resource, Clone, Debug)]
pub struct BodyMeasurements {
    pub measurements: Measurements,
    pub shape: Shape,
    /// Whether the women's shape prior explained the person better (the size charts are
    /// per gender).
    pub female: bool,
    /// Per measure, one standard deviation, cm (from the fit's posterior; the back is not
    /// seen, so girths are less certain than heights).
    pub uncertainty_cm: Vec<(Measure, f32)>,
    /// From the last calibration frame to the result, ms.
    pub latency_ms: f64,
    pub frames: usize,
}

/// A fit under way: its thread, when it began, and how many frames it has.
type Fit = (
    JoinHandle<Result<PersonMeasurement, MeasureError>>,
    Instant,
    usize,
);

/// The calibration's state; the kiosk calls [`Calibration::start`] and [`Calibration::stop`].
///
/// The person stands facing the mirror for a second, then turns halfway to their side and
/// holds still for another ([`Collector`]): the side view shows the depth of the chest,
/// waist and hips that the front cannot (`docs/measure.md`).
#[derive(Resource, Default)]
pub struct Calibration {
    pub status: CalibrationStatus,
    /// The views being collected (and how).
    pub collector: Collector,
    /// Why the last fit failed, if it did (the collection then starts again).
    pub last_error: Option<String>,
    active: bool,
    last_frame: u64,
    job: Option<Fit>,
}

impl Calibration {
    /// Starts measuring the person in view (again).
    pub fn start(&mut self) {
        self.active = true;
        self.collector.clear();
        self.last_error = None;
        self.status = self.collector.collecting(0, None).into();
    }

    /// Stops (the person left); a fit under way is let go.
    pub fn stop(&mut self) {
        self.active = false;
        self.collector.clear();
        self.job = None;
        self.status = CalibrationStatus::Idle;
    }

    pub fn is_active(&self) -> bool {
        self.active
    }

    /// The share of the calibration's frames collected, 0..1 (over all its views).
    pub fn progress(&self) -> f32 {
        match &self.status {
            CalibrationStatus::Collecting(c) => {
                (c.view * c.need + c.frames) as f32 / (c.views * c.need).max(1) as f32
            }
            CalibrationStatus::Fitting | CalibrationStatus::Done => 1.0,
            CalibrationStatus::Idle => 0.0,
        }
    }
}

impl From<Progress> for CalibrationStatus {
    fn from(p: Progress) -> Self {
        match p {
            Progress::Collecting(c) => Self::Collecting(c),
            Progress::Complete => Self::Fitting,
        }
    }
}

/// The shape prior the fit leans on (the shipped one), or why there is none.
#[derive(Resource, Clone)]
pub struct MeasurePrior(pub Result<Arc<ShapePrior>, String>);

pub struct MeasurePlugin;

impl Plugin for MeasurePlugin {
    fn build(&self, app: &mut App) {
        fitroom_schedule::ensure(app);
        let prior = ShapePrior::shipped()
            .map(Arc::new)
            .map_err(|e| e.to_string());
        if let Err(e) = &prior {
            warn!("no shape prior, the person cannot be measured: {e}");
        }
        // The tracker estimates the person's build with the same fit.
        if let Ok(prior) = &prior {
            app.insert_resource(TrackerBuildFit(Arc::new(TrackedBuild::new(prior.clone()))));
        }
        app.init_resource::<Calibration>()
            .insert_resource(MeasurePrior(prior))
            .configure_sets(
                PostUpdate,
                (MeasureSystems::Collect, MeasureSystems::Finish)
                    .chain()
                    .in_set(FitroomSystems::Measure),
            )
            .add_systems(PostUpdate, collect.in_set(MeasureSystems::Collect))
            .add_systems(PostUpdate, finish.in_set(MeasureSystems::Finish));
    }
}

fn collect(
    depth: Option<Res<DepthFeed>>,
    map: Res<UserMap>,
    skeleton: Res<TrackedSkeleton>,
    body: Option<Res<AvatarBody>>,
    prior: Res<MeasurePrior>,
    mut cal: ResMut<Calibration>,
) {
    if !cal.active || cal.job.is_some() || cal.status == CalibrationStatus::Done {
        return;
    }
    if map.frame == cal.last_frame {
        return;
    }
    cal.last_frame = map.frame;
    let (Some(depth), Some(body)) = (depth, body) else {
        return;
    };
    let Some(frame) = depth.latest.as_ref() else {
        return;
    };
    let progress = cal.collector.offer(frame, skeleton.latest.as_ref());
    let complete = progress == Progress::Complete;
    cal.status = progress.into();
    if !complete {
        return;
    }
    let Some(seen) = cal.collector.take_views() else {
        return;
    };
    let Ok(prior) = prior.0.clone() else {
        cal.status = cal
            .collector
            .restart("The measurement is not available (no shape prior)")
            .into();
        return;
    };
    let model = body.model.clone();
    let count = seen.iter().map(|(f, _)| f.len()).sum();
    let job = std::thread::spawn(move || {
        let seen = tracked_views(&model, &seen)?;
        let views: Vec<ViewPose> = seen.iter().map(|v| v.as_view_pose()).collect();
        measure_person(&model, &views, &prior, &FitSettings::default())
    });
    cal.job = Some((job, Instant::now(), count));
    cal.status = CalibrationStatus::Fitting;
}

fn finish(mut commands: Commands, mut cal: ResMut<Calibration>, mut shape: ResMut<AvatarShape>) {
    if !cal.job.as_ref().is_some_and(|(j, _, _)| j.is_finished()) {
        return;
    }
    let Some((job, began, frames)) = cal.job.take() else {
        return;
    };
    let result = job.join().unwrap_or(Err(MeasureError::Worker));
    match result {
        Ok(m) => {
            let latency_ms = began.elapsed().as_secs_f64() * 1e3;
            info!(
                "measured in {latency_ms:.0} ms: stature {:.1} cm, chest {:.1} cm, waist {:.1} cm, hip {:.1} cm",
                m.estimate.measurements.stature_cm,
                m.estimate.measurements.bust_cm,
                m.estimate.measurements.waist_cm,
                m.estimate.measurements.hip_cm
            );
            shape.0 = m.estimate.shape.clone();
            commands.insert_resource(BodyMeasurements {
                measurements: m.estimate.measurements.clone(),
                shape: m.estimate.shape.clone(),
                female: m.female,
                uncertainty_cm: m.estimate.uncertainty_cm.clone(),
                latency_ms,
                frames,
            });
            cal.status = CalibrationStatus::Done;
        }
        Err(e) => {
            warn!("the measurement failed: {e}");
            cal.last_error = Some(e.to_string());
            cal.status = cal
                .collector
                .restart(format!("Measuring again ({e})"))
                .into();
        }
    }
}
