//! The body cannot pass through itself: a forearm folded into a heavy man's belly, where the
//! depth shows no gap between the arm hanging at his side and his trunk, is pushed back out
//! by the fit's contact term (`FitSettings::contact_weight`). (CMU 08_04's heavy man in the
//! T-shirt was tracked so for a whole recording: the left hand 43 cm off.)

mod common;

use common::{render, scene, shaped_body};
use fitroom_depth::synthetic::Label;
use fitroom_sensor::KinectJoint;
use fitroom_tracker::{TrackBody, Tracker, TrackerSettings};
use glam::{Quat, Vec3};

/// The heavy man with his arms hanging against his sides, `z` metres away: tracked for 10
/// frames, then his left forearm turned `inward_deg` towards his belly in the image's plane
/// (into the trunk: the elbow is at his side) and the fit run again on the last frame from
/// there (four frames' worth of steps) with the contact term weighing `contact_weight`, each
/// point's depth averaged over `denoise_px` pixels about it. The left wrist's and hand's mean
/// error, metres.
fn folded_in(contact_weight: f32, denoise_px: usize, inward_deg: f32, z: f32, seed: u64) -> f32 {
    use KinectJoint::*;
    let shape = fitroom_body::Shape {
        gender: 1.0,
        weight: 1.0,
        muscle: 0.3,
        ..Default::default()
    };
    let person = shaped_body(&shape);
    let hanging = [
        ("upperarm_l", Vec3::Z, -40.0),
        ("upperarm_r", Vec3::Z, 40.0),
    ];
    let mut settings = TrackerSettings::default();
    settings.fit.contact_weight = contact_weight;
    settings.denoise_px = denoise_px;
    let track = TrackBody::new(&person.model, &person.positions).expect("body");
    let mut tracker = Tracker::new(track, settings);
    let (skin, truth) = person.posed(&person.locals(&hanging, 1.0), Vec3::new(0.0, -0.8, z));
    let the_scene = scene(vec![(skin, Label::Body)], &person.model.triangles);
    let mut last = None;
    for f in 0..10 {
        let frame = render(&the_scene, seed + f, f as f64 / 30.0);
        let tracked = tracker.track(&frame).expect("tracked");
        last = Some((frame, tracked.pose));
    }
    let (frame, mut pose) = last.expect("ten frames");
    // The forearm turned about the sensor's axis, its hand towards the body's middle (+X for
    // the left arm of a person facing the sensor).
    let forearm = person.bone("lowerarm_l");
    let parent = tracker.body.parents[forearm].expect("the forearm has a parent");
    let above = tracker.body.pose(&pose).rotations[parent];
    let turn = Quat::from_rotation_z(inward_deg.to_radians());
    pose.local[forearm] = (above.inverse() * turn * above * pose.local[forearm]).normalize();
    for _ in 0..4 {
        tracker.refit(&frame, &mut pose, 30).expect("a person");
    }
    let found = tracker.body.kinect_joints(&tracker.body.pose(&pose));
    let arm = [WristLeft, HandLeft];
    arm.iter()
        .map(|j| found[j.index()].distance(truth[j.index()]))
        .sum::<f32>()
        / arm.len() as f32
}

#[test]
fn a_forearm_folded_into_the_belly_is_pushed_back_out() {
    let defaults = TrackerSettings::default();
    let weight = defaults.fit.contact_weight;
    for (inward, z, seed) in [(50.0, 2.5, 3u64), (60.0, 2.7, 23), (70.0, 3.0, 11)] {
        // The case is the depth not telling the arm from the belly: the points as read.
        // (Averaged over their surface, `crate::denoise`, the edge between them shows better
        // and the fit alone pulls the forearm out of the first case.)
        let with = folded_in(weight, 0, inward, z, seed);
        let without = folded_in(0.0, 0, inward, z, seed);
        let tracked = folded_in(weight, defaults.denoise_px, inward, z, seed);
        println!(
            "forearm turned {inward}° into the belly at {z} m: wrist and hand {:.0} mm with the contact term, {:.0} mm without; {:.0} mm as the tracker runs",
            with * 1000.0,
            without * 1000.0,
            tracked * 1000.0
        );
        assert!(
            without > 0.1,
            "the case should stay folded without the term: {without:.3} m"
        );
        assert!(with < 0.05, "not pushed out: {with:.3} m");
        assert!(
            tracked < 0.05,
            "not pushed out as the tracker runs: {tracked:.3} m"
        );
    }
}
