//! Finding the product's `assets/` folder: `FITROOM_ASSETS`, then `assets/` beside the
//! executable or in the working directory, then the source checkout it was built from.

use std::path::PathBuf;

use anyhow::{Result, bail};

/// The converted MakeHuman body, relative to `assets/`.
pub const DEFAULT_BODY: &str = "bodies/makehuman.fitbody";
/// The embedded motion that drives the kiosk without a camera, relative to `assets/`.
pub const DEFAULT_MOTION: &str = "motions/walk.bvh";

/// The assets folder the product reads.
pub fn assets_dir() -> Result<PathBuf> {
    let mut candidates = Vec::new();
    if let Some(dir) = std::env::var_os("FITROOM_ASSETS") {
        candidates.push(PathBuf::from(dir));
    }
    if let Ok(exe) = std::env::current_exe()
        && let Some(dir) = exe.parent()
    {
        candidates.push(dir.join("assets"));
    }
    if let Ok(cwd) = std::env::current_dir() {
        candidates.push(cwd.join("assets"));
    }
    candidates.push(PathBuf::from(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/assets"
    )));
    for dir in &candidates {
        if dir.join(DEFAULT_BODY).is_file() {
            return Ok(dir.clone());
        }
    }
    bail!(
        "no assets folder with {DEFAULT_BODY} found (looked in: {}); set FITROOM_ASSETS to the \
         folder, or create the body with `fitroom import makehuman DIR` (DIR: the MakeHuman data, e.g. MakeHuman's MPFB2 asset folder)",
        candidates
            .iter()
            .map(|p| p.display().to_string())
            .collect::<Vec<_>>()
            .join(", ")
    )
}
