//! The skeleton tracker, frame after frame: segment the person, then either start (the body
//! placed standing under the person, sized by their height, and fitted with the geodesic
//! extrema as targets) or follow (the last pose fitted to the new frame). A fit that explains
//! the frame poorly is restarted from the extrema in the same frame, and the better of the
//! two kept. Out comes the Kinect v1 skeleton: 20 joints with positions, orientations and
//! the SDK's three confidences.

use std::sync::Arc;
use std::thread::JoinHandle;

use fitroom_body::{BodyModel, Shape};
use fitroom_depth::{DepthFrame, HEIGHT, WIDTH};
use fitroom_motion::retarget::twist_correction;
use fitroom_sensor::{JointSample, KinectJoint, SensorFrame};
use glam::{Quat, Vec3};
use serde::Serialize;

use crate::bodyparts::{Forest, PartScratch, Proposal, ProposalSettings, propose};
use crate::denoise::surface_depth_m;
use crate::fit::{FitSettings, FitStats, Fitter, Observation};
use crate::model::{ModelError, Pose, Posed, TrackBody};
use crate::segment::{SegmentSettings, Segmentation, Segmenter};
use crate::shape::{
    BuildFit, Estimate, ShapeSearchError, ShapeSettings, Snapshot, estimate, estimate_with,
};
use crate::silhouette::Silhouette;
use crate::skirt::{SkirtMemory, SkirtSettings, SkirtZone, legs_apart_in_image, skirt_zone};
use crate::sleeve;

/// The person's size from the frames tracked well ([`Tracker::refine_size`]): set anew every
/// `SIZE_EVERY` of them to the `SIZE_QUANTILE` of all so far, until `SIZE_FRAMES`.
const SIZE_EVERY: usize = 15;
const SIZE_FRAMES: usize = 90;
const SIZE_QUANTILE: f32 = 0.8;
/// The body's scale is kept within these (a person 0.75 to 1.3 times the body's height).
const SIZE_LIMITS: (f32, f32) = (0.75, 1.3);

/// How the tracker runs.
#[derive(Clone, Copy, Debug)]
pub struct TrackerSettings {
    pub segment: SegmentSettings,
    pub fit: FitSettings,
    /// Points of the person sampled per frame for the fit (about).
    pub points: usize,
    /// Each sampled point's depth is the mean of the person's readings on its surface within
    /// this many pixels ([`crate::denoise`]; 2: a 5 x 5 window); 0: the reading alone.
    pub denoise_px: usize,
    /// Fit iterations per frame when following, and when starting.
    pub iterations: usize,
    pub start_iterations: usize,
    /// Below this share of points on the model, or above this share of the model outside
    /// the silhouette, the fit is restarted from the extrema.
    pub min_inliers: f32,
    pub max_outside: f32,
    /// Points on a joint's bones that make it tracked (fewer: inferred).
    pub min_support: u32,
    /// Below this share of the person's points near the body (after any restart), the fit
    /// has lost the person and every joint of the frame is reported not tracked: the pose
    /// is kept to follow from, but downstream the gate holds the last good skeleton (the
    /// hip centre not tracked) instead of showing a body folded into the wrong limbs. On the
    /// acceptance set's 90 bare and T-shirt recordings, frames tracked well have 82-93 % of
    /// the points (5th-95th percentile) and those 0.4 m off or more 58-74 %; below 0.7
    /// lay 119 of 9,771 frames, 94 of them the dance's (a cartwheel), 2 within 10 cm of the
    /// truth (docs/STATUS.md, session 50). 0: never.
    pub lost_inliers: f32,
    /// How a skirt is told from bare legs ([`crate::skirt`]): where one hides the legs, its
    /// points are left out of the fit and of the build's.
    pub skirt: SkirtSettings,
    /// The person's size as the body's scale, when known (e.g. measured); `None`: from
    /// their height when first seen whole.
    pub scale: Option<f32>,
    /// How the person's build is estimated (by a tracker made with
    /// [`Tracker::estimating`]).
    pub shape: ShapeSettings,
    /// Try the limbs a followed fit seems to have lost afresh ([`recover`]).
    pub recover: bool,
    /// How much of the body's last turn about the vertical (between the last two frames) is
    /// carried into the next frame's starting pose ([`carry_turn`]): 0 none, 1 all.
    pub carry_turn: f32,
    /// A start facing the other way than the person last faced (or, for a new person, with
    /// their back to the sensor) is taken only when it explains the frame better by this
    /// ([`score`]).
    pub turn_margin: f32,
    /// A person's first start also tries the arms hanging, not pulled to the hands' ends,
    /// and keeps that if it explains the frame better (`tracker/start.rs`).
    pub start_arms_hanging: bool,
    /// How the body-part forest's joint proposals are made (with a forest,
    /// [`Tracker::with_parts`]); proposals lighter than `parts_min_weight` (part probability
    /// times depth², m²) are not used.
    pub parts: ProposalSettings,
    pub parts_min_weight: f32,
    /// A person found again within this many seconds of the last frame they were seen in,
    /// and within `same_person_m` of where they were (their centroid), is the same person:
    /// their size, build and pose are kept. (A dancer's walkover or a foot strike can lose
    /// the person for a few frames; sizing them afresh bent double took a man for a body
    /// 0.75 of his height.) Longer, or elsewhere: a new person.
    pub keep_person_s: f64,
    pub same_person_m: f32,
    /// The person's build is found bare or under a layer of clothing this thick on the
    /// trunk and upper arms ([`TrackBody::clothe`]): as the sleeves say
    /// ([`TrackerSettings::sleeve_seen_m`]), else the clothed body is kept if it explains the
    /// kept frames better ([`crate::shape`]; with a [`BuildFit`], by its own cost:
    /// [`TrackerSettings::clothing_margin`]); 0: bare only.
    pub clothing_m: f32,
    /// With a [`BuildFit`], the layer is taken when the fit's cost under it is lower by this
    /// share ([`crate::shape::estimate_with`]).
    pub clothing_margin: f32,
    /// The layer's choice is left to the costs only when the sleeves do not tell
    /// ([`crate::sleeve`]): a median step in the hanging upper arms' outlines of at least
    /// `sleeve_seen_m` takes the layer, under `sleeve_bare_m` leaves it off (infinity and 0:
    /// the costs always decide).
    pub sleeve_seen_m: f32,
    pub sleeve_bare_m: f32,
    /// Every this many frames a body is followed with its back to the sensor, a start facing
    /// it is tried (`tracker/start.rs`, `check_turn`); 0: never.
    pub turn_check_every: usize,
    /// An arm suspected lost because it is folded up on itself is also tried at rest,
    /// pulled nowhere ([`recover`]). Off: on the acceptance sets (session 44) the means
    /// gained 1.6-2.0 mm on both noises, the T-shirt's lost arms most, but as many
    /// recordings lost as gained, and no rendered case was found where it alone finds the arm.
    pub recover_folded_at_rest: bool,
    /// Legs whose ankles are not at the feet seen near the floor are also tried with the
    /// ankles pulled there (`tracker/feet.rs`): under a skirt, a lost leg has little else
    /// to bring it back.
    pub recover_by_feet: bool,
}

