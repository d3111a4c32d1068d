//! Where the 20 Kinect v1 joints sit on the MakeHuman rig: one table for the synthetic
//! camera's ground truth and for the tracker's output, so the two can only agree.

use fitroom_sensor::KinectJoint;

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
pub const HEAD_ABOVE_SKULL_BASE_M: f32 = 0.09;

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
