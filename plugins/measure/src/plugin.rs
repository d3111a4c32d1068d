//! Bevy adapter: measuring the person while the kiosk calibrates. While [`Calibration`] is
//! active, each tracked depth frame is checked (one person, whole in view, standing still);
//! a second of good frames is averaged and fitted on a thread of its own (the kiosk's
//! frames never wait for it); the result is [`BodyMeasurements`], and the avatar takes the
//! measured shape ([`AvatarShape`]). A frame that fails a check restarts the collection and
//! says why ([`CalibrationStatus::Collecting`]'s hint); no measurement comes from bad frames.

use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::Instant;

use bevy::prelude::*;
use fitroom_body::plugin::{AvatarBody, AvatarShape};
use fitroom_body::{Measure, Measurements, Shape};
use fitroom_depth::plugin::DepthFeed;
use fitroom_depth::{HEIGHT, WIDTH};
use fitroom_schedule::FitroomSystems;
use fitroom_tracker::plugin::{TrackedSkeleton, UserMap};

use crate::MeasureError;
use crate::fit::FitSettings;
use crate::person::{PersonMeasurement, measure_person};
use crate::posed::Placement;
use crate::prior::ShapePrior;
use crate::tracked::{calibration_frame, tracked_pose};
use crate::view::{AveragedView, CalibrationFrame};

/// Systems of the measurement plugin.
#[derive(SystemSet, Debug, Clone, PartialEq, Eq, Hash)]
pub enum MeasureSystems {
    Collect,
    Finish,
}

/// Where the calibration is.
#[derive(Clone, Debug, PartialEq)]
pub enum CalibrationStatus {
    /// Not measuring (nobody to measure, or the kiosk is not calibrating).
    Idle,
    /// Collecting good frames: how many of how many, and, when the last frame was not
    /// good, what the person should do.
    Collecting {
        frames: usize,
        need: usize,
        hint: Option<String>,
    },
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
#[derive(Resource)]
pub struct Calibration {
    pub status: CalibrationStatus,
    /// Good frames needed (one second at 30 Hz).
    pub need: usize,
    /// Largest move of a joint over the collected frames, metres: more is not standing still.
    pub still_m: f32,
    /// Why the last fit failed, if it did (the collection then starts again).
    pub last_error: Option<String>,
    active: bool,
    frames: Vec<CalibrationFrame>,
    pose: Option<(Vec<Quat>, Placement)>,
    last_frame: u64,
    job: Option<Fit>,
}

impl Default for Calibration {
    fn default() -> Self {
        Self {
            status: CalibrationStatus::Idle,
            need: 30,
            still_m: 0.05,
            last_error: None,
            active: false,
            frames: Vec::new(),
            pose: None,
            last_frame: 0,
            job: None,
        }
    }
}

impl Calibration {
    /// Starts measuring the person in view (again).
    pub fn start(&mut self) {
        self.active = true;
        self.frames.clear();
        self.pose = None;
        self.last_error = None;
        self.status = CalibrationStatus::Collecting {
            frames: 0,
            need: self.need,
            hint: None,
        };
    }

    /// Stops (the person left); a fit under way is let go.
    pub fn stop(&mut self) {
        self.active = false;
        self.frames.clear();
        self.pose = None;
        self.job = None;
        self.status = CalibrationStatus::Idle;
    }

    pub fn is_active(&self) -> bool {
        self.active
    }

    /// The collection starts again, and says why.
    fn restart(&mut self, hint: impl Into<String>) {
        self.frames.clear();
        self.pose = None;
        self.status = CalibrationStatus::Collecting {
            frames: 0,
            need: self.need,
            hint: Some(hint.into()),
        };
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

/// Why a tracked frame is not a calibration frame, if it is not.
fn frame_problem(map: &UserMap, tracked: &fitroom_tracker::Tracked) -> Option<&'static str> {
    let person = map.person.as_ref()?;
    if person.people > 1 {
        return Some("Two people in view: one at a time, please");
    }
    let [left, top, right, bottom] = person.bbox.map(usize::from);
    if top <= 1 {
        return Some("Your head is out of view: please step back");
    }
    if bottom + 2 >= HEIGHT {
        return Some("Your feet are out of view: please step back");
    }
    if left <= 1 || right + 2 >= WIDTH {
        return Some("Please step to the middle");
    }
    if tracked
        .joints
        .iter()
        .any(|j| j.confidence != fitroom_tracker::Confidence::Tracked)
    {
        return Some("Hold your arms a little away from your body");
    }
    None
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
    let Some(tracked) = skeleton.latest.as_ref() else {
        cal.restart("Step in front of the mirror");
        return;
    };
    if let Some(problem) = frame_problem(&map, tracked) {
        cal.restart(problem);
        return;
    }
    let f = calibration_frame(frame, tracked);
    if let Some(first) = cal.frames.first() {
        let moved = f
            .joints
            .iter()
            .zip(&first.joints)
            .map(|(a, b)| a.distance(*b))
            .fold(0.0, f32::max);
        if moved > cal.still_m {
            cal.restart("Please stand still for a second");
            return;
        }
    }
    cal.pose = Some(tracked_pose(tracked));
    cal.frames.push(f);
    let (frames, need) = (cal.frames.len(), cal.need);
    cal.status = CalibrationStatus::Collecting {
        frames,
        need,
        hint: None,
    };
    if frames < need {
        return;
    }
    let Ok(prior) = prior.0.clone() else {
        cal.restart("The measurement is not available (no shape prior)");
        return;
    };
    let Some((locals, placement)) = cal.pose.clone() else {
        return;
    };
    let model = body.model.clone();
    let frames = std::mem::take(&mut cal.frames);
    let count = frames.len();
    let job = std::thread::spawn(move || {
        let view = AveragedView::new(&frames)?;
        measure_person(
            &model,
            &view,
            &locals,
            placement,
            &prior,
            &FitSettings::default(),
        )
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
            cal.restart(format!("Measuring again ({e})"));
        }
    }
}