impl Default for TrackerSettings {
    fn default() -> Self {
        Self {
            segment: SegmentSettings::default(),
            fit: FitSettings::default(),
            points: 1200,
            denoise_px: 2,
            iterations: 8,
            start_iterations: 30,
            min_inliers: 0.6,
            max_outside: 0.25,
            min_support: 4,
            lost_inliers: 0.7,
            skirt: SkirtSettings::default(),
            scale: None,
            shape: ShapeSettings::default(),
            recover: true,
            carry_turn: 1.0,
            turn_margin: 0.06,
            start_arms_hanging: true,
            parts: ProposalSettings::default(),
            parts_min_weight: 2.0,
            keep_person_s: 0.5,
            same_person_m: 1.0,
            clothing_m: 0.025,
            clothing_margin: 0.01,
            sleeve_seen_m: 0.02,
            sleeve_bare_m: 0.01,
            turn_check_every: 10,
            recover_folded_at_rest: false,
            recover_by_feet: true,
        }
    }
}

/// The SDK's three joint states.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Confidence {
    Tracked,
    /// Seen too little (occluded, or the fit's guess): the position is inferred.
    Inferred,
    /// Outside the image or no one tracked.
    NotTracked,
}

impl Confidence {
    /// As [`JointSample::confidence`]: 1, 0.5, 0.
    pub fn value(self) -> f32 {
        match self {
            Self::Tracked => 1.0,
            Self::Inferred => 0.5,
            Self::NotTracked => 0.0,
        }
    }
}

/// One joint of the tracked skeleton.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct TrackedJointOut {
    /// Sensor space, metres.
    pub position: Vec3,
    /// Its pixel in the depth image (may lie outside the image).
    pub pixel: [f32; 2],
    pub confidence: Confidence,
    /// As [`JointSample::orientation`].
    #[serde(skip)]
    pub orientation: Quat,
}

