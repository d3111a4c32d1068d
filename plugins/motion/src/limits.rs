//! Anatomical joint-angle limits (seed 000 §4.4.2, first stage: "constraints on the joint data
//! based on the natural limits of human bones").
//!
//! # Angles
//!
//! Every limited bone's local rotation `L` (relative to its parent bone, as in
//! [`AvatarPose::local_rotations`]) is measured against an *anatomical neutral* `N` of that
//! joint: `D = N^-1 * L`, a rotation in the bone's own neutral frame. `D` is split into
//! `swing * twist` ([`crate::retarget::swing_twist`]) about the bone's +Y axis (head to tail):
//!
//! * **twist**: the rotation about the bone's own axis (axial rotation, pronation/supination,
//!   inversion/eversion);
//! * **swing**: the rotation that moves the bone's axis, written as its rotation vector
//!   `s = angle * axis` (the axis lies in the bone's local XZ plane) and read on two
//!   anatomical axes: `flexion = s . a_flex` and `abduction = s . a_abd`.
//!
//! `a_flex` is the local axis about which the bone's tail moves towards the joint's flexion
//! direction (e.g. the ankle backwards for the knee), `a_abd = ±(Y x a_flex)` the one that
//! moves it towards abduction. Both come from the body's anatomical directions in the neutral
//! pose ([`Anat`]: the avatar faces the sensor, front = -Z, left = -X, up = +Y), expressed in
//! the bone's neutral frame; see [`JointKind::directions`] for the positive sense of each
//! angle. [`JointLimits::axes_report`] prints the axes; on the shipped MakeHuman body (local
//! frames of the *neutral* pose, left side; the right side mirrors Z and the twist sign):
//!
//! | joint (bone) | flexion axis | abduction axis | + twist |
//! |---|---|---|---|
//! | trunk, neck, head (`spine_0x`, `neck_01`, `head`) | +X | -Z (bend left) | +Y (turn left) |
//! | clavicle | ≈ +Z (elevation) | ≈ +X (protraction) | -Y (posterior rotation) |
//! | shoulder (`upperarm`) | (0.92, 0, 0.38) | (-0.38, 0, 0.92) | +Y (internal) |
//! | elbow (`lowerarm`) | (0.99, 0, 0.17) ≈ +X | ≈ +Z | +Y (pronation) |
//! | wrist (`hand`) | (-0.33, 0, -0.94) (palmar) | (0.94, 0, -0.33) (radial) | +Y (pronation) |
//! | hip (`thigh`) | (-0.90, 0, 0.44) | (-0.44, 0, -0.90) | +Y (internal) |
//! | knee (`calf`) | +X (1.00, 0, 0.06) | -Z | +Y (internal) |
//! | ankle (`foot`) | -X (dorsiflexion) | -Z (toe out) | -Y (inversion) |
//!
//! So knee flexion is a rotation about the calf's local +X axis and hip flexion one about
//! (nearly) the thigh's local -X axis. A walking clip (07_01) confirms the signs: the knee
//! flexes 11° in stance and 76-78° in swing with under 1° of mean abduction, the hip goes from
//! -18° (extension) to +44°, the elbow stays 20-67° flexed with 1.4° of abduction.
//!
//! The allowed swing region is the convex "quadrant ellipse" with semi-axes equal to the four
//! range ends (flexion max / extension, abduction max / adduction): in each quadrant
//! `(flex / f)^2 + (abd / a)^2 <= 1`. It contains each pure range exactly and interpolates
//! between them (a shoulder flexed 90° may adduct 0.87 of its pure adduction, a knee flexed
//! 120° may only show 0.55 of its varus/valgus play). The twist range is an interval.
//!
//! # The anatomical neutral
//!
//! The avatar's rest pose (MakeHuman's A-pose: arms 40° abducted, elbows 47° flexed, knees
//! ~8° flexed, trunk bones drawn along the rest curvature, the hand bone's +Y 24° off the
//! middle finger) is *not* the anatomical zero, so limits are not relative to it. The limits
//! act on retargeted poses, so the neutral is the pose the retargeter produces for a performer
//! standing in the anatomical neutral ([`NeutralRule::Kinect`]): each Kinect-driven bone is
//! its rest frame carried onto the bone's Kinect T-pose direction (the retargeter's twist
//! convention), then turned with the sensor's zero-twist frame onto the neutral direction:
//!
//! * trunk, neck, head: vertical (an upright performer gives vertical spine bones);
//! * thigh, calf: vertical (legs straight and parallel, knees forward);
//! * upper arm, forearm, hand: hanging straight down with the forearm's zero twist of the
//!   sensor convention (the forearm and hand twists of the walking clips centre on it, medians
//!   0-7°: the mid position of pronation/supination), and the whole arm turned by
//!   [`ELBOW_HINGE_OFFSET_DEG`] about its axis so that the elbow's observed hinge is pure
//!   flexion (measured on all 15 clips: the same 25-36° on every clip);
//! * forearm twist bone: its rest local rotation (colinear, no twist);
//! * clavicle: lateral, [`KINECT_CLAVICLE_DROP_DEG`] below horizontal (the Kinect shoulder
//!   centre is above the shoulder line);
//! * foot: forward, [`KINECT_FOOT_PITCH_DEG`] below horizontal.
//!
//! Relative to the avatar's rest pose these neutrals differ by the offsets the axes report
//! prints (e.g. elbow 45° of flexion, knee 8°, spine_01 20°, clavicle 34°, hand 39°).
//! Where the Kinect mapping and the avatar's own anatomy disagree (the clavicle is drawn
//! horizontal but the Kinect shoulder bone points 20° down; the hand bone's +Y is not the
//! hand's axis but follows the performer's wrist -> hand direction; the avatar's ankle -> ball
//! bone follows the performer's ankle -> toe vector), the neutral follows the mapping so that
//! clean motion is inside the limits; these are retargeting offsets, not anatomy.
//!
//! # Clamping
//!
//! [`JointLimits::clamp`] projects the swing point onto the allowed region (nearest point in
//! the (flexion, abduction) chart, exact for the ellipse by bisection) and clamps the twist to
//! its interval, then recomposes `N * swing * twist`. A rotation inside the limits is
//! returned unchanged (bit for bit). The projection is continuous, so a trajectory that
//! leaves the region slides along its boundary instead of jumping.
//!
//! # Sources (per joint, see [`LIMIT_TABLE`])
//!
//! * **AAOS**: Greene & Heckman, *The Clinical Measurement of Joint Motion*, American Academy
//!   of Orthopaedic Surgeons, 1994 (the AAOS "average normal" ranges).
//! * **Soucie**: Soucie et al., "Range of motion measurements: reference values and a database
//!   for comparison studies", *Haemophilia* 17(3):500–507, 2011 (healthy 2–69 year-olds;
//!   used for hyperextension of elbow and knee: mean values of a few degrees, larger in women
//!   and children).
//! * **Kapandji**: I. A. Kapandji, *The Physiology of the Joints*, vols. 1–3 (shoulder
//!   adduction with flexion, lumbar/thoracic split of the trunk ranges, carrying angle, tibial
//!   rotation, atlanto-occipital motion).
//! * **Neumann**: D. A. Neumann, *Kinesiology of the Musculoskeletal System*, 2nd ed., 2010
//!   (sternoclavicular joint: elevation 45°, depression 10°, protraction/retraction 15–30°,
//!   posterior rotation 20–35°).
//!
//! Textbook values describe one anatomical joint; several avatar joints are driven by Kinect
//! bones that span more than one anatomical joint or segment (the clavicle by the shoulder
//! centre -> shoulder vector, the lumbar segment by hip centre -> spine, the neck by shoulder
//! centre -> head), and the retargeter maps motion-capture bones onto a differently
//! proportioned rig. Where clean motion capture (15 CMU clips) exceeds a textbook range the
//! range was widened and the row says so (`widened:`); the measured shares are in the test
//! report.

