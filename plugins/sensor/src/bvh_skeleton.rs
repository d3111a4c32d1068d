//! Which CMU BVH skeleton a clip uses, and how its joints map onto the 20 Kinect v1 joints.
//!
//! Two variants of the CMU database circulate and both are supported:
//!
//! | Kinect joint      | cgspeed "DAZ-friendly" (root `hip`) | MotionBuilder-style (root `Hips`) |
//! |-------------------|--------------------------------------|-----------------------------------|
//! | HipCenter         | `hip`                                | `Hips`                            |
//! | Spine             | `abdomen`                            | `Spine`                           |
//! | ShoulderCenter    | `neck`                               | `Neck1`                           |
//! | Head              | `head`                               | `Head`                            |
//! | ShoulderL/R       | `lShldr` / `rShldr`                  | `LeftArm` / `RightArm`            |
//! | ElbowL/R          | `lForeArm` / `rForeArm`              | `LeftForeArm` / `RightForeArm`    |
//! | WristL/R          | `lHand` / `rHand`                    | `LeftHand` / `RightHand`          |
//! | HandL/R           | `lMid1` / `rMid1`                    | `LeftHandIndex1` / `RightHandIndex1` |
//! | HipL/R            | `lThigh` / `rThigh`                  | `LeftUpLeg` / `RightUpLeg`        |
//! | KneeL/R           | `lShin` / `rShin`                    | `LeftLeg` / `RightLeg`            |
//! | AnkleL/R          | `lFoot` / `rFoot`                    | `LeftFoot` / `RightFoot`          |
//! | FootL/R           | end site of `lFoot` / `rFoot` (toe)  | `LeftToeBase` / `RightToeBase`    |
//!
//! Notes on the choices: the MotionBuilder `Neck` sits at the base of the clavicles, about 7 cm
//! *below* the shoulder joints, while `Neck1` sits about 3 cm above them, like the DAZ `neck`
//! (5 cm above) and like Kinect's ShoulderCenter; `Spine` / `abdomen` are both about 20 cm above
//! the hip-joint line (navel height). `LeftFingerBase` has a zero offset from `LeftHand`, so the
//! hand end is `LeftHandIndex1`. In both files `l...` / `Left...` is the performer's left: in
//! the zero-rotation rest pose the toes point +Z, up is +Y, and the `l` / `Left` hips, shoulders
//! and arms are at +X, which for a right-handed Y-up frame facing +Z is the performer's left
//! (left = up x forward = Y x Z = +X). Kinect `*Left` joints therefore take the `l` / `Left`
//! joints unchanged; in sensor space (performer facing -Z) they end up at -X.
//!
//! Units: the metre scale comes from the leg length (hip joint -> knee -> ankle in the rest
//! pose, both legs averaged) against [`REFERENCE_LEG_LENGTH_M`]; both variants give about
//! 0.82 m for the CMU subjects at their nominal scale (centimetres, 0.056 m).

use glam::Vec3;

use crate::bvh::{BvhClip, BvhError, BvhPoint};
use crate::frame::KinectJoint;

/// Leg length (hip joint to ankle along the thigh and shin) the skeleton is scaled to, metres.
pub const REFERENCE_LEG_LENGTH_M: f32 = 0.82;

/// The supported CMU skeleton variants.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum BvhSkeletonKind {
    /// The cgspeed "DAZ-friendly" conversion: root `hip`, 43 joints, 132 channels, frame 0 an
    /// added T-pose.
    CgspeedDaz,
    /// The MotionBuilder-style export: root `Hips`, 31 joints, 96 channels, no T-pose frame.
    MotionBuilder,
}

/// A mapping target named in the variant's table.
#[derive(Clone, Copy)]
enum Target {
    Joint(&'static str),
    EndSiteOf(&'static str),
}

impl BvhSkeletonKind {
    /// `"cgspeed-daz"` or `"motionbuilder"`.
    pub fn name(self) -> &'static str {
        match self {
            BvhSkeletonKind::CgspeedDaz => "cgspeed-daz",
            BvhSkeletonKind::MotionBuilder => "motionbuilder",
        }
    }

    /// The root joint's name in this variant.
    pub fn root_name(self) -> &'static str {
        match self {
            BvhSkeletonKind::CgspeedDaz => "hip",
            BvhSkeletonKind::MotionBuilder => "Hips",
        }
    }

    /// Number of joints in the CMU files of this variant (43 or 31).
    pub fn expected_joint_count(self) -> usize {
        match self {
            BvhSkeletonKind::CgspeedDaz => 43,
            BvhSkeletonKind::MotionBuilder => 31,
        }
    }

