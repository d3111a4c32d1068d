//! A garment or fabric file edited into a malformed state while the app runs: the app reports
//! the file, the line and the field, and keeps simulating the garment it had; a fixed file is
//! worn again. The whole app, headless without a renderer, on copies of the shipped files.

use std::path::{Path, PathBuf};
use std::time::{Duration, SystemTime};

use fitroom::{AppOptions, Mode, headless};
use fitroom_garment::plugin::{GarmentStatus, WornGarment};

/// A scratch copy of the skirt with its fabrics and size charts (the relative paths a
/// garment file uses), removed when dropped.
struct Scratch(PathBuf);

impl Scratch {
    fn new() -> Self {
        let root = std::env::temp_dir().join(format!("fitroom-reload-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&root);
        let assets = fitroom::assets::assets_dir().expect("assets");
        for dir in ["garments", "fabrics", "sizecharts"] {
            std::fs::create_dir_all(root.join(dir)).expect("scratch folder");
        }
        for (dir, file) in [
            ("garments", "skirt.ron"),
            ("fabrics", "denim.ron"),
            ("sizecharts", "en13402-female-seed002.ron"),
        ] {
            std::fs::copy(assets.join(dir).join(file), root.join(dir).join(file))
                .expect("copy a shipped file");
        }
        Self(root)
    }

    fn garment(&self) -> PathBuf {
        self.0.join("garments/skirt.ron")
    }

    fn fabric(&self) -> PathBuf {
        self.0.join("fabrics/denim.ron")
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Writes `text` to `path` with a modification time `ahead` seconds from now (so the app's
/// watcher sees a change whatever the file system's time resolution).
fn write(path: &Path, text: &str, ahead: u64) {
    std::fs::write(path, text).expect("write");
    let file = std::fs::File::options()
        .write(true)
        .open(path)
        .expect("open");
    file.set_modified(SystemTime::now() + Duration::from_secs(ahead))
        .expect("set the modification time");
}

fn status(app: &bevy::app::App) -> GarmentStatus {
    app.world().resource::<GarmentStatus>().clone()
}

fn worn_entities(app: &mut bevy::app::App) -> Vec<bevy::ecs::entity::Entity> {
    let world = app.world_mut();
    let mut query =
        world.query_filtered::<bevy::ecs::entity::Entity, bevy::ecs::query::With<WornGarment>>();
    query.iter(world).collect()
}

/// The 1-based line of the first line of `text` holding `needle`.
fn line_of(text: &str, needle: &str) -> usize {
    text.lines()
        .position(|l| l.contains(needle))
        .expect("needle present")
        + 1
}

#[test]
fn a_malformed_edit_is_reported_and_the_garment_kept() {
    let scratch = Scratch::new();
    let mut options =
        AppOptions::with_defaults(Mode::Headless { render: false }).expect("assets exist");
    options.garment = Some(scratch.garment());
    let mut app = headless::headless_app(&options).expect("app builds");
    let mut frames = 0;
    while status(&app).steps < 10 {
        app.update();
        frames += 1;
        assert!(frames < 600, "the skirt was not worn: {:?}", status(&app));
    }
    let before = status(&app);
    assert!(before.error.is_none(), "{:?}", before.error);
    // Loaded on one frame's pose and stepped on a later one's, far away: carried along, not
    // blown up.
    assert_eq!(
        before.resets, 0,
        "blow-up resets while putting the skirt on"
    );
    let worn = worn_entities(&mut app);
    assert_eq!(worn.len(), 1);

    // The garment file: a value of the wrong type. The watcher polls twice a second; the app
    // runs 1/60 s a frame.
    let good = std::fs::read_to_string(scratch.garment()).expect("read");
    let bad = good.replace("fabric: \"denim\"", "fabric: 12");
    assert_ne!(bad, good);
    write(&scratch.garment(), &bad, 5);
    for _ in 0..60 {
        app.update();
    }
    let after = status(&app);
    let error = after
        .error
        .clone()
        .expect("the malformed garment is reported");
    let place = format!(
        "{}:{}:",
        scratch.garment().display(),
        line_of(&bad, "fabric: 12")
    );
    assert!(
        error.starts_with(&place) && error.contains("in `fabric`"),
        "expected `{place}` and the field: {error}"
    );
    assert_eq!(after.worn, before.worn, "the garment worn is kept");
    assert_eq!(worn_entities(&mut app), worn, "the same garment entity");
    assert!(
        after.steps > before.steps + 30,
        "the kept garment is still simulated: {} -> {} steps",
        before.steps,
        after.steps
    );

    // Its fabric: a value of the wrong type (the garment file fixed, so that it reloads).
    let fabric = std::fs::read_to_string(scratch.fabric()).expect("read");
    let bad_fabric = fabric.replacen("friction:", "friction: \"high\", //", 1);
    assert_ne!(bad_fabric, fabric);
    write(&scratch.fabric(), &bad_fabric, 10);
    write(&scratch.garment(), &good, 10);
    for _ in 0..60 {
        app.update();
    }
    let error = status(&app)
        .error
        .expect("the malformed fabric is reported");
    // (Named as the garment reached it: `<garment dir>/../fabrics/denim.ron`.)
    let place = format!("fabrics/denim.ron:{}:", line_of(&bad_fabric, "friction:"));
    assert!(
        error.contains(&place) && error.contains("in `friction`"),
        "expected `{place}` and the field: {error}"
    );
    assert_eq!(worn_entities(&mut app), worn, "the same garment entity");

    // Both fixed: the skirt is worn again, without an error.
    write(&scratch.fabric(), &fabric, 15);
    write(&scratch.garment(), &good, 15);
    for _ in 0..60 {
        app.update();
    }
    let fixed = status(&app);
    assert!(fixed.error.is_none(), "{:?}", fixed.error);
    assert_eq!(fixed.resets, 0, "blow-up resets after the reload");
    assert_eq!(fixed.worn, before.worn);
    let again = worn_entities(&mut app);
    assert_eq!(again.len(), 1);
    assert_ne!(again, worn, "the fixed file is loaded anew");
}
