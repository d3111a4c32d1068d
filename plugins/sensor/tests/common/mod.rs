//! Shared helpers for the BVH tests: where the CMU clips are and what INDEX.tsv says about them.

#![allow(dead_code)]

use std::path::PathBuf;

/// `$FITROOM_SHARED/data/mocap/cmu` if `FITROOM_SHARED` is set, else the `shared/` directory
/// beside the repository checkout.
pub fn cmu_dir() -> PathBuf {
    match std::env::var_os("FITROOM_SHARED") {
        Some(shared) => PathBuf::from(shared).join("data/mocap/cmu"),
        None => PathBuf::from(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../../shared/data/mocap/cmu"
        )),
    }
}

/// One row of INDEX.tsv.
#[derive(Clone, Debug)]
pub struct IndexEntry {
    pub file: String,
    pub frames: usize,
    pub frame_time: f64,
    pub description: String,
}

impl IndexEntry {
    pub fn path(&self) -> PathBuf {
        cmu_dir().join(&self.file)
    }

    /// The MotionBuilder-style clips (the others are cgspeed DAZ-friendly).
    pub fn is_motionbuilder(&self) -> bool {
        self.description.contains("MotionBuilder-style")
    }
}

/// Parses INDEX.tsv (header: file, source repo, source path, frames, frame_time, description).
pub fn index() -> Vec<IndexEntry> {
    let path = cmu_dir().join("INDEX.tsv");
    let text = std::fs::read_to_string(&path)
        .unwrap_or_else(|e| panic!("cannot read {}: {e} (set FITROOM_SHARED)", path.display()));
    let mut lines = text.lines();
    let header: Vec<&str> = lines
        .next()
        .expect("INDEX.tsv has a header")
        .split('\t')
        .collect();
    let column = |name: &str| {
        header
            .iter()
            .position(|h| *h == name)
            .unwrap_or_else(|| panic!("INDEX.tsv has no column '{name}'"))
    };
    let (file, frames, frame_time, description) = (
        column("file"),
        column("frames"),
        column("frame_time"),
        column("description"),
    );
    let entries: Vec<IndexEntry> = lines
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            let cells: Vec<&str> = l.split('\t').collect();
            IndexEntry {
                file: cells[file].to_string(),
                frames: cells[frames]
                    .parse()
                    .expect("frames column is a whole number"),
                frame_time: cells[frame_time]
                    .parse()
                    .expect("frame_time column is a number"),
                description: cells[description].to_string(),
            }
        })
        .collect();
    assert_eq!(entries.len(), 15, "INDEX.tsv lists the 15 CMU clips");
    entries
}

/// The text of one clip.
pub fn clip_text(file: &str) -> String {
    let path = cmu_dir().join(file);
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()))
}
