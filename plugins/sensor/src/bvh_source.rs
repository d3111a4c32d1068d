//! A [`SensorSource`] that replays a BVH motion-capture clip as a Kinect v1 skeleton stream.
//!
//! The clip (120 Hz CMU data) is resampled to the source's rate (30 Hz by default, as a Kinect
//! v1) and looped forever; timestamps and sequence numbers keep increasing across loops.
//!
//! # What is emitted
//!
//! * **Positions** (sensor space, metres): forward kinematics of every clip frame gives the BVH
//!   positions of the mapped points ([`crate::bvh_skeleton`]); [`Placement::to_sensor`] scales
//!   them by the skeleton's metres-per-unit (from the leg length), turns them about the vertical
//!   so that the performer faces the sensor at the first played frame, and moves them so that
//!   the hip centre of the first played frame is at `x = 0, z = start_distance_m` (2.5 m) and
//!   the clip's floor is at `y = -sensor_height_m` (the sensor 0.8 m above the floor). The
//!   clip's floor is the lowest ankle or foot point over all played frames (so the lowest toe or
//!   ankle of the clip touches the floor).
//! * **Facing**: the performer's left is `(left hip - right hip) + (left shoulder - right
//!   shoulder)` made horizontal; forward is `left x up`. The yaw turns forward onto sensor -Z,
//!   which puts the performer's left at sensor -X (the sensor's right), as the Kinect SDK does.
//!   BVH world is Y-up like sensor space, so the yaw is the only rotation.
//! * **Orientations**, per the contract of [`JointSample::orientation`]: with `R` the yaw,
//!   `C` the half turn about +Y that turns the BVH rest pose (facing +Z) to face the sensor,
//!   `G_D(t)` the global BVH rotation of the joint `D` that drives the bone ending at `J`
//!   ([`KinectMapping::driver`]) and `F0 = bone_reference_frame(C * d_rest)` where `d_rest` is
//!   the bone's direction in the zero-rotation rest pose, the raw bone frame is
//!   `Q = R * G_D(t) * C^-1 * F0`; it equals `F0` when the performer stands in the rest pose
//!   facing the sensor and its +Y follows the BVH bone. Because a Kinect bone may span several
//!   BVH bones (Spine -> ShoulderCenter spans abdomen, chest, neck), the emitted orientation is
//!   `arc(Q * Y -> current bone direction) * Q`, so its +Y points exactly from the parent joint
//!   to the joint. `HipCenter` gets `R * G_hip(t) * C^-1`, the identity for a rest-pose
//!   performer facing the sensor.
//! * **Confidence** is 1.0 for every joint (clean mocap data).
//! * **Treadmill** ([`BvhSourceOptions::treadmill`], off by default): every played frame's
//!   positions are then moved horizontally (sensor x and z, the same shift for all joints of
//!   the frame) so that its hip centre stays at the first played frame's `x = 0, z =
//!   start_distance_m`. The vertical motion, the pose relative to the hip and the
//!   orientations are unchanged; the feet slide on the floor. A walk then stays in the
//!   sensor's view and range for as long as it plays.
//!
//! # Resampling
//!
//! Output frame `k` has timestamp `k / fps`. Time `t` maps to the fractional played frame
//! `(t mod clip_duration_s) / frame_time`; the positions of the two neighbouring clip frames are
//! interpolated linearly and the raw bone frames `Q` (and the pelvis orientation) spherically,
//! then the orientation is aligned with the interpolated bone as above. The loop period
//! [`BvhSource::clip_duration_s`] is `(played frames - 1) * frame_time`: the last played frame
//! is followed directly by the first (the performer jumps back to the start).
//!
//! # The added T-pose
//!
//! The cgspeed conversion prepends a T-pose frame and blends from it into the captured motion
//! over the next frames; neither is played: playback starts at
//! [`BvhSkeletonKind::first_motion_frame`] (frame 8 for those clips, frame 0 for the others).
//! See [`BvhSkeletonKind::has_added_tpose`] for the detection rule and
//! [`crate::bvh_skeleton::TPOSE_BLEND_FRAMES`] for the evidence.

use std::f32::consts::PI;
use std::path::Path;

use glam::{Quat, Vec3};
use serde::{Deserialize, Serialize};

