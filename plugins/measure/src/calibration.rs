//! Collecting the calibration from tracked depth frames, Bevy-free (the kiosk's plugin and
//! `fitroom measure dump` share it): a second of frames facing the sensor, then a second
//! turned halfway to the left, each frame checked (one person, whole in view, tracked,
//! standing still, turned as asked); a bad frame restarts its view and says why.

use fitroom_depth::{DepthFrame, HEIGHT, WIDTH};
use fitroom_sensor::KinectJoint;
use fitroom_tracker::{Confidence, Tracked};
use glam::Vec3;

use crate::posed::Placement;
use crate::tracked::{calibration_frame, tracked_placement};
use crate::view::CalibrationFrame;

/// What the person is asked to do for the turned view.
pub const TURN_HINT: &str = "Now turn halfway to your left and hold still";

/// The joints that say whether a person stands still (turned, the only ones judged).
const TRUNK: [KinectJoint; 4] = [
    KinectJoint::HipCenter,
    KinectJoint::Spine,
    KinectJoint::ShoulderCenter,
    KinectJoint::Head,
];

/// What the person is asked when nobody is tracked.
pub const AWAY_HINT: &str = "Step in front of the mirror";

/// How the calibration is collected.
#[derive(Clone, Debug, PartialEq)]
pub struct CollectSettings {
    /// Good frames needed per view (one second at 30 Hz).
    pub need: usize,
    /// Views to collect: 2 (front, then turned), or 1 (the front alone).
    pub views: usize,
    /// The turned view's turn from the front one, degrees: at least, at most.
    pub turn_deg: (f32, f32),
    /// Largest move of a trunk joint over a view's frames, metres: more is not standing
    /// still.
    pub still_m: f32,
    /// The same for the limbs' joints (judged facing the camera only), metres. Larger: on a
    /// person standing still the tracker's hands, elbows and feet wander by up to 5 cm (a
    /// hand cut off from its arm by a depth edge in one frame and not the next moves the
    /// arm), and at the trunk's 5 cm the view restarted again and again.
    pub still_limbs_m: f32,
}

impl Default for CollectSettings {
    fn default() -> Self {
        Self {
            need: 30,
            views: 2,
            turn_deg: (25.0, 75.0),
            still_m: 0.05,
            still_limbs_m: 0.10,
        }
    }
}

/// One view collected: its frames and where the body stood in the last of them.
pub type CollectedView = (Vec<CalibrationFrame>, Placement);

/// Collecting view `view` of `views` (0: facing the sensor, 1: turned to the side):
/// `frames` good frames of `need`, and, when the last frame was not good, what the person
/// should do. (The collector's progress and the plugin's status both.)
#[derive(Clone, Debug, PartialEq)]
pub struct Collecting {
    pub view: usize,
    pub views: usize,
    pub frames: usize,
    pub need: usize,
    pub hint: Option<String>,
}

/// Where the collection is after a frame.
#[derive(Clone, Debug, PartialEq)]
pub enum Progress {
    Collecting(Collecting),
    /// Every view is collected: [`Collector::take_views`] hands them over.
    Complete,
}

/// The calibration's frames as they are collected.
#[derive(Debug, Default)]
pub struct Collector {
    pub settings: CollectSettings,
    frames: Vec<CalibrationFrame>,
    done: Vec<CollectedView>,
    /// The joints a still person keeps to, and the tracker's body they were found with
    /// ([`Tracked::body_changes`]): the view's first frame, or the first since the tracker
    /// changed its body (its joints move then, the person does not).
    still: Option<(u32, [Vec3; KinectJoint::COUNT])>,
}

/// How far `a` is turned from `b` about the vertical, degrees.
fn turn_between(a: &Placement, b: &Placement) -> f32 {
    let f = (a.rotation * b.rotation.inverse()) * Vec3::Z;
    f.x.atan2(f.z).abs().to_degrees()
}

