//! Speed of the hand state: both hands of one frame (a synthetic person at 2 m with one hand
//! raised, the other hanging), our classifier and the seed's method. Goal: both hands and
//! the swipe detector within 2 ms a frame.

use std::hint::black_box;
use std::path::Path;

use criterion::{Criterion, criterion_group, criterion_main};
use fitroom_body::BodyModel;
use fitroom_depth::synthetic::NoiseSettings;
use fitroom_gesture::HandSide;
use fitroom_gesture::eval::hand_joints;
use fitroom_gesture::hand::classify::{HandModel, look};
use fitroom_gesture::hand::seed::seed_score;
use fitroom_gesture::synth::{HandPose, HandStudio};

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