use crate::bvh::{BvhClip, BvhError};
use crate::bvh_skeleton::{BvhSkeletonKind, KinectMapping};
use crate::frame::{JointSample, KinectJoint, SensorFrame, bone_reference_frame};
use crate::source::{SensorSource, SourceError};

/// At most this many frames are returned by one [`SensorSource::advance`] call; after a longer
/// stall the oldest due frames are dropped (their timestamps are skipped, `sequence` stays
/// consecutive).
pub const MAX_FRAMES_PER_ADVANCE: usize = 300;

/// Half a turn about +Y: turns the BVH rest pose (facing +Z) to face the sensor (-Z).
const REST_TO_SENSOR: Quat = Quat::from_xyzw(0.0, 1.0, 0.0, 0.0);

/// Where the replayed performer is put in front of the virtual sensor.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct BvhSourceOptions {
    /// Height of the sensor above the floor, metres: the floor is at `y = -sensor_height_m`.
    pub sensor_height_m: f32,
    /// Distance of the performer's hip centre from the sensor at the first played frame, metres
    /// (along +Z).
    pub start_distance_m: f32,
    /// Output frame rate, frames per second (30 for Kinect v1).
    pub fps: f64,
    /// Keep the performer on the spot, as on a treadmill: every played frame is moved
    /// horizontally (sensor x and z) so that its hip centre is where the first played frame's
    /// is (`x = 0, z = start_distance_m`). Heights and orientations are kept; the feet slide
    /// backwards on the floor instead of the body travelling. For recordings that must keep
    /// the person in the sensor's view and range over a whole walk (the clips walk towards
    /// and past the sensor otherwise). Default off.
    #[serde(default)]
    pub treadmill: bool,
}

impl Default for BvhSourceOptions {
    fn default() -> Self {
        Self {
            sensor_height_m: 0.8,
            start_distance_m: 2.5,
            fps: 30.0,
            treadmill: false,
        }
    }
}

/// The map from BVH world (file units, Y-up) to sensor space (metres):
/// `p_sensor = yaw * ((p_bvh - bvh_origin) * metres_per_unit) + sensor_origin`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placement {
    /// Rotation about +Y that makes the performer face the sensor at the first played frame.
    pub yaw: Quat,
    pub metres_per_unit: f32,
    /// BVH point that lands on `sensor_origin`: the first played frame's hip centre in x and z,
    /// the clip's floor in y. File units.
    pub bvh_origin: Vec3,
    /// `(0, -sensor_height_m, start_distance_m)`.
    pub sensor_origin: Vec3,
}

impl Placement {
    /// A BVH world position in sensor space.
    pub fn to_sensor(&self, bvh_position: Vec3) -> Vec3 {
        self.yaw * ((bvh_position - self.bvh_origin) * self.metres_per_unit) + self.sensor_origin
    }
}

/// Per played clip frame: sensor-space positions and raw bone frames `Q` (pelvis orientation for
/// `HipCenter`), indexed by [`KinectJoint::index`].
#[derive(Clone, Copy, Debug)]
struct KinectSample {
    positions: [Vec3; KinectJoint::COUNT],
    rotations: [Quat; KinectJoint::COUNT],
}

/// Replays a BVH clip as a looping Kinect v1 stream. See the module docs.
#[derive(Clone, Debug)]
pub struct BvhSource {
    name: String,
    clip: BvhClip,
    mapping: KinectMapping,
    options: BvhSourceOptions,
    placement: Placement,
    first_played_frame: usize,
    samples: Vec<KinectSample>,
    /// Seconds advanced so far.
    clock_s: f64,
    /// Index of the next output time slot (timestamp `slot / fps`).
    next_slot: u64,
    /// Frames emitted so far.
    sequence: u64,
}

impl BvhSource {
    /// Loads a BVH file and prepares it for replay.
    pub fn load(path: impl AsRef<Path>, options: BvhSourceOptions) -> Result<Self, BvhError> {
        Self::from_clip(BvhClip::load(path)?, options)
    }

