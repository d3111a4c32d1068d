//! Retargeting a Kinect v1 skeleton stream onto the avatar's own skeleton (seed 000 §4.1-4.2,
//! Algorithm 1, and the split forearm of §4.4.3).
//!
//! Algorithm 1 sets each avatar bone to the sensor's bone orientation relative to the bone's
//! initial orientation, and only when the joint's confidence exceeds 0.5; otherwise the bone
//! keeps its last good orientation. Here the "initial orientation" is made explicit: both the
//! sensor and the avatar express a bone's twist against [`bone_reference_frame`] of its rest
//! direction, so the constant `C_b = reference(avatar rest direction)^-1 * avatar rest frame`
//! maps a sensor bone orientation `Q` onto the avatar bone frame `G_b = Q * C_b`. The avatar's
//! +Y bone axis therefore points exactly along the sensor's bone, while its joint positions come
//! from forward kinematics over the avatar's *own* bone lengths (retargeting, not copying
//! source positions). The root translation is scaled by the ratio of avatar to performer leg
//! length so that the avatar's stride matches its legs.
//!
//! Spaces: everything here is in sensor space (metres, Kinect v1 axes). The avatar's model
//! space (facing +Z) is turned to face the sensor by [`MODEL_TO_SENSOR`].

use fitroom_body::MODEL_TO_SENSOR;
use fitroom_sensor::{KinectJoint, SensorFrame, frame::bone_reference_frame};
use glam::{Quat, Vec3};

/// The minimum joint confidence for a new orientation to be used (Algorithm 1, line 5).
pub const CONFIDENCE_THRESHOLD: f32 = 0.5;

/// One avatar bone's rest data, in sensor space.
#[derive(Clone, Debug)]
pub struct AvatarBone {
    pub name: String,
    pub parent: Option<usize>,
    /// Rest head position, sensor space (model rotated by [`MODEL_TO_SENSOR`]).
    pub rest_head: Vec3,
    /// Rest bone frame, sensor space.
    pub rest_rotation: Quat,
    /// Head position relative to the parent's rest frame (the avatar's own bone lengths).
    pub local_translation: Vec3,
    /// Rest rotation relative to the parent's rest frame.
    pub rest_local_rotation: Quat,
}

/// The avatar skeleton the retargeter drives.
#[derive(Clone, Debug)]
pub struct AvatarSkeleton {
    pub bones: Vec<AvatarBone>,
    /// Height of the floor under the avatar's rest pose (lowest body vertex), sensor space y.
    pub rest_floor_y: f32,
}

/// Why an avatar skeleton cannot be retargeted.
#[derive(Debug, thiserror::Error)]
pub enum RetargetError {
    #[error("the avatar skeleton has no bone named '{0}', which the Kinect mapping needs")]
    MissingBone(String),
    #[error("bone '{bone}' lists parent {parent}, which does not come before it")]
    BadParent { bone: String, parent: usize },
}

impl AvatarSkeleton {
    /// Builds the skeleton from a rest pose in the avatar's model space.
    ///
    /// `parents[i] < i` must hold (bones parents-first).
    pub fn from_model_rest(
        names: &[String],
        parents: &[Option<usize>],
        heads_model: &[Vec3],
        rotations_model: &[Quat],
        floor_y_model: f32,
    ) -> Result<Self, RetargetError> {
        let mut bones = Vec::with_capacity(names.len());
        for (i, name) in names.iter().enumerate() {
            let parent = parents.get(i).copied().flatten();
            let rest_head = MODEL_TO_SENSOR * heads_model[i];
            let rest_rotation = (MODEL_TO_SENSOR * rotations_model[i]).normalize();
            let (local_translation, rest_local_rotation) = match parent {
                Some(p) if p < i => {
                    let parent_bone: &AvatarBone = &bones[p];
                    let inv = parent_bone.rest_rotation.inverse();
                    (
                        inv * (rest_head - parent_bone.rest_head),
                        (inv * rest_rotation).normalize(),
                    )
                }
                Some(p) => {
                    return Err(RetargetError::BadParent {
                        bone: name.clone(),
                        parent: p,
                    });
                }
                None => (rest_head, rest_rotation),
            };
            bones.push(AvatarBone {
                name: name.clone(),
                parent,
                rest_head,
                rest_rotation,
                local_translation,
                rest_local_rotation,
            });
        }
        Ok(Self {
            bones,
            rest_floor_y: floor_y_model,
        })
    }

