//! Where the 20 Kinect v1 joints sit on the MakeHuman rig: one table for the synthetic
//! camera's ground truth and for the tracker's output, so the two can only agree.

use fitroom_body::{BodyModel, RigidTransform};
use fitroom_sensor::KinectJoint;
use glam::Vec3;

/// The way a skeleton (20 joints in [`KinectJoint::ALL`] order) faces about the vertical,
/// degrees: 0 towards the sensor, ±180 with its back to it. From the hips' and shoulders'
/// left-right line (a person facing the sensor has their left at -X).
pub fn facing_degrees(joints: &[Vec3]) -> f32 {
    let at = |j: KinectJoint| joints.get(j.index()).copied().unwrap_or(Vec3::ZERO);
    let across = (at(KinectJoint::HipLeft) - at(KinectJoint::HipRight))
        + (at(KinectJoint::ShoulderLeft) - at(KinectJoint::ShoulderRight));
    across.z.atan2(-across.x).to_degrees()
}

/// The avatar bone whose head is at each Kinect joint (MakeHuman's `game_engine` rig; `_l`
/// is the person's left, as the Kinect's `Left`), in [`KinectJoint::ALL`] order.
pub const JOINT_BONES: [(KinectJoint, &str); 20] = [
    (KinectJoint::HipCenter, "pelvis"),
    (KinectJoint::Spine, "spine_02"),
    (KinectJoint::ShoulderCenter, "neck_01"),
    (KinectJoint::Head, "head"),
    (KinectJoint::ShoulderLeft, "upperarm_l"),
    (KinectJoint::ElbowLeft, "lowerarm_l"),
    (KinectJoint::WristLeft, "hand_l"),
    (KinectJoint::HandLeft, "middle_01_l"),
    (KinectJoint::ShoulderRight, "upperarm_r"),
    (KinectJoint::ElbowRight, "lowerarm_r"),
    (KinectJoint::WristRight, "hand_r"),
    (KinectJoint::HandRight, "middle_01_r"),
    (KinectJoint::HipLeft, "thigh_l"),
    (KinectJoint::KneeLeft, "calf_l"),
    (KinectJoint::AnkleLeft, "foot_l"),
    (KinectJoint::FootLeft, "ball_l"),
    (KinectJoint::HipRight, "thigh_r"),
    (KinectJoint::KneeRight, "calf_r"),
    (KinectJoint::AnkleRight, "foot_r"),
    (KinectJoint::FootRight, "ball_r"),
];

/// How far above the head bone's head (the skull's base) the Kinect's head joint (the
/// head's centre) sits, along the neck's direction, metres.
const HEAD_ABOVE_SKULL_BASE_M: f32 = 0.09;

/// The Kinect's head joint from the skull's base (the head bone's head) and the neck's base
/// (`neck_01`'s head): [`HEAD_ABOVE_SKULL_BASE_M`] above the skull's base along the neck.
pub fn head_joint(skull_base: Vec3, neck_base: Vec3) -> Vec3 {
    skull_base + (skull_base - neck_base).normalize_or_zero() * HEAD_ABOVE_SKULL_BASE_M
}

/// The 20 Kinect joints of a posed rig (`globals`: its bones' transforms, as
/// `forward_kinematics` gives them) in the rig's space: each at its bone's head
/// ([`JOINT_BONES`]), the head at the head's centre ([`head_joint`]). A bone the rig lacks
/// puts its joint at the pelvis.
pub fn rig_joints(model: &BodyModel, globals: &[RigidTransform]) -> [Vec3; KinectJoint::COUNT] {
    let at = |name: &str| {
        model
            .bone_index(name)
            .and_then(|b| globals.get(b))
            .map(|g| g.translation)
    };
    let pelvis = at("pelvis").unwrap_or(Vec3::ZERO);
    let head = |name: &str| at(name).unwrap_or(pelvis);
    let mut joints = [Vec3::ZERO; KinectJoint::COUNT];
    for (joint, bone) in JOINT_BONES {
        joints[joint.index()] = if joint == KinectJoint::Head {
            head_joint(head(bone), head("neck_01"))
        } else {
            head(bone)
        };
    }
    joints
}

/// The rig bone whose rotation turns the Kinect bone that ends at each joint (the bone from
/// the joint's parent to it), in [`KinectJoint::ALL`] order; for `HipCenter`, the pelvis.
pub const DRIVER_BONES: [&str; 20] = [
    "pelvis",
    "spine_01",
    "spine_03",
    "neck_01",
    "clavicle_l",
    "upperarm_l",
    "lowerarm_l",
    "hand_l",
    "clavicle_r",
    "upperarm_r",
    "lowerarm_r",
    "hand_r",
    "pelvis",
    "thigh_l",
    "calf_l",
    "foot_l",
    "pelvis",
    "thigh_r",
    "calf_r",
    "foot_r",
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_tables_are_in_kinect_order() {
        for (i, (joint, _)) in JOINT_BONES.iter().enumerate() {
            assert_eq!(joint.index(), i);
            assert_eq!(KinectJoint::ALL[i], *joint);
            // The ground truth files name the joints in the same order.
            assert_eq!(joint.name(), fitroom_depth::truth::JOINT_NAMES[i]);
        }
        assert_eq!(DRIVER_BONES.len(), KinectJoint::COUNT);
    }

    /// A person facing the sensor has their left at -X; turned about the vertical by an
    /// angle, the facing is that angle's size.
    #[test]
    fn facing_is_the_turn_about_the_vertical() {
        let mut joints = [Vec3::ZERO; KinectJoint::COUNT];
        for (joint, x, y) in [
            (KinectJoint::ShoulderLeft, -0.2, 0.5),
            (KinectJoint::ShoulderRight, 0.2, 0.5),
            (KinectJoint::HipLeft, -0.1, 0.0),
            (KinectJoint::HipRight, 0.1, 0.0),
        ] {
            joints[joint.index()] = Vec3::new(x, y, 0.0);
        }
        for degrees in [0.0f32, 30.0, 90.0, 150.0, 180.0] {
            let turn = glam::Quat::from_rotation_y(degrees.to_radians());
            let turned: Vec<Vec3> = joints.iter().map(|&p| turn * p).collect();
            let found = facing_degrees(&turned).abs();
            assert!((found - degrees).abs() < 1e-3, "{degrees}: {found}");
        }
    }
}