use glam::{Quat, Vec3};

use crate::retarget::{AvatarPose, AvatarSkeleton, swing_twist};
use fitroom_sensor::frame::bone_reference_frame;

/// Violations smaller than this are ignored by [`JointLimits::violations`], degrees.
pub const DEFAULT_TOLERANCE_DEG: f32 = 0.5;

/// Semi-axes of the swing region are at least this (radians) so the region never degenerates.
const MIN_SEMI_AXIS: f32 = 1e-3;

/// How far below horizontal the Kinect shoulder bone (shoulder centre -> shoulder) of an
/// upright performer points, degrees. The Kinect shoulder centre (CMU `neck` / `Neck1`) sits
/// 3-5 cm above the shoulder joints and ~17 cm medial; on the clean CMU clips the retargeted
/// clavicle's median elevation against the horizontal is -20..-25° (DAZ export) and -11..-19°
/// (MotionBuilder export).
pub const KINECT_CLAVICLE_DROP_DEG: f32 = 20.0;

/// How far below horizontal the Kinect foot bone (ankle -> foot) of a performer standing
/// flat points, degrees. Measured: a planted foot points 18° below horizontal in 07_01 (DAZ
/// export, ankle -> toe end site) and 13-25° in 16_11 (MotionBuilder export, ankle -> toe
/// base); over whole walking cycles the median is 3-6° (DAZ) and 16° (MotionBuilder) below.
/// 10° is a compromise; the ±10° uncertainty is why the dorsiflexion range was widened.
pub const KINECT_FOOT_PITCH_DEG: f32 = 10.0;