    pub fn index_of(&self, name: &str) -> Option<usize> {
        self.bones.iter().position(|b| b.name == name)
    }

    fn require(&self, name: &str) -> Result<usize, RetargetError> {
        self.index_of(name)
            .ok_or_else(|| RetargetError::MissingBone(name.to_string()))
    }

    /// Length of the leg (hip joint to knee to ankle) in the rest pose, metres.
    pub fn leg_length(&self) -> Option<f32> {
        let thigh = self.index_of("thigh_l")?;
        let calf = self.index_of("calf_l")?;
        let foot = self.index_of("foot_l")?;
        let b = &self.bones;
        Some(
            b[thigh].rest_head.distance(b[calf].rest_head)
                + b[calf].rest_head.distance(b[foot].rest_head),
        )
    }
}

/// How an avatar bone follows the sensor.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Drive {
    /// Keeps its rest rotation relative to its parent (fingers, toes, the ground root).
    Rest,
    /// Pelvis: the sensor's root orientation times the rest frame.
    Root,
    /// Follows the orientation of the sensor bone ending at this joint: `G = Q * C`.
    Bone {
        joint: KinectJoint,
        correction: Quat,
    },
    /// The proximal half of a split forearm: swing plus a share of the forearm's twist. The
    /// twist of the hand about the forearm's axis (pronation, which CMU data carry on the hand)
    /// is moved into the forearm too: the wrist cannot twist, the forearm does.
    ForearmProximal {
        joint: KinectJoint,
        correction: Quat,
        distal: usize,
        hand_joint: KinectJoint,
        hand_correction: Quat,
    },
    /// The distal (twist) half of a split forearm: set together with its proximal bone.
    ForearmDistal,
}

/// The avatar's pose in one frame, sensor space.
#[derive(Clone, Debug, PartialEq)]
pub struct AvatarPose {
    /// Bone head positions (sensor space).
    pub heads: Vec<Vec3>,
    /// Bone frames (sensor space).
    pub rotations: Vec<Quat>,
    /// Rotations relative to the parent bone's frame (what a joint `Transform` holds).
    pub local_rotations: Vec<Quat>,
    /// Timestamp of the sensor frame this pose came from.
    pub timestamp_s: f64,
}

/// Calibration taken from the first frame of a new user (Algorithm 1, line 10-11).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Calibration {
    /// Midpoint of the performer's hip joints at calibration, sensor space.
    pub start_hip: Vec3,
    /// Avatar leg length / performer leg length.
    pub scale: f32,
    /// Floor height in sensor space.
    pub floor_y: f32,
}

/// Options of the retargeter.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RetargetOptions {
    /// Share of the forearm twist given to the proximal forearm bone; the distal (twist) bone
    /// carries the rest so the wrist gets all of it. 0 is the literal split of seed 000 §4.4.3
    /// (all twist on the distal bone); 0.5 halves the angle between any two blended bones,
    /// which keeps the linear-blend cross-section above 80% at -90° (see `fitroom_body`).
    pub forearm_twist_share_proximal: f32,
    /// Floor height in sensor space (the sensor's mounting height below it). The BVH source
    /// places the floor at `-sensor_height_m`.
    pub floor_y: f32,
}

impl Default for RetargetOptions {
    fn default() -> Self {
        Self {
            forearm_twist_share_proximal: 0.5,
            floor_y: -0.8,
        }
    }
}