/// What the tracker made of one frame.
#[derive(Clone, Debug)]
pub struct Tracked {
    pub joints: [TrackedJointOut; KinectJoint::COUNT],
    /// The fitted body pose.
    pub pose: Pose,
    pub fit: FitStats,
    /// Whether this frame (re)started the fit from the extrema.
    pub started: bool,
    /// Shared: the app's user map holds the same one (no copy of the mask per frame).
    pub person: Arc<Segmentation>,
    /// How many times the tracker has changed its body's build or size: the joints move
    /// when it does, though the person did not (to tell the two apart, e.g. when checking
    /// that the person stands still).
    pub body_changes: u32,
    /// Where a skirt hid the legs ([`crate::skirt`]): found in this frame (its points left
    /// out of the fit) or worn, found in the last ones (its points weighed as a skirt's).
    pub skirt: Option<SkirtZone>,
}

impl Tracked {
    /// The Kinect v1 skeleton frame of this result.
    pub fn sensor_frame(&self, timestamp_s: f64, sequence: u64) -> SensorFrame {
        let mut joints = [JointSample::default(); KinectJoint::COUNT];
        for (out, j) in joints.iter_mut().zip(&self.joints) {
            *out = JointSample {
                position: j.position,
                orientation: j.orientation,
                confidence: j.confidence.value(),
            };
        }
        SensorFrame {
            timestamp_s,
            sequence,
            joints,
        }
    }
}

/// A frame the person is tracked well in, wholly in the image: the build and the size are
/// measured on such frames.
fn tracked_well(started: bool, fit: &FitStats, person: &Segmentation) -> bool {
    !started
        && fit.inliers >= WELL_INLIERS
        && fit.outside <= 0.1
        && person.bbox[1] > 0
        && usize::from(person.bbox[3]) + 1 < HEIGHT
}

/// The share of the person's points near the body in a frame tracked well. (It was 0.8: a
/// body sized too small, by a person crouching when first seen, or fitted under a loose
/// T-shirt, stayed under it and was never sized again nor given its build: in 8 of the
/// acceptance set's 45 T-shirt recordings. At 0.6 the T-shirt set went 99.1 -> 89.8 mm,
/// trunk 75.8 -> 67.0, the bare set 59.0 -> 56.5, trunk 34.4 -> 32.7; 0.5 gave the same.)
const WELL_INLIERS: f32 = 0.6;

/// A later look at the person's build takes frames in which the body's top seen is at least
/// this share of its height ([`Tracker::standing_tall`]). The first look takes the first
/// frames tracked well, whatever the person does there: a person first seen crouching (the
/// T-shirt recordings of CMU 02_04 and 13_39 start in a jump's crouch) is started on a body
/// sized to the crouch (0.75 of a man's height), and the build fitted to those frames kept a
/// 175 cm man 157-162 cm tall for good; from frames of him standing it is 172-174 cm.
const TALL: f32 = 0.92;

/// A skirt worn is taken to hang below the hips only while the trunk leans less than 45°
/// from the floor's normal (cosine).
const UPRIGHT_COS: f32 = std::f32::consts::FRAC_1_SQRT_2;

/// Where the estimate of the person's build is.
enum Estimation {
    /// The tracker keeps its body.
    Off,
    /// Keeping frames the person is tracked well in; frames since the last one kept.
    Collecting(Vec<Snapshot>, usize),
    /// The search runs on its own thread.
    Running(JoinHandle<Result<Estimate, ShapeSearchError>>),
    /// The body is the person's build (or the search failed: the body kept).
    Done,
}

mod feet;
mod front;
mod recover;
mod start;

use start::carry_turn;

/// The tracker's state between frames.
pub struct Tracker {
    pub body: TrackBody,
    pub settings: TrackerSettings,
    segmenter: Segmenter,
    silhouette: Silhouette,
    fitter: Fitter,
    posed: Posed,
    points: Vec<Vec3>,
    /// Scratch: the points standing out of the body this frame (`front`).
    standing_out: Vec<Vec3>,
    pose: Option<Pose>,
    /// The root's rotation in the frame before `pose`'s, when both were followed (the body's
    /// turn, [`carry_turn`]).
    previous: Option<Quat>,
    /// The person's size (the body's scale), measured when they were first seen whole.
    scale: Option<f32>,
    /// The sizes the frames tracked well imply ([`Self::refine_size`]).
    sizing: Vec<f32>,
    /// See [`Tracked::body_changes`].
    body_changes: u32,
    /// Per Kinect bone, the inverse of the motion pipeline's constant `C` (its driver's rest
    /// frame against the sensor's T-pose reference): the orientation reported is the driver's
    /// frame times it, so the retargeter's `G = Q C` gives back the fitted frame.
    corrections: [Quat; KinectJoint::COUNT],
    /// How many times the fit was (re)started.
    pub starts: usize,
    /// Frames followed since the last start or turn check.
    followed: usize,
    /// How many times a lost limb was found again ([`recover`]), and that search's fitter.
    pub recoveries: usize,
    recovery: Fitter,
    /// The body model the person's build is estimated with (`None`: no estimation), and
    /// its default body (each new person's until their build is known).
    model: Option<Arc<BodyModel>>,
    default_body: Option<Box<TrackBody>>,
    /// The fitter of the person's build, if not the macro search ([`crate::shape`]).
    build_fit: Option<Arc<dyn BuildFit>>,
    estimation: Estimation,
    /// How many searches for the build ran for this person.
    looks: usize,
    /// The steps in the person's sleeves measured in the frames kept so far ([`crate::sleeve`]).
    sleeve_steps: Vec<f32>,
    /// The build estimated for the person tracked, and its search's report.
    pub shape: Option<Estimate>,
    /// Why the last search for a build failed (the body kept), or what part of it did (the
    /// body under the clothing: the clothed build worn), if anything did.
    pub shape_error: Option<String>,
    /// The time of the search for the build, ms, if one ran in the last frame tracked.
    pub search_ms: Option<f64>,
    /// The body-part forest, if the tracker uses one, its buffers and this frame's joint
    /// proposals.
    parts: Option<Arc<Forest>>,
    part_scratch: PartScratch,
    proposals: Vec<Proposal>,
    /// When the person was last seen (the frame's time, s) and where (their centroid).
    last_seen: Option<(f64, Vec3)>,
    /// Where a skirt hides the legs in this frame, from the pose followed into it.
    skirt: Option<SkirtZone>,
    /// The skirts found in the last frames: one worn where this frame does not show it.
    skirts: SkirtMemory,
}