/// Twist of the hanging arm's neutral about its axis (the person's left arm turned
/// internally, i.e. the front towards medial; mirrored on the right), degrees. The elbow is a
/// hinge; through the retargeter its observed hinge axis (the swing axis of the forearm against
/// the upper arm) lies 25-36° (median 27°, the same on all 15 CMU clips, both BVH exports) from
/// the forward-flexion axis of the sensor's zero-twist frame: the source skeleton's humeral
/// twist in its T-pose. Turning the neutral of the whole arm (upper arm, forearm, hand) by this
/// angle makes elbow flexion a pure flexion, and centres the humeral rotation.
pub const ELBOW_HINGE_OFFSET_DEG: f32 = 27.0;

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
fn kinect_neutral(name: &str, rest: Quat, a: Anat, side: Side, drop_deg: f32) -> Option<Quat> {
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

/// One row of the limits table: ranges in degrees, `(min, max)` with `min <= 0 <= max`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LimitSpec {
    pub kind: JointKind,
    /// Flexion range: negative = extension (see [`JointKind::directions`]).
    pub flexion_deg: (f32, f32),
    /// Abduction range: negative = adduction.
    pub abduction_deg: (f32, f32),
    /// Twist range: negative = external rotation / supination / eversion.
    pub twist_deg: (f32, f32),
    /// Where the numbers come from, and what was widened after measuring clean mocap.
    pub source: &'static str,
}