/// Turns sensor frames into avatar poses.
#[derive(Clone, Debug)]
pub struct Retargeter {
    skeleton: AvatarSkeleton,
    drives: Vec<Drive>,
    pelvis: usize,
    options: RetargetOptions,
    avatar_leg_m: f32,
    /// Last orientation per Kinect joint that passed the confidence test.
    last_good: [Option<Quat>; KinectJoint::COUNT],
    /// Last confident midpoint of the two hip joints, sensor space.
    last_hip: Option<Vec3>,
    calibration: Option<Calibration>,
    /// The avatar's thigh bones, whose heads are its hip joints.
    thighs: [usize; 2],
    /// Number of joint samples rejected for low confidence or non-finite values.
    pub rejected_samples: u64,
}

/// The mapping from avatar bones (MakeHuman `game_engine` rig with split forearms) to the
/// Kinect bone whose orientation drives them.
pub const BONE_MAP: &[(&str, KinectJoint)] = &[
    ("spine_01", KinectJoint::Spine),
    ("spine_02", KinectJoint::ShoulderCenter),
    ("spine_03", KinectJoint::ShoulderCenter),
    // The head keeps its rest turn on the neck (the Kinect has no head orientation): aimed
    // along the neck too, it nodded 8° forwards of the body's rest, on every frame.
    ("neck_01", KinectJoint::Head),
    ("clavicle_l", KinectJoint::ShoulderLeft),
    ("upperarm_l", KinectJoint::ElbowLeft),
    ("hand_l", KinectJoint::HandLeft),
    ("clavicle_r", KinectJoint::ShoulderRight),
    ("upperarm_r", KinectJoint::ElbowRight),
    ("hand_r", KinectJoint::HandRight),
    ("thigh_l", KinectJoint::KneeLeft),
    ("calf_l", KinectJoint::AnkleLeft),
    ("foot_l", KinectJoint::FootLeft),
    ("thigh_r", KinectJoint::KneeRight),
    ("calf_r", KinectJoint::AnkleRight),
    ("foot_r", KinectJoint::FootRight),
];

/// Split forearms: (proximal bone, distal twist bone, Kinect joint at the wrist, hand bone,
/// Kinect joint at the hand).
pub const FOREARM_MAP: &[(&str, &str, KinectJoint, &str, KinectJoint)] = &[
    (
        "lowerarm_l",
        "lowerarm_twist_l",
        KinectJoint::WristLeft,
        "hand_l",
        KinectJoint::HandLeft,
    ),
    (
        "lowerarm_r",
        "lowerarm_twist_r",
        KinectJoint::WristRight,
        "hand_r",
        KinectJoint::HandRight,
    ),
];

/// Splits `q` into swing and twist about `axis`: `q = swing * twist`.
pub fn swing_twist(q: Quat, axis: Vec3) -> (Quat, Quat) {
    let r = Vec3::new(q.x, q.y, q.z);
    let p = axis * r.dot(axis);
    let twist = Quat::from_xyzw(p.x, p.y, p.z, q.w);
    let twist = if twist.length_squared() < 1e-12 {
        Quat::IDENTITY
    } else {
        twist.normalize()
    };
    ((q * twist.inverse()).normalize(), twist)
}

/// The direction (sensor space) of the bone ending at `joint` when the person stands in the
/// T-pose facing the sensor: the pose in which the sensor's twist reference is defined. The
/// person's left is the sensor's -X.
pub fn tpose_direction(joint: KinectJoint) -> Vec3 {
    use KinectJoint::*;
    match joint {
        HipCenter | Spine | ShoulderCenter | Head => Vec3::Y,
        ShoulderLeft | ElbowLeft | WristLeft | HandLeft => Vec3::NEG_X,
        ShoulderRight | ElbowRight | WristRight | HandRight => Vec3::X,
        HipLeft => Vec3::NEG_X,
        HipRight => Vec3::X,
        KneeLeft | AnkleLeft | KneeRight | AnkleRight => Vec3::NEG_Y,
        FootLeft | FootRight => Vec3::NEG_Z,
    }
}

