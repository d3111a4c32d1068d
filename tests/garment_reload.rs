//! Hot reload through the asset server, the whole app headless without a renderer, on copies of
//! the shipped files: editing only the fabric of the worn garment dresses the avatar again in
//! the new fabric; a fabric or garment file edited into a malformed state is reported with its
//! file, line and field while the garment worn stays on and keeps being simulated; fixed files
//! are worn again.

mod common;

use std::path::PathBuf;
use std::time::{Duration, Instant};

use bevy::asset::Assets;
use fitroom::{Mode, headless};
use fitroom_garment::asset::GarmentAsset;
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

fn status(app: &bevy::app::App) -> GarmentStatus {
    app.world().resource::<GarmentStatus>().clone()
}

fn worn_entities(app: &mut bevy::app::App) -> Vec<bevy::ecs::entity::Entity> {
    let world = app.world_mut();
    let mut query =
        world.query_filtered::<bevy::ecs::entity::Entity, bevy::ecs::query::With<WornGarment>>();
    query.iter(world).collect()
}

/// The fabric of the garment asset the avatar was asked to wear.
fn worn_fabric(app: &bevy::app::App) -> Option<fitroom_cloth::Fabric> {
    let assets = app.world().resource::<Assets<GarmentAsset>>();
    let (_, garment) = assets.iter().next()?;
    Some(garment.0.fabric().fabric)
}

/// Updates the app (each update is 1/60 s of the app's clock; the file watcher and the asset
/// loads run on wall-clock time) until `done` holds; panics after 20 s with `what`.
fn run_until(app: &mut bevy::app::App, what: &str, done: impl Fn(&mut bevy::app::App) -> bool) {
    let start = Instant::now();
    while !done(app) {
        assert!(
            start.elapsed() < Duration::from_secs(20),
            "{what}: not within 20 s; status {:?}",
            status(app)
        );
        app.update();
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// The 1-based line of the first line of `text` holding `needle`.
fn line_of(text: &str, needle: &str) -> usize {
    text.lines()
        .position(|l| l.contains(needle))
        .expect("needle present")
        + 1
}

#[test]
fn edits_reload_through_the_asset_server_and_malformed_ones_keep_the_garment() {
    let scratch = Scratch::new();
    let mut options = common::clip_options(Mode::Headless { render: false });
    options.garment = Some(scratch.garment());
    let mut app = headless::headless_app(&options).expect("app builds");
    run_until(&mut app, "the skirt is worn and stepped", |app| {
        status(app).steps >= 10
    });
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

    // Only the fabric is edited (a heavier denim): the garment is dressed again with it.
    let fabric = std::fs::read_to_string(scratch.fabric()).expect("read");
    let density = fitroom_garment::FabricSpec::from_ron_str(&fabric, "denim.ron")
        .expect("the shipped denim")
        .fabric
        .areal_density_kg_m2;
    assert_eq!(
        worn_fabric(&app).map(|f| f.areal_density_kg_m2),
        Some(density)
    );
    let heavier = density * 1.5;
    let heavy_fabric = fabric.replacen(
        "areal_density_kg_m2:",
        &format!("areal_density_kg_m2: {heavier}, //"),
        1,
    );
    assert_ne!(heavy_fabric, fabric);
    std::fs::write(scratch.fabric(), &heavy_fabric).expect("write");
    run_until(
        &mut app,
        "the skirt is dressed in the edited fabric",
        |app| {
            worn_fabric(app).map(|f| f.areal_density_kg_m2) == Some(heavier)
                && worn_entities(app).len() == 1
                && worn_entities(app) != worn
        },
    );
    let reworn = worn_entities(&mut app);
    assert!(status(&app).error.is_none(), "{:?}", status(&app).error);

    // The fabric broken: a value of the wrong type. Reported with file, line and field; the
    // garment stays on and keeps being simulated.
    let bad_fabric = fabric.replacen("friction:", "friction: \"high\", //", 1);
    assert_ne!(bad_fabric, fabric);
    std::fs::write(scratch.fabric(), &bad_fabric).expect("write");
    run_until(&mut app, "the malformed fabric is reported", |app| {
        status(app).error.is_some()
    });
    let error = status(&app).error.unwrap_or_default();
    // (Named as the garment reached it: `<garment dir>/../fabrics/denim.ron`.)
    let place = format!("fabrics/denim.ron:{}:", line_of(&bad_fabric, "friction:"));
    assert!(
        error.contains(&place) && error.contains("in `friction`"),
        "expected `{place}` and the field: {error}"
    );
    let steps = status(&app).steps;
    for _ in 0..30 {
        app.update();
    }
    assert_eq!(worn_entities(&mut app), reworn, "the same garment entity");
    assert!(
        status(&app).steps > steps + 20,
        "the kept garment is still simulated"
    );
    assert_eq!(
        worn_fabric(&app).map(|f| f.areal_density_kg_m2),
        Some(heavier)
    );

    // The garment file broken too: its own file and line are reported.
    std::fs::write(scratch.fabric(), &fabric).expect("write");
    let good = std::fs::read_to_string(scratch.garment()).expect("read");
    let bad = good.replace("fabric: \"denim\"", "fabric: 12");
    assert_ne!(bad, good);
    std::fs::write(scratch.garment(), &bad).expect("write");
    let place = format!(
        "{}:{}:",
        scratch.garment().display(),
        line_of(&bad, "fabric: 12")
    );
    run_until(&mut app, "the malformed garment is reported", |app| {
        status(app)
            .error
            .is_some_and(|e| e.contains(&place) && e.contains("in `fabric`"))
    });
    assert_eq!(worn_entities(&mut app), reworn, "the same garment entity");

    // Both fixed: the skirt is worn anew in the shipped denim, without an error.
    std::fs::write(scratch.garment(), &good).expect("write");
    run_until(&mut app, "the fixed skirt is worn again", |app| {
        status(app).error.is_none()
            && worn_fabric(app).map(|f| f.areal_density_kg_m2) == Some(density)
            && worn_entities(app).len() == 1
            && worn_entities(app) != reworn
    });
    let fixed = status(&app);
    assert_eq!(fixed.resets, 0, "blow-up resets after the reloads");
    assert_eq!(fixed.worn, before.worn);
}
