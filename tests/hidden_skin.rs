//! Rendering test on a software Vulkan driver (Mesa lavapipe): the skin a garment covers is not
//! drawn. The sun dress walks 150 frames of the embedded clip twice, with the covered skin
//! hidden (the default) and drawn; the two images differ only where the body was drawn under
//! the dress. Hidden skin must never open a hole (a pixel where the body was drawn and only the
//! room is now), and the skin that showed through the dress with the body drawn must be gone.

mod common;

use fitroom::{Mode, headless};
use fitroom_body::plugin::HiddenSkin;
use fitroom_garment::plugin::ClothSettings;

/// Skin-coloured pixels: the avatar's material is the only warm colour in the room.
fn is_skin(p: &image::Rgba<u8>) -> bool {
    let [r, g, b, _] = p.0.map(i32::from);
    r > 60 && r > b + 25 && r >= g
}

/// The garment's blue.
fn is_garment(p: &image::Rgba<u8>) -> bool {
    let [r, _, b, _] = p.0.map(i32::from);
    b > r + 40
}

/// The room: the background (25, 28, 36) and the floor's greys, lit or in shadow (124-143,
/// 127-146, 134-155 measured), all a little bluer than grey; not the dress's edges blended
/// with the skin.
fn is_room(p: &image::Rgba<u8>) -> bool {
    let [r, g, b, _] = p.0.map(i32::from);
    (g - r - 3).abs() <= 3 && (b - g - 8).abs() <= 4
}

/// The image after 150 frames of the dress on the walk, with the covered skin hidden or not,
/// and the number of body vertices hidden.
fn dress_after_150_frames(hide: bool) -> (image::RgbaImage, usize) {
    let mut options = common::clip_options(Mode::Headless { render: true });
    let assets = fitroom::assets::assets_dir().expect("assets");
    options.garment = Some(assets.join("garments/sundress.ron"));
    let mut app = headless::headless_app(&options).expect("app builds");
    app.world_mut()
        .resource_mut::<ClothSettings>()
        .hide_covered_skin = hide;
    for _ in 0..150 {
        app.update();
    }
    let hidden = app
        .world()
        .resource::<HiddenSkin>()
        .0
        .as_ref()
        .map_or(0, |h| h.iter().filter(|&&c| c).count());
    let image = headless::capture(&mut app).expect("lavapipe renders an image");
    (image, hidden)
}

#[test]
fn covered_skin_is_hidden_without_holes() {
    let (hiding, hidden) = dress_after_150_frames(true);
    let (drawing, none) = dress_after_150_frames(false);
    for (name, image) in [("hidden", &hiding), ("drawn", &drawing)] {
        let path = common::out_dir().join(format!("dress-skin-{name}.png"));
        image.save(&path).expect("screenshot saved");
        println!("screenshot: {}", path.display());
    }
    assert!(
        hidden > 1000,
        "only {hidden} body vertices hidden under the dress"
    );
    assert_eq!(none, 0, "nothing is hidden when the setting is off");
    let (mut holes, mut covered, mut skin) = (0usize, 0usize, 0usize);
    for (a, b) in hiding.pixels().zip(drawing.pixels()) {
        if is_skin(b) {
            skin += 1;
            if is_garment(a) {
                covered += 1;
            } else if is_room(a) {
                holes += 1;
            }
        }
    }
    println!(
        "{hidden} body vertices hidden; of {skin} skin pixels drawn with the body whole, \
         {covered} show the dress instead, {holes} show the room"
    );
    assert!(
        covered > 50,
        "no skin showing through the dress was hidden: {covered}"
    );
    assert_eq!(holes, 0, "pixels look through the body into the room");
}
