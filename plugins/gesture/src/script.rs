//! Scripted people: the MakeHuman body standing before the mirror and making gestures
//! (turning for the measurement, raising a hand, swiping, gripping), posed bone by bone with
//! its fingers curled or open, for the synthetic camera to film. The kiosk's demo without a
//! camera (`--sensor performer:motions/gestures.ron`) and the end-to-end gesture tests use
//! it: the tracker, the hand reader and the swipe detector see depth of a person whose hand
//! states and strokes are known.
//!
//! A script is a RON file of steps (`assets/motions/gestures.ron`):
//!
//! ```ron
//! GestureScript(distance_m: 2.8, steps: [
//!     Stand(seconds: 2.0),
//!     Turn(degrees: 40.0, seconds: 1.5),
//!     Turn(degrees: 0.0, seconds: 1.0),
//!     Swipe(hand: Right, direction: Right),
//!     Grip(hand: Right),
//! ])
//! ```

use std::path::Path;
use std::sync::Arc;

use fitroom_body::{BodyModel, MODEL_TO_SENSOR, RestPose, forward_kinematics};
use fitroom_depth::synthetic::{Label, SceneMesh};
use fitroom_sensor::KinectJoint;
use fitroom_tracker::kinect::rig_joints;
use glam::{Quat, Vec3};
use serde::{Deserialize, Serialize};

use crate::eval::swipes::min_jerk;
use crate::swipe::SwipeDirection;
use crate::synth::{ArmPose, pose_arm};
use crate::{HandSide, HandState};

/// Frames per second of a performance (the Kinect v1's).
pub const SCRIPT_FPS: f64 = 30.0;

/// What the person does, step by step.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GestureScript {
    /// From the sensor to the person's pelvis, metres.
    #[serde(default = "default_distance")]
    pub distance_m: f32,
    pub steps: Vec<Step>,
}

/// Far enough for a sensor 0.8 m above the floor to see an average person's head and raised
/// hand (the Kinect v1 sees 21.5° above its axis).
fn default_distance() -> f32 {
    2.8
}

/// One step of a script. Between steps the arms hang a little away from the body.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum Step {
    /// Standing still, arms hanging a little away from the body.
    Stand { seconds: f32 },
    /// Turning to `degrees` from facing the mirror (positive: to the person's left) in 0.8 s,
    /// then standing `seconds`.
    Turn { degrees: f32, seconds: f32 },
    /// The hand rises out to the side and on to the stroke's start (0.9 s), holds 0.5 s,
    /// sweeps `travel` shoulder widths in `seconds` (centred 1.2 widths to the hand's side),
    /// holds 0.2 s and drops (0.7 s); `height` (from the shoulders) and `reach` (in front of
    /// them) in shoulder widths.
    Swipe {
        hand: HandSide,
        direction: SwipeDirection,
        #[serde(default = "default_sweep_s")]
        seconds: f32,
        #[serde(default = "default_travel")]
        travel: f32,
        #[serde(default = "default_height")]
        height: f32,
        #[serde(default = "default_reach")]
        reach: f32,
    },
    /// The hand rises open before its shoulder, a little outside it (0.7 s), holds 0.5 s,
    /// closes into a fist (0.25 s), stays closed `seconds`, opens (0.25 s), holds 0.4 s and
    /// drops (0.7 s).
    Grip {
        hand: HandSide,
        #[serde(default = "default_grip_s")]
        seconds: f32,
    },
}

fn default_sweep_s() -> f32 {
    0.45
}
fn default_travel() -> f32 {
    1.2
}
fn default_height() -> f32 {
    -0.2
}
fn default_reach() -> f32 {
    0.55
}
fn default_grip_s() -> f32 {
    0.8
}

/// A script that cannot be read or played.
#[derive(Debug, thiserror::Error)]
pub enum ScriptError {
    #[error("cannot read the gesture script '{path}': {source}")]
    Io {
        path: String,
        source: std::io::Error,
    },
    #[error(
        "{path}:{line}:{column}: {message} (a gesture script is `GestureScript(distance_m: 2.8, steps: [Stand(seconds: 2.0), Swipe(hand: Right, direction: Right), Grip(hand: Right)])`)"
    )]
    Parse {
        path: String,
        line: usize,
        column: usize,
        message: String,
    },
    #[error("{path}: {message}")]
    Invalid { path: String, message: String },
    #[error("the body's rig lacks the bone '{0}' a gesture script poses")]
    MissingBone(String),
}

