//! Kinect v1-style skeleton frames: the one currency between every sensor source and the
//! motion pipeline.
//!
//! Sensor space follows the Kinect v1 skeleton space: right-handed, metres, origin at the
//! sensor, +Y up, +Z along the optical axis towards the person, +X to the sensor's left.

use glam::{Quat, Vec3};
use serde::{Deserialize, Serialize};

/// The 20 joints of the Kinect v1 skeleton, in the SDK's `NUI_SKELETON_POSITION_INDEX` order.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[repr(u8)]
pub enum KinectJoint {
    HipCenter = 0,
    Spine,
    ShoulderCenter,
    Head,
    ShoulderLeft,
    ElbowLeft,
    WristLeft,
    HandLeft,
    ShoulderRight,
    ElbowRight,
    WristRight,
    HandRight,
    HipLeft,
    KneeLeft,
    AnkleLeft,
    FootLeft,
    HipRight,
    KneeRight,
    AnkleRight,
    FootRight,
}

impl KinectJoint {
    pub const COUNT: usize = 20;

    /// The same joint on the body's other side (itself on the midline).
    pub fn mirror(self) -> KinectJoint {
        let i = self.index();
        let m = match i {
            4..=7 | 12..=15 => i + 4,
            8..=11 | 16..=19 => i - 4,
            _ => i,
        };
        Self::ALL[m]
    }

    /// All joints in index order.
    pub const ALL: [KinectJoint; 20] = [
        KinectJoint::HipCenter,
        KinectJoint::Spine,
        KinectJoint::ShoulderCenter,
        KinectJoint::Head,
        KinectJoint::ShoulderLeft,
        KinectJoint::ElbowLeft,
        KinectJoint::WristLeft,
        KinectJoint::HandLeft,
        KinectJoint::ShoulderRight,
        KinectJoint::ElbowRight,
        KinectJoint::WristRight,
        KinectJoint::HandRight,
        KinectJoint::HipLeft,
        KinectJoint::KneeLeft,
        KinectJoint::AnkleLeft,
        KinectJoint::FootLeft,
        KinectJoint::HipRight,
        KinectJoint::KneeRight,
        KinectJoint::AnkleRight,
        KinectJoint::FootRight,
    ];

    pub fn index(self) -> usize {
        self as usize
    }

    /// The joint at the start of the bone that ends at `self` (`None` for the root).
    pub fn parent(self) -> Option<KinectJoint> {
        use KinectJoint::*;
        Some(match self {
            HipCenter => return None,
            Spine => HipCenter,
            ShoulderCenter => Spine,
            Head => ShoulderCenter,
            ShoulderLeft | ShoulderRight => ShoulderCenter,
            ElbowLeft => ShoulderLeft,
            WristLeft => ElbowLeft,
            HandLeft => WristLeft,
            ElbowRight => ShoulderRight,
            WristRight => ElbowRight,
            HandRight => WristRight,
            HipLeft | HipRight => HipCenter,
            KneeLeft => HipLeft,
            AnkleLeft => KneeLeft,
            FootLeft => AnkleLeft,
            KneeRight => HipRight,
            AnkleRight => KneeRight,
            FootRight => AnkleRight,
        })
    }

    /// Snake-case name used in reports and JSON (`"elbow_left"`).
    pub fn name(self) -> &'static str {
        use KinectJoint::*;
        match self {
            HipCenter => "hip_center",
            Spine => "spine",
            ShoulderCenter => "shoulder_center",
            Head => "head",
            ShoulderLeft => "shoulder_left",
            ElbowLeft => "elbow_left",
            WristLeft => "wrist_left",
            HandLeft => "hand_left",
            ShoulderRight => "shoulder_right",
            ElbowRight => "elbow_right",
            WristRight => "wrist_right",
            HandRight => "hand_right",
            HipLeft => "hip_left",
            KneeLeft => "knee_left",
            AnkleLeft => "ankle_left",
            FootLeft => "foot_left",
            HipRight => "hip_right",
            KneeRight => "knee_right",
            AnkleRight => "ankle_right",
            FootRight => "foot_right",
        }
    }
}

/// One tracked joint.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct JointSample {
    /// Position in sensor space, metres.
    pub position: Vec3,
    /// Absolute orientation (sensor space) of the bone that *ends* at this joint, as the Kinect
    /// SDK reports it: the bone's +Y axis points from the parent joint to this joint. Its
    /// reference (twist zero) is [`bone_reference_frame`] of the bone direction when the person
    /// stands in the source's rest T-pose facing the sensor. For `HipCenter` it is the pelvis
    /// orientation, identity when the person faces the sensor (looks along -Z).
    pub orientation: Quat,
    /// 1.0 tracked, 0.5 inferred, 0.0 not tracked (the SDK's three states as a number).
    pub confidence: f32,
}

