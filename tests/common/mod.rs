//! Helpers shared by the workspace tests.
#![allow(dead_code)]

use std::path::PathBuf;

use fitroom::{AppOptions, Mode, sensors::SensorSpec};

/// Every clip listed in the committed `INDEX.tsv`: (clip name, frame count).
pub fn cmu_index() -> Vec<(String, usize)> {
    fitroom_testdata::cmu_index()
        .into_iter()
        .map(|c| (c.file, c.frames))
        .collect()
}

/// Fails the test, with the command's stderr and `what` it was, unless it succeeded.
#[track_caller]
pub fn assert_succeeded(out: &std::process::Output, what: impl std::fmt::Display) {
    assert!(
        out.status.success(),
        "{what}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Where test outputs (screenshots, reports) go.
pub fn out_dir() -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("fitroom-tests");
    std::fs::create_dir_all(&dir).expect("can create the test output folder");
    dir
}

/// The app's defaults with the embedded clip's own skeleton as the sensor (`bvh:`, replayed as
/// recorded): for the tests of what lies downstream of the sensor (motion, garments, rendering,
/// reloads), which should not depend on the tracker. The shipped default films the clip's
/// performer on a treadmill and tracks it (`tests/headless_ecs.rs` runs that chain).
pub fn clip_options(mode: Mode) -> AppOptions {
    let mut options = AppOptions::with_defaults(mode).expect("the shipped assets read");
    options.sensor = SensorSpec::Bvh(options.motion.clone());
    options.treadmill = false;
    options
}

/// A copy of the shipped `assets/kiosk.ron` in a fresh scratch folder named after `name` and
/// this process, each of `edits` (`(from, to)`) replaced once (each must be found): the
/// copy's path and its text.
pub fn kiosk_config_copy(name: &str, edits: &[(&str, &str)]) -> (PathBuf, String) {
    let scratch = std::env::temp_dir().join(format!("fitroom-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&scratch);
    std::fs::create_dir_all(&scratch).expect("scratch folder");
    let shipped = fitroom::assets::assets_dir()
        .expect("assets")
        .join("kiosk.ron");
    let mut text = std::fs::read_to_string(shipped).expect("the shipped configuration");
    for (from, to) in edits {
        assert!(text.contains(from), "the shipped kiosk.ron has `{from}`");
        text = text.replacen(from, to, 1);
    }
    let config = scratch.join("kiosk.ron");
    std::fs::write(&config, &text).expect("write");
    (config, text)
}
