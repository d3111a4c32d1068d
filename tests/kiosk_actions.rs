//! The try-on screen driven by kiosk actions: the keyboard's right arrow twice and Enter
//! dress the avatar in the configuration's third garment; so do two swipes to the right and
//! a grip of a scripted person the synthetic Kinect films, end to end (depth -> tracker ->
//! hand reader and swipes -> actions -> the garment worn).

mod common;

use bevy::prelude::*;
use fitroom::kiosk::KioskState;
use fitroom::kiosk::actions::TryOn;
use fitroom::{AppOptions, Mode, headless};
use fitroom_garment::plugin::{GarmentRequest, GarmentStatus};
use fitroom_gesture::plugin::GestureEvent;
use fitroom_gesture::swipe::SwipeDirection;

/// The shipped configuration with the garments' files made absolute and `sensor`, with
/// `edits` besides.
fn app_with(name: &str, sensor: &str, more: &[(&str, &str)], depth_seed: u64) -> App {
    let assets = fitroom::assets::assets_dir().expect("assets");
    let garments = assets.join("garments");
    let garment = |name: &str| {
        (
            format!("\"garments/{name}\""),
            format!("\"{}\"", garments.join(name).display()),
        )
    };
    let mut edits: Vec<(String, String)> = vec![
        (
            "sensor: \"performer\"".into(),
            format!("sensor: \"{sensor}\""),
        ),
        garment("sundress.ron"),
        garment("tshirt.ron"),
        garment("skirt.ron"),
        garment("tube_skirt.obj"),
    ];
    edits.extend(more.iter().map(|(a, b)| (a.to_string(), b.to_string())));
    let edits: Vec<(&str, &str)> = edits
        .iter()
        .map(|(a, b)| (a.as_str(), b.as_str()))
        .collect();
    let (config, _) = common::kiosk_config_copy(name, &edits);
    let mut options =
        AppOptions::with_config(Mode::Headless { render: false }, &config).expect("it reads");
    options.depth_seed = depth_seed;
    headless::headless_app(&options).expect("the app builds")
}

/// A skeleton clip as the sensor (the quickest way into `TryOn`).
fn app() -> App {
    let clip = fitroom::assets::assets_dir()
        .expect("assets")
        .join("motions/walk.bvh");
    app_with("actions", &format!("bvh:{}", clip.display()), &[], 1)
}

