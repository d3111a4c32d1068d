//! The depth camera's speed goal in the product's own scene: one synthetic 640x480 frame of
//! the dressed avatar (the sun dress on the default body waving hello, CMU 141_16, 2.5 m
//! from the sensor, posed and simulated by the headless app), in the room, with every part
//! of the error model. The frame is rendered on the calling thread: run it on one core with
//! `taskset -c 0 cargo bench --bench depth_frame`.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use fitroom::{AppOptions, Mode, depth_scene, headless};
use fitroom_body::plugin::SensorPlacement;
use fitroom_depth::DepthCamera;
use fitroom_depth::synthetic::{NoiseSettings, SyntheticCamera};

fn bench(c: &mut Criterion) {
    let mut options =
        AppOptions::with_defaults(Mode::Headless { render: false }).expect("the defaults");
    options.garment = Some(
        fitroom::assets::assets_dir()
            .expect("assets")
            .join("garments/sundress.ron"),
    );
    // A clip that stays in place (the embedded walk goes towards the sensor and past it).
    options.motion = fitroom_testdata::clip_path("141_16.bvh");
    options.sensor = fitroom::sensors::SensorSpec::Bvh(options.motion.clone());
    let mut app = headless::headless_app(&options).expect("the app");
    // The garment loads on the asset server's threads: step until it is worn, then one more
    // second of the clip.
    for _ in 0..3000 {
        app.update();
        let world = app.world_mut();
        let mut worn = world.query::<&fitroom_garment::plugin::WornGarment>();
        if worn.iter(world).any(|g| !g.surface().0.is_empty()) {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(2));
    }
    for _ in 0..60 {
        app.update();
    }
    let world = app.world_mut();
    let placement = *world.resource::<SensorPlacement>();
    let mut scene = depth_scene::room(&placement);
    scene
        .meshes
        .extend(depth_scene::avatar_meshes(world).expect("the avatar"));
    assert!(
        scene.meshes.len() == 4,
        "floor, wall, body and dress: {} meshes",
        scene.meshes.len()
    );
    let triangles: usize = scene.meshes.iter().map(|m| m.triangles.len()).sum();
    let hip = depth_scene::avatar_kinect_joints(world).expect("the joints")[0];
    let mut camera = SyntheticCamera::new(DepthCamera::default(), NoiseSettings::default(), 1);
    c.bench_function(
        &format!(
            "synthetic_frame_640x480_dressed_avatar_{triangles}_triangles_hip_at_{:.1}_m",
            hip.z
        ),
        |b| b.iter(|| black_box(camera.render(&scene, 0.0))),
    );
}

criterion_group!(benches, bench);
criterion_main!(benches);