impl GestureScript {
    pub fn load(path: &Path) -> Result<Self, ScriptError> {
        let text = std::fs::read_to_string(path).map_err(|source| ScriptError::Io {
            path: path.display().to_string(),
            source,
        })?;
        Self::from_ron_str(&text, &path.display().to_string())
    }

    /// Parses and checks a script (`name` is for errors).
    pub fn from_ron_str(text: &str, name: &str) -> Result<Self, ScriptError> {
        let script: Self = ron::from_str(text).map_err(|e| ScriptError::Parse {
            path: name.into(),
            line: e.span.start.line,
            column: e.span.start.col,
            message: e.code.to_string(),
        })?;
        let invalid = |message: String| ScriptError::Invalid {
            path: name.into(),
            message,
        };
        if !(0.8..=5.0).contains(&script.distance_m) {
            return Err(invalid(format!(
                "distance_m {} is outside the Kinect's 0.8-5 m",
                script.distance_m
            )));
        }
        if script.steps.is_empty() {
            return Err(invalid("the script has no steps".into()));
        }
        for (k, step) in script.steps.iter().enumerate() {
            let (what, value, range) = match *step {
                Step::Stand { seconds } => ("seconds", seconds, 0.0..=600.0),
                Step::Turn { degrees, seconds } => {
                    if !(-90.0..=90.0).contains(&degrees) {
                        return Err(invalid(format!(
                            "step {}: Turn degrees {degrees} is outside -90..90",
                            k + 1
                        )));
                    }
                    ("seconds", seconds, 0.0..=600.0)
                }
                Step::Swipe {
                    seconds,
                    travel,
                    height,
                    reach,
                    ..
                } => {
                    for (field, v, r) in [
                        ("travel", travel, 0.5..=2.0),
                        ("height", height, -1.5..=1.0),
                        ("reach", reach, 0.3..=1.5),
                    ] {
                        if !r.contains(&v) {
                            return Err(invalid(format!(
                                "step {}: Swipe {field} {v} is outside {:?} shoulder widths",
                                k + 1,
                                r
                            )));
                        }
                    }
                    ("seconds", seconds, 0.1..=3.0)
                }
                Step::Grip { seconds, .. } => ("seconds", seconds, 0.1..=600.0),
            };
            if !range.contains(&value) {
                return Err(invalid(format!(
                    "step {}: {what} {value} is outside {range:?}",
                    k + 1
                )));
            }
        }
        Ok(script)
    }

    /// The script's length, seconds.
    pub fn duration_s(&self) -> f32 {
        self.segments(&BodyFrame::default())
            .iter()
            .map(|s| s.seconds)
            .sum()
    }

