//! Geodesic extrema on synthetic Kinect frames of the MakeHuman body in its rest pose, seen
//! from 2 to 3.2 m, against the rig's own joints: the head's end by the head's centre, each
//! hand's end beyond its wrist, each foot's end by its ball, each on the right side; and the
//! joints estimated from the surface around the ends within 12 cm of the rig's.

use std::path::Path;

mod common;

use fitroom_body::BodyModel;
use fitroom_depth::synthetic::{Label, NoiseSettings, Scene, SceneMesh, SyntheticCamera};
use fitroom_depth::{DepthCamera, DepthFrame};
use fitroom_sensor::KinectJoint;
use fitroom_tracker::{Extremum, Part, SegmentSettings, Segmenter, geodesic_extrema};
use glam::Vec3;

/// The extrema of the person segmented in `frame`.
fn ends_of(frame: &DepthFrame) -> Vec<Extremum> {
    let person = Segmenter::new(SegmentSettings::default())
        .segment(frame)
        .expect("a person");
    geodesic_extrema(frame, &person)
}

/// The end named `part` (the scene `z` m away, for the message).
fn named(ends: &[Extremum], part: Part, z: f32) -> Extremum {
    *ends
        .iter()
        .find(|e| e.part == part)
        .unwrap_or_else(|| panic!("{z} m: no {part:?} among {ends:?}"))
}

#[test]
fn head_hands_and_feet_are_the_ends_of_the_surface() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/bodies/makehuman.fitbody");
    let model = BodyModel::read(&path).expect("the shipped body");
    let n = model.body_vertex_count as usize;
    let rest = model.rest_pose(&model.positions);
    let standing = model.standing_in_sensor_space(&model.positions);
    for (seed, z) in [(1u64, 2.0f32), (2, 2.6), (3, 3.2)] {
        let place = |p: Vec3| standing.transform_point3(p) + Vec3::new(0.05, -0.8, z);
        let bone = |name: &str| {
            let i = model
                .bones
                .iter()
                .position(|b| b.name == name)
                .unwrap_or_else(|| panic!("the rig has {name}"));
            place(rest.heads[i])
        };
        let mut scene = Scene::room(-0.8, 3.9);
        scene.meshes.push(SceneMesh {
            positions: model.positions[..n].iter().map(|&p| place(p)).collect(),
            triangles: model.triangles.clone(),
            label: Label::Body,
            closed: true,
        });
        let frame = SyntheticCamera::new(DepthCamera::default(), NoiseSettings::default(), seed)
            .render(&scene, 0.0)
            .frame;
        let ends = ends_of(&frame);
        let find = |part: Part| named(&ends, part, z).position;
        // The end of each part against the rig. The head's end lies on the visible cap of
        // the head (its top is too oblique to the sensor to be read): within 15 cm of the
        // head's centre, 9 cm above the head bone (which starts at the skull's base). A
        // fingertip is 5-25 cm from the wrist; a toe tip within 12 cm of the ball of the foot.
        let head = find(Part::Head);
        let centre = bone("head") + Vec3::Y * 0.09;
        assert!(
            head.distance(centre) < 0.15,
            "{z} m: head end {head} vs {centre}"
        );
        for (part, wrist) in [(Part::HandLeft, "hand_l"), (Part::HandRight, "hand_r")] {
            let d = find(part).distance(bone(wrist));
            assert!(
                (0.05..0.25).contains(&d),
                "{z} m: {part:?} {d:.3} m from {wrist}"
            );
        }
        for (part, ball) in [(Part::FootLeft, "ball_l"), (Part::FootRight, "ball_r")] {
            let d = find(part).distance(bone(ball));
            assert!(d < 0.12, "{z} m: {part:?} {d:.3} m from {ball}");
        }
        // The joints estimated from the surface around each end, against the joints the
        // ground truth uses (the head's centre, the hand's middle knuckle, the ball of the
        // foot): within 12 cm (measured 4-11 cm; the recordings of a moving body do better,
        // see `fitroom track extrema`).
        for (part, joint) in [
            (Part::Head, centre),
            (Part::HandLeft, bone("middle_01_l")),
            (Part::HandRight, bone("middle_01_r")),
            (Part::FootLeft, bone("ball_l")),
            (Part::FootRight, bone("ball_r")),
        ] {
            let estimated = ends
                .iter()
                .find(|e| e.part == part)
                .map(|e| e.joint)
                .unwrap_or_else(|| panic!("{z} m: no {part:?}"));
            let d = estimated.distance(joint);
            println!("{z} m: {part:?} joint {d:.3} m from the rig's");
            assert!(d < 0.12, "{z} m: {part:?} joint {d:.3} m from the rig's");
        }
    }
}

