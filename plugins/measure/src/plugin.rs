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
use crate::fit::{FitSettings, ViewPose};
use crate::person::{PersonMeasurement, measure_person};
use crate::posed::Placement;
use crate::prior::ShapePrior;
use crate::tracked::{calibration_frame, tracked_placement, tracked_views};
use crate::view::CalibrationFrame;

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
    /// Collecting good frames of view `view` of `views` (0: facing the sensor, 1: turned
    /// to the side): how many of how many, and, when the last frame was not good, what the
    /// person should do.
    Collecting {
        view: usize,
        views: usize,
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

/// One view collected: its frames and where the body stood in the last of them.
type View = (Vec<CalibrationFrame>, Placement);

/// The calibration's state; the kiosk calls [`Calibration::start`] and [`Calibration::stop`].
///
/// The person stands facing the mirror for a second, then turns halfway to their side and
/// holds still for another: the side view shows the depth of the chest, waist and hips that
/// the front cannot (on 200 subjects the chest's error fell by a third; `docs/measure.md`).
#[derive(Resource)]
pub struct Calibration {
    pub status: CalibrationStatus,
    /// Good frames needed per view (one second at 30 Hz).
    pub need: usize,
    /// Views to collect: 2 (front, then turned), or 1 (the front alone).
    pub views: usize,
    /// The turned view's turn from the front one, degrees: at least, at most.
    pub turn_deg: (f32, f32),
    /// Largest move of a joint over the collected frames, metres: more is not standing still.
    pub still_m: f32,
    /// Why the last fit failed, if it did (the collection then starts again).
    pub last_error: Option<String>,
    active: bool,
    frames: Vec<CalibrationFrame>,
    pose: Option<Placement>,
    done: Vec<View>,
    last_frame: u64,
    job: Option<Fit>,
}

impl Default for Calibration {
    fn default() -> Self {
        Self {
            status: CalibrationStatus::Idle,
            need: 30,
            views: 2,
            turn_deg: (25.0, 75.0),
            still_m: 0.05,
            last_error: None,
            active: false,
            frames: Vec::new(),
            pose: None,
            done: Vec::new(),
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
        self.done.clear();
        self.last_error = None;
        self.status = self.collecting(0, None);
    }

    /// Stops (the person left); a fit under way is let go.
    pub fn stop(&mut self) {
        self.active = false;
        self.frames.clear();
        self.pose = None;
        self.done.clear();
        self.job = None;
        self.status = CalibrationStatus::Idle;
    }

    pub fn is_active(&self) -> bool {
        self.active
    }

    /// The whole collection starts again (from the front view), and says why.
    fn restart(&mut self, hint: impl Into<String>) {
        self.done.clear();
        self.restart_view(hint);
    }

    /// The view being collected starts again, and says why.
    fn restart_view(&mut self, hint: impl Into<String>) {
        self.frames.clear();
        self.pose = None;
        self.status = self.collecting(0, Some(hint.into()));
    }

    fn collecting(&self, frames: usize, hint: Option<String>) -> CalibrationStatus {
        CalibrationStatus::Collecting {
            view: self.done.len(),
            views: self.views.max(1),
            frames,
            need: self.need,
            hint,
        }
    }

    /// The share of the calibration's frames collected, 0..1 (over all its views).
    pub fn progress(&self) -> f32 {
        match &self.status {
            CalibrationStatus::Collecting {
                view,
                views,
                frames,
                need,
                ..
            } => (view * need + frames) as f32 / (views * need).max(1) as f32,
            CalibrationStatus::Fitting | CalibrationStatus::Done => 1.0,
            CalibrationStatus::Idle => 0.0,
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

/// What the person is asked to do for the turned view.
pub const TURN_HINT: &str = "Now turn halfway to your left and hold still";

/// How far `a` is turned from `b` about the vertical, degrees.
fn turn_between(a: &Placement, b: &Placement) -> f32 {
    let f = (a.rotation * b.rotation.inverse()) * Vec3::Z;
    f.x.atan2(f.z).abs().to_degrees()
}

/// Why a tracked frame is not a calibration frame, if it is not. In the turned view the
/// far arm may be hidden behind the body: only the front view needs every joint.
fn frame_problem(
    map: &UserMap,
    tracked: &fitroom_tracker::Tracked,
    front: bool,
) -> Option<&'static str> {
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
    if front
        && tracked
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
    let front = cal.done.is_empty();
    if let Some(problem) = frame_problem(&map, tracked, front) {
        cal.restart_view(problem);
        return;
    }
    let pose = tracked_placement(tracked);
    if let Some((_, first)) = cal.done.first() {
        let turn = turn_between(&pose, first);
        if turn < cal.turn_deg.0 {
            cal.restart_view(TURN_HINT);
            return;
        }
        if turn > cal.turn_deg.1 {
            cal.restart_view("Not so far: turn back a little towards the mirror");
            return;
        }
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
            cal.restart_view("Please stand still for a second");
            return;
        }
    }
    cal.pose = Some(pose);
    cal.frames.push(f);
    let frames = cal.frames.len();
    cal.status = cal.collecting(frames, None);
    if frames < cal.need {
        return;
    }
    let Some(placement) = cal.pose.take() else {
        return;
    };
    let view = (std::mem::take(&mut cal.frames), placement);
    cal.done.push(view);
    if cal.done.len() < cal.views.max(1) {
        cal.status = cal.collecting(0, Some(TURN_HINT.into()));
        return;
    }
    let Ok(prior) = prior.0.clone() else {
        cal.restart("The measurement is not available (no shape prior)");
        return;
    };
    let model = body.model.clone();
    let seen = std::mem::take(&mut cal.done);
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
            cal.restart(format!("Measuring again ({e})"));
        }
    }
}
