//! Shared helpers of the integration tests: where the MakeHuman data is, and the imported
//! model (imported once per test binary).

#![allow(dead_code)]

use std::path::PathBuf;
use std::sync::OnceLock;
use std::time::{Duration, Instant};

use fitroom_body::{BodyModel, ImportReport, import_makehuman_with_report};

/// The MakeHuman data: `$FITROOM_SHARED/data/makehuman`, by default `../shared` next to the
/// project checkout.
pub fn makehuman_dir() -> PathBuf {
    let shared = std::env::var_os("FITROOM_SHARED")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared")));
    shared.join("data/makehuman")
}

pub struct Imported {
    pub model: BodyModel,
    pub report: ImportReport,
    pub import_time: Duration,
}

/// The body imported from the shared data (once per test binary).
pub fn imported() -> &'static Imported {
    static MODEL: OnceLock<Imported> = OnceLock::new();
    MODEL.get_or_init(|| {
        let dir = makehuman_dir();
        let start = Instant::now();
        let (model, report) = import_makehuman_with_report(&dir, &mut |_, _, _| {})
            .unwrap_or_else(|e| panic!("importing {} failed: {e}", dir.display()));
        Imported {
            model,
            report,
            import_time: start.elapsed(),
        }
    })
}

pub fn model() -> &'static BodyModel {
    &imported().model
}

/// The shipped body asset (`assets/bodies/makehuman.fitbody`), read once per test binary.
pub fn asset_model() -> &'static BodyModel {
    static MODEL: OnceLock<BodyModel> = OnceLock::new();
    MODEL.get_or_init(|| {
        let path = std::path::Path::new(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../assets/bodies/makehuman.fitbody"
        ));
        BodyModel::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
    })
}
