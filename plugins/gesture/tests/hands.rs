//! Hand state on synthetic hands the models were not trained on (held-out seeds: other
//! bodies, poses, distances and noise), with the skeleton's joints disturbed as a tracker's
//! are; and garbage in.

use std::path::Path;
use std::sync::Arc;

use fitroom_body::BodyModel;
use fitroom_depth::{DepthCamera, DepthFrame, PIXELS};
use fitroom_gesture::HandState;
use fitroom_gesture::eval::{Sampling, TEST_SEEDS, film_samples, pooled, score};
use fitroom_gesture::hand::classify::{HandModel, look, train};
use fitroom_gesture::hand::region::HandJoints;
use fitroom_gesture::hand::seed::seed_score;
use glam::Vec3;

fn model() -> BodyModel {
    BodyModel::read(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/bodies/makehuman.fitbody"),
    )
    .expect("the shipped body")
}

const EDGES: [f32; 6] = [1.0, 1.5, 2.0, 2.5, 3.0, 3.5];

/// Trained here on 300 hands, tested on 300 others: at least 95 % right at 1.0-2.5 m, and
/// better than the seed's method (its threshold trained on the same hands).
#[test]
fn a_model_trained_on_some_hands_reads_others() {
    let body = model();
    let training = film_samples(&body, &Sampling::new(300, 0), 2, &|_| {}).expect("filmed");
    let examples: Vec<_> = training.iter().map(|s| s.example).collect();
    let hand_model = train(&examples, "test".into());
    let test = film_samples(&body, &Sampling::new(300, TEST_SEEDS), 2, &|_| {}).expect("filmed");
    let bands = score(&hand_model, &test, &EDGES);
    let (ours, seed) = pooled(&bands, 1.0, 2.5);
    println!("{bands:#?}\n1.0-2.5 m: ours {ours:.3}, seed {seed:.3}");
    assert!(ours >= 0.95, "ours {ours}");
    assert!(ours > seed, "ours {ours}, seed {seed}");
}

/// The shipped model (`assets/gesture/hands.ron`) on held-out hands.
#[test]
fn the_shipped_model_reads_held_out_hands() {
    let hand_model = HandModel::embedded().expect("the shipped model parses");
    let mut sampling = Sampling::new(240, TEST_SEEDS + 50_000);
    sampling.near_m = 1.0;
    sampling.far_m = 2.5;
    let test = film_samples(&model(), &sampling, 2, &|_| {}).expect("filmed");
    let bands = score(&hand_model, &test, &EDGES[..4]);
    let (ours, seed) = pooled(&bands, 1.0, 2.5);
    println!("{bands:#?}\nours {ours:.3}, seed {seed:.3}");
    assert!(ours >= 0.95, "ours {ours}");
    assert!(ours > seed, "ours {ours}, seed {seed}");
}

/// Empty, saturated, random frames and NaN or absent joints: unknown, never a panic.
#[test]
fn garbage_frames_and_joints_give_unknown() {
    let hand_model = HandModel::embedded().expect("the shipped model parses");
    let camera = DepthCamera::default();
    let frame = |depth: Vec<u16>| DepthFrame {
        depth_mm: Arc::from(depth),
        raw: None,
        rgb: None,
        time_s: 0.0,
        timestamp: 0,
        camera,
    };
    let mut state = 7u64;
    let random: Vec<u16> = (0..PIXELS)
        .map(|_| (fitroom_depth::synthetic::next_unit(&mut state) * 5000.0) as u16)
        .collect();
    let joints = HandJoints {
        hand: Vec3::new(0.1, 0.2, 1.8),
        wrist: Vec3::new(0.1, 0.1, 1.85),
        elbow: Vec3::new(0.15, -0.1, 1.9),
        head_neck_m: 0.2,
    };
    let nan = HandJoints {
        hand: Vec3::NAN,
        ..joints
    };
    let behind = HandJoints {
        hand: Vec3::new(0.0, 0.0, -1.0),
        ..joints
    };
    for depth in [vec![0u16; PIXELS], vec![u16::MAX; PIXELS], random] {
        let f = frame(depth);
        for j in [joints, nan, behind] {
            let l = look(&f, &j, &hand_model);
            if j != joints {
                assert_eq!(l.state, HandState::Unknown);
                assert!(seed_score(&f, &j).is_none());
            }
            assert!(l.p_open.is_finite());
        }
        // Nothing there at all: unknown.
        if f.depth_mm[0] == 0 {
            assert_eq!(look(&f, &joints, &hand_model).state, HandState::Unknown);
        }
    }
}
