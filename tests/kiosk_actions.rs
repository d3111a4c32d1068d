//! The try-on screen driven by kiosk actions: the keyboard's right arrow twice and Enter
//! dress the avatar in the configuration's third garment (the same actions a hand's two
//! swipes to the right and a grip produce).

mod common;

use bevy::prelude::*;
use fitroom::kiosk::KioskState;
use fitroom::kiosk::actions::TryOn;
use fitroom::{AppOptions, Mode, headless};
use fitroom_garment::plugin::{GarmentRequest, GarmentStatus};

/// The shipped configuration with the garments' files made absolute and a skeleton clip as
/// the sensor (the quickest way into `TryOn`).
fn app() -> App {
    let assets = fitroom::assets::assets_dir().expect("assets");
    let garments = assets.join("garments");
    let clip = assets.join("motions/walk.bvh");
    let garment = |name: &str| {
        (
            format!("\"garments/{name}\""),
            format!("\"{}\"", garments.join(name).display()),
        )
    };
    let edits: Vec<(String, String)> = vec![
        (
            "sensor: \"performer\"".into(),
            format!("sensor: \"bvh:{}\"", clip.display()),
        ),
        garment("sundress.ron"),
        garment("tshirt.ron"),
        garment("skirt.ron"),
        garment("tube_skirt.obj"),
    ];
    let edits: Vec<(&str, &str)> = edits
        .iter()
        .map(|(a, b)| (a.as_str(), b.as_str()))
        .collect();
    let (config, _) = common::kiosk_config_copy("actions", &edits);
    let options =
        AppOptions::with_config(Mode::Headless { render: false }, &config).expect("it reads");
    headless::headless_app(&options).expect("the app builds")
}

fn state(app: &App) -> KioskState {
    *app.world().resource::<State<KioskState>>().get()
}

/// Presses and releases `key` over two updates.
fn tap(app: &mut App, key: KeyCode) {
    app.world_mut()
        .resource_mut::<ButtonInput<KeyCode>>()
        .press(key);
    app.update();
    let mut keys = app.world_mut().resource_mut::<ButtonInput<KeyCode>>();
    keys.release(key);
    keys.clear();
    app.update();
    app.world_mut()
        .resource_mut::<ButtonInput<KeyCode>>()
        .clear();
}

#[test]
fn two_nexts_and_a_select_wear_the_third_garment() {
    let mut app = app();
    if !app.world().contains_resource::<ButtonInput<KeyCode>>() {
        app.init_resource::<ButtonInput<KeyCode>>();
    }
    // Keys before TryOn do nothing.
    tap(&mut app, KeyCode::ArrowRight);
    for _ in 0..400 {
        app.update();
        if state(&app) == KioskState::TryOn {
            break;
        }
    }
    assert_eq!(state(&app), KioskState::TryOn);
    app.update();
    // Entering TryOn dressed the avatar in the first garment.
    let first = app.world().resource::<GarmentRequest>().path.clone();
    assert!(
        first.as_ref().is_some_and(|p| p.ends_with("sundress.ron")),
        "{first:?}"
    );
    assert_eq!(app.world().resource::<TryOn>().shown, 0);
    tap(&mut app, KeyCode::ArrowRight);
    tap(&mut app, KeyCode::ArrowRight);
    assert_eq!(app.world().resource::<TryOn>().shown, 2);
    // Browsing does not dress.
    assert_eq!(app.world().resource::<GarmentRequest>().path, first);
    tap(&mut app, KeyCode::Enter);
    let worn = app.world().resource::<GarmentRequest>().path.clone();
    assert!(
        worn.as_ref().is_some_and(|p| p.ends_with("skirt.ron")),
        "{worn:?}"
    );
    assert_eq!(app.world().resource::<TryOn>().worn, Some(2));
    // The garment loads (on the asset server's threads: wait on the clock) and the avatar
    // wears it.
    let start = std::time::Instant::now();
    while start.elapsed().as_secs() < 60 {
        app.update();
        if app.world().resource::<GarmentStatus>().worn.is_some() {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    let status = app.world().resource::<GarmentStatus>();
    assert!(
        status
            .file
            .as_ref()
            .is_some_and(|p| p.ends_with("skirt.ron"))
            && status
                .worn
                .as_ref()
                .is_some_and(|w| w.to_lowercase().contains("skirt")),
        "{:?} {:?} {:?}",
        status.file,
        status.worn,
        status.error
    );
    // Previous wraps around to the last garment; Back returns to the one worn.
    tap(&mut app, KeyCode::ArrowLeft);
    tap(&mut app, KeyCode::ArrowLeft);
    tap(&mut app, KeyCode::ArrowLeft);
    assert_eq!(app.world().resource::<TryOn>().shown, 3);
    tap(&mut app, KeyCode::Escape);
    assert_eq!(app.world().resource::<TryOn>().shown, 2);
}
