//! Ground truth beside a recording: `groundtruth.jsonl`, one JSON object per depth frame in
//! the order of `INDEX.txt`, written by the synthetic camera's recorder so that every later
//! evaluation (tracking, measurement, gestures) can run on files. A recording from a device
//! has none.
//!
//! Each line holds the frame's time, the 20 Kinect v1 joints of the avatar in sensor space
//! (the Kinect SDK's order, [`JOINT_NAMES`]) and its body and garment pixels as runs along
//! rows; `body.json` beside it holds what does not change over the recording (the shape and
//! its measurements), as the recorder wrote it.

use std::fs::File;
use std::io::{BufRead, BufReader, BufWriter, Write};
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::camera::{PIXELS, WIDTH};

/// The file of per-frame ground truth.
pub const TRUTH_FILE: &str = "groundtruth.jsonl";
/// The file of the recording's body (shape, measurements).
pub const BODY_FILE: &str = "body.json";

/// The Kinect v1 joints in the order of [`FrameTruth::joints`].
pub const JOINT_NAMES: [&str; 20] = [
    "hip_center",
    "spine",
    "shoulder_center",
    "head",
    "shoulder_left",
    "elbow_left",
    "wrist_left",
    "hand_left",
    "shoulder_right",
    "elbow_right",
    "wrist_right",
    "hand_right",
    "hip_left",
    "knee_left",
    "ankle_left",
    "foot_left",
    "hip_right",
    "knee_right",
    "ankle_right",
    "foot_right",
];

/// The ground truth of one depth frame.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FrameTruth {
    /// Index of the depth frame in the recording.
    pub frame: usize,
    pub time_s: f64,
    pub timestamp: u32,
    /// The avatar's 20 Kinect joints, sensor space, metres ([`JOINT_NAMES`] order).
    pub joints: Vec<[f32; 3]>,
    /// Pixels that see the body, as `[row, first column, end column]` runs.
    pub body_runs: Vec<[u16; 3]>,
    /// Pixels that see the garment, likewise.
    pub garment_runs: Vec<[u16; 3]>,
}

impl FrameTruth {
    /// The pixels of `runs` as a mask over the image.
    pub fn mask(runs: &[[u16; 3]]) -> Vec<bool> {
        let mut mask = vec![false; PIXELS];
        for &[row, start, end] in runs {
            let row = usize::from(row) * WIDTH;
            let (start, end) = (usize::from(start).min(WIDTH), usize::from(end).min(WIDTH));
            if row < PIXELS && start < end {
                mask[row + start..row + end].fill(true);
            }
        }
        mask
    }
}

/// The runs of pixels of `labels` equal to `label`, row by row.
pub fn runs_of(labels: &[u8], label: u8) -> Vec<[u16; 3]> {
    let mut runs = Vec::new();
    for (row, line) in labels.chunks_exact(WIDTH).enumerate() {
        let mut i = 0;
        while i < WIDTH {
            if line[i] != label {
                i += 1;
                continue;
            }
            let start = i;
            while i < WIDTH && line[i] == label {
                i += 1;
            }
            runs.push([row as u16, start as u16, i as u16]);
        }
    }
    runs
}

/// Why ground truth could not be read or written.
#[derive(Debug, thiserror::Error)]
pub enum TruthError {
    #[error("{}: {action}: {source}", path.display())]
    Io {
        path: PathBuf,
        action: &'static str,
        source: std::io::Error,
    },
    #[error("{}:{line}: not a ground-truth line ({problem}); the recorder writes one JSON object per depth frame", path.display())]
    BadLine {
        path: PathBuf,
        line: usize,
        problem: String,
    },
}

/// Appends frames' ground truth to a recording's [`TRUTH_FILE`].
pub struct TruthWriter {
    path: PathBuf,
    out: BufWriter<File>,
}

