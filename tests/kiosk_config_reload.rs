//! The kiosk configuration is followed while the app runs: an edit of the timings takes
//! effect; an edit that does not parse keeps the last good configuration, and the error names
//! the file, the line and the field. The whole app, headless, on a scratch copy of the
//! shipped `assets/kiosk.ron`.

mod common;

use std::time::{Duration, Instant};

use fitroom::kiosk::KioskTimings;
use fitroom::kiosk::config::ActiveKioskConfig;
use fitroom::{AppOptions, Mode, headless};

fn run_until(app: &mut bevy::app::App, what: &str, done: impl Fn(&bevy::app::App) -> bool) {
    let start = Instant::now();
    while !done(app) {
        assert!(
            start.elapsed() < Duration::from_secs(20),
            "{what}: not within 20 s"
        );
        app.update();
        std::thread::sleep(Duration::from_millis(5));
    }
}

fn timings(app: &bevy::app::App) -> KioskTimings {
    *app.world().resource::<KioskTimings>()
}

fn config_error(app: &bevy::app::App) -> Option<String> {
    app.world().resource::<ActiveKioskConfig>().error.clone()
}

#[test]
fn an_edited_configuration_takes_effect_and_a_broken_one_is_kept_out() {
    let (config, text) = common::kiosk_config_copy("config", &[]);

    let options =
        AppOptions::with_config(Mode::Headless { render: false }, &config).expect("it reads");
    let mut app = headless::headless_app(&options).expect("app builds");
    for _ in 0..5 {
        app.update();
    }
    assert_eq!(timings(&app).lost_s, 3.0);

    // The timings edited: followed while the app runs.
    let longer = text.replacen("lost_s: 3.0", "lost_s: 7.5", 1);
    assert_ne!(longer, text);
    std::fs::write(&config, &longer).expect("write");
    run_until(&mut app, "the edited timings take effect", |app| {
        timings(app).lost_s == 7.5
    });
    assert!(config_error(&app).is_none());

    // A value of the wrong type: reported, the last good configuration kept.
    let broken = text.replacen("lost_s: 3.0", "lost_s: \"long\"", 1);
    std::fs::write(&config, &broken).expect("write");
    run_until(&mut app, "the broken configuration is reported", |app| {
        config_error(app).is_some()
    });
    let error = config_error(&app).unwrap_or_default();
    let line = broken
        .lines()
        .position(|l| l.contains("lost_s"))
        .expect("line")
        + 1;
    assert!(
        error.contains(&format!("kiosk.ron:{line}:")) && error.contains("lost_s"),
        "{error}"
    );
    assert_eq!(timings(&app).lost_s, 7.5, "the last good timings stay");
    if let Some(scratch) = config.parent() {
        let _ = std::fs::remove_dir_all(scratch);
    }
}