/// The constant twist `C` with `G = Q * C`: the avatar bone's rest frame, first swung by the
/// shortest arc onto the T-pose direction of its sensor bone (where the sensor's reference is
/// defined and well conditioned), expressed in that reference. MakeHuman's rest forearms point
/// half forward; taking the reference at the rest direction itself would twist them.
/// (Public so a source with the avatar's own rig, the depth tracker, can report `Q = G C⁻¹`.)
pub fn twist_correction(rest_rotation: Quat, joint: KinectJoint) -> Quat {
    let rest_dir = rest_rotation * Vec3::Y;
    let tpose = tpose_direction(joint);
    let swung = Quat::from_rotation_arc(rest_dir, tpose) * rest_rotation;
    (bone_reference_frame(tpose).inverse() * swung).normalize()
}

/// Midpoint of the two hip joints when both are confidently tracked and finite.
fn mid_hips(frame: &SensorFrame) -> Option<Vec3> {
    let l = frame.joint(KinectJoint::HipLeft);
    let r = frame.joint(KinectJoint::HipRight);
    let ok = |j: &fitroom_sensor::JointSample| {
        j.confidence > CONFIDENCE_THRESHOLD && j.position.is_finite()
    };
    (ok(l) && ok(r)).then(|| 0.5 * (l.position + r.position))
}

fn is_usable(q: Quat) -> bool {
    q.is_finite() && (q.length_squared() - 1.0).abs() < 0.01
}

impl Retargeter {
    pub fn new(skeleton: AvatarSkeleton, options: RetargetOptions) -> Result<Self, RetargetError> {
        let mut drives = vec![Drive::Rest; skeleton.bones.len()];
        let pelvis = skeleton.require("pelvis")?;
        drives[pelvis] = Drive::Root;
        for &(name, joint) in BONE_MAP {
            let i = skeleton.require(name)?;
            drives[i] = Drive::Bone {
                joint,
                correction: twist_correction(skeleton.bones[i].rest_rotation, joint),
            };
        }
        for &(proximal, distal, joint, hand, hand_joint) in FOREARM_MAP {
            let p = skeleton.require(proximal)?;
            let d = skeleton.require(distal)?;
            let h = skeleton.require(hand)?;
            // The proximal and distal halves share one axis; the correction is the proximal's.
            drives[p] = Drive::ForearmProximal {
                joint,
                correction: twist_correction(skeleton.bones[p].rest_rotation, joint),
                distal: d,
                hand_joint,
                hand_correction: twist_correction(skeleton.bones[h].rest_rotation, hand_joint),
            };
            drives[d] = Drive::ForearmDistal;
        }
        let thighs = [skeleton.require("thigh_l")?, skeleton.require("thigh_r")?];
        let avatar_leg_m = skeleton
            .leg_length()
            .ok_or_else(|| RetargetError::MissingBone("thigh_l/calf_l/foot_l".into()))?;
        Ok(Self {
            skeleton,
            drives,
            pelvis,
            options,
            avatar_leg_m,
            last_good: [None; KinectJoint::COUNT],
            last_hip: None,
            calibration: None,
            thighs,
            rejected_samples: 0,
        })
    }

    pub fn skeleton(&self) -> &AvatarSkeleton {
        &self.skeleton
    }

    pub fn calibration(&self) -> Option<Calibration> {
        self.calibration
    }

    /// Forgets the current user: the next frame calibrates again (Algorithm 1, "user is new").
    pub fn reset(&mut self) {
        self.last_good = [None; KinectJoint::COUNT];
        self.last_hip = None;
        self.calibration = None;
    }

