//! The body plugin alone in an app, in the style of Bevy's `tests/how_to_test_systems.rs`:
//! the avatar's joints are spawned where the rest pose puts them, and a new shape reshapes and
//! re-measures the avatar.

mod common;

use std::sync::Arc;

use bevy::prelude::*;
use fitroom_body::{
    Shape,
    plugin::{AvatarBody, AvatarJoint, AvatarMeasurements, AvatarShape, BodyPlugin},
};

fn app() -> App {
    let model = Arc::new(common::asset_model().clone());
    let mut app = App::new();
    app.add_plugins((MinimalPlugins, BodyPlugin { render_mesh: false }))
        .insert_resource(AvatarBody::unshaped(model));
    app
}

fn stature_cm(app: &App) -> f32 {
    let measured = app.world().resource::<AvatarMeasurements>();
    measured
        .measurements
        .as_ref()
        .map(|m| m.stature_cm)
        .unwrap_or_else(|| panic!("the avatar is measured: {:?}", measured.error))
}

#[test]
fn the_avatar_has_a_joint_per_bone_and_follows_its_shape() {
    let mut app = app();
    app.update();
    let bones = common::asset_model().bones.len();
    let mut joints = app.world_mut().query::<&AvatarJoint>();
    assert_eq!(joints.iter(app.world()).count(), bones);
    let default_stature = stature_cm(&app);
    assert!(
        (160.0..175.0).contains(&default_stature),
        "{default_stature}"
    );

    app.world_mut().resource_mut::<AvatarShape>().0 = Shape {
        height: 1.0,
        ..Shape::default()
    };
    app.update();
    let tall = stature_cm(&app);
    assert!(
        tall > default_stature + 5.0,
        "{default_stature} -> {tall} cm"
    );

    // An invalid shape keeps the body and says why.
    app.world_mut().resource_mut::<AvatarShape>().0 = Shape {
        height: 7.0,
        ..Shape::default()
    };
    app.update();
    let measured = app.world().resource::<AvatarMeasurements>();
    assert!(
        measured.error.is_some(),
        "an out-of-range slider is reported"
    );
    assert_eq!(stature_cm(&app), tall);
}