    /// The script as timed segments between arm and body states.
    fn segments(&self, body: &BodyFrame) -> Vec<Segment> {
        let hang = [body.hanging(HandSide::Left), body.hanging(HandSide::Right)];
        let mut out = Vec::new();
        let mut yaw = 0.0;
        // One arm moving through `moves` (seconds, from, to), the other hanging.
        let arm =
            |out: &mut Vec<Segment>, yaw: f32, hand: HandSide, moves: &[(f32, ArmKey, ArmKey)]| {
                let with = |key: ArmKey| {
                    let mut arms = hang;
                    arms[hand.index()] = key;
                    arms
                };
                out.extend(moves.iter().map(|&(seconds, a, b)| Segment {
                    seconds,
                    yaw: (yaw, yaw),
                    arms: (with(a), with(b)),
                }));
            };
        for step in &self.steps {
            match *step {
                Step::Stand { seconds } => out.push(Segment {
                    seconds,
                    yaw: (yaw, yaw),
                    arms: (hang, hang),
                }),
                Step::Turn { degrees, seconds } => {
                    out.push(Segment {
                        seconds: 0.8,
                        yaw: (yaw, degrees),
                        arms: (hang, hang),
                    });
                    yaw = degrees;
                    out.push(Segment {
                        seconds,
                        yaw: (yaw, yaw),
                        arms: (hang, hang),
                    });
                }
                Step::Swipe {
                    hand,
                    direction,
                    seconds,
                    travel,
                    height,
                    reach,
                } => {
                    let side = hand.rightward();
                    let sign = match direction {
                        SwipeDirection::Right => 1.0,
                        SwipeDirection::Left => -1.0,
                    };
                    // The stroke is on the hand's own side, outside the shoulder: an arm
                    // before the chest is the depth tracker's hardest case (it hides in
                    // front of the body), and the tracker loses it there.
                    let mid = side * 1.2;
                    let at = |x: f32| ArmKey::raised(body.at(x, height, reach), OPEN_CURL);
                    let (start, end) =
                        (at(mid - sign * travel * 0.5), at(mid + sign * travel * 0.5));
                    // The arm rises out to the side first, then forwards to the start:
                    // outside the body's outline all the way, as people raise an arm to
                    // swipe (and where a depth tracker can follow it).
                    let aside = ArmKey {
                        wrist: body.at(side * 1.5, -1.0, 0.25),
                        curl: OPEN_CURL,
                        raised: 0.5,
                    };
                    let down = hang[hand.index()];
                    arm(
                        &mut out,
                        yaw,
                        hand,
                        &[
                            (0.5, down, aside),
                            (0.4, aside, start),
                            (0.5, start, start),
                            (seconds, start, end),
                            (0.2, end, end),
                            (0.7, end, down),
                        ],
                    );
                }
                Step::Grip { hand, seconds } => {
                    // Before and a little outside the shoulder, the forearm raised (the
                    // hand in the hand cursor's box's upper part).
                    let wrist = body.at(hand.rightward() * 0.9, -0.2, 0.55);
                    let open = ArmKey::raised(wrist, OPEN_CURL);
                    let closed = ArmKey::raised(wrist, 1.0);
                    let down = hang[hand.index()];
                    arm(
                        &mut out,
                        yaw,
                        hand,
                        &[
                            (0.7, down, open),
                            (0.5, open, open),
                            (0.25, open, closed),
                            (seconds, closed, closed),
                            (0.25, closed, open),
                            (0.4, open, open),
                            (0.7, open, down),
                        ],
                    );
                }
            }
        }
        out
    }
}

/// An open raised hand's curl, and a hanging hand's (relaxed).
const OPEN_CURL: f32 = 0.05;
const HANGING_CURL: f32 = 0.3;

/// Where one arm is at a key: its wrist (model space) and its fingers' curl; `raised` 0
/// (hanging) to 1 (raised before the body: the palm to the mirror).
#[derive(Clone, Copy, Debug, PartialEq)]
struct ArmKey {
    wrist: Vec3,
    curl: f32,
    raised: f32,
}

impl ArmKey {
    fn raised(wrist: Vec3, curl: f32) -> Self {
        Self {
            wrist,
            curl,
            raised: 1.0,
        }
    }

    fn lerp(self, other: Self, t: f32) -> Self {
        Self {
            wrist: self.wrist.lerp(other.wrist, t),
            curl: self.curl + (other.curl - self.curl) * t,
            raised: self.raised + (other.raised - self.raised) * t,
        }
    }
}

/// A stretch of time from one state to another (min-jerk in between).
#[derive(Clone, Copy, Debug)]
struct Segment {
    seconds: f32,
    yaw: (f32, f32),
    arms: ([ArmKey; 2], [ArmKey; 2]),
}

/// The body's frame in model space, standing in its rest pose: the shoulder centre, the
/// shoulder width, both shoulders and the arm's two bone lengths.
#[derive(Clone, Copy, Debug)]
struct BodyFrame {
    centre: Vec3,
    width: f32,
    /// [left, right].
    shoulders: [Vec3; 2],
    upper_m: f32,
    forearm_m: f32,
}

impl Default for BodyFrame {
    /// An average body's (only the timing is read from it).
    fn default() -> Self {
        Self {
            centre: Vec3::new(0.0, 1.45, 0.0),
            width: 0.36,
            shoulders: [Vec3::new(0.18, 1.42, 0.0), Vec3::new(-0.18, 1.42, 0.0)],
            upper_m: 0.28,
            forearm_m: 0.26,
        }
    }
}

impl BodyFrame {
    /// A point before the body: `x` to the person's right, `up` and `forward` (shoulder
    /// widths) from the shoulder centre (model space: the body faces +Z, +X its left).
    fn at(&self, x: f32, up: f32, forward: f32) -> Vec3 {
        self.centre + Vec3::new(-x, up, forward) * self.width
    }