    /// The avatar's rest pose (used before the first frame arrives).
    pub fn rest_pose(&self) -> AvatarPose {
        let bones = &self.skeleton.bones;
        AvatarPose {
            heads: bones.iter().map(|b| b.rest_head).collect(),
            rotations: bones.iter().map(|b| b.rest_rotation).collect(),
            local_rotations: bones.iter().map(|b| b.rest_local_rotation).collect(),
            timestamp_s: 0.0,
        }
    }

    fn calibrate(&mut self, frame: &SensorFrame) -> Option<Calibration> {
        let p = |j: KinectJoint| frame.joint(j).position;
        let leg = |hip, knee, ankle| p(hip).distance(p(knee)) + p(knee).distance(p(ankle));
        let performer_leg = 0.5
            * (leg(
                KinectJoint::HipLeft,
                KinectJoint::KneeLeft,
                KinectJoint::AnkleLeft,
            ) + leg(
                KinectJoint::HipRight,
                KinectJoint::KneeRight,
                KinectJoint::AnkleRight,
            ));
        let hip = mid_hips(frame)?;
        if !(performer_leg.is_finite() && performer_leg > 0.2) {
            return None;
        }
        Some(Calibration {
            start_hip: hip,
            scale: self.avatar_leg_m / performer_leg,
            floor_y: self.options.floor_y,
        })
    }

    /// Updates the per-joint orientations from a frame (confidence gate of Algorithm 1) and
    /// returns the avatar pose. Joints below the confidence threshold, or with non-finite
    /// data, keep their last good orientation.
    pub fn update(&mut self, frame: &SensorFrame) -> AvatarPose {
        for joint in KinectJoint::ALL {
            let sample = frame.joint(joint);
            if sample.confidence > CONFIDENCE_THRESHOLD && is_usable(sample.orientation) {
                self.last_good[joint.index()] = Some(sample.orientation.normalize());
            } else {
                self.rejected_samples += 1;
            }
        }
        if let Some(hips) = mid_hips(frame) {
            self.last_hip = Some(hips);
        }
        if self.calibration.is_none() {
            self.calibration = self.calibrate(frame);
        }
        self.solve(frame.timestamp_s)
    }

    /// Where the midpoint of the avatar's hip joints goes: the performer's, with the motion
    /// and the height above the floor scaled by the leg-length ratio.
    fn hips_target(&self) -> Option<Vec3> {
        match (self.calibration, self.last_hip) {
            (Some(c), Some(hip)) => {
                let horizontal = Vec3::new(c.start_hip.x, 0.0, c.start_hip.z)
                    + Vec3::new(hip.x - c.start_hip.x, 0.0, hip.z - c.start_hip.z) * c.scale;
                Some(Vec3::new(
                    horizontal.x,
                    c.floor_y + (hip.y - c.floor_y) * c.scale,
                    horizontal.z,
                ))
            }
            _ => None,
        }
    }