impl Tracker {
    /// A tracker that fits `body` as it is.
    pub fn new(body: TrackBody, settings: TrackerSettings) -> Self {
        Self {
            corrections: corrections(&body),
            body,
            segmenter: Segmenter::new(settings.segment),
            settings,
            silhouette: Silhouette::default(),
            fitter: Fitter::default(),
            posed: Posed::default(),
            points: Vec::new(),
            standing_out: Vec::new(),
            pose: None,
            previous: None,
            scale: None,
            sizing: Vec::new(),
            body_changes: 0,
            starts: 0,
            followed: 0,
            recoveries: 0,
            recovery: Fitter::default(),
            model: None,
            default_body: None,
            build_fit: None,
            estimation: Estimation::Off,
            looks: 0,
            sleeve_steps: Vec::new(),
            shape: None,
            shape_error: None,
            search_ms: None,
            parts: None,
            part_scratch: PartScratch::default(),
            proposals: Vec::new(),
            last_seen: None,
            skirt: None,
            skirts: SkirtMemory::default(),
        }
    }

    /// This tracker with joint proposals from `forest` ([`crate::bodyparts`]) for the limbs
    /// it suspects lost ([`recover`]).
    pub fn with_parts(mut self, forest: Arc<Forest>) -> Self {
        self.parts = Some(forest);
        self
    }

    /// The forest's joint proposals for `frame` into `self.proposals` (none without a forest).
    fn propose(&mut self, frame: &DepthFrame, person: &Segmentation) {
        self.proposals.clear();
        if let Some(forest) = &self.parts {
            let s = self.settings;
            self.proposals = propose(forest, frame, &person.mask, s.parts, &mut self.part_scratch);
            self.proposals.retain(|q| q.weight >= s.parts_min_weight);
        }
    }

    /// A tracker that starts from `model`'s default body and estimates each person's build
    /// while tracking them ([`crate::shape`]).
    pub fn estimating(
        model: Arc<BodyModel>,
        settings: TrackerSettings,
    ) -> Result<Self, ModelError> {
        let body = TrackBody::new(&model, &model.positions)?;
        Ok(Self {
            model: Some(model),
            default_body: Some(Box::new(body.clone())),
            estimation: Estimation::Collecting(Vec::new(), usize::MAX),
            ..Self::new(body, settings)
        })
    }

    /// This tracker with the person's build found by `fit` instead of the macro search (the
    /// body it gives has the person's size). Only for a tracker [`Self::estimating`].
    pub fn with_build_fit(mut self, fit: Arc<dyn BuildFit>) -> Self {
        self.build_fit = Some(fit);
        self
    }

    /// The median step in the person's sleeves seen so far, metres ([`crate::sleeve`];
    /// `None`: fewer than three hanging upper arms seen in the frames kept for the build).
    pub fn sleeve_step_m(&self) -> Option<f32> {
        sleeve::median_step(&self.sleeve_steps)
    }

    /// The person's build, once estimated.
    pub fn person_shape(&self) -> Option<&Shape> {
        self.shape.as_ref().map(|e| &e.shape)
    }

