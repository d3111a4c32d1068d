//! The joint-limits table (seed 000 §4.4.2: "constraints on the joint data based on the
//! natural limits of human bones"): textbook ranges per anatomical joint, each row with its
//! sources and what was widened after measuring clean motion capture.

use super::JointKind;

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
/// split over the two forearm bones by
/// [`LimitOptions::forearm_twist_share_proximal`](super::LimitOptions::forearm_twist_share_proximal).
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
