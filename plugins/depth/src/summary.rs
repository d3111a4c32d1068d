//! What a recording holds, in numbers: how many frames of each kind, how long and at what
//! rate, how much of the depth image has readings and over what range, and whether a
//! synthetic recording's ground truth lies beside it. For a listing of recordings (which one
//! to replay, which one is broken) and for a report to carry as JSON.

use std::fs;
use std::io::{BufRead, BufReader};
use std::path::Path;

use crate::camera::DepthCamera;
use crate::fakenect::{EntryKind, FakenectError, Recording};
use crate::truth::TRUTH_FILE;

/// A recording in numbers (see [`summarise`]).
#[derive(Debug, Clone, serde::Serialize)]
pub struct RecordingSummary {
    /// The recording's folder, as given.
    pub folder: String,
    pub depth_frames: usize,
    pub rgb_frames: usize,
    pub accel_records: usize,
    /// From the first depth frame to the last, seconds (0 for one frame).
    pub duration_s: f64,
    /// Depth frames per second, `(depth_frames - 1) / duration_s`; 0 when it cannot be
    /// measured (fewer than two depth frames, or all at one time).
    pub fps: f64,
    /// The share of pixels with a reading, 0-1, the mean over the depth frames (0 without
    /// any).
    pub valid_share: f64,
    /// Nearest and farthest reading over all depth frames, millimetres (`None` without a
    /// single reading).
    pub depth_range_mm: Option<(u16, u16)>,
    /// Whether [`TRUTH_FILE`] lies beside `INDEX.txt`.
    pub ground_truth: bool,
    /// Its non-blank lines, when it is there: one per depth frame if it is complete (a
    /// different count is reported, not refused).
    pub ground_truth_lines: Option<usize>,
}

/// Summarises the recording in `dir`, reading every depth frame (RGB and accelerometer lines
/// are counted, not read). Fails as [`Recording::open`] does, when a depth frame cannot be
/// read, or when the ground-truth file is there but cannot be read.
pub fn summarise(dir: &Path, camera: DepthCamera) -> Result<RecordingSummary, FakenectError> {
    let recording = Recording::open(dir)?;
    let count = |kind| {
        recording
            .entries()
            .iter()
            .filter(|e| e.kind == kind)
            .count()
    };

    let mut depth_frames = 0;
    let mut valid_sum = 0.0;
    let mut range: Option<(u16, u16)> = None;
    let mut times: Option<(f64, f64)> = None;
    for entry in recording.depth_entries() {
        let frame = recording.read_depth(entry, camera)?;
        depth_frames += 1;
        valid_sum += frame.valid_share();
        if let Some((lo, hi)) = frame.depth_range_mm() {
            range = Some(range.map_or((lo, hi), |(a, b)| (a.min(lo), b.max(hi))));
        }
        // The index's own times (the recording machine's clock): the device's timestamps
        // wrap, and a synthetic source's count frames.
        times = Some(times.map_or((entry.time_s, entry.time_s), |(first, _)| {
            (first, entry.time_s)
        }));
    }
    let duration_s = times.map_or(0.0, |(first, last)| last - first);
    let fps = if depth_frames > 1 && duration_s > 0.0 {
        (depth_frames - 1) as f64 / duration_s
    } else {
        0.0
    };

    let truth = dir.join(TRUTH_FILE);
    let ground_truth_lines = if truth.is_file() {
        Some(count_lines(&truth)?)
    } else {
        None
    };

    Ok(RecordingSummary {
        folder: dir.display().to_string(),
        depth_frames,
        rgb_frames: count(EntryKind::Rgb),
        accel_records: count(EntryKind::Accel),
        duration_s,
        fps,
        valid_share: if depth_frames > 0 {
            valid_sum / depth_frames as f64
        } else {
            0.0
        },
        depth_range_mm: range,
        ground_truth: ground_truth_lines.is_some(),
        ground_truth_lines,
    })
}

/// Non-blank lines of a file, read in pieces (the file may be large; its content is not
/// parsed, nor required to be UTF-8).
fn count_lines(path: &Path) -> Result<usize, FakenectError> {
    let io = |source| FakenectError::Io {
        path: path.to_owned(),
        action: "cannot read",
        source,
    };
    let mut reader = BufReader::new(fs::File::open(path).map_err(io)?);
    let mut line = Vec::new();
    let mut lines = 0;
    loop {
        line.clear();
        if reader.read_until(b'\n', &mut line).map_err(io)? == 0 {
            return Ok(lines);
        }
        if !line.trim_ascii().is_empty() {
            lines += 1;
        }
    }
}