    /// Keeps `tracked`'s frame for the build's search if the person is tracked well in it;
    /// runs the search when enough are kept; takes its answer when it is ready.
    fn estimate_shape(&mut self, frame: &DepthFrame, tracked: &Tracked) {
        let settings = self.settings.shape;
        // A later look is taken from frames of the person standing upright.
        let again = self.looks > 0 && matches!(self.estimation, Estimation::Collecting(..));
        let good = tracked_well(tracked.started, &tracked.fit, &tracked.person)
            && (!again || self.standing_tall(tracked));
        match &mut self.estimation {
            Estimation::Collecting(kept, since) => {
                *since = since.saturating_add(1);
                let every = if again {
                    settings.again_every
                } else {
                    settings.every
                };
                if !good || *since < every {
                    return;
                }
                *since = 0;
                kept.push(Snapshot {
                    frame: frame.clone(),
                    tracked: tracked.clone(),
                });
                if kept.len() < settings.snapshots {
                    return;
                }
                let Some(model) = self.model.clone() else {
                    return;
                };
                let kept = std::mem::take(kept);
                for k in &kept {
                    let joints: Vec<_> = k
                        .tracked
                        .joints
                        .iter()
                        .map(|j| (j.position, j.pixel))
                        .collect();
                    self.sleeve_steps.extend(sleeve::steps(
                        &k.frame,
                        &k.tracked.person.mask,
                        &joints,
                    ));
                }
                let sleeves = sleeve::judge(
                    &self.sleeve_steps,
                    self.settings.sleeve_seen_m,
                    self.settings.sleeve_bare_m,
                );
                let (body, mut tracker_settings) = (self.body.clone(), self.settings);
                tracker_settings.points = settings.points;
                let build_fit = self.build_fit.clone();
                self.looks += 1;
                let search = move || match build_fit {
                    Some(fit) => estimate_with(&model, &*fit, &kept, &tracker_settings, sleeves),
                    None => estimate(
                        &model,
                        &body,
                        &kept,
                        &tracker_settings,
                        settings.iterations,
                        sleeves,
                    ),
                };
                if settings.background {
                    self.estimation = Estimation::Running(std::thread::spawn(search));
                } else {
                    let start = std::time::Instant::now();
                    let found = search();
                    self.search_ms = Some(start.elapsed().as_secs_f64() * 1e3);
                    self.adopt(found);
                }
            }
            Estimation::Running(handle) if handle.is_finished() => {
                let Estimation::Running(handle) =
                    std::mem::replace(&mut self.estimation, Estimation::Done)
                else {
                    return;
                };
                let found = handle.join().unwrap_or(Err(ShapeSearchError::Stopped));
                self.adopt(found);
            }
            _ => {}
        }
    }

    /// Whether `tracked`'s body (`self.posed`) stands upright with its head as its top: its
    /// top seen over the floor at least [`TALL`] of its height (not crouched nor bowed), and
    /// no hand above the head.
    fn standing_tall(&self, tracked: &Tracked) -> bool {
        let floor = tracked.person.floor;
        let on_floor = -floor.normal * floor.d;
        let head = self.body.kinect[KinectJoint::Head.index()].0;
        let height = self.body.height_m * tracked.pose.scale;
        matches!(
            self.body.seen_top(&self.posed, on_floor, floor.normal),
            Some((top, bone)) if bone == head && top >= TALL * height
        )
    }

    /// Fits the person with the body of their build from now on: at the same size as before,
    /// or at its own if it has the person's ([`Estimate::sized`]).
    fn adopt(&mut self, found: Result<Estimate, ShapeSearchError>) {
        self.estimation = if self.looks < self.settings.shape.looks {
            Estimation::Collecting(Vec::new(), 0)
        } else {
            Estimation::Done
        };
        let estimate = match found {
            Ok(e) => e,
            Err(e) => {
                self.shape_error = Some(e.to_string());
                return;
            }
        };
        self.shape_error = estimate
            .under_clothes_error
            .as_ref()
            .map(|e| format!("the body under the clothing: {e}; the clothed build is worn"));
        if estimate.sized {
            // The body is the person's size: scale 1 from now on, the soles where they were.
            if let Some(pose) = &mut self.pose {
                let was = self.body.sole_y * pose.scale;
                pose.translation += pose.rotation * (Vec3::Y * (was - estimate.body.sole_y));
                pose.scale = 1.0;
            }
            self.scale = Some(1.0);
        } else {
            let resize = self.body.height_m / estimate.body.height_m;
            if let Some(scale) = &mut self.scale {
                *scale *= resize;
            }
            if let Some(pose) = &mut self.pose {
                pose.scale *= resize;
            }
        }
        self.body = estimate.body.clone();
        self.corrections = corrections(&self.body);
        self.shape = Some(estimate);
        // The new body's head reads otherwise: measure the size on it again.
        self.sizing.clear();
        self.body_changes = self.body_changes.wrapping_add(1);
    }