    /// The hanging arm's key: the arm nearly straight, 18° away from the body (the pose
    /// the measurement asks for: arms a hand's width from the body).
    fn hanging(&self, side: HandSide) -> ArmKey {
        let out = side.outward();
        let angle = 18f32.to_radians();
        let length = (self.upper_m + self.forearm_m) * 0.97;
        let dir = Vec3::new(out * angle.sin(), -angle.cos(), 0.05).normalize();
        ArmKey {
            wrist: self.shoulders[side.index()] + dir * length,
            curl: HANGING_CURL,
            raised: 0.0,
        }
    }

    /// The upper arm's and forearm's directions that put `side`'s wrist at `wrist` (two-bone
    /// IK; the elbow bends down, out and back).
    fn arm_dirs(&self, side: HandSide, wrist: Vec3) -> (Vec3, Vec3) {
        let shoulder = self.shoulders[side.index()];
        let (l1, l2) = (self.upper_m, self.forearm_m);
        let to = wrist - shoulder;
        let d = to.length().clamp((l1 - l2).abs() + 1e-3, (l1 + l2) * 0.999);
        let dir = to.normalize_or(Vec3::NEG_Y);
        let pole = Vec3::new(side.outward() * 0.5, -1.0, -0.6);
        let bend = (pole - dir * pole.dot(dir)).normalize_or(Vec3::NEG_Z);
        let a = (l1 * l1 - l2 * l2 + d * d) / (2.0 * d);
        let h = (l1 * l1 - a * a).max(0.0).sqrt();
        let elbow = shoulder + dir * a + bend * h;
        let wrist = shoulder + dir * d;
        (
            (elbow - shoulder).normalize_or(Vec3::NEG_Y),
            (wrist - elbow).normalize_or(Vec3::NEG_Y),
        )
    }
}

/// One frame of a performance.
#[derive(Clone, Debug)]
pub struct ScriptFrame {
    pub time_s: f64,
    /// Per bone, the rotation from rest (model space).
    pub locals: Vec<Quat>,
    /// The body turned from facing the mirror, degrees (positive: to its left).
    pub yaw_deg: f32,
    /// [left, right]: the fingers' curl, and the hand's state as a person would call it
    /// (open or closed when raised before the body, unknown while hanging or moving).
    pub curl: [f32; 2],
    pub hands: [HandState; 2],
}

/// A body performing a script in sensor space: the skin and the 20 Kinect joints of each
/// frame.
pub struct ScriptedPerson {
    model: Arc<BodyModel>,
    positions: Vec<Vec3>,
    rest: RestPose,
    /// The rest pose's pelvis (model space) and sole height: the turning axis and the floor.
    pivot: Vec3,
    floor_y: f32,
    distance_m: f32,
    frames: Vec<ScriptFrame>,
}

impl ScriptedPerson {
    /// `script` performed by the body `positions` (all vertices, morphed) with rest pose
    /// `rest`, standing on the floor `floor_y` (sensor space).
    pub fn new(
        model: Arc<BodyModel>,
        positions: Vec<Vec3>,
        rest: RestPose,
        script: &GestureScript,
        floor_y: f32,
    ) -> Result<Self, ScriptError> {
        let globals = forward_kinematics(&model.bones, &rest, &[], Vec3::ZERO);
        let head = |name: &str| {
            model
                .bone_index(name)
                .and_then(|b| globals.get(b))
                .map(|g| g.translation)
                .ok_or_else(|| ScriptError::MissingBone(name.into()))
        };
        let shoulders = [head("upperarm_l")?, head("upperarm_r")?];
        let body = BodyFrame {
            centre: head("neck_01")?,
            width: shoulders[0].distance(shoulders[1]),
            shoulders,
            upper_m: head("lowerarm_l")?.distance(shoulders[0]),
            forearm_m: head("hand_l")?.distance(head("lowerarm_l")?),
        };
        let pelvis = head("pelvis")?;
        let n = (model.body_vertex_count as usize).min(positions.len());
        let sole = positions[..n]
            .iter()
            .map(|p| p.y)
            .fold(f32::INFINITY, f32::min);
        let segments = script.segments(&body);
        let total: f32 = segments.iter().map(|s| s.seconds).sum();
        let count = (f64::from(total) * SCRIPT_FPS).ceil().max(1.0) as usize;
        let mut frames = Vec::with_capacity(count);
        for k in 0..count {
            let t = k as f64 / SCRIPT_FPS;
            let (yaw, arms) = sample(&segments, t as f32);
            let mut locals = vec![Quat::IDENTITY; model.bones.len()];
            let mut hands = [HandState::Unknown; 2];
            let mut curl = [0.0; 2];
            for side in [HandSide::Left, HandSide::Right] {
                let i = side.index();
                let key = arms[i];
                let (upper_dir, forearm_dir) = body.arm_dirs(side, key.wrist);
                // The palm faces the thigh while hanging, the mirror when raised.
                let r = key.raised.clamp(0.0, 1.0);
                let palm = (Vec3::new(-side.outward(), 0.0, 0.0) * (1.0 - r) + Vec3::Z * r)
                    .normalize_or(Vec3::Z);
                let arm = ArmPose {
                    upper_dir,
                    forearm_dir,
                    palm,
                    tilt_deg: 0.0,
                    curl: key.curl,
                    spread: 0.6 + 0.4 * r,
                };
                pose_arm(&model, &rest, &mut locals, side, &arm);
                curl[i] = key.curl;
                hands[i] = if r < 0.99 {
                    HandState::Unknown
                } else if key.curl >= 0.8 {
                    HandState::Closed
                } else if key.curl <= 0.2 {
                    HandState::Open
                } else {
                    HandState::Unknown
                };
            }
            frames.push(ScriptFrame {
                time_s: t,
                locals,
                yaw_deg: yaw,
                curl,
                hands,
            });
        }
        Ok(Self {
            model,
            positions,
            rest,
            pivot: Vec3::new(pelvis.x, sole, pelvis.z),
            floor_y,
            distance_m: script.distance_m,
            frames,
        })
    }

