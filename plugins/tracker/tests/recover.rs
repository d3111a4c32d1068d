//! Limbs lost by the followed fit are found again: sudden moves (from one frame to the next)
//! that leave a limb where a fit started from the last frame cannot follow it. Each case is
//! run without recovery too, to show it loses the limb. (An arm raised out of the image's top
//! in one frame is not found again: what is left of it in view is too little.) The cases are
//! run with the arms' pull back onto the surface seen unbounded (`FitSettings::
//! arm_front_cap_m`), as it was when they were written: with the bound the followed fit
//! follows two of them by itself (the last test), and they would no longer test recovery.

mod common;

use common::{ARMS_OUT, Turns, body, render, scene};
use fitroom_depth::synthetic::Label;
use fitroom_sensor::KinectJoint;
use fitroom_tracker::{TrackBody, Tracker, TrackerSettings};
use glam::Vec3;

/// Mean error (m) of `joints` over the last 10 of 30 frames: 10 frames of `before`, then
/// `after` at once, with and without recovery; the arms' pull unbounded.
fn jump(before: Turns, after: Turns, joints: &[KinectJoint]) -> (f32, f32) {
    jump_bounded(before, after, joints, f32::INFINITY)
}

/// [`jump`] with the arms' pull bounded by `arm_front_cap_m`.
fn jump_bounded(
    before: Turns,
    after: Turns,
    joints: &[KinectJoint],
    arm_front_cap_m: f32,
) -> (f32, f32) {
    let person = body();
    let mut out = [0.0; 2];
    for (k, recover) in [false, true].into_iter().enumerate() {
        let mut settings = TrackerSettings {
            recover,
            ..TrackerSettings::default()
        };
        settings.fit.arm_front_cap_m = arm_front_cap_m;
        let track = TrackBody::new(&person.model, &person.model.positions).expect("body");
        let mut tracker = Tracker::new(track, settings);
        let (mut sum, mut n) = (0.0, 0);
        for f in 0..30 {
            let turns = if f < 10 { before } else { after };
            let (skin, truth) = person.posed(&person.locals(turns, 1.0), Vec3::new(0.0, -0.8, 2.5));
            let frame = render(
                &scene(vec![(skin, Label::Body)], &person.model.triangles),
                f as u64 + 7,
                f as f64 / 30.0,
            );
            let tracked = tracker.track(&frame).expect("tracked");
            if f == 29 && recover && std::env::var("PIC").is_ok() {
                let mut bytes = b"P6 640 480 255\n".to_vec();
                bytes.extend(fitroom_tracker::draw::picture(
                    &frame,
                    Some(&tracked),
                    &truth,
                ));
                std::fs::write("/tmp/case.ppm", bytes).expect("picture");
            }
            if f >= 20 {
                for j in joints {
                    sum += tracked.joints[j.index()]
                        .position
                        .distance(truth[j.index()]);
                    n += 1;
                }
            }
        }
        out[k] = sum / n as f32;
    }
    (out[0], out[1])
}

/// Runs [`jump`] and checks that without recovery the case loses its limbs (mean error over
/// `lost_above` metres) and that recovery finds them again (under `found_below`).
fn found_again(
    case: &str,
    (before, after): (Turns, Turns),
    joints: &[KinectJoint],
    lost_above: f32,
    found_below: f32,
) {
    let (without, with) = jump(before, after, joints);
    println!(
        "{case}: {:.0} mm without recovery, {:.0} mm with",
        without * 1000.0,
        with * 1000.0
    );
    assert!(
        without > lost_above,
        "{case}: the case should lose the limb: {without:.3} m"
    );
    assert!(with < found_below, "{case}: not found again: {with:.3} m");
}

/// The left arm swung across the body in front of the face (from out to the side).
const ARM_ACROSS: Turns = &[
    ("upperarm_l", Vec3::X, -80.0),
    ("upperarm_l", Vec3::Y, -60.0),
];