/// Both arms raised straight up, the hands 27 cm above the head's centre and 8 cm either side
/// of the body's axis (CMU 13_10 reaches up so): the head is still the end that sits on the
/// trunk, an arm's length nearer the centre along the surface than either hand. (Named by
/// height and nearness to the body's axis alone, a hand took the head's name here, 30 cm
/// off, and on 13_10 the tracker sized a small woman from her raised hand, 13 % too tall.)
#[test]
fn arms_raised_beside_the_head_leave_the_head_its_name() {
    let body = common::body();
    let arms: common::Turns = &[
        ("upperarm_l", Vec3::Z, 150.0),
        ("upperarm_r", Vec3::Z, -150.0),
        ("lowerarm_l", Vec3::X, -60.0),
        ("lowerarm_r", Vec3::X, -60.0),
    ];
    for (seed, z) in [(4u64, 2.6f32), (5, 3.0)] {
        let (skin, joints) = body.posed(&body.locals(arms, 1.0), Vec3::new(0.05, -0.8, z));
        let at = |j: KinectJoint| joints[j.index()];
        let hands = [at(KinectJoint::HandLeft), at(KinectJoint::HandRight)];
        assert!(
            hands.iter().all(|h| h.y > at(KinectJoint::Head).y + 0.2),
            "the scene shows the case: hands {hands:?} above the head {}",
            at(KinectJoint::Head)
        );
        let frame = common::render(
            &common::scene(vec![(skin, Label::Body)], &body.model.triangles),
            seed,
            0.0,
        );
        let ends = ends_of(&frame);
        let find = |part: Part| named(&ends, part, z).joint;
        let head = find(Part::Head).distance(at(KinectJoint::Head));
        println!(
            "{z} m: head joint {:.0} mm from the head's centre",
            head * 1e3
        );
        assert!(head < 0.12, "{z} m: head {head:.3} m off");
        for (part, joint) in [
            (Part::HandLeft, KinectJoint::HandLeft),
            (Part::HandRight, KinectJoint::HandRight),
        ] {
            let d = find(part).distance(at(joint));
            assert!(d < 0.15, "{z} m: {part:?} {d:.3} m from the hand");
        }
    }
}

/// Arms hanging against the sides, the hands beside the thighs: the hands are no ends of the
/// surface (they touch the body), and the ends found there were named hands 39-52 cm from
/// either (the shoulders' corners, the knees): the start pulled the arms to them, folded up
/// or behind the back. An end named a hand is near one, or there is none; with the arms
/// hanging clear of the body both hands are still found.
#[test]
fn arms_hanging_against_the_sides_lend_no_hand_to_a_shoulder_or_a_knee() {
    // A small woman (near the acceptance set's: ANSUR II's 5th percentile) and the default.
    let woman = fitroom_body::Shape {
        gender: 0.0,
        weight: 0.44,
        muscle: 0.29,
        height: 0.46,
        proportions: 0.36,
        ..Default::default()
    };
    for (name, body) in [
        ("default", common::body()),
        ("small woman", common::shaped_body(&woman)),
    ] {
        // Degrees the upper arms turn down from the rest pose's: 30 hangs clear, 40-50 lays
        // the hands against the thighs.
        for (deg, seed) in [(30.0f32, 7u64), (40.0, 8), (45.0, 9), (50.0, 10)] {
            let arms: common::Turns =
                &[("upperarm_l", Vec3::Z, -deg), ("upperarm_r", Vec3::Z, deg)];
            let (skin, joints) = body.posed(&body.locals(arms, 1.0), Vec3::new(0.05, -0.8, 3.0));
            let frame = common::render(
                &common::scene(vec![(skin, Label::Body)], &body.model.triangles),
                seed,
                0.0,
            );
            let ends = ends_of(&frame);
            let hands = [
                joints[KinectJoint::HandLeft.index()],
                joints[KinectJoint::HandRight.index()],
            ];
            let named: Vec<(Part, f32)> = ends
                .iter()
                .filter(|e| matches!(e.part, Part::HandLeft | Part::HandRight))
                .map(|e| {
                    (
                        e.part,
                        hands
                            .iter()
                            .map(|h| h.distance(e.joint))
                            .fold(f32::MAX, f32::min),
                    )
                })
                .collect();
            println!("{name}, arms {deg}° down: hands named {named:?}");
            for (part, d) in &named {
                assert!(
                    *d < 0.2,
                    "{name}, arms {deg}° down: {part:?} named {d:.2} m from either hand"
                );
            }
            if deg <= 30.0 {
                assert_eq!(
                    named.len(),
                    2,
                    "{name}, arms hanging clear: both hands found: {ends:?}"
                );
            }
        }
    }
}
