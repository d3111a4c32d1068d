//! Where the tests and benchmarks find their recorded data, and how to read it.
//!
//! The data sits compressed next to this crate (see `data/README.md` for provenance and
//! licences), so a fresh clone of the repository runs every test without any folder beside it:
//! - `mocap/cmu/`: 15 real CMU motion-capture clips (`*.bvh.gz`) and their `INDEX.tsv`;
//! - `ansur2/`: the ANSUR II public anthropometric tables (`*.csv.gz`).
//!
//! The full MakeHuman data (43 MB) is not committed: the product ships the converted body
//! (`assets/bodies/makehuman.fitbody`) and the tests run on it. The tests that re-import the
//! raw MakeHuman files run when `FITROOM_MAKEHUMAN` names that folder ([`makehuman_dir`]).

#![forbid(unsafe_code)]

use std::io::Read;
use std::path::{Path, PathBuf};

/// The folder of this crate, which holds the data.
///
/// Found at run time first: `cargo test` and `cargo bench` set `CARGO_MANIFEST_DIR` to the
/// package they run, inside this workspace, so its nearest ancestor holding `data/` is this
/// checkout's. The path compiled in is the fallback only: a build cache shared by two
/// checkouts reuses this crate compiled in either of them.
pub fn data_dir() -> PathBuf {
    let this_checkout = std::env::var_os("CARGO_MANIFEST_DIR").and_then(|dir| {
        Path::new(&dir)
            .ancestors()
            .map(|a| a.join("data"))
            .find(|d| d.join("mocap/cmu/INDEX.tsv").is_file())
    });
    this_checkout.unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")))
}

/// The CMU clips and their index.
pub fn cmu_dir() -> PathBuf {
    data_dir().join("mocap/cmu")
}

/// The compressed file of the clip named as in `INDEX.tsv` (`"07_01.bvh"`).
pub fn clip_path(file: &str) -> PathBuf {
    cmu_dir().join(format!("{file}.gz"))
}

/// The text of a clip named as in `INDEX.tsv`, decompressed.
pub fn clip_text(file: &str) -> String {
    read_gz_text(&clip_path(file))
}

/// The ANSUR II tables (`ANSUR_II_FEMALE_Public.csv.gz`, `ANSUR_II_MALE_Public.csv.gz`).
pub fn ansur_dir() -> PathBuf {
    data_dir().join("ansur2")
}

/// The raw MakeHuman data folder (`…/data/makehuman` of the project's shared material) when
/// `FITROOM_MAKEHUMAN` names one; `None` otherwise. Tests that need it say they were skipped.
pub fn makehuman_dir() -> Option<PathBuf> {
    let dir = PathBuf::from(std::env::var_os("FITROOM_MAKEHUMAN")?);
    dir.join("3dobjs/base.obj").is_file().then_some(dir)
}

/// Reads a gzip-compressed text file; panics with the path on failure (test data only).
pub fn read_gz_text(path: &Path) -> String {
    let file = std::fs::File::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut text = String::new();
    flate2::read::GzDecoder::new(file)
        .read_to_string(&mut text)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    text
}

/// One row of the clips' `INDEX.tsv`.
#[derive(Clone, Debug)]
pub struct ClipEntry {
    /// The clip's name (`07_01.bvh`); its file is [`ClipEntry::path`].
    pub file: String,
    pub frames: usize,
    pub frame_time: f64,
    pub description: String,
}

impl ClipEntry {
    /// The compressed clip file.
    pub fn path(&self) -> PathBuf {
        clip_path(&self.file)
    }

    /// The MotionBuilder-style clips (the others are cgspeed DAZ-friendly).
    pub fn is_motionbuilder(&self) -> bool {
        self.description.contains("MotionBuilder-style")
    }
}

/// The 15 clips of `INDEX.tsv` (header: file, source repo, source path, frames, frame_time,
/// description), in its order.
pub fn cmu_index() -> Vec<ClipEntry> {
    let path = cmu_dir().join("INDEX.tsv");
    let text = std::fs::read_to_string(&path)
        .unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()));
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
    let entries: Vec<ClipEntry> = lines
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            let cells: Vec<&str> = l.split('\t').collect();
            ClipEntry {
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
