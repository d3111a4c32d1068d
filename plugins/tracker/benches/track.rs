//! Tracking speed: one 640x480 synthetic frame after another (segmentation, then the fit
//! started from the last frame's pose), the MakeHuman body at 2.5 m turning and crossing an
//! arm in front of itself and back (a second of motion each way, pre-rendered).
//!
//! Run: `taskset -c 0 cargo bench -p fitroom_tracker --no-default-features --bench track`.

#[path = "../tests/common/mod.rs"]
mod common;

use std::hint::black_box;

use common::{TURN_AND_CROSS, body, render, scene};
use criterion::{Criterion, criterion_group, criterion_main};
use fitroom_depth::synthetic::Label;
use fitroom_tracker::{TrackBody, Tracker, TrackerSettings};
use glam::Vec3;

fn bench(c: &mut Criterion) {
    let body = body();
    let frames: Vec<_> = (0..30)
        .map(|i| {
            let (skin, _) = body.posed(
                &body.locals(TURN_AND_CROSS, i as f32 / 29.0),
                Vec3::new(0.0, -0.8, 2.5),
            );
            render(
                &scene(vec![(skin, Label::Body)], &body.model.triangles),
                i,
                i as f64 / 30.0,
            )
        })
        .collect();
    let track = TrackBody::new(&body.model, &body.model.positions).expect("a trackable body");
    let mut tracker = Tracker::new(track, TrackerSettings::default());
    // Forwards and back, so each frame follows its neighbour.
    let order: Vec<usize> = (0..30).chain((0..30).rev()).collect();
    for (k, &i) in order.iter().enumerate() {
        let mut frame = frames[i].clone();
        frame.time_s = k as f64 / 30.0;
        assert!(tracker.track(&frame).is_some());
    }
    // The clock runs on as a sensor's does (played back, the frames' own times would jump
    // back, and a person seen earlier than last is someone new: started afresh).
    let (mut at, mut clock) = (0, order.len() as f64 / 30.0);
    c.bench_function("track_640x480_segment_and_fit", |b| {
        b.iter(|| {
            at = (at + 1) % order.len();
            clock += 1.0 / 30.0;
            let mut frame = frames[order[at]].clone();
            frame.time_s = clock;
            black_box(tracker.track(&frame))
        })
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