    /// The variant by root name (exact, case-sensitive), `None` for any other skeleton.
    pub fn detect(clip: &BvhClip) -> Option<BvhSkeletonKind> {
        match clip.root().name.as_str() {
            "hip" => Some(BvhSkeletonKind::CgspeedDaz),
            "Hips" => Some(BvhSkeletonKind::MotionBuilder),
            _ => None,
        }
    }

    fn target(self, joint: KinectJoint) -> Target {
        use KinectJoint::*;
        use Target::{EndSiteOf, Joint};
        match self {
            BvhSkeletonKind::CgspeedDaz => match joint {
                HipCenter => Joint("hip"),
                Spine => Joint("abdomen"),
                ShoulderCenter => Joint("neck"),
                Head => Joint("head"),
                ShoulderLeft => Joint("lShldr"),
                ElbowLeft => Joint("lForeArm"),
                WristLeft => Joint("lHand"),
                HandLeft => Joint("lMid1"),
                ShoulderRight => Joint("rShldr"),
                ElbowRight => Joint("rForeArm"),
                WristRight => Joint("rHand"),
                HandRight => Joint("rMid1"),
                HipLeft => Joint("lThigh"),
                KneeLeft => Joint("lShin"),
                AnkleLeft => Joint("lFoot"),
                FootLeft => EndSiteOf("lFoot"),
                HipRight => Joint("rThigh"),
                KneeRight => Joint("rShin"),
                AnkleRight => Joint("rFoot"),
                FootRight => EndSiteOf("rFoot"),
            },
            BvhSkeletonKind::MotionBuilder => match joint {
                HipCenter => Joint("Hips"),
                Spine => Joint("Spine"),
                ShoulderCenter => Joint("Neck1"),
                Head => Joint("Head"),
                ShoulderLeft => Joint("LeftArm"),
                ElbowLeft => Joint("LeftForeArm"),
                WristLeft => Joint("LeftHand"),
                HandLeft => Joint("LeftHandIndex1"),
                ShoulderRight => Joint("RightArm"),
                ElbowRight => Joint("RightForeArm"),
                WristRight => Joint("RightHand"),
                HandRight => Joint("RightHandIndex1"),
                HipLeft => Joint("LeftUpLeg"),
                KneeLeft => Joint("LeftLeg"),
                AnkleLeft => Joint("LeftFoot"),
                FootLeft => Joint("LeftToeBase"),
                HipRight => Joint("RightUpLeg"),
                KneeRight => Joint("RightLeg"),
                AnkleRight => Joint("RightFoot"),
                FootRight => Joint("RightToeBase"),
            },
        }
    }

    /// Whether frame 0 of a clip of this variant is the T-pose the cgspeed conversion adds:
    /// the clip is [`BvhSkeletonKind::CgspeedDaz`], has more than one frame, and in frame 0
    /// every rotation channel of the root, both shoulders and both forearms is within 0.001 deg
    /// of zero (in captured frames these are never all zero; the legs of the added frame are
    /// not exactly zero, so they are not tested).
    pub fn has_added_tpose(self, clip: &BvhClip) -> bool {
        if self != BvhSkeletonKind::CgspeedDaz || clip.frame_count() < 2 {
            return false;
        }
        let Some(values) = clip.frame(0) else {
            return false;
        };
        let names = ["hip", "lShldr", "rShldr", "lForeArm", "rForeArm"];
        names.iter().all(|name| {
            clip.joint_index(name)
                .and_then(|j| clip.joints().get(j))
                .is_some_and(|joint| {
                    joint.channels.iter().enumerate().all(|(i, c)| {
                        !c.is_rotation()
                            || values
                                .get(joint.first_channel + i)
                                .is_some_and(|v| v.abs() < 1e-3)
                    })
                })
        })
    }

    /// The first frame of captured motion: 0, or for a clip with the added T-pose the frame
    /// after the T-pose and its blend-in ([`TPOSE_BLEND_FRAMES`]), capped so that at least one
    /// frame remains.
    pub fn first_motion_frame(self, clip: &BvhClip) -> usize {
        if self.has_added_tpose(clip) {
            (1 + TPOSE_BLEND_FRAMES).min(clip.frame_count() - 1)
        } else {
            0
        }
    }
}

/// Frames after the added T-pose that the cgspeed conversion blends from the T-pose into the
/// captured motion. In all 12 cgspeed CMU clips the shoulders' Z rotation goes from 0 to its
/// captured value over frames 1-4 (e.g. 0, -24, -49, -72, -87 deg), overshoots at frames 5-6
/// and settles by frame 8, while the root rotation takes its captured value at frame 1: a
/// smoothing artifact (an arm cannot swing 80 deg in 33 ms), not motion. Playback starts at
/// frame `1 + TPOSE_BLEND_FRAMES` = 8 (67 ms into the file).
pub const TPOSE_BLEND_FRAMES: usize = 7;

