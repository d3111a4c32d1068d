//! The fakenect format: frames written and read back bit for bit, in order, with their RGB
//! and accelerometer lines; and every kind of bad recording refused with an error naming
//! the file (and the index line), never a panic.

use std::path::{Path, PathBuf};

use fitroom_depth::camera::{metres_to_raw, raw_to_mm};
use fitroom_depth::fakenect::{
    AccelState, EntryKind, FakenectError, INDEX, Recording, RecordingWriter,
};
use fitroom_depth::{DepthCamera, PIXELS, RAW_NO_VALUE, WIDTH};

struct Scratch(PathBuf);

impl Scratch {
    fn new(name: &str) -> Self {
        let dir =
            std::env::temp_dir().join(format!("fitroom-fakenect-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        Self(dir)
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// A slanted plane from 1 m (left) to 3.5 m (right), with a hole of no readings and a
/// different offset per frame.
fn raw_frame(k: usize) -> Vec<u16> {
    (0..PIXELS)
        .map(|i| {
            let (u, v) = (i % WIDTH, i / WIDTH);
            if (200..260).contains(&u) && (100..140).contains(&v) {
                return RAW_NO_VALUE;
            }
            let z = 1.0 + 2.5 * u as f32 / WIDTH as f32 + 0.01 * k as f32;
            metres_to_raw(z).expect("in the scale")
        })
        .collect()
}

fn record(dir: &Path, frames: usize) -> Vec<Vec<u16>> {
    let mut writer = RecordingWriter::create(dir).expect("a new folder");
    let mut written = Vec::new();
    for k in 0..frames {
        let t = 100.0 + k as f64 / 30.0;
        writer
            .write_accel(
                t,
                k as u32 * 2_000_000,
                AccelState {
                    accel: [10, -819, 3],
                    tilt_angle: -4,
                    tilt_status: 0,
                },
            )
            .expect("accel");
        let rgb: Vec<u8> = (0..PIXELS * 3).map(|i| ((i + k) % 251) as u8).collect();
        writer
            .write_rgb(t + 0.001, k as u32 * 2_000_000 + 1, &rgb)
            .expect("rgb");
        let raw = raw_frame(k);
        writer
            .write_depth(t + 0.002, k as u32 * 2_000_000 + 2, &raw)
            .expect("depth");
        written.push(raw);
    }
    written
}

#[test]
fn frames_round_trip_bit_for_bit_in_order() {
    let scratch = Scratch::new("roundtrip");
    let written = record(&scratch.0, 5);
    let recording = Recording::open(&scratch.0).expect("reads");
    assert_eq!(recording.depth_count(), 5);
    assert_eq!(recording.entries().len(), 15);
    let frames: Vec<_> = recording
        .depth_frames(DepthCamera::default())
        .collect::<Result<_, _>>()
        .expect("every frame reads");
    assert_eq!(frames.len(), 5);
    for (k, (frame, raw)) in frames.iter().zip(&written).enumerate() {
        assert_eq!(frame.raw.as_deref(), Some(raw.as_slice()), "frame {k}");
        assert_eq!(frame.timestamp, k as u32 * 2_000_000 + 2);
        // Times count from the first line, to the microsecond the names keep.
        assert!(
            (frame.time_s - (k as f64 / 30.0 + 0.002)).abs() < 2e-6,
            "{}",
            frame.time_s
        );
        // Millimetres through the camera's scale; no reading is 0.
        assert_eq!(frame.depth_mm[0], raw_to_mm(raw[0]));
        assert_eq!(frame.depth_mm[120 * WIDTH + 230], 0);
        let rgb = frame.rgb.as_ref().expect("the RGB before it");
        assert_eq!(rgb[0], (k % 251) as u8);
    }
    let accel = recording
        .entries()
        .iter()
        .find(|e| e.kind == EntryKind::Accel)
        .expect("an accel line");
    assert_eq!(
        recording.read_accel(accel).expect("reads"),
        AccelState {
            accel: [10, -819, 3],
            tilt_angle: -4,
            tilt_status: 0
        }
    );
    // The near and far ends of the plane.
    let (near, far) = frames[0].depth_range_mm().expect("readings");
    assert!(
        (995..=1005).contains(&near) && (3450..=3520).contains(&far),
        "{near}-{far}"
    );
    assert!(
        RecordingWriter::create(&scratch.0).is_err(),
        "a recording is not overwritten"
    );
}

/// A recording of one frame with its files, then `damage` applied; the error message.
fn damaged(name: &str, damage: impl FnOnce(&Path)) -> String {
    let scratch = Scratch::new(name);
    record(&scratch.0, 1);
    damage(&scratch.0);
    let result = Recording::open(&scratch.0).and_then(|r| {
        r.depth_frames(DepthCamera::default())
            .collect::<Result<Vec<_>, FakenectError>>()
    });
    match result {
        Ok(_) => panic!("{name}: the damaged recording was accepted"),
        Err(e) => {
            eprintln!("{name}: {e}");
            e.to_string()
        }
    }
}

fn file_of(dir: &Path, prefix: &str) -> PathBuf {
    std::fs::read_dir(dir)
        .expect("folder")
        .map(|e| e.expect("entry").path())
        .find(|p| {
            p.file_name()
                .is_some_and(|n| n.to_string_lossy().starts_with(prefix))
        })
        .expect("the file")
}

#[test]
fn bad_recordings_are_refused_naming_file_and_line() {
    // An index line naming a missing file.
    let m = damaged("missing", |d| {
        std::fs::remove_file(file_of(d, "d-")).expect("rm")
    });
    assert!(
        m.contains("INDEX.txt:3") && m.contains("not in the folder"),
        "{m}"
    );
    // A truncated depth image.
    let m = damaged("truncated", |d| {
        let f = file_of(d, "d-");
        let bytes = std::fs::read(&f).expect("read");
        std::fs::write(&f, &bytes[..bytes.len() / 2]).expect("write");
    });
    assert!(
        m.contains(".pgm") && m.contains("line 3") && m.contains("truncated"),
        "{m}"
    );
    // A wrong header (a big-endian 16-bit PGM of another size).
    let m = damaged("header", |d| {
        let f = file_of(d, "d-");
        let mut bytes = b"P5 320 240 65535\n".to_vec();
        bytes.extend(std::iter::repeat_n(0u8, 320 * 240 * 2));
        std::fs::write(&f, bytes).expect("write");
    });
    assert!(
        m.contains(".pgm") && m.contains("header \"P5 320 240 65535\""),
        "{m}"
    );
    // An unknown prefix.
    let m = damaged("prefix", |d| {
        let index = d.join(INDEX);
        let text = std::fs::read_to_string(&index).expect("read");
        std::fs::write(&index, format!("{text}x-1.000000-3.pgm\n")).expect("write");
    });
    assert!(
        m.contains("INDEX.txt:4") && m.contains("unknown prefix 'x'"),
        "{m}"
    );
    // Garbage bytes for the index and for the image.
    let m = damaged("garbage-index", |d| {
        std::fs::write(d.join(INDEX), [0xff, 0xfe, 0x00, 0x13, 0x80, b'\n', 0x01]).expect("write")
    });
    assert!(m.contains("INDEX.txt:1"), "{m}");
    let m = damaged("garbage-image", |d| {
        std::fs::write(file_of(d, "d-"), [0x13u8; 1000]).expect("write")
    });
    assert!(m.contains(".pgm") && m.contains("no header line"), "{m}");
    // An empty folder, and an index without frames.
    let empty = Scratch::new("empty");
    std::fs::create_dir_all(&empty.0).expect("mkdir");
    let m = Recording::open(&empty.0).expect_err("no index").to_string();
    assert!(
        m.contains("has no INDEX.txt") && m.contains("fitroom sensor record"),
        "{m}"
    );
    std::fs::write(empty.0.join(INDEX), "\n\n").expect("write");
    let m = Recording::open(&empty.0)
        .expect_err("no frames")
        .to_string();
    assert!(m.contains("lists no frame"), "{m}");
}
