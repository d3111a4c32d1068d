//! The anatomy behind the joint limits (seed 000 §4.4.2: "the natural limits of human
//! bones"): the limited joints ([`JointKind`]), the body's anatomical directions in the
//! neutral pose ([`Anat`]) and how each joint's anatomical neutral is derived from the rest
//! pose ([`NeutralRule`]; see the [module docs](super)).

use glam::{Quat, Vec3};

use fitroom_sensor::frame::bone_reference_frame;

use super::{KINECT_CLAVICLE_DROP_DEG, KINECT_FOOT_PITCH_DEG};

/// Which side of the body a joint is on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Side {
    Left,
    Right,
    Center,
}

/// Anatomical directions of the body in the neutral pose, in sensor space: the avatar faces
/// the sensor (front = -Z), up = +Y, the person's left = -X. `Medial`/`Lateral` depend on
/// the side; `Palmar`/`Radial` are read from the rest hand (finger bases).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Anat {
    Front,
    Back,
    Up,
    Down,
    Left,
    Right,
    Medial,
    Lateral,
    /// Towards the palm (from the rest finger bases).
    Palmar,
    /// Towards the thumb side of the hand (index base - little finger base).
    Radial,
}

/// The anatomical joints that are limited.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum JointKind {
    /// `spine_01` relative to the pelvis.
    Lumbar,
    /// `spine_02` relative to `spine_01`.
    Thoracic,
    /// `spine_03` relative to `spine_02`.
    UpperThoracic,
    /// `neck_01` relative to `spine_03` (cervical spine).
    Neck,
    /// `head` relative to `neck_01` (atlanto-occipital).
    Head,
    /// `clavicle` relative to `spine_03` (sternoclavicular).
    Clavicle,
    /// `upperarm` relative to the clavicle (glenohumeral + scapular).
    Shoulder,
    /// `lowerarm` (proximal forearm half) relative to the upper arm: elbow hinge plus its share
    /// of the forearm twist.
    Elbow,
    /// `lowerarm_twist` (distal forearm half) relative to `lowerarm`: the rest of the forearm
    /// twist.
    ForearmTwist,
    /// `hand` relative to `lowerarm_twist`.
    Wrist,
    /// `thigh` relative to the pelvis.
    Hip,
    /// `calf` relative to the thigh.
    Knee,
    /// `foot` relative to the calf.
    Ankle,
}

/// How a joint's anatomical neutral is derived from the rest pose (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum NeutralRule {
    /// The frame the retargeter gives this bone for a performer whose Kinect bone points along
    /// the direction (tilted this many degrees below horizontal when the direction is
    /// horizontal) with the sensor's zero twist: `F(dir) * F(t)^-1 * arc(rest axis -> t) *
    /// rest` with `F` = [`fitroom_sensor::frame::bone_reference_frame`] and `t` the Kinect
    /// bone's T-pose direction ([`crate::retarget::tpose_direction`]).
    Kinect(Anat, f32),
    /// The rest local rotation under the neutral parent.
    RestLocal,
}

/// The neutral frame of a Kinect-driven bone (see [`NeutralRule::Kinect`]); `None` if the
/// bone is not driven by a Kinect bone.
pub(super) fn kinect_neutral(
    name: &str,
    rest: Quat,
    a: Anat,
    side: Side,
    drop_deg: f32,
) -> Option<Quat> {
    let joint = crate::retarget::BONE_MAP
        .iter()
        .find(|(n, _)| *n == name)
        .map(|(_, j)| *j)
        .or_else(|| {
            crate::retarget::FOREARM_MAP
                .iter()
                .find(|(n, _, _, _, _)| *n == name)
                .map(|(_, _, j, _, _)| *j)
        })?;
    let tpose = crate::retarget::tpose_direction(joint);
    let base = anat_dir(a, side, Vec3::ZERO, Vec3::ZERO);
    let dir = if base.y.abs() > 0.9 {
        base
    } else {
        let drop = drop_deg.to_radians();
        (base * drop.cos() - Vec3::Y * drop.sin()).normalize()
    };
    let swung = Quat::from_rotation_arc(rest * Vec3::Y, tpose) * rest;
    Some((bone_reference_frame(dir) * bone_reference_frame(tpose).inverse() * swung).normalize())
}