    /// Prepares a parsed clip for replay: maps the skeleton, skips the added T-pose, places the
    /// performer and precomputes every played frame. Fails for a skeleton that cannot be mapped
    /// (naming the file and the `ROOT` line) or for unusable options.
    pub fn from_clip(clip: BvhClip, options: BvhSourceOptions) -> Result<Self, BvhError> {
        let invalid = |message: &str| BvhError::InvalidOptions {
            file: clip.file_name().to_string(),
            message: message.to_string(),
        };
        if !(options.fps.is_finite() && options.fps > 0.0) {
            return Err(invalid("fps must be a positive number"));
        }
        if !(options.sensor_height_m.is_finite() && options.start_distance_m.is_finite()) {
            return Err(invalid(
                "sensor_height_m and start_distance_m must be finite",
            ));
        }
        let mapping = KinectMapping::new(&clip)?;
        let first_played_frame = mapping.kind().first_motion_frame(&clip);

        // BVH-space points and driver rotations of every played frame.
        let rest = clip.rest_pose();
        let mut bvh_frames = Vec::with_capacity(clip.frame_count() - first_played_frame);
        for k in first_played_frame..clip.frame_count() {
            let Some(pose) = clip.pose(k) else { break };
            let mut positions = [Vec3::ZERO; KinectJoint::COUNT];
            let mut rotations = [Quat::IDENTITY; KinectJoint::COUNT];
            for joint in KinectJoint::ALL {
                positions[joint.index()] = pose.point(mapping.point(joint)).unwrap_or(Vec3::ZERO);
                rotations[joint.index()] = pose
                    .rotations
                    .get(mapping.driver(joint))
                    .copied()
                    .unwrap_or(Quat::IDENTITY);
            }
            bvh_frames.push(KinectSample {
                positions,
                rotations,
            });
        }
        let Some(first) = bvh_frames.first() else {
            return Err(BvhError::Skeleton {
                file: clip.file_name().to_string(),
                line: clip.root().line,
                message: "the clip has no frame to play".to_string(),
            });
        };

        // Placement: facing from the first played frame, floor from all played frames.
        use KinectJoint::*;
        let at = |j: KinectJoint| first.positions[j.index()];
        let mut left = (at(HipLeft) - at(HipRight)) + (at(ShoulderLeft) - at(ShoulderRight));
        left.y = 0.0;
        let mut forward = left.cross(Vec3::Y);
        if forward.length() < 1e-6 {
            forward = first.rotations[HipCenter.index()] * Vec3::Z;
            forward.y = 0.0;
        }
        if forward.length() < 1e-6 {
            forward = Vec3::Z;
        }
        // Ry(a) adds `a` to the heading atan2(x, z); sensor -Z has heading PI.
        let yaw = Quat::from_rotation_y(PI - forward.x.atan2(forward.z));
        let floor_y = bvh_frames
            .iter()
            .flat_map(|s| {
                [AnkleLeft, AnkleRight, FootLeft, FootRight].map(|j| s.positions[j.index()].y)
            })
            .fold(f32::INFINITY, f32::min);
        let hip0 = at(HipCenter);
        let placement = Placement {
            yaw,
            metres_per_unit: mapping.metres_per_unit(),
            bvh_origin: Vec3::new(hip0.x, floor_y, hip0.z),
            sensor_origin: Vec3::new(0.0, -options.sensor_height_m, options.start_distance_m),
        };

        // Twist references of the Kinect bones from the rest pose.
        let mut references = [Quat::IDENTITY; KinectJoint::COUNT];
        for joint in KinectJoint::ALL {
            if let Some(parent) = joint.parent() {
                let rest_at = |j: KinectJoint| rest.point(mapping.point(j)).unwrap_or(Vec3::ZERO);
                let direction = (rest_at(joint) - rest_at(parent)).normalize_or(Vec3::Y);
                references[joint.index()] = bone_reference_frame(REST_TO_SENSOR * direction);
            }
        }

        let to_sensor_rest = REST_TO_SENSOR.inverse();
        // With the treadmill, the first played frame's hip centre in x and z (where the
        // placement puts it).
        let hip_spot = placement.to_sensor(hip0);
        let samples = bvh_frames
            .iter()
            .map(|s| {
                let mut out = *s;
                for joint in KinectJoint::ALL {
                    let i = joint.index();
                    out.positions[i] = placement.to_sensor(s.positions[i]);
                    out.rotations[i] =
                        (yaw * s.rotations[i] * to_sensor_rest * references[i]).normalize();
                }
                if options.treadmill {
                    let hip = out.positions[HipCenter.index()];
                    let shift = Vec3::new(hip_spot.x - hip.x, 0.0, hip_spot.z - hip.z);
                    for position in &mut out.positions {
                        *position += shift;
                    }
                }
                out
            })
            .collect();

        let file_name = clip.file_name();
        let stem = Path::new(file_name.strip_suffix(".gz").unwrap_or(file_name))
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| clip.file_name().to_string());
        Ok(BvhSource {
            name: format!("bvh:{stem}"),
            clip,
            mapping,
            options,
            placement,
            first_played_frame,
            samples,
            clock_s: 0.0,
            next_slot: 0,
            sequence: 0,
        })
    }

    /// The parsed clip.
    pub fn clip(&self) -> &BvhClip {
        &self.clip
    }

    /// The skeleton mapping in use.
    pub fn mapping(&self) -> &KinectMapping {
        &self.mapping
    }

    pub fn skeleton_kind(&self) -> BvhSkeletonKind {
        self.mapping.kind()
    }

    pub fn options(&self) -> &BvhSourceOptions {
        &self.options
    }

    /// The BVH-to-sensor map.
    pub fn placement(&self) -> &Placement {
        &self.placement
    }

    /// Index of the first clip frame played (8 when the added T-pose and its blend-in are
    /// skipped, else 0).
    pub fn first_played_frame(&self) -> usize {
        self.first_played_frame
    }

    /// Number of clip frames played per loop.
    pub fn played_frame_count(&self) -> usize {
        self.samples.len()
    }

    /// Frame rate of the source clip (120 for CMU).
    pub fn clip_fps(&self) -> f64 {
        self.clip.fps()
    }

    /// Loop period, seconds: `(played frames - 1) * frame_time` (0 for a one-frame clip).
    pub fn clip_duration_s(&self) -> f64 {
        self.samples.len().saturating_sub(1) as f64 * self.clip.frame_time_s()
    }

    /// Seconds the source has been advanced by.
    pub fn clock_s(&self) -> f64 {
        self.clock_s
    }

    /// The fractional clip frame index (counting the skipped T-pose, like
    /// [`BvhClip::frame`]) shown at playback time `time_s`.
    pub fn clip_frame_at(&self, time_s: f64) -> f64 {
        let (i, f) = self.sample_position(time_s);
        (self.first_played_frame + i) as f64 + f64::from(f)
    }

    /// Played-sample index and interpolation weight towards the next sample at `time_s`.
    fn sample_position(&self, time_s: f64) -> (usize, f32) {
        let n = self.samples.len();
        let period = self.clip_duration_s();
        if n < 2 || !time_s.is_finite() || period <= 0.0 {
            return (0, 0.0);
        }
        let mut t = time_s.rem_euclid(period);
        if period - t < 1e-9 {
            // Rounding just below a whole number of loops: that is the start of the next loop.
            t = 0.0;
        }
        let u = t / self.clip.frame_time_s();
        let i = (u.floor().max(0.0) as usize).min(n - 2);
        let f = ((u - i as f64) as f32).clamp(0.0, 1.0);
        (i, f)
    }

    /// The frame the stream shows at playback time `time_s` (looping), without advancing.
    /// Its `timestamp_s` is `time_s` and its `sequence` the output slot `floor(time_s * fps)`.
    pub fn frame_at(&self, time_s: f64) -> SensorFrame {
        let (i, f) = self.sample_position(time_s);
        let mut joints = [JointSample::default(); KinectJoint::COUNT];
        if let (Some(a), Some(b)) = (
            self.samples.get(i),
            self.samples.get(i + 1).or(self.samples.get(i)),
        ) {
            let mut positions = [Vec3::ZERO; KinectJoint::COUNT];
            for joint in KinectJoint::ALL {
                let k = joint.index();
                positions[k] = a.positions[k].lerp(b.positions[k], f);
            }
            for joint in KinectJoint::ALL {
                let k = joint.index();
                let raw = a.rotations[k].slerp(b.rotations[k], f).normalize();
                let orientation = match joint.parent() {
                    None => raw,
                    Some(parent) => align_to_bone(raw, positions[k] - positions[parent.index()]),
                };
                joints[k] = JointSample {
                    position: positions[k],
                    orientation,
                    confidence: 1.0,
                };
            }
        }
        let slot = if time_s.is_finite() && time_s > 0.0 {
            (time_s * self.options.fps + 1e-9).floor() as u64
        } else {
            0
        };
        SensorFrame {
            timestamp_s: time_s,
            sequence: slot,
            joints,
        }
    }
}