/// Updates until the garment requested has loaded and is worn (on the asset server's
/// threads: wait on the clock; the first garment is worn meanwhile); it must be the
/// configuration's third, the skirt.
fn assert_wears_the_skirt(app: &mut App) {
    let start = std::time::Instant::now();
    while start.elapsed().as_secs() < 60 {
        app.update();
        let worn = app.world().resource::<GarmentStatus>().worn.clone();
        if worn.is_some_and(|w| w.to_lowercase().contains("skirt")) {
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
    // The garment loads and the avatar wears it.
    assert_wears_the_skirt(&mut app);
    // Previous wraps around to the last garment; Back returns to the one worn.
    tap(&mut app, KeyCode::ArrowLeft);
    tap(&mut app, KeyCode::ArrowLeft);
    tap(&mut app, KeyCode::ArrowLeft);
    assert_eq!(app.world().resource::<TryOn>().shown, 3);
    tap(&mut app, KeyCode::Escape);
    assert_eq!(app.world().resource::<TryOn>().shown, 2);
}

/// The shipped gesture script (`assets/motions/gestures.ron`) performed before the synthetic
/// Kinect: the person is found and measured (or given up on after 5 s), then swipes right
/// twice with the right hand and grips. Only depth reaches the app: the tracker's skeleton
/// and the hand reader's states make the actions. The avatar then wears the third garment,
/// as with the keys above. The camera's noise seed is 1; `FITROOM_E2E_SEEDS=1,2,3` runs
/// others (a study: the measurement's thread makes runs differ a little anyway).
#[test]
fn a_person_who_swipes_right_twice_and_grips_wears_the_third_garment() {
    let seeds: Vec<u64> = std::env::var("FITROOM_E2E_SEEDS").map_or_else(
        |_| vec![1],
        |s| {
            s.split(',')
                .map(|x| {
                    x.trim()
                        .parse()
                        .expect("FITROOM_E2E_SEEDS: numbers, comma separated")
                })
                .collect()
        },
    );
    let script = fitroom::assets::assets_dir()
        .expect("assets")
        .join("motions/gestures.ron");
    for seed in seeds {
        let mut app = app_with(
            "gestures",
            &format!("performer:{}", script.display()),
            &[("measure_s: 12.0", "measure_s: 5.0")],
            seed,
        );
        // The script: 8.6 s of being measured and standing, two swipes (2.75 s each), the
        // grip (3.6 s), 2 s standing, then a swipe to the left at 19.7 s. Stop at 19 s.
        let mut events = Vec::new();
        let mut try_on_at = None;
        let mut cursor = app
            .world()
            .resource::<Messages<GestureEvent>>()
            .get_cursor();
        for k in 0..(19 * 60) {
            app.update();
            let t = k as f32 / 60.0;
            if try_on_at.is_none() && state(&app) == KioskState::TryOn {
                try_on_at = Some(t);
            }
            let messages = app.world().resource::<Messages<GestureEvent>>();
            events.extend(cursor.read(messages).map(|e| (t, *e)));
        }
        println!("seed {seed}: try on at {try_on_at:?} s; gestures: {events:?}");
        let try_on_at = try_on_at.expect("the kiosk reached Try on");
        assert!(try_on_at < 8.0, "{try_on_at}");
        let kinds: Vec<GestureEvent> = events.iter().map(|e| e.1).collect();
        assert_eq!(
            kinds,
            [
                GestureEvent::Swipe(SwipeDirection::Right),
                GestureEvent::Swipe(SwipeDirection::Right),
                GestureEvent::Press,
                GestureEvent::Release
            ],
            "seed {seed}"
        );
        assert_eq!(state(&app), KioskState::TryOn);
        let tryon = app.world().resource::<TryOn>().clone();
        assert_eq!((tryon.shown, tryon.worn), (2, Some(2)), "seed {seed}");
        assert_wears_the_skirt(&mut app);
    }
}

/// Updates (on the clock: garments load on the asset server's threads) until `done`.
fn update_until(app: &mut App, what: &str, done: impl Fn(&mut App) -> bool) {
    let start = std::time::Instant::now();
    while !done(app) {
        assert!(start.elapsed().as_secs() < 60, "waited a minute for {what}");
        app.update();
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
}

/// The sizes of the garment worn, smallest first, from its size chart.
fn sizes_worn(app: &App) -> Vec<String> {
    let status = app.world().resource::<GarmentStatus>();
    let assets = app
        .world()
        .resource::<Assets<fitroom_garment::asset::GarmentAsset>>();
    let source = status
        .asset
        .as_ref()
        .and_then(|h| assets.get(h))
        .expect("the garment worn is loaded");
    fitroom_measure::garment_size::garment_chart(&source.0)
        .expect("it has a size chart")
        .sizes
        .into_iter()
        .map(|s| s.label)
        .collect()
}

#[test]
fn compare_puts_a_twin_beside_the_avatar_in_the_next_size() {
    let mut app = app();
    if !app.world().contains_resource::<ButtonInput<KeyCode>>() {
        app.init_resource::<ButtonInput<KeyCode>>();
    }
    update_until(&mut app, "the first garment worn in TryOn", |app| {
        state(app) == KioskState::TryOn && app.world().resource::<GarmentStatus>().worn.is_some()
    });
    let sizes = sizes_worn(&app);
    let status = |app: &App| app.world().resource::<GarmentStatus>().clone();
    // Where a size is in the chart (the avatar's, or the twin's).
    let at = |size: Option<&str>| sizes.iter().position(|s| Some(s.as_str()) == size);
    let worn_at = |app: &App| at(status(app).worn_size());
    let first = worn_at(&app).expect("a size of the chart");
    assert!(
        first + 1 < sizes.len(),
        "{sizes:?}: the middle size is worn"
    );

    tap(&mut app, KeyCode::KeyV);
    update_until(&mut app, "the twin dressed", |app| {
        status(app).compare_worn.is_some()
    });
    let dressed = status(&app);
    assert_eq!(at(dressed.compare_size()), Some(first + 1), "{dressed:?}");
    assert_eq!(dressed.error, None);
    // Two simulations, one the twin's; the twin's joints are the avatar's, moved beside it.
    app.update();
    let mut garments = app
        .world_mut()
        .query::<&fitroom_garment::plugin::WornGarment>();
    let twins: Vec<bool> = garments.iter(app.world()).map(|g| g.is_twin()).collect();
    assert_eq!(twins.len(), 2);
    assert_eq!(twins.iter().filter(|&&t| t).count(), 1);
    let offset = app
        .world()
        .resource::<fitroom_body::twin::TwinAvatar>()
        .offset;
    let mut avatar = app
        .world_mut()
        .query::<(&fitroom_body::plugin::AvatarJoint, &GlobalTransform)>();
    let mut bones = std::collections::HashMap::new();
    for (joint, global) in avatar.iter(app.world()) {
        bones.insert(joint.0, global.translation());
    }
    let mut twin = app
        .world_mut()
        .query::<(&fitroom_body::twin::TwinJoint, &GlobalTransform)>();
    let mut followed = 0;
    for (joint, global) in twin.iter(app.world()) {
        let expected = bones[&joint.0] + offset;
        assert!(
            global.translation().distance(expected) < 1e-4,
            "bone {}: {} vs {expected}",
            joint.0,
            global.translation()
        );
        followed += 1;
    }
    assert_eq!(followed, bones.len());
    // A size up moves both along.
    tap(&mut app, KeyCode::ArrowUp);
    update_until(&mut app, "both re-dressed", |app| {
        worn_at(app) == Some(first + 1) && status(app).compare_worn.is_some()
    });
    let expected = if first + 2 < sizes.len() {
        first + 2
    } else {
        first
    };
    assert_eq!(at(status(&app).compare_size()), Some(expected));
    // Compare again: one avatar, one garment.
    tap(&mut app, KeyCode::KeyV);
    update_until(&mut app, "the twin gone", |app| {
        status(app).compare_worn.is_none()
    });
    app.update();
    assert!(
        !app.world()
            .contains_resource::<fitroom_body::twin::TwinAvatar>()
    );
    assert_eq!(twin.iter(app.world()).count(), 0);
    assert_eq!(garments.iter(app.world()).count(), 1);
}
