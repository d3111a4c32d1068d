//! A scene's still part (`Scene::still`, the room) is kept rendered from frame to frame and
//! only the moving meshes are drawn again: the frames must be, bit for bit, those of drawing
//! everything. Checked with the body moving about, crossing the image's edges, close enough
//! for a wide projector shadow, gone, and with a still mesh changed behind the camera's back.

use std::path::Path;

use fitroom_body::BodyModel;
use fitroom_depth::DepthCamera;
use fitroom_depth::synthetic::{
    Label, NoiseSettings, Scene, SceneMesh, SyntheticCamera, SyntheticFrame,
};
use glam::Vec3;

fn body_at(model: &BodyModel, at: Vec3) -> SceneMesh {
    let n = model.body_vertex_count as usize;
    let standing = model.standing_in_sensor_space(&model.positions);
    SceneMesh {
        positions: model.positions[..n]
            .iter()
            .map(|&p| standing.transform_point3(p) + at)
            .collect(),
        triangles: model.triangles.clone(),
        label: Label::Body,
        closed: true,
    }
}

fn assert_same(a: &SyntheticFrame, b: &SyntheticFrame, what: &str) {
    assert!(a.frame.depth_mm == b.frame.depth_mm, "{what}: depth");
    assert!(a.frame.raw == b.frame.raw, "{what}: raw");
    assert!(a.labels == b.labels, "{what}: labels");
    let bits = |f: &SyntheticFrame| {
        f.true_depth_m
            .iter()
            .map(|z| z.to_bits())
            .collect::<Vec<_>>()
    };
    assert!(bits(a) == bits(b), "{what}: true depth");
}

#[test]
fn the_still_part_kept_gives_the_frames_of_drawing_everything() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/bodies/makehuman.fitbody");
    let model = BodyModel::read(&path).expect("the shipped body");
    // Where the body stands, frame by frame (`None`: nobody), and whether the back wall
    // moves behind the camera's back (a still mesh changed).
    let steps: [(Option<Vec3>, bool); 9] = [
        (Some(Vec3::new(0.0, -0.8, 2.5)), false),
        (Some(Vec3::new(0.05, -0.8, 2.45)), false),
        // Across the image's left and right edges, and its bottom.
        (Some(Vec3::new(1.3, -0.8, 2.2)), false),
        (Some(Vec3::new(-1.4, -0.5, 2.0)), false),
        // Near: a wide shadow.
        (Some(Vec3::new(0.2, -1.2, 1.1)), false),
        (None, false),
        (Some(Vec3::new(0.0, -0.8, 2.5)), true),
        (Some(Vec3::new(0.1, -0.8, 2.6)), true),
        (Some(Vec3::new(0.1, -0.8, 2.6)), false),
    ];
    let settings = [
        NoiseSettings::default(),
        NoiseSettings {
            quantise: false,
            ..NoiseSettings::default()
        },
        NoiseSettings {
            shadow: true,
            ..NoiseSettings::exact()
        },
    ];
    for (s, noise) in settings.into_iter().enumerate() {
        let seed = 40 + s as u64;
        let mut kept = SyntheticCamera::new(DepthCamera::default(), noise, seed);
        let mut drawn = SyntheticCamera::new(DepthCamera::default(), noise, seed);
        for (f, &(body, wall_moved)) in steps.iter().enumerate() {
            let mut scene = Scene::room(-0.8, if wall_moved { 3.4 } else { 3.6 });
            scene.add_box(
                Vec3::new(0.9, -0.3, 2.3),
                Vec3::new(0.25, 0.5, 0.25),
                Label::Other,
            );
            // The room and the box stand still.
            scene.still = scene.meshes.len();
            scene.meshes.extend(body.map(|at| body_at(&model, at)));
            let a = kept.render(&scene, f as f64);
            let b_scene = Scene {
                still: 0,
                ..scene.clone()
            };
            let b = drawn.render(&b_scene, f as f64);
            assert_same(&a, &b, &format!("settings {s}, frame {f}"));
            // Some frames keep their images, some do not: both are written in full.
            if f % 3 == 0 {
                std::mem::forget(a);
            }
        }
    }
}