    fn forget_size(&mut self) {
        self.scale = None;
        self.sizing.clear();
    }

    /// The size measured again in frames tracked well: each frame's top seen against the
    /// top of the fitted body's outline as posed (frames whose fitted top is not the head
    /// are skipped). The size measured when the tracking starts comes from one frame and
    /// the rest pose, and the person may walk with bent knees or a bowed head there; the fit
    /// explains a person bowed as well by a smaller body standing straighter. A posture only
    /// ever lowers the top, so the size is an upper quantile of the frames'
    /// ([`SIZE_QUANTILE`]), set anew every [`SIZE_EVERY`] frames until [`SIZE_FRAMES`].
    fn refine_size(&mut self, person: &Segmentation, pose: &mut Pose, well: bool) {
        // A body of the person's size (a `BuildFit` made it) is not sized again.
        let sized = self.shape.as_ref().is_some_and(|e| e.sized);
        if self.sizing.len() >= SIZE_FRAMES || !well || sized || self.settings.scale.is_some() {
            return;
        }
        let floor = person.floor;
        let on_floor = -floor.normal * floor.d;
        let head = self.body.kinect[KinectJoint::Head.index()].0;
        match self.body.seen_top(&self.posed, on_floor, floor.normal) {
            Some((top, bone)) if bone == head && top > 0.5 => {
                self.sizing.push(pose.scale * person.top_m / top);
            }
            _ => return,
        }
        if !self.sizing.len().is_multiple_of(SIZE_EVERY) {
            return;
        }
        let mut sorted = self.sizing.clone();
        sorted.sort_by(f32::total_cmp);
        let at = ((sorted.len() - 1) as f32 * SIZE_QUANTILE).round() as usize;
        let size = sorted[at].clamp(SIZE_LIMITS.0, SIZE_LIMITS.1);
        // Grown about the soles, which stay where they are.
        let sole = Vec3::Y * self.body.sole_y;
        pose.translation += pose.rotation * (sole * (pose.scale - size));
        pose.scale = size;
        self.scale = Some(size);
        self.body_changes = self.body_changes.wrapping_add(1);
    }

    /// A new person: the default body until their build is estimated anew (a body of the
    /// last person's build fits the next one worse than the default: on 90 recordings
    /// evaluated one after the other, 128 mm against 92).
    fn forget_shape(&mut self) {
        if self.model.is_none() {
            return;
        }
        self.estimation = Estimation::Collecting(Vec::new(), usize::MAX);
        self.looks = 0;
        self.sleeve_steps.clear();
        if self.shape.take().is_some()
            && let Some(body) = &self.default_body
        {
            self.body = (**body).clone();
            self.corrections = corrections(&self.body);
        }
    }

    /// Forgets the person: the next frame starts afresh.
    pub fn reset(&mut self) {
        self.forget_person();
        self.segmenter.reset();
    }

    /// The next person seen is someone new: started afresh, sized and measured anew.
    fn forget_person(&mut self) {
        self.pose = None;
        self.previous = None;
        self.last_seen = None;
        self.skirts.clear();
        self.forget_size();
        self.forget_shape();
    }

    /// Whether a person seen at `time_s` (at `centroid`, if seen) may be the one last seen
    /// ([`TrackerSettings::keep_person_s`]).
    fn same_person(&self, time_s: f64, centroid: Option<Vec3>) -> bool {
        let Some((seen_s, seen_at)) = self.last_seen else {
            return false;
        };
        let gap = time_s - seen_s;
        (0.0..=self.settings.keep_person_s).contains(&gap)
            && centroid.is_none_or(|c| c.distance(seen_at) <= self.settings.same_person_m)
    }

