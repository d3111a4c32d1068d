//! A recording's contact sheet and summary, on recordings written with `RecordingWriter`:
//! the sheet's size, black where there was no reading, the nearer block in another colour
//! than the plane behind it; the summary's counts, rate, readings, range and ground truth.

use std::path::{Path, PathBuf};

use fitroom_depth::camera::{metres_to_raw, raw_to_mm};
use fitroom_depth::fakenect::{AccelState, FakenectError, Recording, RecordingWriter};
use fitroom_depth::sheet::{GAP, GAP_COLOUR, contact_sheet};
use fitroom_depth::summary::summarise;
use fitroom_depth::truth::TRUTH_FILE;
use fitroom_depth::{DepthCamera, HEIGHT, PIXELS, RAW_NO_VALUE, WIDTH};

struct Scratch(PathBuf);

impl Scratch {
    fn new(name: &str) -> Self {
        let dir = std::env::temp_dir().join(format!("fitroom-sheet-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        Self(dir)
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// The hole of no readings: columns 0-63, rows 0-47 (whole blocks at every scale used).
const HOLE: (usize, usize) = (64, 48);
/// The nearer block: columns 320-447, rows 240-335.
const BLOCK_U: std::ops::Range<usize> = 320..448;
const BLOCK_V: std::ops::Range<usize> = 240..336;

/// A plane sloping from 2 m (left) to 3.5 m (right), a block at 1.2 m in front of it and a
/// hole of no readings in the top-left corner; frame `k` moves the plane back by `k` cm.
fn raw_frame(k: usize) -> Vec<u16> {
    (0..PIXELS)
        .map(|i| {
            let (u, v) = (i % WIDTH, i / WIDTH);
            if u < HOLE.0 && v < HOLE.1 {
                RAW_NO_VALUE
            } else if BLOCK_U.contains(&u) && BLOCK_V.contains(&v) {
                metres_to_raw(1.2).expect("in the scale")
            } else {
                metres_to_raw(2.0 + 1.5 * u as f32 / WIDTH as f32 + 0.01 * k as f32)
                    .expect("in the scale")
            }
        })
        .collect()
}

/// `frames` depth frames 1/30 s apart, each after an accelerometer line, and an RGB line
/// every other frame.
fn record(dir: &Path, frames: usize) -> Vec<Vec<u16>> {
    let mut writer = RecordingWriter::create(dir).expect("a new folder");
    let mut written = Vec::new();
    for k in 0..frames {
        let t = 1000.0 + k as f64 / 30.0;
        let timestamp = k as u32 * 2_000_000;
        writer
            .write_accel(t, timestamp, AccelState::default())
            .expect("accel");
        if k % 2 == 0 {
            writer
                .write_rgb(t, timestamp, &vec![128u8; PIXELS * 3])
                .expect("rgb");
        }
        let raw = raw_frame(k);
        writer.write_depth(t, timestamp, &raw).expect("depth");
        written.push(raw);
    }
    written
}

fn pixel(sheet: &fitroom_depth::sheet::Sheet, x: usize, y: usize) -> [u8; 3] {
    let i = (y * sheet.width as usize + x) * 3;
    [sheet.rgb[i], sheet.rgb[i + 1], sheet.rgb[i + 2]]
}

#[test]
fn the_sheet_lays_out_spread_frames_with_holes_black_and_the_block_apart() {
    let scratch = Scratch::new("grid");
    record(&scratch.0, 5);
    let recording = Recording::open(&scratch.0).expect("a recording");
    let camera = DepthCamera::default();
    let scale = 4;
    let sheet = contact_sheet(&recording, camera, 3, 4, scale).expect("a sheet");

    let (tw, th) = (WIDTH / 4, HEIGHT / 4);
    let gap = GAP as usize;
    assert_eq!(sheet.frames, [0, 1, 3, 4]);
    assert_eq!(sheet.width as usize, 3 * tw + 4 * gap);
    assert_eq!(sheet.height as usize, 2 * th + 3 * gap);
    assert_eq!(
        sheet.rgb.len(),
        sheet.width as usize * sheet.height as usize * 3
    );
    // The range comes from the readings: about 1.2 m to 3.5 m.
    assert!(
        (1150..1250).contains(&sheet.near_mm),
        "near {}",
        sheet.near_mm
    );
    assert!((3300..3600).contains(&sheet.far_mm), "far {}", sheet.far_mm);

    for n in 0..4 {
        let (x0, y0) = (gap + (n % 3) * (tw + gap), gap + (n / 3) * (th + gap));
        // The hole, 16x12 thumbnail pixels, is black.
        for y in 0..HOLE.1 / 4 {
            for x in 0..HOLE.0 / 4 {
                assert_eq!(pixel(&sheet, x0 + x, y0 + y), [0, 0, 0], "frame {n}");
            }
        }
        // The block (at 1.2 m, the near end: red) against the plane beside it at the same
        // columns' left (about 2.7 m: cooler).
        let block = pixel(&sheet, x0 + 96, y0 + 72);
        let plane = pixel(&sheet, x0 + 96, y0 + 40);
        assert_ne!(block, plane, "frame {n}");
        assert!(
            block[0] > plane[0] && block[2] <= plane[2],
            "{block:?} {plane:?}"
        );
        assert!(block[0] > 100 && block[0] > block[2], "block {block:?}");
        // Plane colours vary along the slope.
        assert_ne!(
            pixel(&sheet, x0 + 20, y0 + 100),
            pixel(&sheet, x0 + 150, y0 + 100)
        );
    }
    // Gaps, and the empty last cells, are the gap colour.
    assert_eq!(pixel(&sheet, 0, 0), GAP_COLOUR);
    assert_eq!(pixel(&sheet, gap + tw + 1, gap + 5), GAP_COLOUR);
    let last_cell = (gap + 2 * (tw + gap) + 10, gap + th + gap + 10);
    assert_eq!(pixel(&sheet, last_cell.0, last_cell.1), GAP_COLOUR);
}

#[test]
fn a_full_size_sheet_of_one_frame() {
    let scratch = Scratch::new("one");
    let written = record(&scratch.0, 3);
    let recording = Recording::open(&scratch.0).expect("a recording");
    let sheet = contact_sheet(&recording, DepthCamera::default(), 0, 1, 1).expect("a sheet");
    assert_eq!(sheet.frames, [0]);
    assert_eq!(
        (sheet.width as usize, sheet.height as usize),
        (WIDTH + 2 * GAP as usize, HEIGHT + 2 * GAP as usize)
    );
    // Full size: every pixel is the colour of its reading.
    let g = GAP as usize;
    for (i, &raw) in written[0].iter().enumerate().step_by(97) {
        let (u, v) = (i % WIDTH, i / WIDTH);
        let expected =
            fitroom_depth::colour::depth_colour(raw_to_mm(raw), sheet.near_mm, sheet.far_mm);
        assert_eq!(pixel(&sheet, g + u, g + v), expected, "pixel {u},{v}");
    }
}

#[test]
fn a_recording_without_depth_has_no_sheet() {
    let scratch = Scratch::new("rgb-only");
    let mut writer = RecordingWriter::create(&scratch.0).expect("a new folder");
    writer
        .write_rgb(1.0, 1, &vec![0u8; PIXELS * 3])
        .expect("rgb");
    drop(writer);
    let recording = Recording::open(&scratch.0).expect("an RGB recording");
    let error =
        contact_sheet(&recording, DepthCamera::default(), 4, 16, 4).expect_err("no depth to show");
    assert!(matches!(error, FakenectError::NoDepth { .. }), "{error}");
    assert!(error.to_string().contains("INDEX.txt"), "{error}");
    // The summary of such a recording is still a summary.
    let summary = summarise(&scratch.0, DepthCamera::default()).expect("a summary");
    assert_eq!((summary.depth_frames, summary.rgb_frames), (0, 1));
    assert_eq!((summary.fps, summary.valid_share), (0.0, 0.0));
    assert_eq!(summary.depth_range_mm, None);
}

#[test]
fn the_summary_counts_frames_rate_readings_and_range() {
    let scratch = Scratch::new("summary");
    let written = record(&scratch.0, 10);
    let summary = summarise(&scratch.0, DepthCamera::default()).expect("a summary");

    assert_eq!(summary.folder, scratch.0.display().to_string());
    assert_eq!(summary.depth_frames, 10);
    assert_eq!(summary.rgb_frames, 5);
    assert_eq!(summary.accel_records, 10);
    assert!(
        (summary.duration_s - 9.0 / 30.0).abs() < 1e-5,
        "{}",
        summary.duration_s
    );
    // Times are written with six decimals: 30 to within their rounding.
    assert!((summary.fps - 30.0).abs() < 1e-3, "{}", summary.fps);

    let holes = HOLE.0 * HOLE.1;
    assert_eq!(
        written[0].iter().filter(|&&r| r == RAW_NO_VALUE).count(),
        holes
    );
    let expected_share = (PIXELS - holes) as f64 / PIXELS as f64;
    assert!((summary.valid_share - expected_share).abs() < 1e-12);

    let readings = written
        .iter()
        .flatten()
        .filter(|&&r| r != RAW_NO_VALUE)
        .map(|&r| raw_to_mm(r));
    let expected = (
        readings.clone().min().expect("readings"),
        readings.max().expect("readings"),
    );
    assert_eq!(summary.depth_range_mm, Some(expected));
    assert_eq!(
        expected.0,
        raw_to_mm(metres_to_raw(1.2).expect("in the scale"))
    );

    assert!(!summary.ground_truth);
    assert_eq!(summary.ground_truth_lines, None);
}

#[test]
fn the_summary_finds_ground_truth_and_counts_its_lines() {
    let scratch = Scratch::new("truth");
    record(&scratch.0, 4);
    let lines: String = (0..4).map(|k| format!("{{\"frame\":{k}}}\n")).collect();
    std::fs::write(scratch.0.join(TRUTH_FILE), lines + "\n").expect("ground truth");
    let summary = summarise(&scratch.0, DepthCamera::default()).expect("a summary");
    assert!(summary.ground_truth);
    assert_eq!(summary.ground_truth_lines, Some(4));

    // Short by one: reported by the count, not refused.
    std::fs::write(scratch.0.join(TRUTH_FILE), "{}\n{}\n{}").expect("ground truth");
    let summary = summarise(&scratch.0, DepthCamera::default()).expect("a summary");
    assert_eq!(summary.ground_truth_lines, Some(3));
    assert_ne!(summary.ground_truth_lines, Some(summary.depth_frames));
}

#[test]
fn a_single_frame_has_no_rate() {
    let scratch = Scratch::new("single");
    record(&scratch.0, 1);
    let summary = summarise(&scratch.0, DepthCamera::default()).expect("a summary");
    assert_eq!(summary.depth_frames, 1);
    assert_eq!((summary.duration_s, summary.fps), (0.0, 0.0));
}
