//! Starting from nothing: the tracker's first frame of a person, rendered from the body
//! crate's own kinematics and skinning in poses it was not tuned on.

mod common;

use common::{Turns, body, render, scene};
use fitroom_depth::synthetic::Label;
use fitroom_sensor::KinectJoint;
use fitroom_tracker::{TrackBody, Tracker, TrackerSettings};
use glam::Vec3;

/// Arms hanging close to the body, the hands against the thighs' sides.
const ARMS_CLOSE: Turns = &[
    ("upperarm_l", Vec3::Z, -50.0),
    ("upperarm_r", Vec3::Z, 50.0),
];

/// Arms hanging, the hands before the thighs.
const HANDS_BEFORE_THIGHS: Turns = &[
    ("upperarm_l", Vec3::Z, -45.0),
    ("upperarm_r", Vec3::Z, 45.0),
    ("upperarm_l", Vec3::Y, -20.0),
    ("upperarm_r", Vec3::Y, 20.0),
    ("lowerarm_l", Vec3::X, -20.0),
    ("lowerarm_r", Vec3::X, -20.0),
];

/// The mean error (m) of the elbows, wrists and hands and of the trunk in the first frame
/// the person is seen, posed by `turns`, `z` metres away.
fn first_frame(turns: Turns, start_arms_hanging: bool, z: f32, seed: u64) -> (f32, f32) {
    use KinectJoint::*;
    let person = body();
    let settings = TrackerSettings {
        start_arms_hanging,
        ..TrackerSettings::default()
    };
    let track = TrackBody::new(&person.model, &person.model.positions).expect("body");
    let mut tracker = Tracker::new(track, settings);
    let (skin, truth) = person.posed(&person.locals(turns, 1.0), Vec3::new(0.05, -0.8, z));
    let frame = render(
        &scene(vec![(skin, Label::Body)], &person.model.triangles),
        seed,
        0.0,
    );
    let tracked = tracker.track(&frame).expect("tracked");
    let mean = |joints: &[KinectJoint]| {
        joints
            .iter()
            .map(|j| {
                tracked.joints[j.index()]
                    .position
                    .distance(truth[j.index()])
            })
            .sum::<f32>()
            / joints.len() as f32
    };
    (
        mean(&[
            ElbowLeft, WristLeft, HandLeft, ElbowRight, WristRight, HandRight,
        ]),
        mean(&fitroom_tracker::eval::TRUNK),
    )
}

/// A hand resting against the thigh is no geodesic end of the body: the end taken for it
/// (an elbow, a hip) pulled the arm into the trunk and the trunk askew with it (CMU 07_06's
/// small woman: both arms 20-50 cm off for the first 20 frames, and one arm never found
/// again). The start also tries the arms hanging, not pulled to the hands' ends; and the
/// extrema no longer name such an end a hand (`extrema.rs`, `could_be_hand`), so a
/// start pulled to the ends alone (which put these arms 25 cm or more off) finds them too.
#[test]
fn a_person_first_seen_with_the_hands_by_the_thighs_is_started_with_them_there() {
    for (name, turns) in [
        ("arms close", ARMS_CLOSE),
        ("hands before the thighs", HANDS_BEFORE_THIGHS),
    ] {
        for (z, seed) in [(2.5, 5u64), (3.0, 9), (3.0, 21)] {
            let (arms, trunk) = first_frame(turns, true, z, seed);
            let (pulled, _) = first_frame(turns, false, z, seed);
            println!(
                "{name} at {z} m: arms {:.0} mm (trunk {:.0} mm); pulled to the ends only: {:.0} mm",
                arms * 1000.0,
                trunk * 1000.0,
                pulled * 1000.0
            );
            assert!(arms < 0.1, "{name} at {z} m: arms {arms:.3} m");
            assert!(pulled < 0.1, "{name} at {z} m: pulled {pulled:.3} m");
        }
    }
}
