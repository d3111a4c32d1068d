//! The depth camera's speed goals: a synthetic 640x480 frame of the avatar in a room (the
//! MakeHuman body at 2.5 m, floor and back wall; every part of the error model) on one core,
//! and reading one recorded frame back from a fakenect folder. The room is the scene's still
//! part (`Scene::still`, as `Scene::room` makes it): kept rendered, the body drawn every
//! frame, as in the app; the second synthetic case draws everything every frame.
//!
//! Run: `taskset -c 0 cargo bench -p fitroom_depth --no-default-features --bench depth` (the
//! Bevy-free core only; add `-- --quick` for a short run).

mod common;

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use fitroom_depth::DepthCamera;
use fitroom_depth::fakenect::{Recording, RecordingWriter};
use fitroom_depth::synthetic::{NoiseSettings, Scene, SyntheticCamera};

fn bench(c: &mut Criterion) {
    let scene = common::avatar_scene().expect("the shipped body");
    let triangles: usize = scene.meshes.iter().map(|m| m.triangles.len()).sum();
    let mut camera = SyntheticCamera::new(DepthCamera::default(), NoiseSettings::default(), 1);
    c.bench_function(
        &format!("synthetic_frame_640x480_avatar_in_room_{triangles}_triangles"),
        |b| b.iter(|| black_box(camera.render(&scene, 0.0))),
    );
    let everything = Scene {
        still: 0,
        ..scene.clone()
    };
    let mut uncached = SyntheticCamera::new(DepthCamera::default(), NoiseSettings::default(), 1);
    c.bench_function(
        &format!("synthetic_frame_640x480_avatar_in_room_{triangles}_triangles_all_drawn"),
        |b| b.iter(|| black_box(uncached.render(&everything, 0.0))),
    );

    let dir = std::env::temp_dir().join(format!("fitroom-depth-bench-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let mut writer = RecordingWriter::create(&dir).expect("a scratch folder");
    let frame = camera.render(&scene, 0.0);
    let raw = frame.frame.raw.expect("raw values");
    writer.write_depth(0.0, 0, &raw).expect("written");
    let recording = Recording::open(&dir).expect("reads");
    let entry = recording.depth_entries().next().expect("a frame").clone();
    c.bench_function("fakenect_read_one_depth_frame", |b| {
        b.iter(|| {
            black_box(
                recording
                    .read_depth(&entry, DepthCamera::default())
                    .expect("reads"),
            )
        })
    });
    let _ = std::fs::remove_dir_all(&dir);
}

criterion_group!(benches, bench);
criterion_main!(benches);