    /// The skeleton in `frame`, `None` when no one is there.
    pub fn track(&mut self, frame: &DepthFrame) -> Option<Tracked> {
        self.search_ms = None;
        let Some(person) = self.segmenter.segment(frame) else {
            // Gone for a moment (kept), or gone.
            self.previous = None;
            if !self.same_person(frame.time_s, None) {
                self.forget_person();
            }
            return None;
        };
        if !self.same_person(frame.time_s, Some(person.centroid)) {
            self.forget_person();
        }
        self.last_seen = Some((frame.time_s, person.centroid));
        self.sample_points(frame, &person);
        self.silhouette.update(&person.mask, person.bbox);
        let settings = self.settings;
        let mut started = false;
        let previous = self.previous.take();
        // The skirt about the hips of the pose followed into the frame (a start has none).
        // A skirt worn but not seen in this frame is taken as found in the last ones.
        let followed = self.pose.take();
        if let Some(pose) = &followed {
            let found = self.skirt_at(frame, &person, pose);
            self.skirts
                .note(frame.time_s, found.as_ref(), &self.settings.skirt);
            self.skirt = found.or_else(|| self.skirt_worn(frame, &person, pose));
        } else {
            self.skirt = None;
        }
        self.pose = followed;
        let (pose, fit) = match self.pose.take() {
            Some(mut pose) => {
                let last = pose.rotation;
                if let Some(before) = previous {
                    carry_turn(&mut pose, before, person.floor.normal, settings.carry_turn);
                }
                self.previous = Some(last);
                let fit = self.fit(frame, &person, &mut pose, &[], settings.iterations);
                let (pose, fit) = if settings.recover {
                    self.recover(frame, &person, pose, fit)
                } else {
                    (pose, fit)
                };
                self.followed += 1;
                if fit.inliers < settings.min_inliers || fit.outside > settings.max_outside {
                    let away = self.faces_away(&pose);
                    let support = self.fitter.support.clone();
                    let (fresh, fresh_fit) = self.start(frame, &person, away, false);
                    started = true;
                    self.previous = None;
                    if score(&fresh_fit) > score(&fit) {
                        (fresh, fresh_fit)
                    } else {
                        // The kept fit's evidence per capsule is its own, not the start's.
                        self.fitter.support = support;
                        (pose, fit)
                    }
                } else if settings.turn_check_every > 0
                    && self.followed >= settings.turn_check_every
                    && self.faces_away(&pose)
                {
                    self.followed = 0;
                    let (mut pose, mut fit) = (pose, fit);
                    if self.check_turn(frame, &person, &mut pose, &mut fit) {
                        self.starts += 1;
                        started = true;
                        self.previous = None;
                    }
                    (pose, fit)
                } else {
                    (pose, fit)
                }
            }
            None => {
                started = true;
                self.start(frame, &person, false, true)
            }
        };
        if !pose.is_finite() {
            self.pose = None;
            self.previous = None;
            return None;
        }
        let mut joints = self.joints(frame, &pose);
        if fit.inliers < settings.lost_inliers {
            for j in &mut joints {
                j.confidence = Confidence::NotTracked;
            }
        }
        let mut pose = pose;
        self.refine_size(&person, &mut pose, tracked_well(started, &fit, &person));
        self.pose = Some(pose.clone());
        let tracked = Tracked {
            joints,
            pose,
            fit,
            started,
            person: Arc::new(person),
            body_changes: self.body_changes,
            skirt: self.skirt.clone(),
        };
        self.estimate_shape(frame, &tracked);
        Some(tracked)
    }

    /// Fits `pose` to `frame` for `iterations` steps as a frame being followed, the person
    /// segmented afresh, leaving the tracker's state between frames alone: what a body makes
    /// of a frame it did not track (for comparing bodies). `None` when no one is in `frame`.
    pub fn refit(
        &mut self,
        frame: &DepthFrame,
        pose: &mut Pose,
        iterations: usize,
    ) -> Option<FitStats> {
        let person = Segmenter::new(self.settings.segment).segment(frame)?;
        self.sample_points(frame, &person);
        self.silhouette.update(&person.mask, person.bbox);
        self.skirt = self.skirt_at(frame, &person, pose);
        Some(self.fit(frame, &person, pose, &[], iterations))
    }

    /// The skirt the frame shows about the hip joints of `pose` ([`skirt_zone`]).
    fn skirt_at(
        &mut self,
        frame: &DepthFrame,
        person: &Segmentation,
        pose: &Pose,
    ) -> Option<SkirtZone> {
        self.body.pose_into(pose, &mut self.posed);
        let joints = self.body.kinect_joints(&self.posed);
        let at = |j: KinectJoint| joints[j.index()];
        skirt_zone(
            frame,
            &person.mask,
            person.floor.normal,
            at(KinectJoint::HipLeft),
            at(KinectJoint::HipRight),
            &self.settings.skirt,
        )
    }

    /// The skirt worn ([`SkirtMemory::worn`]) about the hip joints of `pose`, if the person
    /// stands upright enough for the hem to be below the hips (not in a cartwheel) and faces
    /// the sensor enough for the legs to part in the image (seen from the side, the legs
    /// hidden by a skirt swapped sides).
    fn skirt_worn(
        &mut self,
        frame: &DepthFrame,
        person: &Segmentation,
        pose: &Pose,
    ) -> Option<SkirtZone> {
        let drop = self.skirts.worn(&self.settings.skirt)?;
        self.body.pose_into(pose, &mut self.posed);
        let joints = self.body.kinect_joints(&self.posed);
        let at = |j: KinectJoint| joints[j.index()];
        let up = person.floor.normal;
        let spine = at(KinectJoint::ShoulderCenter) - at(KinectJoint::HipCenter);
        let (left, right) = (at(KinectJoint::HipLeft), at(KinectJoint::HipRight));
        if up.dot(spine) < UPRIGHT_COS * spine.length()
            || !legs_apart_in_image(&frame.camera, left, right)
        {
            return None;
        }
        Some(SkirtZone {
            seen: false,
            ..SkirtZone::below(up, left, right, drop, &self.settings.skirt)
        })
    }