impl JointKind {
    /// The avatar bone base name (`_l`/`_r` appended for sided joints).
    pub fn bone_base(self) -> &'static str {
        match self {
            JointKind::Lumbar => "spine_01",
            JointKind::Thoracic => "spine_02",
            JointKind::UpperThoracic => "spine_03",
            JointKind::Neck => "neck_01",
            JointKind::Head => "head",
            JointKind::Clavicle => "clavicle",
            JointKind::Shoulder => "upperarm",
            JointKind::Elbow => "lowerarm",
            JointKind::ForearmTwist => "lowerarm_twist",
            JointKind::Wrist => "hand",
            JointKind::Hip => "thigh",
            JointKind::Knee => "calf",
            JointKind::Ankle => "foot",
        }
    }

    pub fn sided(self) -> bool {
        !matches!(
            self,
            JointKind::Lumbar
                | JointKind::Thoracic
                | JointKind::UpperThoracic
                | JointKind::Neck
                | JointKind::Head
        )
    }

    pub fn neutral_rule(self) -> NeutralRule {
        match self {
            JointKind::Lumbar
            | JointKind::Thoracic
            | JointKind::UpperThoracic
            | JointKind::Neck
            | JointKind::Head => NeutralRule::Kinect(Anat::Up, 0.0),
            JointKind::Clavicle => NeutralRule::Kinect(Anat::Lateral, KINECT_CLAVICLE_DROP_DEG),
            JointKind::Hip | JointKind::Knee => NeutralRule::Kinect(Anat::Down, 0.0),
            JointKind::Ankle => NeutralRule::Kinect(Anat::Front, KINECT_FOOT_PITCH_DEG),
            JointKind::Shoulder | JointKind::Elbow | JointKind::Wrist => {
                NeutralRule::Kinect(Anat::Down, 0.0)
            }
            JointKind::ForearmTwist => NeutralRule::RestLocal,
        }
    }

    /// The anatomical meaning of positive angles, as directions in the neutral pose:
    /// `(flexion, abduction, twist probe, twist towards)`. Positive flexion moves the bone's
    /// tail towards `flexion`; positive abduction towards `abduction`; positive twist turns a
    /// vector pointing along `twist probe` towards `twist towards`.
    ///
    /// | joint | +flexion | +abduction | +twist |
    /// |---|---|---|---|
    /// | trunk, neck, head | forward bending | bending to the left | turning to the left |
    /// | clavicle | elevation | protraction (forwards) | posterior rotation (top turns back) |
    /// | shoulder, hip | flexion (forwards) | abduction | internal rotation |
    /// | elbow | flexion | valgus (forearm outwards) | pronation |
    /// | forearm twist | (none) | (none) | pronation |
    /// | wrist | palmar flexion | radial deviation | pronation sense |
    /// | knee | flexion (ankle backwards) | valgus | internal tibial rotation |
    /// | ankle | dorsiflexion | abduction (toe out) | inversion |
    pub fn directions(self) -> (Anat, Anat, Anat, Anat) {
        use Anat::*;
        match self {
            JointKind::Lumbar
            | JointKind::Thoracic
            | JointKind::UpperThoracic
            | JointKind::Neck
            | JointKind::Head => (Front, Left, Front, Left),
            JointKind::Clavicle => (Up, Front, Up, Back),
            JointKind::Shoulder | JointKind::Hip => (Front, Lateral, Front, Medial),
            JointKind::Elbow | JointKind::ForearmTwist => (Front, Lateral, Front, Medial),
            JointKind::Wrist => (Palmar, Radial, Radial, Palmar),
            JointKind::Knee => (Back, Lateral, Front, Medial),
            JointKind::Ankle => (Up, Lateral, Up, Lateral),
        }
    }
}

pub(super) fn anat_dir(a: Anat, side: Side, palmar: Vec3, radial: Vec3) -> Vec3 {
    let medial = match side {
        Side::Left => Vec3::X,
        Side::Right => Vec3::NEG_X,
        Side::Center => Vec3::ZERO,
    };
    match a {
        Anat::Front => Vec3::NEG_Z,
        Anat::Back => Vec3::Z,
        Anat::Up => Vec3::Y,
        Anat::Down => Vec3::NEG_Y,
        Anat::Left => Vec3::NEG_X,
        Anat::Right => Vec3::X,
        Anat::Medial => medial,
        Anat::Lateral => -medial,
        Anat::Palmar => palmar,
        Anat::Radial => radial,
    }
}