    pub fn frames(&self) -> &[ScriptFrame] {
        &self.frames
    }

    /// The performance's length, seconds.
    pub fn duration_s(&self) -> f64 {
        self.frames.len() as f64 / SCRIPT_FPS
    }

    /// Model space to sensor space at frame `k`: turned about the pelvis, the soles on the
    /// floor, the pelvis `distance_m` before the sensor.
    fn to_sensor(&self, k: usize) -> impl Fn(Vec3) -> Vec3 + '_ {
        let yaw = self.frames.get(k).map_or(0.0, |f| f.yaw_deg);
        let turn = Quat::from_rotation_y(yaw.to_radians()) * MODEL_TO_SENSOR;
        let shift = Vec3::new(0.0, self.floor_y, self.distance_m);
        move |p: Vec3| turn * (p - self.pivot) + shift
    }

    /// The skin at frame `k` (clamped to the last), as the synthetic camera's scene mesh.
    pub fn mesh(&self, k: usize) -> SceneMesh {
        let k = k.min(self.frames.len().saturating_sub(1));
        let locals = self.frames.get(k).map_or(&[][..], |f| &f.locals[..]);
        let globals = forward_kinematics(&self.model.bones, &self.rest, locals, Vec3::ZERO);
        let n = (self.model.body_vertex_count as usize).min(self.positions.len());
        let to_sensor = self.to_sensor(k);
        let positions = self
            .model
            .skin_positions(&self.positions[..n], &self.rest, &globals)
            .into_iter()
            .map(to_sensor)
            .collect();
        SceneMesh {
            positions,
            triangles: self.model.triangles.clone(),
            label: Label::Body,
            closed: true,
        }
    }

    /// The 20 Kinect joints at frame `k` (sensor space; the tracker's rig bones): exact.
    pub fn joints(&self, k: usize) -> [Vec3; KinectJoint::COUNT] {
        let k = k.min(self.frames.len().saturating_sub(1));
        let locals = self.frames.get(k).map_or(&[][..], |f| &f.locals[..]);
        let globals = forward_kinematics(&self.model.bones, &self.rest, locals, Vec3::ZERO);
        rig_joints(&self.model, &globals).map(self.to_sensor(k))
    }
}

/// The body's yaw and both arms' keys at `t` seconds (the last state after the end).
fn sample(segments: &[Segment], t: f32) -> (f32, [ArmKey; 2]) {
    let mut t0 = 0.0;
    for s in segments {
        if t < t0 + s.seconds {
            let x = min_jerk((t - t0) / s.seconds.max(1e-6));
            let yaw = s.yaw.0 + (s.yaw.1 - s.yaw.0) * x;
            let arms = [
                s.arms.0[0].lerp(s.arms.1[0], x),
                s.arms.0[1].lerp(s.arms.1[1], x),
            ];
            return (yaw, arms);
        }
        t0 += s.seconds;
    }
    segments
        .last()
        .map_or((0.0, [ArmKey::raised(Vec3::ZERO, 0.0); 2]), |s| {
            (s.yaw.1, s.arms.1)
        })
}
