//! The whole per-frame motion pipeline on 20 joints: gate, our filter, retargeting onto the
//! 55-bone avatar, joint limits (twice) and foot-skate correction with two-bone IK. The issue's
//! budget is 50 µs per frame.

use std::{hint::black_box, path::Path};

use criterion::{Criterion, criterion_group, criterion_main};
use fitroom_motion::{
    AvatarPipeline, MotionPipeline,
    eval::{clean_stream, evaluation_noise},
    filter::FilterKind,
};
use fitroom_sensor::{bvh_source::BvhSource, noise::corrupt_stream};

fn bench_pipeline(c: &mut Criterion) {
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/../..");
    let model = fitroom_body::BodyModel::read(Path::new(&format!(
        "{root}/assets/bodies/makehuman.fitbody"
    )))
    .expect("body asset");
    let rest = model.rest_pose(&model.positions);
    let skeleton = fitroom_motion::avatar_skeleton(&model, &rest).expect("skeleton");
    let source = BvhSource::load(
        format!("{root}/assets/motions/walk.bvh"),
        Default::default(),
    )
    .expect("walk clip");
    // Kinect-like input: the noise model the evaluation uses, seed 1.
    let frames: Vec<_> = corrupt_stream(&clean_stream(&source), &evaluation_noise(), 1)
        .into_iter()
        .map(|n| n.frame)
        .collect();
    let floor = -source.options().sensor_height_m;

    c.bench_function("pipeline_per_frame_20_joints", |b| {
        let mut pipeline = MotionPipeline::new(
            AvatarPipeline::new(&skeleton, floor).expect("pipeline"),
            FilterKind::default().build(),
        );
        let mut i = 0usize;
        let mut accepted = 0u64;
        b.iter(|| {
            if i.is_multiple_of(frames.len()) {
                // The clip starts again: a new user, as after a loop of the kiosk's replay.
                pipeline.reset();
            }
            let frame = &frames[i % frames.len()];
            i += 1;
            if let Some(step) = pipeline.push(frame) {
                accepted += 1;
                black_box(step.pose);
            }
        });
        // Duplicated frames (1% in the noise model) are rejected; everything else is posed.
        assert!(
            accepted * 10 >= i as u64 * 9,
            "only {accepted} of {i} frames were posed"
        );
    });
}

criterion_group!(benches, bench_pipeline);
criterion_main!(benches);