/// The limits table. Forearm twist rows hold the *total* pronation/supination range; it is
/// split over the two forearm bones by [`LimitOptions::forearm_twist_share_proximal`].
pub const LIMIT_TABLE: &[LimitSpec] = &[
    LimitSpec {
        kind: JointKind::Lumbar,
        flexion_deg: (-35.0, 60.0),
        abduction_deg: (-30.0, 30.0),
        twist_deg: (-30.0, 30.0),
        source: "Kapandji vol. 3 lumbar spine: flexion 60, extension 35; AAOS thoracolumbar \
                 lateral bending 35 and rotation 45 of which the lumbar segment carries a part; \
                 widened: lateral bending 20 -> 30 and rotation 5 -> 30, because the Kinect \
                 hip-centre -> spine bone spans lumbar and lower thoracic spine",
    },
    LimitSpec {
        kind: JointKind::Thoracic,
        flexion_deg: (-25.0, 45.0),
        abduction_deg: (-30.0, 30.0),
        twist_deg: (-45.0, 45.0),
        source: "Kapandji vol. 3 thoracic spine: flexion 45 (AAOS thoracolumbar 80 minus the \
                 lumbar share), extension 25 (AAOS 25), lateral bending 30; widened: rotation \
                 35 -> 45 (the AAOS thoracolumbar total), because the Kinect spine -> shoulder \
                 centre bone starts at navel height and so also carries lumbar rotation; clean \
                 mocap reaches 39-44 in 11_01 and 05_06",
    },
    LimitSpec {
        kind: JointKind::UpperThoracic,
        flexion_deg: (-10.0, 10.0),
        abduction_deg: (-10.0, 10.0),
        twist_deg: (-10.0, 10.0),
        source: "upper thoracic segment (T1-T4 are stiffened by the rib cage, Kapandji vol. 3); \
                 the retargeter drives spine_02 and spine_03 with one Kinect bone, so this \
                 joint stays at its neutral",
    },
    LimitSpec {
        kind: JointKind::Neck,
        flexion_deg: (-45.0, 45.0),
        abduction_deg: (-45.0, 45.0),
        twist_deg: (-60.0, 60.0),
        source: "AAOS cervical spine: flexion 45, extension 45, lateral bending 45, rotation 60",
    },
    LimitSpec {
        kind: JointKind::Head,
        flexion_deg: (-15.0, 15.0),
        abduction_deg: (-8.0, 8.0),
        twist_deg: (-5.0, 5.0),
        source: "Kapandji vol. 3 / Neumann atlanto-occipital joint: flexion-extension ~15 each, \
                 lateral ~8, negligible rotation (the atlanto-axial rotation is in the neck \
                 row); the retargeter drives neck and head with one Kinect bone",
    },
    LimitSpec {
        kind: JointKind::Clavicle,
        flexion_deg: (-10.0, 45.0),
        abduction_deg: (-30.0, 30.0),
        twist_deg: (-10.0, 35.0),
        source: "Neumann sternoclavicular joint: elevation 45, depression 10, protraction and \
                 retraction 15-30 (30 used), posterior rotation 20-35 (35 used), anterior \
                 rotation ~10",
    },
    LimitSpec {
        kind: JointKind::Shoulder,
        flexion_deg: (-60.0, 180.0),
        abduction_deg: (-45.0, 180.0),
        twist_deg: (-110.0, 95.0),
        source: "AAOS shoulder: flexion 180, extension 60, abduction 180; adduction 45 \
                 (Kapandji vol. 1: 30-45 combined with flexion; 0 in the pure frontal plane \
                 where the trunk blocks it); widened: external rotation 90 -> 110 and internal \
                 rotation 70 -> 95: this twist is measured from the hanging neutral by \
                 swing-twist, which also holds the axial rotation that elevating the arm \
                 forces (Codman's paradox); clean mocap reaches 100-118 external rotation with \
                 the arms abducted 100-135 (14_19, hands to the head) and 93-99 internal \
                 rotation with the arm across the body (10_03, 11_01)",
    },
    LimitSpec {
        kind: JointKind::Elbow,
        flexion_deg: (-10.0, 150.0),
        abduction_deg: (-10.0, 20.0),
        twist_deg: (-80.0, 80.0),
        source: "AAOS elbow: flexion 150, extension 0; hyperextension up to 10 (Soucie: mean \
                 a few degrees, more in women); valgus 20 / varus 10 around the neutral for \
                 the carrying angle (Kapandji vol. 1: 5-15 valgus); twist = this bone's share \
                 of the AAOS forearm pronation 80 / supination 80",
    },
    LimitSpec {
        kind: JointKind::ForearmTwist,
        flexion_deg: (-2.0, 2.0),
        abduction_deg: (-2.0, 2.0),
        twist_deg: (-80.0, 80.0),
        source: "AAOS forearm: pronation 80, supination 80, split over the two forearm bones; \
                 the distal half is a pure twist bone (no swing)",
    },
    LimitSpec {
        kind: JointKind::Wrist,
        flexion_deg: (-70.0, 80.0),
        abduction_deg: (-30.0, 20.0),
        twist_deg: (-80.0, 80.0),
        source: "AAOS wrist: flexion 80, extension 70, radial deviation 20, ulnar deviation 30; \
                 twist: the wrist itself has no axial rotation, but the CMU data carry the \
                 forearm's pronation/supination on the hand joint (the forearm bones of the \
                 retargeted pose stay within +-15), so the hand's twist gets the AAOS forearm \
                 range, pronation 80 / supination 80",
    },
    LimitSpec {
        kind: JointKind::Hip,
        flexion_deg: (-30.0, 120.0),
        abduction_deg: (-30.0, 45.0),
        twist_deg: (-45.0, 45.0),
        source: "AAOS hip: flexion 120, extension 30, abduction 45, adduction 30, internal \
                 rotation 45, external rotation 45",
    },
    LimitSpec {
        kind: JointKind::Knee,
        flexion_deg: (-5.0, 150.0),
        abduction_deg: (-10.0, 10.0),
        twist_deg: (-40.0, 30.0),
        source: "AAOS knee: flexion 135 (150 passive, Kapandji vol. 2: 140 active / 160 \
                 passive), extension 0; hyperextension 5 (Soucie: mean 1-2, up to ~5); \
                 Kapandji vol. 2 tibial rotation (knee flexed): internal 30, external 40; \
                 varus/valgus play 10",
    },
    LimitSpec {
        kind: JointKind::Ankle,
        flexion_deg: (-50.0, 30.0),
        abduction_deg: (-20.0, 35.0),
        twist_deg: (-15.0, 35.0),
        source: "AAOS ankle: plantar flexion 50; AAOS foot inversion 35, eversion 15, forefoot \
                 adduction 20; widened: dorsiflexion 20 -> 30 because the neutral pitch of the \
                 Kinect foot bone is uncertain by about 10 (KINECT_FOOT_PITCH_DEG); abduction \
                 (toe-out) 10 -> 35 because the toe-out of stance and gait (foot progression \
                 angle, typically 5-15, from hip and tibial external rotation) appears at this \
                 joint: the retargeted thigh and shank keep the twist of their Kinect bones; \
                 clean walking shows a median of 12-14 and a 99th percentile of 34-35",
    },
];

/// Options of [`JointLimits::new`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LimitOptions {
    /// Share of the forearm twist range given to the proximal forearm bone; must match
    /// [`crate::RetargetOptions::forearm_twist_share_proximal`].
    pub forearm_twist_share_proximal: f32,
    /// Violations up to this many degrees are not reported.
    pub tolerance_deg: f32,
}

impl Default for LimitOptions {
    fn default() -> Self {
        Self {
            forearm_twist_share_proximal: crate::RetargetOptions::default()
                .forearm_twist_share_proximal,
            tolerance_deg: DEFAULT_TOLERANCE_DEG,
        }
    }
}

