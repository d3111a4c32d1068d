//! Shared helpers of the integration tests: the shipped body asset, and the raw MakeHuman data
//! with the model imported from it when `FITROOM_MAKEHUMAN` names that data.

#![allow(dead_code)]

use std::path::PathBuf;
use std::sync::OnceLock;
use std::time::{Duration, Instant};

use fitroom_body::{BodyModel, ImportReport, import_makehuman_with_report};

/// The raw MakeHuman data when `FITROOM_MAKEHUMAN` names it (it is not committed: the
/// product ships the converted body, `assets/bodies/makehuman.fitbody`, and most tests run on
/// that); `None` prints why the calling test skips its re-import checks.
pub fn makehuman_dir() -> Option<PathBuf> {
    let dir = fitroom_testdata::makehuman_dir();
    if dir.is_none() {
        println!(
            "skipped: set FITROOM_MAKEHUMAN to the MakeHuman data folder to check the importer \
             against the raw files"
        );
    }
    dir
}

pub struct Imported {
    pub model: BodyModel,
    pub report: ImportReport,
    pub import_time: Duration,
}

/// The body imported from the raw MakeHuman data (once per test binary), when
/// [`makehuman_dir`] has it.
pub fn imported() -> Option<&'static Imported> {
    static MODEL: OnceLock<Option<Imported>> = OnceLock::new();
    MODEL
        .get_or_init(|| {
            let dir = makehuman_dir()?;
            let start = Instant::now();
            let (model, report) = import_makehuman_with_report(&dir, &mut |_, _, _| {})
                .unwrap_or_else(|e| panic!("importing {} failed: {e}", dir.display()));
            Some(Imported {
                model,
                report,
                import_time: start.elapsed(),
            })
        })
        .as_ref()
}

/// The body the tests run on: the shipped asset (the importer's output, checked against a
/// fresh import by `makehuman.rs` when the raw data is there).
pub fn model() -> &'static BodyModel {
    asset_model()
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
