//! Where the 20 Kinect v1 joints sit on the MakeHuman rig: one table for the synthetic
//! camera's ground truth and for the tracker's output, so the two can only agree.

use fitroom_body::{BodyModel, RigidTransform};
use fitroom_sensor::KinectJoint;
use glam::Vec3;

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
}
