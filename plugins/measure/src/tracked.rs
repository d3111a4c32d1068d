//! The tracker's view of the person as calibration input: the person's pixels and skeleton
//! of a tracked frame, where the body stands, and the fit's starting pose (the standing
//! calibration pose, its limbs aimed by the tracked skeleton).

use fitroom_body::{BodyModel, forward_kinematics};
use fitroom_depth::DepthFrame;
use fitroom_sensor::KinectJoint;
use fitroom_tracker::Tracked;
use fitroom_tracker::kinect::JOINT_BONES;
use glam::{Mat3, Quat, Vec3};

use crate::MeasureError;
use crate::fit::ViewPose;
use crate::posed::Placement;
use crate::view::{AveragedView, CalibrationFrame};

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
        floor: Some(tracked.person.floor),
    }
}

/// Where `tracked` saw the body stand: upright on the floor, facing where the tracker's body
/// faces, its pelvis at the tracked hip centre (the Kinect hip centre is the pelvis bone's
/// head).
///
/// Upright, not the tracker's own root turn: its capsule body splits a lean between the
/// pelvis and the spine, and on people standing straight its pelvis leaned 5-20° forward
/// or back; the fit started from such a tilted trunk ended in another minimum (trading the
/// lean against the shape: through the tracker, size right 82.0 % against 86.5 % from the
/// filmed placement). The calibration asks the person to stand straight.
pub fn tracked_placement(tracked: &Tracked) -> Placement {
    Placement {
        rotation: upright(tracked.pose.rotation, tracked.person.floor.normal),
        pelvis: tracked.joints[KinectJoint::HipCenter.index()].position,
    }
}

/// `rotation` (model to sensor space) stood upright: the model's up (+Y) along `up`, its
/// forward (+Z) the old forward's shadow on the floor (the heading kept; the least turn,
/// `Quat::from_rotation_arc`, would swing the heading by part of a sideways lean). Returns
/// `rotation` when either is degenerate (facing straight up or down, no floor).
fn upright(rotation: Quat, up: Vec3) -> Quat {
    let up = up.normalize_or_zero();
    let forward = rotation * Vec3::Z;
    let flat = (forward - up * forward.dot(up)).normalize_or_zero();
    if up == Vec3::ZERO || flat == Vec3::ZERO {
        return rotation;
    }
    Quat::from_mat3(&Mat3::from_cols(up.cross(flat), up, flat)).normalize()
}

/// The limbs aimed by the skeleton: (bone, the joint at its head, the joint at its end).
const AIMED: [(&str, KinectJoint, KinectJoint); 8] = [
    (
        "upperarm_l",
        KinectJoint::ShoulderLeft,
        KinectJoint::ElbowLeft,
    ),
    ("lowerarm_l", KinectJoint::ElbowLeft, KinectJoint::WristLeft),
    (
        "upperarm_r",
        KinectJoint::ShoulderRight,
        KinectJoint::ElbowRight,
    ),
    (
        "lowerarm_r",
        KinectJoint::ElbowRight,
        KinectJoint::WristRight,
    ),
    ("thigh_l", KinectJoint::HipLeft, KinectJoint::KneeLeft),
    ("calf_l", KinectJoint::KneeLeft, KinectJoint::AnkleLeft),
    ("thigh_r", KinectJoint::HipRight, KinectJoint::KneeRight),
    ("calf_r", KinectJoint::KneeRight, KinectJoint::AnkleRight),
];

