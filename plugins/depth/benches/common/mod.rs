//! The speed goal's scene, shared by the criterion bench (`benches/depth.rs`) and
//! `examples/frame_time.rs`.

use std::path::Path;

use fitroom_body::{AssetError, BodyModel};
use fitroom_depth::synthetic::{Label, Scene, SceneMesh};
use glam::Vec3;

/// The shipped body standing 2.5 m in front of a sensor 0.8 m above the floor, in a room.
pub fn avatar_scene() -> Result<Scene, AssetError> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/bodies/makehuman.fitbody");
    let model = BodyModel::read(&path)?;
    let n = model.body_vertex_count as usize;
    let standing = model.standing_in_sensor_space(&model.positions);
    let positions = model.positions[..n]
        .iter()
        .map(|&p| standing.transform_point3(p) + Vec3::new(0.0, -0.8, 2.5))
        .collect();
    let mut scene = Scene::room(-0.8, 3.6);
    scene.meshes.push(SceneMesh {
        positions,
        triangles: model.triangles.clone(),
        label: Label::Body,
        closed: true,
    });
    Ok(scene)
}
