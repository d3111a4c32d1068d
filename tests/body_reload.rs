//! The body file is an asset the app watches: a body file re-written with the same rig (here
//! every vertex raised 5 cm) replaces the avatar's model while the app runs, in the avatar's
//! shape; a file with another rig, and a file that is not a body at all, keep the avatar as it
//! was and say why, naming the file. The whole app, headless, on a scratch copy of the
//! shipped body.

mod common;

use std::path::PathBuf;
use std::time::{Duration, Instant};

use bevy::app::App;
use fitroom::{Mode, headless};
use fitroom_body::BodyModel;
use fitroom_body::plugin::AvatarBody;
use fitroom_body::reload::BodyFile;

fn run_until(app: &mut App, what: &str, done: impl Fn(&App) -> bool) {
    let start = Instant::now();
    while !done(app) {
        assert!(
            start.elapsed() < Duration::from_secs(30),
            "{what}: not within 30 s; body file error {:?}",
            error(app)
        );
        app.update();
        std::thread::sleep(Duration::from_millis(5));
    }
}

fn error(app: &App) -> Option<String> {
    app.world().get_resource::<BodyFile>()?.error.clone()
}

/// Mean height of the avatar's body vertices, metres.
fn mean_y(app: &App) -> f32 {
    let body = app.world().resource::<AvatarBody>();
    let n = body.model.body_vertex_count as usize;
    body.positions[..n].iter().map(|p| p.y).sum::<f32>() / n as f32
}

struct Scratch(PathBuf);

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Writes in place (an editor's save; Bevy 0.19's asset server does not reload a file renamed
/// over the watched one).
fn write_in_place(path: &std::path::Path, model: &BodyModel) {
    std::fs::write(path, model.to_bytes().expect("encodes")).expect("write");
}

#[test]
fn a_rewritten_body_file_reshapes_the_avatar_and_a_bad_one_is_kept_out() {
    let scratch =
        Scratch(std::env::temp_dir().join(format!("fitroom-body-{}", std::process::id())));
    let _ = std::fs::remove_dir_all(&scratch.0);
    std::fs::create_dir_all(&scratch.0).expect("scratch folder");
    let file = scratch.0.join("body.fitbody");
    let mut options = common::clip_options(Mode::Headless { render: false });
    std::fs::copy(&options.body, &file).expect("copy the shipped body");
    options.body = file.clone();
    let model = BodyModel::read(&file).expect("the shipped body reads");

    let mut app = headless::headless_app(&options).expect("app builds");
    run_until(&mut app, "the body file is loaded", |app| {
        app.world().get_resource::<BodyFile>().is_some_and(|f| {
            app.world()
                .resource::<bevy::asset::AssetServer>()
                .is_loaded(&f.handle)
        })
    });
    let before = mean_y(&app);

    // Same rig, every vertex 5 cm higher: the avatar is made again from it.
    let mut raised = model.clone();
    for p in &mut raised.positions {
        p.y += 0.05;
    }
    write_in_place(&file, &raised);
    run_until(&mut app, "the raised body replaces the avatar", |app| {
        (mean_y(app) - before - 0.05).abs() < 1e-3
    });
    assert_eq!(error(&app), None);

    // Another rig (a bone renamed): kept out, and said why.
    let mut other_rig = raised.clone();
    other_rig.bones[1].name.push_str("_renamed");
    write_in_place(&file, &other_rig);
    run_until(&mut app, "the other rig is refused", |app| {
        error(app).is_some_and(|e| e.contains("another rig"))
    });
    assert!((mean_y(&app) - before - 0.05).abs() < 1e-3);

    // Not a body file: kept out, the error names the file.
    std::fs::write(&file, b"not a body").expect("write");
    run_until(&mut app, "the broken file is refused", |app| {
        error(app).is_some_and(|e| e.contains("body.fitbody") && !e.contains("another rig"))
    });
    assert!((mean_y(&app) - before - 0.05).abs() < 1e-3);
    // The app goes on.
    for _ in 0..5 {
        app.update();
    }
}
