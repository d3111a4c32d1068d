//! Mesh garments (OBJ + MTL, binary glTF) are worn in the app like patterns: the same loading
//! path (the asset server and `GarmentSource`) serves the command line and the kiosk. The whole
//! app, headless without a renderer.

mod common;

use std::time::{Duration, Instant};

use fitroom::{Mode, headless};
use fitroom_garment::plugin::GarmentStatus;

fn wears(file: &str) {
    let mut options = common::clip_options(Mode::Headless { render: false });
    options.garment = Some(
        fitroom::assets::assets_dir()
            .expect("assets")
            .join("garments")
            .join(file),
    );
    let mut app = headless::headless_app(&options).expect("app builds");
    let start = Instant::now();
    loop {
        app.update();
        let status = app.world().resource::<GarmentStatus>().clone();
        assert!(status.error.is_none(), "{file}: {:?}", status.error);
        if status.steps >= 60 {
            assert_eq!(
                status.worn.as_deref(),
                Some("tube_skirt one size"),
                "{file}"
            );
            assert!(
                status.particles > 100,
                "{file}: {} particles",
                status.particles
            );
            assert_eq!(status.resets, 0, "{file}: blow-up resets");
            break;
        }
        assert!(
            start.elapsed() < Duration::from_secs(30),
            "{file} was not worn within 30 s: {status:?}"
        );
        std::thread::sleep(Duration::from_millis(2));
    }
}

#[test]
fn an_obj_garment_is_worn_in_the_kiosk() {
    wears("tube_skirt.obj");
}

#[test]
fn a_gltf_garment_is_worn_in_the_kiosk() {
    wears("tube_skirt.glb");
}
