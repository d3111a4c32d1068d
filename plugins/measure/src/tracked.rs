//! The tracker's view of the person as calibration input: the person's pixels and skeleton
//! of a tracked frame, and the tracked pose as the fit's pose (the tracker's body and the
//! measured body share MakeHuman's rig, so the bones' turns carry over whatever the shape).

use fitroom_depth::DepthFrame;
use fitroom_sensor::KinectJoint;
use fitroom_tracker::Tracked;
use glam::{Quat, Vec3};

use crate::posed::Placement;
use crate::view::CalibrationFrame;

/// A calibration frame of `frame` as `tracked` saw it.
pub fn calibration_frame(frame: &DepthFrame, tracked: &Tracked) -> CalibrationFrame {
    let mut joints = [Vec3::ZERO; KinectJoint::COUNT];
    for (j, t) in joints.iter_mut().zip(&tracked.joints) {
        *j = t.position;
    }
    CalibrationFrame {
        depth: frame.clone(),
        mask: tracked.person.mask.clone().into(),
        joints,
    }
}

/// The pose `tracked` found, as the fit takes it: each bone's turn from rest, and where the
/// body stands (its rotation, and its pelvis: the Kinect hip centre is the pelvis bone's
/// head).
pub fn tracked_pose(tracked: &Tracked) -> (Vec<Quat>, Placement) {
    let placement = Placement {
        rotation: tracked.pose.rotation,
        pelvis: tracked.joints[KinectJoint::HipCenter.index()].position,
    };
    (tracked.pose.local.clone(), placement)
}