/// A joint's angles relative to its anatomical neutral, radians (signs per
/// [`JointKind::directions`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JointAngles {
    pub flexion: f32,
    pub abduction: f32,
    pub twist: f32,
}

/// One limited bone.
#[derive(Clone, Debug, PartialEq)]
pub struct JointLimit {
    pub bone: usize,
    pub name: String,
    pub kind: JointKind,
    pub side: Side,
    /// Anatomical neutral local rotation (relative to the parent bone).
    pub neutral: Quat,
    /// Local (neutral frame) swing axis of positive flexion; perpendicular to +Y.
    pub flexion_axis: Vec3,
    /// Local swing axis of positive abduction; `±(Y x flexion_axis)`.
    pub abduction_axis: Vec3,
    /// +1 if positive twist is a right-handed turn about the bone's +Y, else -1.
    pub twist_sign: f32,
    /// Ranges, radians.
    pub flexion: (f32, f32),
    pub abduction: (f32, f32),
    pub twist: (f32, f32),
}

/// Which part of a joint's limit is exceeded.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum LimitPart {
    /// The swing (flexion/abduction) lies outside its region.
    Swing,
    /// The twist lies outside its interval.
    Twist,
}

/// A limit exceeded by more than the tolerance.
#[derive(Clone, Debug, PartialEq)]
pub struct Violation {
    pub bone: usize,
    pub kind: JointKind,
    pub side: Side,
    pub part: LimitPart,
    /// How far outside, degrees: the distance of the swing point from the region (in the
    /// flexion/abduction chart), or of the twist from its interval.
    pub excess_deg: f32,
    /// The joint's angles, degrees.
    pub angles_deg: JointAngles,
}

/// The limits of every joint of an avatar skeleton.
#[derive(Clone, Debug, PartialEq)]
pub struct JointLimits {
    joints: Vec<JointLimit>,
    /// Index into `joints` per bone.
    by_bone: Vec<Option<usize>>,
    tolerance_rad: f32,
}

