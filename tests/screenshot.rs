//! Rendering test on a software Vulkan driver (Mesa lavapipe): the avatar's silhouette lies
//! where the camera should see it. The expected place comes from projecting the avatar's world
//! joint positions through the camera; the silhouette comes from the rendered pixels.

mod common;

use bevy::prelude::*;
use fitroom::{AppOptions, Mode, headless, kiosk::MirrorCamera};
use fitroom_body::plugin::AvatarJoint;

/// Skin-coloured pixels: the avatar's material is the only warm colour in the room.
fn is_skin(p: &image::Rgba<u8>) -> bool {
    let [r, g, b, _] = p.0.map(i32::from);
    r > 60 && r > b + 25 && r >= g
}

#[test]
fn avatar_silhouette_is_where_the_camera_looks() {
    let options = AppOptions::with_defaults(Mode::Headless { render: true }).expect("assets");
    let mut app = headless::headless_app(&options).expect("app builds");
    for _ in 0..45 {
        app.update();
    }
    let image = headless::capture(&mut app).expect("lavapipe renders an image");
    let path = common::out_dir().join("silhouette.png");
    image.save(&path).expect("screenshot saved");
    println!("screenshot: {}", path.display());

    // Project every joint through the camera.
    let world = app.world_mut();
    let mut cameras = world.query_filtered::<(&Camera, &GlobalTransform), With<MirrorCamera>>();
    let (camera, camera_transform) = cameras.single(world).expect("one mirror camera");
    let (camera, camera_transform) = (camera.clone(), *camera_transform);
    let mut joints = world.query::<(&AvatarJoint, &GlobalTransform)>();
    let projected: Vec<Vec2> = joints
        .iter(world)
        .filter_map(|(_, t)| {
            camera
                .world_to_viewport(&camera_transform, t.translation())
                .ok()
        })
        .collect();
    assert!(projected.len() > 50, "joints in view: {}", projected.len());
    let min = projected
        .iter()
        .fold(Vec2::splat(f32::MAX), |a, p| a.min(*p));
    let max = projected
        .iter()
        .fold(Vec2::splat(f32::MIN), |a, p| a.max(*p));
    // The skin extends a little beyond the joints (head top, shoulders, soles).
    let margin = (max - min) * 0.15 + Vec2::splat(6.0);
    let (lo, hi) = (min - margin, max + margin);
    let (w, h) = (image.width() as f32, image.height() as f32);
    assert!(
        lo.x > 0.0 && lo.y > 0.0 && hi.x < w && hi.y < h,
        "the avatar is cut off: {lo} {hi} in {w}x{h}"
    );

    let mut inside = 0usize;
    let mut outside = 0usize;
    for (x, y, p) in image.enumerate_pixels() {
        if is_skin(p) {
            let q = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
            if q.cmpge(lo).all() && q.cmple(hi).all() {
                inside += 1
            } else {
                outside += 1
            }
        }
    }
    let box_area = (max - min).x.max(1.0) * (max - min).y.max(1.0);
    println!("skin pixels: {inside} inside, {outside} outside; joint box {min} .. {max}");
    assert!(
        inside as f32 > 0.12 * box_area,
        "too little avatar in the expected box: {inside} px vs box {box_area}"
    );
    assert!(
        outside as f32 <= 0.02 * inside as f32,
        "skin outside the expected box: {outside}"
    );
    // The silhouette fills the box from top to bottom: the head and the feet are drawn.
    let rows: Vec<u32> = image
        .enumerate_pixels()
        .filter(|(_, _, p)| is_skin(p))
        .map(|(_, y, _)| y)
        .collect();
    let top = *rows.iter().min().expect("skin") as f32;
    let bottom = *rows.iter().max().expect("skin") as f32;
    assert!(
        (top - min.y).abs() < 0.2 * (max.y - min.y),
        "head top {top} vs joints {}",
        min.y
    );
    assert!(
        (bottom - max.y).abs() < 0.2 * (max.y - min.y),
        "soles {bottom} vs joints {}",
        max.y
    );
}
