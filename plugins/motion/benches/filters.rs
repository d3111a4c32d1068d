//! Per-frame cost of the joint filters (20 joints) and of the frame gate.
//!
//! `CARGO_TARGET_DIR=... cargo bench -p fitroom_motion --no-default-features --bench filters`
//!
//! The budget of the whole motion pipeline is 50 µs per frame; each figure here is one filter's
//! share of it. Input: a real CMU clip (07_01, walk) replayed at 30 Hz with seeded noise
//! (1.5 cm), cycled.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use fitroom_motion::filter::{FilterKind, FrameGate, HoltParams, KalmanParams, OneEuroParams};
use fitroom_sensor::{SensorFrame, bvh_source::BvhSource};

fn clip_frames() -> Vec<SensorFrame> {
    let path = fitroom_testdata::clip_path("07_01.bvh");
    let source = match BvhSource::load(&path, Default::default()) {
        Ok(s) => s,
        Err(e) => panic!("bench clip {}: {e}", path.display()),
    };
    let n = (source.clip_duration_s() * 30.0).floor() as usize;
    // Seeded noise: xorshift64* uniform pairs through Box-Muller, 1.5 cm per axis.
    let mut state: u64 = 0x9E37_79B9_7F4A_7C15;
    let mut uniform = move || {
        state ^= state >> 12;
        state ^= state << 25;
        state ^= state >> 27;
        ((state.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    };
    (0..=n)
        .map(|k| {
            let mut frame = source.frame_at(k as f64 / 30.0);
            for joint in frame.joints.iter_mut() {
                for axis in 0..3 {
                    let (u1, u2) = (uniform(), uniform());
                    let g = (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos();
                    joint.position[axis] += (0.015 * g) as f32;
                }
            }
            frame
        })
        .collect()
}

fn bench_filters(c: &mut Criterion) {
    let frames = clip_frames();
    let kinds = [
        ("none", FilterKind::None),
        ("holt", FilterKind::Holt(HoltParams::DEFAULT)),
        ("oneeuro", FilterKind::OneEuro(OneEuroParams::default())),
        ("kalman", FilterKind::Kalman(KalmanParams::default())),
    ];
    let mut group = c.benchmark_group("filter_per_frame_20_joints");
    for (name, kind) in kinds {
        let mut filter = kind.build();
        let mut k = 0usize;
        let mut t_offset = 0.0;
        let period = frames.len() as f64 / 30.0;
        group.bench_function(name, |b| {
            b.iter(|| {
                let mut frame = frames[k].clone();
                frame.timestamp_s += t_offset;
                k += 1;
                if k == frames.len() {
                    k = 0;
                    t_offset += period;
                }
                black_box(filter.filter(black_box(&frame)))
            })
        });
    }
    group.bench_function("gate_check", |b| {
        let mut gate = FrameGate::new();
        let mut k = 0u64;
        let mut frame = frames[0].clone();
        b.iter(|| {
            k += 1;
            frame.timestamp_s = k as f64 / 30.0;
            black_box(gate.check(black_box(&frame)))
        })
    });
    group.finish();
}

criterion_group!(benches, bench_filters);
criterion_main!(benches);