fn anat_dir(a: Anat, side: Side, palmar: Vec3, radial: Vec3) -> Vec3 {
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

/// `D = swing * twist`, `D.w >= 0`; returns (swing rotation vector, twist angle about +Y).
fn decompose(d: Quat) -> (Vec3, f32) {
    let d = if d.w < 0.0 { -d } else { d };
    let (swing, twist) = swing_twist(d, Vec3::Y);
    let (swing, twist) = if swing.w < 0.0 {
        (-swing, -twist)
    } else {
        (swing, twist)
    };
    let twist_angle = {
        let a = 2.0 * twist.y.atan2(twist.w);
        // Wrap into (-pi, pi].
        if a > std::f32::consts::PI {
            a - std::f32::consts::TAU
        } else if a <= -std::f32::consts::PI {
            a + std::f32::consts::TAU
        } else {
            a
        }
    };
    let v = Vec3::new(swing.x, 0.0, swing.z);
    let s = v.length();
    let swing_vec = if s < 1e-9 {
        Vec3::ZERO
    } else {
        v / s * 2.0 * s.atan2(swing.w.max(0.0))
    };
    (swing_vec, twist_angle)
}

/// Nearest point of the quadrant ellipse `{(x/ex)^2 + (y/ey)^2 <= 1}` (semi-axes chosen by
/// the signs of the point) to `(x, y)`; the point itself if inside.
fn project_quadrant_ellipse(x: f32, y: f32, xr: (f32, f32), yr: (f32, f32)) -> (f32, f32) {
    let ex = if x >= 0.0 { xr.1 } else { -xr.0 }.max(MIN_SEMI_AXIS) as f64;
    let ey = if y >= 0.0 { yr.1 } else { -yr.0 }.max(MIN_SEMI_AXIS) as f64;
    let (px, py) = ((x as f64).abs(), (y as f64).abs());
    // Points on the boundary up to rounding count as inside, so a clamped rotation is a fixed
    // point of the clamp.
    if (px / ex).powi(2) + (py / ey).powi(2) <= 1.0 + 1e-5 {
        return (x, y);
    }
    // Nearest point: (e_i^2 p_i / (t + e_i^2)) with t > 0 the root of
    // F(t) = sum (e_i p_i / (t + e_i^2))^2 - 1, decreasing on t >= 0 (Eberly, "Distance from a
    // point to an ellipse"). Bisection in f64.
    let f = |t: f64| (ex * px / (t + ex * ex)).powi(2) + (ey * py / (t + ey * ey)).powi(2) - 1.0;
    let mut lo = 0.0f64;
    let mut hi = (std::f64::consts::SQRT_2 * (ex * px).max(ey * py)).max(1e-12);
    while f(hi) > 0.0 {
        hi *= 2.0;
    }
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if f(mid) > 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let t = hi;
    let qx = ex * ex * px / (t + ex * ex);
    let qy = ey * ey * py / (t + ey * ey);
    (
        (qx as f32).copysign(if x == 0.0 { 1.0 } else { x }),
        (qy as f32).copysign(if y == 0.0 { 1.0 } else { y }),
    )
}

impl JointLimit {
    /// The joint's angles for a local rotation.
    pub fn angles(&self, local: Quat) -> JointAngles {
        let (s, t) = decompose(self.neutral.inverse() * local);
        JointAngles {
            flexion: s.dot(self.flexion_axis),
            abduction: s.dot(self.abduction_axis),
            twist: t * self.twist_sign,
        }
    }

    /// The local rotation with these angles.
    pub fn rotation(&self, angles: JointAngles) -> Quat {
        let s = self.flexion_axis * angles.flexion + self.abduction_axis * angles.abduction;
        let swing = Quat::from_scaled_axis(s);
        let twist = Quat::from_rotation_y(angles.twist * self.twist_sign);
        (self.neutral * swing * twist).normalize()
    }

    /// (swing excess, twist excess), radians, and the clamped angles.
    fn excess(&self, angles: JointAngles) -> (f32, f32, JointAngles) {
        let (f, a) = project_quadrant_ellipse(
            angles.flexion,
            angles.abduction,
            self.flexion,
            self.abduction,
        );
        let t = angles.twist.clamp(self.twist.0, self.twist.1);
        let swing_excess = ((f - angles.flexion).powi(2) + (a - angles.abduction).powi(2)).sqrt();
        (
            swing_excess,
            (t - angles.twist).abs(),
            JointAngles {
                flexion: f,
                abduction: a,
                twist: t,
            },
        )
    }

    /// The nearest allowed local rotation (the input itself if allowed).
    pub fn clamp(&self, local: Quat) -> Quat {
        if !local.is_finite() {
            return self.neutral;
        }
        let angles = self.angles(local);
        let (swing_excess, twist_excess, clamped) = self.excess(angles);
        if swing_excess == 0.0 && twist_excess == 0.0 {
            local
        } else {
            self.rotation(clamped)
        }
    }
}

impl JointLimits {
    /// Builds the limits of [`LIMIT_TABLE`] for the bones of `skeleton` that exist (a missing
    /// bone is simply not limited; see [`JointLimits::joints`]).
    pub fn new(skeleton: &AvatarSkeleton, options: LimitOptions) -> Self {
        Self::from_table(skeleton, LIMIT_TABLE, options)
    }

    /// Builds limits from a custom table.
    pub fn from_table(
        skeleton: &AvatarSkeleton,
        table: &[LimitSpec],
        options: LimitOptions,
    ) -> Self {
        let bones = &skeleton.bones;
        let n = bones.len();
        let find = |name: &str| skeleton.index_of(name);
        let share = if options.forearm_twist_share_proximal.is_finite() {
            options.forearm_twist_share_proximal.clamp(0.0, 1.0)
        } else {
            0.5
        };

        let rule_of = |i: usize| -> Option<(JointKind, Side)> {
            let name = bones[i].name.as_str();
            table.iter().find_map(|spec| {
                let base = spec.kind.bone_base();
                if !spec.kind.sided() {
                    return (name == base).then_some((spec.kind, Side::Center));
                }
                match name.strip_prefix(base) {
                    Some("_l") => Some((spec.kind, Side::Left)),
                    Some("_r") => Some((spec.kind, Side::Right)),
                    _ => None,
                }
            })
        };

        // Rest palm normal and radial direction per side (sensor space), from the finger
        // bases: along = middle base - hand head, radial = index base - little finger base,
        // palm = along x radial (left) / radial x along (right).
        let hand_dirs = |side: Side| -> Option<(Vec3, Vec3)> {
            let sfx = if side == Side::Left { "_l" } else { "_r" };
            let hand = bones[find(&format!("hand{sfx}"))?].rest_head;
            let index = bones[find(&format!("index_01{sfx}"))?].rest_head;
            let pinky = bones[find(&format!("pinky_01{sfx}"))?].rest_head;
            let middle = bones[find(&format!("middle_01{sfx}"))?].rest_head;
            let along = (middle - hand).try_normalize()?;
            let radial = (index - pinky).try_normalize()?;
            let palm = if side == Side::Left {
                along.cross(radial)
            } else {
                radial.cross(along)
            };
            Some((palm.try_normalize()?, radial))
        };

        // Neutral global frames, parents first. A bone without a rule keeps its rest local
        // rotation under its (neutral) parent.
        let mut neutral_global: Vec<Quat> = Vec::with_capacity(n);
        let mut kinds: Vec<Option<(JointKind, Side)>> = Vec::with_capacity(n);
        for (i, bone) in bones.iter().enumerate() {
            let parent_neutral = match bone.parent {
                Some(p) if p < i => neutral_global[p],
                _ => Quat::IDENTITY,
            };
            let candidate = (parent_neutral * bone.rest_local_rotation).normalize();
            let kind = rule_of(i);
            kinds.push(kind);
            let global = match kind {
                None => candidate,
                Some((kind, side)) => match kind.neutral_rule() {
                    NeutralRule::RestLocal => candidate,
                    NeutralRule::Kinect(a, drop_deg) => {
                        let frame =
                            kinect_neutral(&bone.name, bone.rest_rotation, a, side, drop_deg)
                                .unwrap_or(candidate);
                        if matches!(
                            kind,
                            JointKind::Shoulder | JointKind::Elbow | JointKind::Wrist
                        ) {
                            // The humeral twist of the source's T-pose (see
                            // ELBOW_HINGE_OFFSET_DEG), applied to the whole hanging arm.
                            let sign = if side == Side::Left { 1.0 } else { -1.0 };
                            (Quat::from_axis_angle(
                                Vec3::NEG_Y,
                                sign * ELBOW_HINGE_OFFSET_DEG.to_radians(),
                            ) * frame)
                                .normalize()
                        } else {
                            frame
                        }
                    }
                },
            };
            neutral_global.push(global);
        }

        // Local neutrals, axes and ranges.
        let mut joints = Vec::new();
        let mut by_bone = vec![None; n];
        for (i, bone) in bones.iter().enumerate() {
            let Some((kind, side)) = kinds[i] else {
                continue;
            };
            let Some(spec) = table.iter().find(|s| s.kind == kind) else {
                continue;
            };
            let parent_neutral = match bone.parent {
                Some(p) if p < i => neutral_global[p],
                _ => Quat::IDENTITY,
            };
            let neutral = (parent_neutral.inverse() * neutral_global[i]).normalize();
            let (palmar, radial) = if kind == JointKind::Wrist {
                match hand_dirs(side) {
                    // Carried from the rest hand into its neutral frame, in sensor space.
                    Some((p, r)) => {
                        let to_neutral = neutral_global[i] * bone.rest_rotation.inverse();
                        (to_neutral * p, to_neutral * r)
                    }
                    None => continue,
                }
            } else {
                (Vec3::ZERO, Vec3::ZERO)
            };
            let (flex, abd, probe, towards) = kind.directions();
            let to_local = neutral_global[i].inverse();
            let local = |a: Anat| to_local * anat_dir(a, side, palmar, radial);
            let y = Vec3::Y;
            let flexion_axis = {
                let a = y.cross(local(flex));
                Vec3::new(a.x, 0.0, a.z).try_normalize()
            };
            let Some(flexion_axis) = flexion_axis else {
                continue;
            };
            let abduction_axis = {
                let candidate = y.cross(flexion_axis);
                let wanted = y.cross(local(abd));
                if candidate.dot(wanted) >= 0.0 {
                    candidate
                } else {
                    -candidate
                }
            };
            let twist_sign = {
                let p = local(probe);
                if y.cross(p).dot(local(towards)) >= 0.0 {
                    1.0
                } else {
                    -1.0
                }
            };
            let rad = |r: (f32, f32)| (r.0.to_radians(), r.1.to_radians());
            let mut twist = rad(spec.twist_deg);
            match kind {
                JointKind::Elbow => twist = (twist.0 * share, twist.1 * share),
                JointKind::ForearmTwist => {
                    twist = (twist.0 * (1.0 - share), twist.1 * (1.0 - share))
                }
                _ => {}
            }
            by_bone[i] = Some(joints.len());
            joints.push(JointLimit {
                bone: i,
                name: bone.name.clone(),
                kind,
                side,
                neutral,
                flexion_axis,
                abduction_axis,
                twist_sign,
                flexion: rad(spec.flexion_deg),
                abduction: rad(spec.abduction_deg),
                twist,
            });
        }
        Self {
            joints,
            by_bone,
            tolerance_rad: options.tolerance_deg.max(0.0).to_radians(),
        }
    }

    /// The limited joints.
    pub fn joints(&self) -> &[JointLimit] {
        &self.joints
    }

    /// The limit of a bone, if it has one.
    pub fn joint(&self, bone: usize) -> Option<&JointLimit> {
        self.by_bone
            .get(bone)
            .copied()
            .flatten()
            .map(|k| &self.joints[k])
    }

    /// The nearest allowed local rotation of `bone` (relative to its parent); the input itself
    /// if allowed or if the bone is not limited.
    pub fn clamp(&self, bone: usize, local: Quat) -> Quat {
        match self.joint(bone) {
            Some(j) => j.clamp(local),
            None => local,
        }
    }

    /// Clamps every limited joint of `pose` and recomputes its global rotations and heads
    /// (the roots keep their heads). Returns the number of joints changed.
    pub fn clamp_pose(&self, skeleton: &AvatarSkeleton, pose: &mut AvatarPose) -> usize {
        let mut changed = 0;
        for j in &self.joints {
            if let Some(local) = pose.local_rotations.get_mut(j.bone) {
                let clamped = j.clamp(*local);
                if clamped != *local {
                    *local = clamped;
                    changed += 1;
                }
            }
        }
        if changed > 0 {
            crate::ik::forward_kinematics(skeleton, pose);
        }
        changed
    }

    /// The joints of `pose` outside their limits by more than the tolerance.
    pub fn violations(&self, pose: &AvatarPose) -> Vec<Violation> {
        let mut out = Vec::new();
        for j in &self.joints {
            let Some(&local) = pose.local_rotations.get(j.bone) else {
                continue;
            };
            let angles = j.angles(local);
            let (swing, twist, _) = j.excess(angles);
            let deg = JointAngles {
                flexion: angles.flexion.to_degrees(),
                abduction: angles.abduction.to_degrees(),
                twist: angles.twist.to_degrees(),
            };
            for (part, excess) in [(LimitPart::Swing, swing), (LimitPart::Twist, twist)] {
                if excess > self.tolerance_rad || excess.is_nan() {
                    out.push(Violation {
                        bone: j.bone,
                        kind: j.kind,
                        side: j.side,
                        part,
                        excess_deg: excess.to_degrees(),
                        angles_deg: deg,
                    });
                }
            }
        }
        out
    }

    /// A human-readable list of each joint's local axes (neutral frame) and neutral offset
    /// from the rest pose.
    pub fn axes_report(&self, skeleton: &AvatarSkeleton) -> String {
        let mut s = String::new();
        for j in &self.joints {
            let rest = skeleton.bones[j.bone].rest_local_rotation;
            let offset = (j.neutral.inverse() * rest).normalize();
            let a = j.angles(rest);
            s.push_str(&format!(
                "{:<18} flex axis {:>6.2?} abd axis {:>6.2?} twist sign {:+} | rest = \
                 flex {:+6.1} abd {:+6.1} twist {:+6.1} (offset {:5.1}°)\n",
                j.name,
                j.flexion_axis,
                j.abduction_axis,
                j.twist_sign,
                a.flexion.to_degrees(),
                a.abduction.to_degrees(),
                a.twist.to_degrees(),
                offset.angle_between(Quat::IDENTITY).to_degrees(),
            ));
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ellipse_projection_is_nearest_and_idempotent() {
        let xr = (-0.2, 1.0);
        let yr = (-0.5, 0.3);
        for &(x, y) in &[
            (2.0, 1.0),
            (-1.0, -1.0),
            (0.0, 3.0),
            (3.0, 0.0),
            (0.5, -2.0),
        ] {
            let (px, py) = project_quadrant_ellipse(x, y, xr, yr);
            // On the boundary.
            let ex = if px >= 0.0 { xr.1 } else { -xr.0 };
            let ey = if py >= 0.0 { yr.1 } else { -yr.0 };
            let r = (px / ex).powi(2) + (py / ey).powi(2);
            assert!((r - 1.0).abs() < 1e-4, "{x},{y} -> {px},{py}: {r}");
            assert_eq!(
                project_quadrant_ellipse(px * 0.999, py * 0.999, xr, yr),
                (px * 0.999, py * 0.999)
            );
            // No boundary sample is nearer.
            let d = ((px - x).powi(2) + (py - y).powi(2)).sqrt();
            for k in 0..2000 {
                let t = k as f32 / 2000.0 * std::f32::consts::TAU;
                let (c, s) = (t.cos(), t.sin());
                let bx = c * if c >= 0.0 { xr.1 } else { -xr.0 };
                let by = s * if s >= 0.0 { yr.1 } else { -yr.0 };
                let db = ((bx - x).powi(2) + (by - y).powi(2)).sqrt();
                assert!(db >= d - 1e-4, "{x},{y}: {d} > {db}");
            }
        }
    }

    #[test]
    fn decompose_recomposes() {
        let q = Quat::from_euler(glam::EulerRot::YXZ, 0.7, 0.5, -0.9);
        let (s, t) = decompose(q);
        let r = Quat::from_scaled_axis(s) * Quat::from_rotation_y(t);
        assert!(r.abs_diff_eq(q, 1e-5) || r.abs_diff_eq(-q, 1e-5));
    }
}
