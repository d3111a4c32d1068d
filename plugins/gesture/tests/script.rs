//! Scripted people: the body goes where the script says (checked against the skeleton's own
//! body frame), and a person who swipes right twice and grips, filmed by the synthetic Kinect
//! with its noise, is read as exactly that by the hand reader (bodies and distances the hand
//! model and the swipe thresholds were not set on).

use std::path::Path;
use std::sync::Arc;

use fitroom_body::{BodyModel, Shape};
use fitroom_depth::DepthCamera;
use fitroom_depth::synthetic::{NoiseSettings, Scene, SyntheticCamera};
use fitroom_gesture::HandState;
use fitroom_gesture::cursor::Click;
use fitroom_gesture::hand::classify::HandModel;
use fitroom_gesture::reader::GestureReader;
use fitroom_gesture::script::{GestureScript, SCRIPT_FPS, ScriptError, ScriptedPerson};
use fitroom_gesture::swipe::{SwipeDirection, body_frame};
use fitroom_sensor::{JointSample, KinectJoint, SensorFrame};
use glam::{Quat, Vec3};

fn model() -> Arc<BodyModel> {
    Arc::new(
        BodyModel::read(
            &Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/bodies/makehuman.fitbody"),
        )
        .expect("the shipped body"),
    )
}

const SCRIPT: &str = "GestureScript(steps: [
    Stand(seconds: 1.0),
    Swipe(hand: Right, direction: Right),
    Swipe(hand: Right, direction: Right),
    Grip(hand: Right),
    Stand(seconds: 1.0),
])";

fn person(model: &Arc<BodyModel>, shape: &Shape, script: &GestureScript) -> ScriptedPerson {
    let shaped = model.shaped(shape).expect("a shape");
    ScriptedPerson::new(
        model.clone(),
        shaped.positions,
        shaped.rest_pose,
        script,
        -0.8,
    )
    .expect("performed")
}

fn skeleton(joints: &[Vec3; KinectJoint::COUNT], k: usize) -> SensorFrame {
    SensorFrame {
        timestamp_s: k as f64 / SCRIPT_FPS,
        sequence: k as u64,
        joints: std::array::from_fn(|j| JointSample {
            position: joints[j],
            orientation: Quat::IDENTITY,
            confidence: 1.0,
        }),
    }
}

/// The grip's wrist is where the script puts it: before the right shoulder (0.9 shoulder
/// widths to the right, 0.2 down, 0.55 forward), measured
/// in the body frame the swipe detector reads off the skeleton; both feet on the floor.
#[test]
fn the_body_goes_where_the_script_says() {
    let model = model();
    let script = GestureScript::from_ron_str(
        "GestureScript(distance_m: 2.5, steps: [Grip(hand: Right, seconds: 1.0)])",
        "grip.ron",
    )
    .expect("valid");
    for shape in [
        Shape::default(),
        Shape {
            gender: 1.0,
            height: 0.8,
            weight: 0.3,
            ..Shape::default()
        },
    ] {
        let person = person(&model, &shape, &script);
        // Held closed: after rising (0.7 s), open (0.5 s) and closing (0.25 s).
        let k = ((0.7 + 0.5 + 0.25 + 0.5) * SCRIPT_FPS) as usize;
        assert_eq!(person.frames()[k].hands[1], HandState::Closed);
        assert_eq!(person.frames()[k].hands[0], HandState::Unknown);
        let joints = person.joints(k);
        let (centre, right, forward, width) = body_frame(&skeleton(&joints, k)).expect("a body");
        let want = centre + (right * 0.9 - Vec3::Y * 0.2 + forward * 0.55) * width;
        let wrist = joints[KinectJoint::WristRight.index()];
        assert!(wrist.distance(want) < 0.01, "{wrist} vs {want}");
        // The hand is before the person (towards the sensor), the pelvis at the distance.
        assert!(wrist.z < joints[KinectJoint::HipCenter.index()].z - 0.1);
        assert!((joints[KinectJoint::HipCenter.index()].z - 2.5).abs() < 0.15);
        let mesh = person.mesh(k);
        let sole = mesh.positions.iter().map(|p| p.y).fold(f32::MAX, f32::min);
        assert!((sole + 0.8).abs() < 0.005, "{sole}");
    }
}

