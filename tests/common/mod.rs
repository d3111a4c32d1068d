//! Helpers shared by the workspace tests.
#![allow(dead_code)]

use std::path::PathBuf;

/// Every clip listed in the committed `INDEX.tsv`: (clip name, frame count).
pub fn cmu_index() -> Vec<(String, usize)> {
    fitroom_testdata::cmu_index()
        .into_iter()
        .map(|c| (c.file, c.frames))
        .collect()
}

/// Where test outputs (screenshots, reports) go.
pub fn out_dir() -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("fitroom-tests");
    std::fs::create_dir_all(&dir).expect("can create the test output folder");
    dir
}
