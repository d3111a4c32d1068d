//! Helpers shared by the workspace tests.
#![allow(dead_code)]

use std::path::PathBuf;

/// The shared data folder (`../shared` beside the checkout, or `FITROOM_SHARED`).
pub fn shared_dir() -> PathBuf {
    std::env::var_os("FITROOM_SHARED")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../shared")))
}

pub fn cmu_dir() -> PathBuf {
    shared_dir().join("data/mocap/cmu")
}

/// Every clip listed in `INDEX.tsv`: (file name, frame count).
pub fn cmu_index() -> Vec<(String, usize)> {
    let text = std::fs::read_to_string(cmu_dir().join("INDEX.tsv")).expect("INDEX.tsv is readable");
    text.lines()
        .skip(1)
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            let cols: Vec<&str> = l.split('\t').collect();
            (
                cols[0].to_string(),
                cols[3].parse().expect("frames column is a number"),
            )
        })
        .collect()
}

/// Where test outputs (screenshots, reports) go.
pub fn out_dir() -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("fitroom-tests");
    std::fs::create_dir_all(&dir).expect("can create the test output folder");
    dir
}
