//! The live source end to end, without a Kinect: a recording written in pure Rust (synthetic
//! camera frames and frames holding every raw value) is replayed
//! by Debian's fakenect through libfreenect's own API (the library the source loads, found
//! through `LD_LIBRARY_PATH`), captured by `freenect-capture` in a child process, and must come
//! back bit for bit, every frame, in order.
//!
//! A child process, because fakenect reads `FAKENECT_PATH` and the loader reads
//! `LD_LIBRARY_PATH` from the process environment, which must be set before it starts.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use fitroom_depth::fakenect::{AccelState, Recording, RecordingWriter};
use fitroom_depth::synthetic::{Label, NoiseSettings, Scene, SyntheticCamera};
use fitroom_depth::{DepthCamera, PIXELS, RAW_NO_VALUE, WIDTH};
use glam::Vec3;

/// Debian 12's fakenect (package libfreenect0.5, pulled in by libfreenect-dev).
const FAKENECT_DIR: &str = "/usr/lib/x86_64-linux-gnu/fakenect";
const FRAMES: usize = 12;
/// A Kinect's timestamp counts 60 MHz ticks: 2,000,000 per frame at 30 Hz.
const TICKS_PER_FRAME: u32 = 2_000_000;

struct Scratch(PathBuf);

impl Scratch {
    fn new(name: &str) -> Self {
        let dir =
            std::env::temp_dir().join(format!("fitroom-freenect-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        Self(dir)
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Frame `k`: for even `k`, the synthetic Kinect v1 seeing a box moving before the wall of a
/// room (every part of its error model, so holes, shadows and noise); for odd `k`, every raw
/// value from 0 to 2046 somewhere, in a pattern that differs per frame, and a block of no
/// readings (2047) that moves with `k`.
fn raw_frame(k: usize) -> Vec<u16> {
    if k.is_multiple_of(2) {
        let mut scene = Scene::room(-0.8, 3.6);
        scene.add_box(
            Vec3::new(-0.4 + 0.1 * k as f32, 0.0, 2.0),
            Vec3::new(0.2, 0.5, 0.15),
            Label::Other,
        );
        let mut camera =
            SyntheticCamera::new(DepthCamera::default(), NoiseSettings::default(), k as u64);
        let frame = camera.render(&scene, k as f64 / 30.0);
        return frame
            .frame
            .raw
            .expect("the synthetic camera gives raw values")
            .to_vec();
    }
    (0..PIXELS)
        .map(|i| {
            let (u, v) = (i % WIDTH, i / WIDTH);
            if (40 * k..40 * k + 64).contains(&u) && (100..180).contains(&v) {
                return RAW_NO_VALUE;
            }
            let mixed = (i.wrapping_mul(7919) ^ (k * 104_729) ^ (i >> 7)) % 2047;
            mixed as u16
        })
        .collect()
}

/// 12 depth frames 1/30 s apart, with accelerometer and RGB lines in between and after (which
/// fakenect reads but does not hand to a depth-only source).
fn write_recording(dir: &Path) -> Recording {
    let mut writer = RecordingWriter::create(dir).expect("create the recording");
    let t0 = 1_700_000_000.0;
    let accel = AccelState {
        accel: [12, -819, 40],
        tilt_angle: 0,
        tilt_status: 0,
    };
    writer.write_accel(t0, 0, accel).expect("accel line");
    let rgb = vec![128u8; PIXELS * 3];
    for k in 0..FRAMES {
        let time = t0 + k as f64 / 30.0;
        let timestamp = 1_000 + k as u32 * TICKS_PER_FRAME;
        writer
            .write_depth(time, timestamp, &raw_frame(k))
            .expect("depth line");
        if k % 4 == 1 {
            writer
                .write_rgb(time + 0.005, timestamp + 10_000, &rgb)
                .expect("rgb line");
        }
    }
    writer
        .write_rgb(t0 + FRAMES as f64 / 30.0, 99, &rgb)
        .expect("trailing rgb line");
    drop(writer);
    Recording::open(dir).expect("the written recording reads back")
}

fn fakenect_library() -> PathBuf {
    let library = Path::new(FAKENECT_DIR).join(fitroom_freenect::DEFAULT_LIBRARY);
    assert!(
        library.exists(),
        "{} is missing: this test replays a recording through Debian's fakenect. Install it \
         with scripts/deps.sh or `sudo apt install libfreenect-dev` (Debian 12)",
        library.display()
    );
    library
}

#[test]
fn fakenect_replay_arrives_bit_for_bit_in_order() {
    fakenect_library();
    let recorded_dir = Scratch::new("recorded");
    let captured_dir = Scratch::new("captured");
    let recorded = write_recording(&recorded_dir.0);
    assert_eq!(recorded.depth_count(), FRAMES);

    let started = Instant::now();
    let output = Command::new(env!("CARGO_BIN_EXE_freenect-capture"))
        .arg(&captured_dir.0)
        .env("LD_LIBRARY_PATH", FAKENECT_DIR)
        .env("FAKENECT_PATH", &recorded_dir.0)
        .output()
        .expect("run freenect-capture");
    let took = started.elapsed();
    let stdout = String::from_utf8_lossy(&output.stdout);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        output.status.success(),
        "freenect-capture failed ({}):\nstdout: {stdout}\nstderr: {stderr}",
        output.status
    );
    println!("{}", stdout.trim());
    assert!(
        stdout.contains("(fakenect)") && stdout.contains("(0 dropped)"),
        "fakenect was not loaded, or frames were dropped: {stdout}"
    );
    // Stopped exactly at the last depth frame: fakenect never ran out of lines.
    assert!(
        !stdout.contains("No more lines"),
        "the source read past the recording: {stdout}"
    );

    let captured = Recording::open(&captured_dir.0).expect("the capture is a recording");
    assert_eq!(captured.depth_count(), FRAMES, "every frame captured, once");
    let camera = DepthCamera::default();
    let pairs = recorded
        .depth_frames(camera)
        .zip(captured.depth_frames(camera));
    let mut times = Vec::new();
    for (k, (want, got)) in pairs.enumerate() {
        let (want, got) = (want.expect("recorded frame"), got.expect("captured frame"));
        assert_eq!(
            got.timestamp, want.timestamp,
            "frame {k}: timestamp, in order"
        );
        assert!(
            got.raw == want.raw,
            "frame {k}: raw depth differs from the recording"
        );
        assert_eq!(got.raw.as_deref(), Some(&raw_frame(k)[..]), "frame {k}");
        times.push(got.time_s);
    }
    // fakenect sleeps each line's recorded gap: the 12 frames span 11/30 s (0.37 s).
    let span = times[FRAMES - 1] - times[0];
    println!("replay: {FRAMES} frames over {span:.3} s, the child ran {took:.2?}");
    assert!(
        (0.3..5.0).contains(&span),
        "frames should arrive at the recorded 30 Hz pace, spanning about 0.37 s, not {span:.3} s"
    );
    assert!(
        times.windows(2).all(|w| w[1] > w[0]),
        "frame times rise: {times:?}"
    );
}