    fn solve(&self, timestamp_s: f64) -> AvatarPose {
        let bones = &self.skeleton.bones;
        let n = bones.len();
        let mut heads = vec![Vec3::ZERO; n];
        let mut rotations = vec![Quat::IDENTITY; n];
        let mut locals = vec![Quat::IDENTITY; n];
        let mut distal_locals: Vec<Option<Quat>> = vec![None; n];

        for i in 0..n {
            let bone = &bones[i];
            let (parent_head, parent_rotation) = match bone.parent {
                Some(p) => (heads[p], rotations[p]),
                None => (Vec3::ZERO, Quat::IDENTITY),
            };
            let rest_global = (parent_rotation * bone.rest_local_rotation).normalize();
            let global = match self.drives[i] {
                Drive::Rest => rest_global,
                Drive::Root => match self.last_good[KinectJoint::HipCenter.index()] {
                    Some(q) => (q * bone.rest_rotation).normalize(),
                    None => rest_global,
                },
                Drive::Bone { joint, correction } => match self.last_good[joint.index()] {
                    Some(q) => (q * correction).normalize(),
                    None => rest_global,
                },
                Drive::ForearmProximal {
                    joint,
                    correction,
                    distal,
                    hand_joint,
                    hand_correction,
                } => match self.last_good[joint.index()] {
                    Some(q) => {
                        let target = (q * correction).normalize();
                        let local = parent_rotation.inverse() * target;
                        let (swing, own_twist) = swing_twist(local, Vec3::Y);
                        let hand_twist = match self.last_good[hand_joint.index()] {
                            Some(h) => {
                                let hand = (h * hand_correction).normalize();
                                swing_twist(target.inverse() * hand, Vec3::Y).1
                            }
                            None => Quat::IDENTITY,
                        };
                        let twist = (own_twist * hand_twist).normalize();
                        let share = self.options.forearm_twist_share_proximal.clamp(0.0, 1.0);
                        let proximal_twist = Quat::IDENTITY.slerp(twist, share);
                        distal_locals[distal] =
                            Some((proximal_twist.inverse() * twist).normalize());
                        (parent_rotation * swing * proximal_twist).normalize()
                    }
                    None => rest_global,
                },
                Drive::ForearmDistal => match distal_locals[i] {
                    Some(local) => (parent_rotation * bone.rest_local_rotation * local).normalize(),
                    None => rest_global,
                },
            };
            rotations[i] = global;
            locals[i] = (parent_rotation.inverse() * global).normalize();
            heads[i] = parent_head + parent_rotation * bone.local_translation;
        }

        // Put the avatar's hip joints where the performer's are (scaled) and move everything
        // with them. The pelvis bone's head is not a hip joint, and its offset from the hip
        // joints differs between performer and avatar: aligning it would sink or lift the feet.
        let avatar_hips = 0.5 * (heads[self.thighs[0]] + heads[self.thighs[1]]);
        let offset = match self.hips_target() {
            Some(target) => target - avatar_hips,
            None => bones[self.pelvis].rest_head - heads[self.pelvis],
        };
        for head in &mut heads {
            *head += offset;
        }
        AvatarPose {
            heads,
            rotations,
            local_rotations: locals,
            timestamp_s,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn swing_twist_recomposes_and_twist_is_about_axis() {
        let q = Quat::from_euler(glam::EulerRot::XYZ, 0.4, -1.1, 0.7);
        let (swing, twist) = swing_twist(q, Vec3::Y);
        assert!((swing * twist).abs_diff_eq(q, 1e-5) || (swing * twist).abs_diff_eq(-q, 1e-5));
        // The twist leaves the axis fixed; the swing has no component about it.
        assert!((twist * Vec3::Y).abs_diff_eq(Vec3::Y, 1e-5));
        assert!(swing.y.abs() < 1e-5);
    }

    #[test]
    fn twist_correction_is_a_pure_twist() {
        for (rot, joint) in [
            (Quat::from_rotation_z(2.0), KinectJoint::ElbowLeft),
            (
                Quat::from_euler(glam::EulerRot::YXZ, 0.3, 2.9, 0.1),
                KinectJoint::KneeRight,
            ),
            (Quat::from_rotation_x(1.4), KinectJoint::FootLeft),
        ] {
            let c = twist_correction(rot, joint);
            assert!((c * Vec3::Y).abs_diff_eq(Vec3::Y, 1e-4), "{rot:?} -> {c:?}");
        }
    }

    #[test]
    fn a_bone_already_in_the_tpose_gets_the_sensor_reference() {
        // An arm pointing to the person's left with its frame equal to the reference: the
        // sensor's reference orientation must reproduce that frame exactly.
        let frame = bone_reference_frame(Vec3::NEG_X);
        let c = twist_correction(frame, KinectJoint::ElbowLeft);
        assert!(c.abs_diff_eq(Quat::IDENTITY, 1e-5) || c.abs_diff_eq(-Quat::IDENTITY, 1e-5));
    }
}
