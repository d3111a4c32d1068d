//! The garment plugin in an app with the body plugin it dresses (and the asset server it
//! loads through), in the style of Bevy's `tests/how_to_test_systems.rs`: a requested garment
//! is loaded, worn and stepped; another size is worn anew; a file outside the garment folder
//! is refused with a message naming it, and the garment worn stays on.

mod common;

use std::sync::Arc;
use std::time::{Duration, Instant};

use bevy::prelude::*;
use bevy::time::TimeUpdateStrategy;
use fitroom_body::plugin::{AvatarBody, BodyPlugin};
use fitroom_garment::plugin::{GarmentPlugin, GarmentRequest, GarmentStatus, WornGarment};

fn app() -> App {
    let root = common::assets();
    let mut app = App::new();
    // The garment folder is an asset source, registered before the asset plugin.
    fitroom_garment::asset::register_garment_source(&mut app, &root);
    app.add_plugins((
        MinimalPlugins,
        TransformPlugin,
        AssetPlugin {
            file_path: root.to_string_lossy().into_owned(),
            ..default()
        },
        BodyPlugin { render_mesh: false },
        GarmentPlugin { root },
    ))
    .insert_resource(TimeUpdateStrategy::ManualDuration(Duration::from_secs_f64(
        1.0 / 60.0,
    )))
    .insert_resource(AvatarBody::unshaped(Arc::new(common::model().clone())));
    app
}

fn status(app: &App) -> GarmentStatus {
    app.world().resource::<GarmentStatus>().clone()
}

/// Updates until `done` holds (asset loads run on wall-clock time); panics after 30 s.
fn run_until(app: &mut App, what: &str, done: impl Fn(&GarmentStatus) -> bool) {
    let start = Instant::now();
    while !done(&status(app)) {
        assert!(
            start.elapsed() < Duration::from_secs(30),
            "{what}: not within 30 s; {:?}",
            status(app)
        );
        app.update();
        std::thread::sleep(Duration::from_millis(2));
    }
}

fn request(app: &mut App, path: std::path::PathBuf, size: &str) {
    *app.world_mut().resource_mut::<GarmentRequest>() = GarmentRequest {
        path: Some(path),
        size: Some(size.to_owned()),
        compare: None,
    };
}

#[test]
fn a_requested_garment_is_worn_stepped_and_resized() {
    let mut app = app();
    request(&mut app, common::garment_path("skirt"), "M");
    run_until(&mut app, "the skirt is worn and stepped", |s| {
        s.worn.as_deref() == Some("A-line skirt M") && s.steps >= 10
    });
    let worn = status(&app);
    assert_eq!(worn.error, None);
    assert!(worn.particles > 100, "{} particles", worn.particles);
    assert_eq!(worn.resets, 0);
    let mut garments = app.world_mut().query::<&WornGarment>();
    assert_eq!(garments.iter(app.world()).count(), 1);

    request(&mut app, common::garment_path("skirt"), "L");
    run_until(&mut app, "size L is worn", |s| {
        s.worn.as_deref() == Some("A-line skirt L")
    });
    assert_eq!(garments.iter(app.world()).count(), 1);

    // Outside the garment folder: refused, named, and the skirt stays on.
    let outside = std::env::temp_dir().join("not-in-the-garment-folder.ron");
    request(&mut app, outside, "M");
    run_until(&mut app, "the outside file is refused", |s| {
        s.error.is_some()
    });
    let refused = status(&app);
    let message = refused.error.unwrap_or_default();
    assert!(
        message.contains("not-in-the-garment-folder.ron") && message.contains("garment folder"),
        "{message}"
    );
    assert_eq!(refused.worn.as_deref(), Some("A-line skirt L"));
    let steps = refused.steps;
    for _ in 0..10 {
        app.update();
    }
    assert!(
        status(&app).steps > steps,
        "the skirt keeps being simulated"
    );
}

#[test]
fn a_second_size_dresses_the_twin_and_a_bad_one_leaves_only_the_twin_bare() {
    let mut app = app();
    let skirt = common::garment_path("skirt");
    app.world_mut()
        .resource_mut::<GarmentRequest>()
        .clone_from(&GarmentRequest {
            path: Some(skirt.clone()),
            size: Some("M".into()),
            compare: Some("L".into()),
        });
    run_until(&mut app, "M worn, L compared", |s| {
        s.worn.as_deref() == Some("A-line skirt M")
            && s.compare_worn.as_deref() == Some("A-line skirt L")
            && s.steps >= 5
    });
    let mut garments = app.world_mut().query::<&WornGarment>();
    let worn: Vec<(bool, usize)> = garments
        .iter(app.world())
        .map(|g| (g.is_twin(), g.surface().0.len()))
        .collect();
    assert_eq!(worn.len(), 2, "{worn:?}");
    assert_eq!(worn.iter().filter(|w| w.0).count(), 1, "{worn:?}");
    assert!(worn.iter().all(|w| w.1 > 100), "both stepped: {worn:?}");

    app.world_mut().resource_mut::<GarmentRequest>().compare = Some("XXXL".into());
    run_until(&mut app, "the bad size refused", |s| s.error.is_some());
    let refused = status(&app);
    let message = refused.error.clone().unwrap_or_default();
    assert!(
        message.contains("twin") && message.contains("XXXL"),
        "{message}"
    );
    assert_eq!(refused.worn.as_deref(), Some("A-line skirt M"));
    assert_eq!(refused.compare_worn, None);
    app.update();
    assert_eq!(garments.iter(app.world()).count(), 1);
}
