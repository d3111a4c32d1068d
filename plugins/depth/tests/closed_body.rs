//! The shipped MakeHuman body is closed with outward faces, as the synthetic camera's
//! back-face culling assumes (`SceneMesh::closed`): drawn with and without culling, it covers
//! the same pixels at the same depths, seen from the front, the back and the side.

use std::path::Path;

use fitroom_body::{BodyModel, MODEL_TO_SENSOR};
use fitroom_depth::synthetic::{DepthBuffer, Label};
use fitroom_depth::{DepthCamera, PIXELS};
use glam::{Quat, Vec3};

#[test]
fn culling_back_faces_of_the_body_changes_no_pixel() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/bodies/makehuman.fitbody");
    let model = BodyModel::read(&path).expect("the shipped body");
    let n = model.body_vertex_count as usize;
    let camera = DepthCamera::default();
    for turn in [0.0f32, 90.0, 180.0] {
        let spin = Quat::from_rotation_y(turn.to_radians());
        let positions: Vec<Vec3> = model.positions[..n]
            .iter()
            .map(|&p| spin * (MODEL_TO_SENSOR * p) + Vec3::new(0.0, -0.9, 2.2))
            .collect();
        let draw = |closed| {
            let mut buffer = DepthBuffer::default();
            buffer.draw(
                &camera,
                &positions,
                &model.triangles,
                Label::Body as u8,
                closed,
            );
            buffer
        };
        let (all, culled) = (draw(false), draw(true));
        let covered = (0..PIXELS).filter(|&k| all.label[k] != 0).count();
        let differ = (0..PIXELS)
            .filter(|&k| all.label[k] != culled.label[k] || (all.z(k) - culled.z(k)).abs() > 1e-4)
            .count();
        assert!(covered > 10_000, "{turn}°: {covered} pixels");
        // Pixel centres exactly on a silhouette edge may go either way.
        assert!(
            differ * 1000 < covered,
            "{turn}°: {differ} of {covered} pixels differ"
        );
    }
}
