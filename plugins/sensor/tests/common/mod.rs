//! Shared helpers for the BVH tests: the committed CMU clips (`data/mocap/cmu`, compressed) and
//! what INDEX.tsv says about them.

#![allow(dead_code, unused_imports)]

pub use fitroom_testdata::{ClipEntry as IndexEntry, clip_path, clip_text, cmu_index as index};
