//! Segmentation speed: one 640x480 synthetic frame of the MakeHuman body at 2.5 m in a room,
//! with a second person behind (the floor kept from the frame before, as in a stream).
//!
//! Run: `taskset -c 0 cargo bench -p fitroom_tracker --no-default-features --bench segment`.

use std::hint::black_box;
use std::path::Path;

use criterion::{Criterion, criterion_group, criterion_main};
use fitroom_body::BodyModel;
use fitroom_depth::DepthCamera;
use fitroom_depth::synthetic::{Label, NoiseSettings, Scene, SceneMesh, SyntheticCamera};
use fitroom_tracker::{SegmentSettings, Segmenter};
use glam::Vec3;

fn bench(c: &mut Criterion) {
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
    c.bench_function("segment_640x480_person_and_passer_by", |b| {
        b.iter(|| black_box(segmenter.segment(&frame)))
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