/// `arc(raw * Y -> bone) * raw`: the raw frame swung so that +Y points along `bone`.
fn align_to_bone(raw: Quat, bone: Vec3) -> Quat {
    let along = (raw * Vec3::Y).normalize_or_zero();
    let bone = bone.normalize_or_zero();
    if along == Vec3::ZERO || bone == Vec3::ZERO {
        return raw;
    }
    (Quat::from_rotation_arc(along, bone) * raw).normalize()
}

impl SensorSource for BvhSource {
    fn name(&self) -> &str {
        &self.name
    }

    fn fps(&self) -> f32 {
        self.options.fps as f32
    }

    /// Emits the frames whose timestamps `k / fps` fall in the advanced time (the first call
    /// emits the frame at t = 0, even for `dt_s = 0`). Negative or non-finite `dt_s` advances
    /// nothing. Never fails.
    fn advance(&mut self, dt_s: f64) -> Result<Vec<SensorFrame>, SourceError> {
        if dt_s.is_finite() && dt_s > 0.0 {
            self.clock_s += dt_s;
        }
        let fps = self.options.fps;
        // Slot of the last frame due (the float-to-int cast saturates). The small epsilon keeps
        // a clock summed from steps like 1/30 from missing a frame by rounding.
        let last_due = ((self.clock_s * fps) + 1e-6).floor() as u64;
        if last_due < self.next_slot {
            return Ok(Vec::new());
        }
        let first = self
            .next_slot
            .max(last_due.saturating_sub(MAX_FRAMES_PER_ADVANCE as u64 - 1));
        let mut frames = Vec::with_capacity((last_due - first + 1) as usize);
        for slot in first..=last_due {
            let mut frame = self.frame_at(slot as f64 / fps);
            frame.sequence = self.sequence;
            self.sequence += 1;
            frames.push(frame);
        }
        self.next_slot = last_due.saturating_add(1);
        Ok(frames)
    }
}

