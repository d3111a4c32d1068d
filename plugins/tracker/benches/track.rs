//! Tracking speed: one 640x480 synthetic frame after another (segmentation, then the fit
//! started from the last frame's pose), the MakeHuman body at 2.5 m turning and crossing an
//! arm in front of itself and back (a second of motion each way, pre-rendered): the mean
//! time per frame over the way there and back.
//!
//! Run: `taskset -c 0 cargo bench -p fitroom_tracker --no-default-features --bench track`.

#[path = "../tests/common/mod.rs"]
mod common;

use std::hint::black_box;
use std::time::{Duration, Instant};

use common::{TURN_AND_CROSS, body, render, scene};
use criterion::{Criterion, SamplingMode, criterion_group, criterion_main};
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
    // Forwards and back, so each frame follows its neighbour.
    let order: Vec<usize> = (0..30).chain((0..30).rev()).collect();
    // The clock runs on as a sensor's does (played back, the frames' own times would jump
    // back, and a person seen earlier than last is someone new: started afresh).
    // Two cycles' frames made once, so no frame is copied while timed.
    let cycles: [Vec<_>; 2] = [0, 1].map(|cycle| {
        order
            .iter()
            .enumerate()
            .map(|(k, &i)| {
                let mut frame = frames[i].clone();
                frame.time_s = (cycle * order.len() + k) as f64 / 30.0;
                frame
            })
            .collect()
    });
    let run = |tracker: &mut Tracker, cycle: &[_]| {
        for frame in cycle {
            black_box(tracker.track(frame));
        }
    };
    // One measured run is the second cycle of a fresh tracker that followed the first (the
    // first holds the start), reported per frame. The cost of a frame depends on the
    // tracker's state (a limb suspected lost is fitted twice, at the turn-back three to five
    // times); each run starting from the same state makes the runs alike, so the figure is
    // the mean over the cycle and not the few frames a sample happened to hold.
    let mut group = c.benchmark_group("track_640x480");
    group.sampling_mode(SamplingMode::Flat).sample_size(10);
    group.bench_function("segment_and_fit_per_frame", |b| {
        b.iter_custom(|runs| {
            let mut total = Duration::ZERO;
            for _ in 0..runs {
                let mut tracker = Tracker::new(track.clone(), TrackerSettings::default());
                run(&mut tracker, &cycles[0]);
                let started = Instant::now();
                run(&mut tracker, &cycles[1]);
                total += started.elapsed();
            }
            total / order.len() as u32
        })
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