/// The mapping of one clip's joints onto the Kinect joints.
#[derive(Clone, Debug, PartialEq)]
pub struct KinectMapping {
    kind: BvhSkeletonKind,
    points: [BvhPoint; KinectJoint::COUNT],
    drivers: [usize; KinectJoint::COUNT],
    leg_length_units: f32,
}

impl KinectMapping {
    /// Detects the variant and resolves every mapped joint. Errors (naming the file and the line
    /// of `ROOT`) for an unknown root, a missing joint or a degenerate leg.
    pub fn new(clip: &BvhClip) -> Result<KinectMapping, BvhError> {
        let root = clip.root();
        let error = |message: String| BvhError::Skeleton {
            file: clip.file_name().to_string(),
            line: root.line,
            message,
        };
        let kind = BvhSkeletonKind::detect(clip).ok_or_else(|| {
            error(format!(
                "unsupported skeleton: the root joint is '{}'; expected root 'hip' (cgspeed \
                 DAZ-friendly CMU conversion) or 'Hips' (MotionBuilder-style CMU export)",
                root.name
            ))
        })?;

        let mut points = [BvhPoint::Joint(0); KinectJoint::COUNT];
        let mut drivers = [0usize; KinectJoint::COUNT];
        for joint in KinectJoint::ALL {
            let (point, driver) = match kind.target(joint) {
                Target::Joint(name) => {
                    let index = clip.joint_index(name).ok_or_else(|| {
                        error(format!(
                            "the {} skeleton has no joint '{name}', which Kinect joint '{}' maps to",
                            kind.name(),
                            joint.name()
                        ))
                    })?;
                    let parent = clip.joints().get(index).and_then(|j| j.parent);
                    (BvhPoint::Joint(index), parent.unwrap_or(index))
                }
                Target::EndSiteOf(name) => {
                    let index = clip
                        .joint_index(name)
                        .filter(|&i| clip.joints().get(i).is_some_and(|j| j.end_site.is_some()))
                        .ok_or_else(|| {
                            error(format!(
                                "the {} skeleton has no joint '{name}' with an End Site, which \
                                 Kinect joint '{}' maps to",
                                kind.name(),
                                joint.name()
                            ))
                        })?;
                    (BvhPoint::EndSite(index), index)
                }
            };
            if joint != KinectJoint::HipCenter
                && matches!(point, BvhPoint::Joint(i) if clip.joints().get(i).is_some_and(|j| j.parent.is_none()))
            {
                return Err(error(format!(
                    "Kinect joint '{}' maps to the root joint; expected a child joint",
                    joint.name()
                )));
            }
            points[joint.index()] = point;
            drivers[joint.index()] = driver;
        }

        let rest = clip.rest_pose();
        let at = |j: KinectJoint| rest.point(points[j.index()]).unwrap_or(Vec3::ZERO);
        let leg = |hip: KinectJoint, knee: KinectJoint, ankle: KinectJoint| {
            at(hip).distance(at(knee)) + at(knee).distance(at(ankle))
        };
        use KinectJoint::*;
        let leg_length_units =
            0.5 * (leg(HipLeft, KneeLeft, AnkleLeft) + leg(HipRight, KneeRight, AnkleRight));
        if !(leg_length_units.is_finite() && leg_length_units > 1e-6) {
            return Err(error(format!(
                "degenerate legs: the rest-pose hip-knee-ankle length is {leg_length_units}; \
                 expected a positive length to derive the metre scale from"
            )));
        }
        Ok(KinectMapping {
            kind,
            points,
            drivers,
            leg_length_units,
        })
    }

    pub fn kind(&self) -> BvhSkeletonKind {
        self.kind
    }

    /// The BVH point whose position is the Kinect joint's position.
    pub fn point(&self, joint: KinectJoint) -> BvhPoint {
        self.points[joint.index()]
    }

    /// The BVH joint whose rotation drives the Kinect bone ending at `joint`: the BVH parent of
    /// the mapped joint, or the joint owning a mapped end site. For `HipCenter`, the root.
    pub fn driver(&self, joint: KinectJoint) -> usize {
        self.drivers[joint.index()]
    }

    /// Rest-pose leg length (hip joint -> knee -> ankle, both legs averaged), file units.
    pub fn leg_length_units(&self) -> f32 {
        self.leg_length_units
    }

    /// Metres per file unit: [`REFERENCE_LEG_LENGTH_M`] / [`Self::leg_length_units`].
    pub fn metres_per_unit(&self) -> f32 {
        REFERENCE_LEG_LENGTH_M / self.leg_length_units
    }
}