impl Default for JointSample {
    fn default() -> Self {
        Self {
            position: Vec3::ZERO,
            orientation: Quat::IDENTITY,
            confidence: 0.0,
        }
    }
}

/// One skeleton frame from a sensor source.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SensorFrame {
    /// Seconds since the source started; strictly increasing within one loop of a source.
    pub timestamp_s: f64,
    /// Counts frames emitted by the source, starting at 0.
    pub sequence: u64,
    /// Indexed by [`KinectJoint::index`].
    pub joints: [JointSample; KinectJoint::COUNT],
}

impl SensorFrame {
    /// A frame in which nobody is tracked (every joint's confidence 0): what a depth tracker
    /// sends when it finds no one, so that what follows sees the gap.
    pub fn nobody(timestamp_s: f64, sequence: u64) -> SensorFrame {
        SensorFrame {
            timestamp_s,
            sequence,
            joints: Default::default(),
        }
    }

    pub fn joint(&self, joint: KinectJoint) -> &JointSample {
        &self.joints[joint.index()]
    }

    /// The frame's mirror image: sensor x negated, the body's left and right joints swapped,
    /// each orientation reflected (S R S with S = diag(-1, 1, 1): the bone's +Y reflected, X
    /// negated to stay a rotation).
    pub fn mirrored(&self) -> SensorFrame {
        let mut out = self.clone();
        for joint in KinectJoint::ALL {
            let mut s = *self.joint(joint.mirror());
            s.position.x = -s.position.x;
            let q = s.orientation;
            s.orientation = glam::Quat::from_xyzw(q.x, -q.y, -q.z, q.w);
            out.joints[joint.index()] = s;
        }
        out
    }
}

/// The twist-zero frame of a bone pointing along `direction` (sensor space) for a person facing
/// the sensor: +Y along the bone, +Z as close as possible to the person's front (towards the
/// sensor, -Z in sensor space), or to up (+Y) when the bone itself points mostly forward or
/// backward (feet). Unlike a shortest arc from +Y, this stays well defined for bones that point
/// down (legs), so a source and an avatar in slightly different rest poses agree on twist.
pub fn bone_reference_frame(direction: Vec3) -> Quat {
    let y = direction.normalize_or(Vec3::Y);
    let front = Vec3::NEG_Z;
    let hint = if y.dot(front).abs() > 0.7 {
        Vec3::Y
    } else {
        front
    };
    let z = (hint - y * hint.dot(y)).normalize_or(Vec3::Z);
    let x = y.cross(z);
    Quat::from_mat3(&glam::Mat3::from_cols(x, y, z)).normalize()
}

#[cfg(test)]
mod mirror_tests {
    use super::{JointSample, KinectJoint, SensorFrame};
    use glam::{Quat, Vec3};

    /// The mirrored frame is the reflection: a joint's image is where the other side's joint
    /// is reflected, and its orientation turns the reflected vectors as the original turns
    /// the vectors (q' S v = S q v); mirroring twice gives the frame back.
    #[test]
    fn a_mirrored_frame_is_the_reflection() {
        let mut f = SensorFrame {
            timestamp_s: 0.0,
            sequence: 0,
            joints: [JointSample {
                position: Vec3::new(0.0, 0.0, 2.0),
                orientation: Quat::IDENTITY,
                confidence: 1.0,
            }; KinectJoint::COUNT],
        };
        let left = KinectJoint::HandLeft.index();
        f.joints[left].position = Vec3::new(-0.3, 0.2, 2.1);
        f.joints[left].orientation = Quat::from_rotation_z(0.4) * Quat::from_rotation_x(0.2);
        f.joints[left].confidence = 0.5;
        let m = f.mirrored();
        let image = m.joint(KinectJoint::HandRight);
        assert_eq!(image.position, Vec3::new(0.3, 0.2, 2.1));
        assert_eq!(image.confidence, 0.5);
        let s = |v: Vec3| Vec3::new(-v.x, v.y, v.z);
        for v in [Vec3::X, Vec3::Y, Vec3::new(0.1, 0.5, -0.2)] {
            let want = s(f.joints[left].orientation * v);
            assert!((image.orientation * s(v) - want).length() < 1e-5);
        }
        let back = m.mirrored();
        for (a, b) in back.joints.iter().zip(&f.joints) {
            assert!(a.position.distance(b.position) < 1e-6);
            assert!(a.orientation.angle_between(b.orientation) < 1e-4);
        }
    }

    #[test]
    fn mirroring_swaps_sides_by_name_and_is_its_own_inverse() {
        for j in KinectJoint::ALL {
            let m = j.mirror();
            assert_eq!(m.mirror(), j);
            let (a, b) = (j.name(), m.name());
            if a.ends_with("_left") {
                assert_eq!(b, a.replace("_left", "_right"));
            } else if a.ends_with("_right") {
                assert_eq!(b, a.replace("_right", "_left"));
            } else {
                assert_eq!(m, j);
            }
        }
    }
}