impl TruthWriter {
    /// Creates (or empties) `dir/groundtruth.jsonl`.
    pub fn create(dir: &Path) -> Result<Self, TruthError> {
        let path = dir.join(TRUTH_FILE);
        let file = File::create(&path).map_err(|source| TruthError::Io {
            path: path.clone(),
            action: "cannot create the ground-truth file",
            source,
        })?;
        Ok(Self {
            path,
            out: BufWriter::new(file),
        })
    }

    pub fn write(&mut self, truth: &FrameTruth) -> Result<(), TruthError> {
        let io = |source| TruthError::Io {
            path: self.path.clone(),
            action: "cannot write",
            source,
        };
        serde_json::to_writer(&mut self.out, truth).map_err(|e| io(e.into()))?;
        self.out.write_all(b"\n").map_err(io)
    }

    /// Writes out what is buffered.
    pub fn finish(mut self) -> Result<(), TruthError> {
        self.out.flush().map_err(|source| TruthError::Io {
            path: self.path.clone(),
            action: "cannot write",
            source,
        })
    }
}

/// The ground truth of the recording in `dir`, `None` when it has none.
pub fn read_truth(dir: &Path) -> Result<Option<Vec<FrameTruth>>, TruthError> {
    let path = dir.join(TRUTH_FILE);
    let file = match File::open(&path) {
        Ok(file) => file,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(source) => {
            return Err(TruthError::Io {
                path,
                action: "cannot open",
                source,
            });
        }
    };
    let mut out = Vec::new();
    for (i, line) in BufReader::new(file).lines().enumerate() {
        let line = line.map_err(|source| TruthError::Io {
            path: path.clone(),
            action: "cannot read",
            source,
        })?;
        if line.trim().is_empty() {
            continue;
        }
        let truth: FrameTruth = serde_json::from_str(&line).map_err(|e| TruthError::BadLine {
            path: path.clone(),
            line: i + 1,
            problem: e.to_string(),
        })?;
        if truth.joints.len() != JOINT_NAMES.len() {
            return Err(TruthError::BadLine {
                path: path.clone(),
                line: i + 1,
                problem: format!("{} joints, 20 expected", truth.joints.len()),
            });
        }
        out.push(truth);
    }
    Ok(Some(out))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn runs_round_trip_through_a_mask() {
        let mut labels = vec![0u8; PIXELS];
        for k in [5, 6, 7, 639, 640, 641, 2000, PIXELS - 1] {
            labels[k] = 1;
        }
        let runs = runs_of(&labels, 1);
        // 639 ends row 0 and 640 starts row 1: separate runs.
        assert_eq!(runs[..3], [[0, 5, 8], [0, 639, 640], [1, 0, 2]]);
        let mask = FrameTruth::mask(&runs);
        assert!((0..PIXELS).all(|k| mask[k] == (labels[k] == 1)));
    }

    #[test]
    fn lines_are_written_and_read_back_and_bad_lines_named() {
        let dir = std::env::temp_dir().join(format!("fitroom-truth-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("scratch folder");
        let truth = FrameTruth {
            frame: 0,
            time_s: 0.5,
            timestamp: 7,
            joints: vec![[0.1, 0.2, 2.5]; 20],
            body_runs: vec![[3, 4, 9]],
            garment_runs: vec![],
        };
        let mut writer = TruthWriter::create(&dir).expect("created");
        writer.write(&truth).expect("written");
        writer
            .write(&FrameTruth {
                frame: 1,
                ..truth.clone()
            })
            .expect("written");
        writer.finish().expect("flushed");
        let read = read_truth(&dir).expect("reads").expect("present");
        assert_eq!(read.len(), 2);
        assert_eq!(read[0], truth);
        std::fs::write(dir.join(TRUTH_FILE), "{\"frame\": 0}\n").expect("written");
        let error = read_truth(&dir)
            .expect_err("a line without joints")
            .to_string();
        assert!(error.contains("groundtruth.jsonl:1:"), "{error}");
        std::fs::remove_dir_all(&dir).expect("cleaned");
        assert!(read_truth(&dir).expect("no folder").is_none());
    }
}
