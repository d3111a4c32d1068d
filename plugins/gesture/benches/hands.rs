//! Speed of the hand state: both hands of one frame (a synthetic person at 2 m with one hand
//! raised, the other hanging), our classifier and the seed's method. Goal: both hands and
//! the swipe detector within 2 ms a frame.

use std::hint::black_box;
use std::path::Path;

use criterion::{Criterion, criterion_group, criterion_main};
use fitroom_body::BodyModel;
use fitroom_depth::synthetic::NoiseSettings;
use fitroom_gesture::cursor::CursorTracker;
use fitroom_gesture::eval::hand_joints;
use fitroom_gesture::hand::classify::{HandModel, look};
use fitroom_gesture::hand::seed::seed_score;
use fitroom_gesture::swipe::SwipeDetector;
use fitroom_gesture::synth::{HandPose, HandStudio};
use fitroom_gesture::{HandSide, HandState};

fn hands(c: &mut Criterion) {
    let body = BodyModel::read(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/bodies/makehuman.fitbody"),
    )
    .expect("the shipped body");
    let model = HandModel::embedded().expect("the shipped model");
    let studio = HandStudio::new(&body, NoiseSettings::default());
    let pose = HandPose::drawn(3, 2.0);
    let shot = studio.film(&pose, 3).expect("filmed");
    let mut state = 1;
    let both = [HandSide::Left, HandSide::Right]
        .map(|side| hand_joints(&shot.joints, side, 0.0, &mut state));
    c.bench_function("hand state, both hands (ours)", |b| {
        b.iter(|| {
            for j in &both {
                black_box(look(black_box(&shot.frame), j, &model));
            }
        })
    });
    // The whole per-frame work of the gesture plugin: both hands, the swipe detector and the
    // cursor on the frame's skeleton.
    let skeleton = fitroom_sensor::SensorFrame {
        timestamp_s: 0.0,
        sequence: 0,
        joints: std::array::from_fn(|j| fitroom_sensor::JointSample {
            position: shot.joints[j],
            orientation: glam::Quat::IDENTITY,
            confidence: 1.0,
        }),
    };
    let mut swipes = SwipeDetector::default();
    let mut cursor = CursorTracker::default();
    let mut t = 0.0;
    c.bench_function("gestures per frame: both hands, swipes, cursor", |b| {
        b.iter(|| {
            let mut states = [HandState::Unknown; 2];
            for (s, j) in states.iter_mut().zip(&both) {
                *s = look(black_box(&shot.frame), j, &model).state;
            }
            let mut frame = skeleton.clone();
            t += 1.0 / 30.0;
            frame.timestamp_s = t;
            black_box(swipes.update(&frame));
            black_box(cursor.update(&frame, states));
        })
    });
    c.bench_function("hand state, both hands (seed's)", |b| {
        b.iter(|| {
            for j in &both {
                black_box(seed_score(black_box(&shot.frame), j));
            }
        })
    });
}

criterion_group!(benches, hands);
criterion_main!(benches);