/// Two swipes to the right and a grip, read from depth by the same reader as the kiosk's.
#[test]
fn a_scripted_person_swipes_right_twice_and_grips() {
    let model = model();
    let script = GestureScript::from_ron_str(SCRIPT, "script.ron").expect("valid");
    let hands = HandModel::embedded().expect("the shipped hand model");
    for (shape, distance, seed) in [
        (
            Shape {
                gender: 1.0,
                height: 0.75,
                weight: 0.35,
                ..Shape::default()
            },
            3.0,
            5,
        ),
        (
            Shape {
                gender: 0.0,
                height: 0.3,
                weight: 0.65,
                ..Shape::default()
            },
            2.2,
            6,
        ),
    ] {
        let script = GestureScript {
            distance_m: distance,
            ..script.clone()
        };
        let person = person(&model, &shape, &script);
        let mut camera =
            SyntheticCamera::new(DepthCamera::default(), NoiseSettings::default(), seed);
        let mut reader = GestureReader::new(Some(hands.clone()));
        let (mut swipes, mut clicks) = (Vec::new(), Vec::new());
        // Hand states during the grip (from 5.5 s), and over the whole script.
        let (mut agree, mut judged) = (0, 0);
        let (mut agree_all, mut judged_all) = (0, 0);
        for (k, truth) in person.frames().iter().enumerate() {
            let mut scene = Scene::room(-0.8, distance + 1.8);
            scene.meshes.push(person.mesh(k));
            let depth = camera.render(&scene, truth.time_s).frame;
            let frame = skeleton(&person.joints(k), k);
            reader.read_hands(&frame, Some(&depth));
            let step = reader.step(&frame);
            if let Some(s) = step.swipe {
                swipes.push(s.direction);
            }
            if let Some(c) = step.click {
                clicks.push((c, truth.curl[1]));
            }
            if truth.hands[1] != HandState::Unknown {
                let right = usize::from(reader.hands[1] == truth.hands[1]);
                judged_all += 1;
                agree_all += right;
                if truth.time_s >= 5.5 {
                    judged += 1;
                    agree += right;
                }
            }
        }
        println!(
            "{shape:?} at {distance} m: swipes {swipes:?}, clicks {clicks:?}, hand state in the grip {agree}/{judged}, in all {agree_all}/{judged_all}"
        );
        assert_eq!(swipes, [SwipeDirection::Right, SwipeDirection::Right]);
        // One press as the fist closes (more than half curled), one release as it opens.
        assert_eq!(clicks.len(), 2, "{clicks:?}");
        assert!(
            clicks[0].0 == Click::Press && clicks[0].1 >= 0.5,
            "{clicks:?}"
        );
        assert!(
            clicks[1].0 == Click::Release && clicks[1].1 <= 0.5,
            "{clicks:?}"
        );
        // The hysteresis lags a few frames behind each change. (A hand held across the chest
        // at a swipe's start is read less well: not judged here.)
        assert!(agree as f32 >= 0.9 * judged as f32, "{agree}/{judged}");
    }
}

#[test]
fn bad_scripts_are_explained() {
    let line_of = |e: ScriptError| e.to_string();
    // A wrong word names the file, its line and column.
    let e = GestureScript::from_ron_str(
        "GestureScript(steps: [\n  Stand(seconds: 1.0),\n  Swipe(hand: Middle, direction: Right),\n])",
        "bad.ron",
    )
    .expect_err("no middle hand");
    let message = line_of(e);
    assert!(message.starts_with("bad.ron:3:"), "{message}");
    let e = GestureScript::from_ron_str(
        "GestureScript(steps: [Swipe(hand: Left, direction: Left, travel: 9.0)])",
        "far.ron",
    )
    .expect_err("too far");
    assert!(e.to_string().contains("travel 9"), "{e}");
    let e = GestureScript::from_ron_str("GestureScript(distance_m: 9.0, steps: [])", "d.ron")
        .expect_err("too far away");
    assert!(e.to_string().contains("distance_m"), "{e}");
    let e = GestureScript::from_ron_str("GestureScript(steps: [])", "empty.ron")
        .expect_err("nothing to do");
    assert!(e.to_string().contains("no steps"), "{e}");
    assert!(GestureScript::load(Path::new("/nonexistent/script.ron")).is_err());
    // The shipped demo script is valid.
    let shipped = GestureScript::load(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/motions/gestures.ron"),
    )
    .expect("the shipped script");
    assert!(shipped.duration_s() > 15.0);
}