/// The calibration stance as the fit's starting pose: the body model's rest pose (standing
/// straight, as the person is asked to), each arm and leg bone turned the least way that
/// aims it along the skeleton `joints` (sensor space) of a body standing at `placement`.
///
/// Why not the tracker's own pose: its capsule body splits a turn between neighbouring
/// bones (clavicle and upper arm, spine and pelvis) and cannot see the feet's turn, so on a
/// still person its bones are 10-30° from the filmed ones even where its joints are close;
/// the skin the fit starts from is then wrong in ways the fit's few steps do not undo.
pub fn standing_pose(
    model: &BodyModel,
    joints: &[Vec3; KinectJoint::COUNT],
    placement: &Placement,
) -> Vec<Quat> {
    let rest = model.rest_pose(&model.positions);
    let mut locals = vec![Quat::IDENTITY; model.bones.len()];
    let to_model = placement.rotation.inverse();
    for (bone, from, to) in AIMED {
        let Some(b) = model.bone_index(bone) else {
            continue;
        };
        let Some(end) = JOINT_BONES
            .iter()
            .find(|(j, _)| *j == to)
            .and_then(|(_, name)| model.bone_index(name))
        else {
            continue;
        };
        let want = (to_model * (joints[to.index()] - joints[from.index()])).normalize_or_zero();
        let globals = forward_kinematics(&model.bones, &rest, &locals, Vec3::ZERO);
        let now = (globals[end].translation - globals[b].translation).normalize_or_zero();
        if want == Vec3::ZERO || now == Vec3::ZERO || !want.is_finite() {
            continue;
        }
        let g = globals[b].rotation;
        let q = Quat::from_rotation_arc(now, want);
        locals[b] = (locals[b] * (g.inverse() * q * g)).normalize();
    }
    locals
}

/// One view of a tracked calibration, ready for the fit.
pub struct TrackedView {
    pub view: AveragedView,
    pub locals: Vec<Quat>,
    pub placement: Placement,
}

impl TrackedView {
    pub fn as_view_pose(&self) -> ViewPose<'_> {
        ViewPose {
            view: &self.view,
            locals: &self.locals,
            placement: self.placement,
        }
    }
}

/// The fit's views of a tracked calibration, from each view's frames and where the tracker
/// saw the body stand in its last frame: the frames averaged, and the [`standing_pose`]
/// aimed by the front (first) view's averaged skeleton in every view (the person keeps
/// their arms as they turn; turned, their far arm is hidden and its joints are guesses).
pub fn tracked_views(
    model: &BodyModel,
    seen: &[(Vec<CalibrationFrame>, Placement)],
) -> Result<Vec<TrackedView>, MeasureError> {
    let mut out: Vec<TrackedView> = Vec::with_capacity(seen.len());
    for (frames, placement) in seen {
        let view = AveragedView::new(frames)?;
        let locals = match out.first() {
            Some(front) => front.locals.clone(),
            None => standing_pose(model, &view.joints, placement),
        };
        out.push(TrackedView {
            view,
            locals,
            placement: *placement,
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A body leaning 15° back and 5° aside, turned 30°, on a floor tilted by the sensor's
    /// pitch: stood upright on that floor, facing the same way across it.
    #[test]
    fn upright_stands_the_body_on_the_floor_and_keeps_its_heading() {
        let pitch = Quat::from_rotation_x(8f32.to_radians());
        let up = pitch * Vec3::Y;
        let heading = Quat::from_rotation_y(30f32.to_radians());
        let lean = Quat::from_rotation_x(-15f32.to_radians()) * Quat::from_rotation_z(0.09);
        let leaning = pitch * heading * lean;
        let stood = upright(leaning, up);
        assert!((stood * Vec3::Y).angle_between(up) < 1e-4);
        // Its forward lies on the floor, and it is the leaning forward's shadow there.
        let forward = stood * Vec3::Z;
        assert!(forward.dot(up).abs() < 1e-4);
        let shadow = leaning * Vec3::Z - up * (leaning * Vec3::Z).dot(up);
        assert!(forward.angle_between(shadow) < 1e-4);
        // Without a lean, nothing changes.
        let straight = pitch * heading;
        assert!(upright(straight, up).angle_between(straight) < 1e-4);
        // No floor normal: the rotation as it was.
        assert_eq!(upright(leaning, Vec3::ZERO), leaning);
    }
}
