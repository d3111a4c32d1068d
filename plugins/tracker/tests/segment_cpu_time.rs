//! Segmentation CPU time per frame, read from `/proc/thread-self/schedstat` (first field:
//! nanoseconds this thread has run), steadier than wall time on a busy machine. The frame is
//! the bench's: the body at 2.5 m in a room, a second person behind.
//!
//! Run: `taskset -c 0 cargo test -p fitroom_tracker --no-default-features --release --test
//! segment_cpu_time -- --ignored --nocapture`.

use std::hint::black_box;
use std::path::Path;
use std::time::Instant;

use fitroom_body::BodyModel;
use fitroom_depth::DepthCamera;
use fitroom_depth::synthetic::{Label, NoiseSettings, Scene, SceneMesh, SyntheticCamera};
use fitroom_tracker::{SegmentSettings, Segmenter};
use glam::Vec3;

/// This thread's CPU time so far, nanoseconds.
fn cpu_ns() -> u64 {
    let text = std::fs::read_to_string("/proc/thread-self/schedstat").expect("schedstat");
    text.split_whitespace()
        .next()
        .and_then(|field| field.parse().ok())
        .expect("a number")
}

#[test]
#[ignore = "timing, run by hand"]
fn segment_cpu_time_per_frame() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/bodies/makehuman.fitbody");
    let model = BodyModel::read(&path).expect("the shipped body");
    let n = model.body_vertex_count as usize;
    let standing = model.standing_in_sensor_space(&model.positions);
    let at = |x: f32, z: f32, label| SceneMesh {
        positions: model.positions[..n]
            .iter()
            .map(|&p| standing.transform_point3(p) + Vec3::new(x, -0.8, z))
            .collect(),
        triangles: model.triangles.clone(),
        label,
        closed: true,
    };
    let mut scene = Scene::room(-0.8, 3.9);
    scene.meshes.push(at(0.0, 2.5, Label::Body));
    scene.meshes.push(at(1.0, 3.4, Label::Other));
    let frame = SyntheticCamera::new(DepthCamera::default(), NoiseSettings::default(), 1)
        .render(&scene, 0.0)
        .frame;
    let mut segmenter = Segmenter::new(SegmentSettings::default());
    assert!(segmenter.segment(&frame).is_some());
    // The CPU clock may advance by scheduler ticks (4 ms here): time batches of calls.
    let batches: usize = std::env::var("BATCHES")
        .ok()
        .and_then(|r| r.parse().ok())
        .unwrap_or(31);
    let per_batch = 40;
    let (mut cpu, mut wall) = (Vec::new(), Vec::new());
    for _ in 0..batches {
        let (c0, w0) = (cpu_ns(), Instant::now());
        for _ in 0..per_batch {
            black_box(segmenter.segment(black_box(&frame)));
        }
        wall.push(w0.elapsed().as_nanos() as f64 * 1e-6 / per_batch as f64);
        cpu.push((cpu_ns() - c0) as f64 * 1e-6 / per_batch as f64);
    }
    cpu.sort_by(f64::total_cmp);
    wall.sort_by(f64::total_cmp);
    let at = |v: &[f64], q: usize| v[(v.len() - 1) * q / 100];
    println!(
        "segment: CPU median {:.3} ms/frame (p10 {:.3}, p90 {:.3}); wall median {:.3} ms; \
         {batches} batches of {per_batch}",
        at(&cpu, 50),
        at(&cpu, 10),
        at(&cpu, 90),
        at(&wall, 50)
    );
}