    /// About [`TrackerSettings::points`] of the person's readings on a regular grid, each
    /// with its noise averaged out ([`TrackerSettings::denoise_px`]).
    fn sample_points(&mut self, frame: &DepthFrame, person: &Segmentation) {
        let step = ((person.pixels as f32 / self.settings.points.max(1) as f32)
            .sqrt()
            .floor() as usize)
            .max(1);
        let [x0, y0, x1, y1] = person.bbox.map(usize::from);
        self.points.clear();
        for y in (y0..=y1.min(HEIGHT - 1)).step_by(step) {
            for x in (x0..=x1.min(WIDTH - 1)).step_by(step) {
                if !person.mask[y * WIDTH + x] {
                    continue;
                }
                let radius = self.settings.denoise_px;
                if let Some(z) = surface_depth_m(&frame.depth_mm, &person.mask, x, y, radius) {
                    self.points
                        .push(frame.camera.unproject(x as f32, y as f32, z));
                }
            }
        }
    }

    fn fit(
        &mut self,
        frame: &DepthFrame,
        person: &Segmentation,
        pose: &mut Pose,
        targets: &[(usize, Vec3, f32)],
        iterations: usize,
    ) -> FitStats {
        let obs = Observation {
            frame,
            mask: &person.mask,
            silhouette: &self.silhouette,
            points: &self.points,
            targets,
            skirt: self.skirt.as_ref(),
        };
        self.fitter
            .fit(&self.body, pose, &obs, &self.settings.fit, iterations)
    }

    /// The Kinect joints of `pose`, their pixels, confidences and orientations.
    fn joints(&mut self, frame: &DepthFrame, pose: &Pose) -> [TrackedJointOut; KinectJoint::COUNT] {
        self.body.pose_into(pose, &mut self.posed);
        let positions = self.body.kinect_joints(&self.posed);
        let turns = self.body.driver_turns(&self.posed);
        let support = self.bone_support();
        let camera = frame.camera;
        let mut out = [TrackedJointOut {
            position: Vec3::ZERO,
            pixel: [0.0; 2],
            confidence: Confidence::NotTracked,
            orientation: Quat::IDENTITY,
        }; KinectJoint::COUNT];
        for joint in KinectJoint::ALL {
            let k = joint.index();
            let p = positions[k];
            let pixel = camera.project(p).map_or([-1.0, -1.0], |v| [v.x, v.y]);
            let in_view = (0.0..WIDTH as f32).contains(&pixel[0])
                && (0.0..HEIGHT as f32).contains(&pixel[1])
                && camera.in_range(p.z);
            let evidence = support[self.body.kinect[k].0] + support[self.body.drivers[k]];
            let confidence = if !in_view {
                Confidence::NotTracked
            } else if evidence >= self.settings.min_support {
                Confidence::Tracked
            } else {
                Confidence::Inferred
            };
            let orientation = match joint.parent() {
                None => turns[k],
                Some(parent) => {
                    let driver = self.posed.rotations[self.body.drivers[k]];
                    let q = (driver * self.corrections[k]).normalize();
                    let bone = (p - positions[parent.index()]).normalize_or_zero();
                    let along = q * Vec3::Y;
                    if bone == Vec3::ZERO {
                        q
                    } else {
                        (Quat::from_rotation_arc(along, bone) * q).normalize()
                    }
                }
            };
            out[k] = TrackedJointOut {
                position: p,
                pixel,
                confidence,
                orientation,
            };
        }
        out
    }
}

impl Tracker {
    /// Per rig bone, the data points on its capsules in the last fit step (the evidence for
    /// it).
    fn bone_support(&self) -> Vec<u32> {
        let mut support = vec![0u32; self.body.parents.len()];
        for (capsule, &n) in self.body.capsules.iter().zip(&self.fitter.support) {
            support[capsule.bone] += n;
        }
        support
    }
}

/// Per Kinect bone, the inverse of the motion pipeline's constant `C` for `body`.
fn corrections(body: &TrackBody) -> [Quat; KinectJoint::COUNT] {
    let mut out = [Quat::IDENTITY; KinectJoint::COUNT];
    for joint in KinectJoint::ALL {
        if joint.parent().is_some() {
            let rest = body.rest_driver_rotations[joint.index()];
            out[joint.index()] = twist_correction(rest, joint).inverse();
        }
    }
    out
}

/// Which of two fits explains the frame better.
fn score(fit: &FitStats) -> f32 {
    fit.inliers - fit.outside
}