/// What `fitroom sensor inspect FILE --json` reports about a BVH file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BvhInfo {
    /// Frames as declared by `Frames:` (including an added T-pose frame).
    pub frames: usize,
    /// `1 / frame_time_s`.
    pub fps: f64,
    pub frame_time_s: f64,
    /// `frames * frame_time_s`, seconds.
    pub duration_s: f64,
    /// Joints in the hierarchy (end sites not counted).
    pub joints: usize,
    /// Values per motion line.
    pub channels: usize,
    /// `"cgspeed-daz"`, `"motionbuilder"`, or `"unknown"` for a skeleton that parses but cannot
    /// be mapped onto the Kinect joints.
    pub skeleton: String,
    /// Whether frame 0 is the T-pose the cgspeed conversion adds (not played by [`BvhSource`]).
    pub tpose_frame: bool,
    /// The first frame [`BvhSource`] plays (after the T-pose and its blend-in), 0-based.
    pub first_played_frame: usize,
}

impl BvhInfo {
    pub fn from_clip(clip: &BvhClip) -> BvhInfo {
        let kind = BvhSkeletonKind::detect(clip);
        BvhInfo {
            frames: clip.frame_count(),
            fps: clip.fps(),
            frame_time_s: clip.frame_time_s(),
            duration_s: clip.duration_s(),
            joints: clip.joints().len(),
            channels: clip.channel_count(),
            skeleton: kind.map_or("unknown", BvhSkeletonKind::name).to_string(),
            tpose_frame: kind.is_some_and(|k| k.has_added_tpose(clip)),
            first_played_frame: kind.map_or(0, |k| k.first_motion_frame(clip)),
        }
    }
}

/// Parses a BVH file and summarises it. Fails only when the file cannot be read or parsed; a
/// skeleton that cannot be mapped is reported as `skeleton: "unknown"`.
pub fn inspect(path: impl AsRef<Path>) -> Result<BvhInfo, BvhError> {
    Ok(BvhInfo::from_clip(&BvhClip::load(path)?))
}