/// Why a tracked frame is not a calibration frame, if it is not: whether the view must
/// start again (the person moved out of view, someone else came in) and what to say.
/// In the turned view the far arm may be hidden behind the body: only the front view needs
/// every joint; a joint the tracker only guessed in one frame skips that frame (it flickers
/// for a frame every second or so on a still person, and a restart then cost a second).
fn frame_problem(tracked: &Tracked, front: bool) -> Option<(bool, &'static str)> {
    let person = &tracked.person;
    if person.people > 1 {
        return Some((true, "Two people in view: one at a time, please"));
    }
    let [left, top, right, bottom] = person.bbox.map(usize::from);
    if top <= 1 {
        return Some((true, "Your head is out of view: please step back"));
    }
    if bottom + 2 >= HEIGHT {
        return Some((true, "Your feet are out of view: please step back"));
    }
    if left <= 1 || right + 2 >= WIDTH {
        return Some((true, "Please step to the middle"));
    }
    if front
        && tracked
            .joints
            .iter()
            .any(|j| j.confidence != Confidence::Tracked)
    {
        return Some((false, "Hold your arms a little away from your body"));
    }
    None
}

impl Collector {
    pub fn new(settings: CollectSettings) -> Self {
        Self {
            settings,
            ..Self::default()
        }
    }

    /// Everything collected is dropped (a new person, or the same one starting over).
    pub fn clear(&mut self) {
        self.frames.clear();
        self.done.clear();
    }

    /// The progress with `frames` in the current view.
    pub fn collecting(&self, frames: usize, hint: Option<String>) -> Progress {
        Progress::Collecting(Collecting {
            view: self.done.len(),
            views: self.settings.views.max(1),
            frames,
            need: self.settings.need,
            hint,
        })
    }

    /// The whole collection starts again (from the front view), and says why.
    pub fn restart(&mut self, hint: impl Into<String>) -> Progress {
        self.clear();
        self.collecting(0, Some(hint.into()))
    }

    /// The view being collected starts again, and says why.
    fn restart_view(&mut self, hint: impl Into<String>) -> Progress {
        self.frames.clear();
        self.collecting(0, Some(hint.into()))
    }

    /// One depth frame and what the tracker found in it (`None`: nobody).
    pub fn offer(&mut self, frame: &DepthFrame, tracked: Option<&Tracked>) -> Progress {
        if self.done.len() >= self.settings.views.max(1) {
            return Progress::Complete;
        }
        let Some(tracked) = tracked else {
            return self.restart(AWAY_HINT);
        };
        match frame_problem(tracked, self.done.is_empty()) {
            Some((true, problem)) => return self.restart_view(problem),
            Some((false, problem)) => {
                return self.collecting(self.frames.len(), Some(problem.into()));
            }
            None => {}
        }
        let placement = tracked_placement(tracked);
        if let Some((_, front)) = self.done.first() {
            let turn = turn_between(&placement, front);
            if turn < self.settings.turn_deg.0 {
                return self.restart_view(TURN_HINT);
            }
            if turn > self.settings.turn_deg.1 {
                return self.restart_view("Not so far: turn back a little towards the mirror");
            }
        }
        let f = calibration_frame(frame, tracked);
        match self.still {
            Some((body, reference)) if !self.frames.is_empty() && body == tracked.body_changes => {
                // Turned, the far arm's joints are the tracker's guesses and wander: the
                // trunk says whether the person stands still.
                let judged: &[KinectJoint] = if self.done.is_empty() {
                    &KinectJoint::ALL
                } else {
                    &TRUNK
                };
                let limit = |j: &KinectJoint| {
                    if TRUNK.contains(j) {
                        self.settings.still_m
                    } else {
                        self.settings.still_limbs_m
                    }
                };
                let moved = judged
                    .iter()
                    .any(|j| f.joints[j.index()].distance(reference[j.index()]) > limit(j));
                if moved {
                    return self.restart_view("Please stand still for a second");
                }
            }
            _ => self.still = Some((tracked.body_changes, f.joints)),
        }
        self.frames.push(f);
        if self.frames.len() < self.settings.need {
            return self.collecting(self.frames.len(), None);
        }
        self.done
            .push((std::mem::take(&mut self.frames), placement));
        if self.done.len() < self.settings.views.max(1) {
            return self.collecting(0, Some(TURN_HINT.into()));
        }
        Progress::Complete
    }

    /// The views, once [`Progress::Complete`]; the collector is empty after.
    pub fn take_views(&mut self) -> Option<Vec<CollectedView>> {
        if self.done.len() < self.settings.views.max(1) {
            return None;
        }
        self.frames.clear();
        Some(std::mem::take(&mut self.done))
    }
}