/// The left arm, out to the side, swung across the body in front of the face between two
/// frames: followed from the last frame, the fit folds the arm down over the chest and leaves
/// the real one unexplained.
#[test]
fn an_arm_swung_across_the_body_is_found_again() {
    use KinectJoint::*;
    let arm = [ElbowLeft, WristLeft, HandLeft];
    found_again("arm across", (ARMS_OUT, ARM_ACROSS), &arm, 0.1, 0.05);
}

/// A step across, the legs' order swapped between two frames: followed, the legs cross.
#[test]
fn legs_that_crossed_are_uncrossed() {
    use KinectJoint::*;
    let step: Turns = &[("thigh_r", Vec3::Z, 25.0), ("thigh_l", Vec3::X, -30.0)];
    let legs = [KneeLeft, AnkleLeft, KneeRight, AnkleRight];
    found_again("step across", (&[], step), &legs, 0.08, 0.03);
}

/// The left hand brought from the side to before the belly between two frames (the forearm
/// bent forward and swung across, as in a walk's arm swing or a hand on the stomach).
const BEFORE_BELLY: Turns = &[
    ("lowerarm_l", Vec3::X, -90.0),
    ("upperarm_l", Vec3::Y, -50.0),
    ("upperarm_l", Vec3::X, -15.0),
];

/// The hand before the belly: it shows no extremum there, and followed from the last frame
/// the fit folds the forearm up along the upper arm and gives the hand's points to the trunk;
/// recovery finds it.
#[test]
fn a_hand_brought_before_the_belly_is_found_again() {
    use KinectJoint::*;
    let arm = [ElbowLeft, WristLeft, HandLeft];
    found_again(
        "hand before the belly",
        (&[], BEFORE_BELLY),
        &arm,
        0.1,
        0.05,
    );
}

/// The arms hanging; then, between two frames, the left forearm raised across the chest, the
/// hand before the other shoulder (a walk's swing brings a forearm there in a few frames).
/// Followed, the fit leaves the arm hanging where the person's edge still lies under it and
/// the forearm's points, close to the chest, go to the trunk: neither few points on the arm
/// nor a folded arm nor points far from the body suspect it (without the forearm standing
/// out of the body as a cue, recovery leaves it 375 mm off). What shows it is the depth: the
/// forearm stands out of the chest around it.
const HANGING: Turns = &[
    ("upperarm_l", Vec3::Z, -35.0),
    ("upperarm_r", Vec3::Z, 35.0),
];
const ACROSS_THE_CHEST: Turns = &[
    ("upperarm_l", Vec3::Z, -35.0),
    ("upperarm_r", Vec3::Z, 35.0),
    ("upperarm_l", Vec3::X, -15.0),
    ("lowerarm_l", Vec3::X, -75.0),
    ("upperarm_l", Vec3::Y, -60.0),
];

#[test]
fn a_forearm_raised_across_the_chest_is_found_again() {
    use KinectJoint::*;
    let arm = [ElbowLeft, WristLeft, HandLeft];
    found_again(
        "forearm across the chest",
        (HANGING, ACROSS_THE_CHEST),
        &arm,
        0.1,
        0.05,
    );
}

/// With the arms' pull back onto the surface seen bounded (the default), the followed fit
/// alone, without recovery, follows the arm swung across the body and the hand brought before
/// the belly between two frames.
#[test]
fn the_bounded_arm_pull_follows_sudden_arm_moves_without_recovery() {
    use KinectJoint::*;
    let bound = TrackerSettings::default().fit.arm_front_cap_m;
    let arm = [ElbowLeft, WristLeft, HandLeft];
    for (case, before, after) in [
        ("arm across", ARMS_OUT, ARM_ACROSS),
        ("hand before the belly", &[][..], BEFORE_BELLY),
    ] {
        let (bounded, _) = jump_bounded(before, after, &arm, bound);
        let (unbounded, _) = jump(before, after, &arm);
        println!(
            "{case}, no recovery: {:.0} mm bounded, {:.0} mm unbounded",
            bounded * 1000.0,
            unbounded * 1000.0
        );
        assert!(bounded < 0.05, "{case}: {bounded:.3} m bounded");
        assert!(unbounded > 0.1, "{case}: {unbounded:.3} m unbounded");
    }
}
