//! `freenect-capture`: records a [`KinectSource`]'s depth frames into a fakenect folder.
//!
//! ```text
//! freenect-capture OUT_DIR [--frames N] [--library PATH] [--device I] [--wait-s S]
//! ```
//!
//! With a Kinect: `--frames N` frames are recorded. With fakenect
//! (`LD_LIBRARY_PATH=/usr/lib/x86_64-linux-gnu/fakenect FAKENECT_PATH=<recording>`), `N`
//! defaults to the recording's depth count, so the replay stops at its last frame; the
//! integration test uses this to check that frames come through libfreenect's API bit for bit.
//! Exits 1 with the reason if no frame arrives for `--wait-s` seconds (default 10).

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::{Duration, Instant};

use fitroom_depth::fakenect::{Recording, RecordingWriter};
use fitroom_freenect::{KinectOptions, KinectSource, SourceStatus};

const USAGE: &str =
    "usage: freenect-capture OUT_DIR [--frames N] [--library PATH] [--device I] [--wait-s S]";

struct Args {
    out: PathBuf,
    frames: Option<u64>,
    library: Option<PathBuf>,
    device: i32,
    wait: Duration,
}

fn main() -> ExitCode {
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(message) => {
            eprintln!("freenect-capture: {message}");
            ExitCode::FAILURE
        }
    }
}

fn run() -> Result<(), String> {
    let args = parse_args(std::env::args().skip(1))?;
    let frames = match (args.frames, std::env::var_os("FAKENECT_PATH")) {
        (Some(n), _) => n,
        (None, Some(dir)) => {
            let recording = Recording::open(Path::new(&dir)).map_err(|e| e.to_string())?;
            recording.depth_count() as u64
        }
        (None, None) => return Err(format!("--frames is needed with a Kinect\n{USAGE}")),
    };
    let mut source = KinectSource::open(KinectOptions {
        library: args.library,
        device_index: args.device,
        max_frames: Some(frames),
        ..KinectOptions::default()
    })
    .map_err(|e| e.to_string())?;
    // Created at the first frame, so that a run without frames leaves no empty recording.
    let mut writer = None;
    let mut written = 0u64;
    let mut last = Instant::now();
    while written < frames {
        if let Some(frame) = source.next_timeout(Duration::from_millis(200)) {
            let raw = frame.raw.as_deref().unwrap_or_default();
            let writer = match &mut writer {
                Some(writer) => writer,
                None => {
                    writer.insert(RecordingWriter::create(&args.out).map_err(|e| e.to_string())?)
                }
            };
            writer
                .write_depth(frame.time_s, frame.timestamp, raw)
                .map_err(|e| e.to_string())?;
            written += 1;
            last = Instant::now();
            continue;
        }
        match source.status() {
            SourceStatus::Ended => break,
            status if last.elapsed() > args.wait => {
                return Err(format!(
                    "no frame for {:.0} s after {written} of {frames} ({status:?})",
                    args.wait.as_secs_f64()
                ));
            }
            _ => {}
        }
    }
    let dropped = source.dropped_frames();
    let replay = if source.is_replay() {
        " (fakenect)"
    } else {
        ""
    };
    let library = source.library().to_owned();
    drop(source);
    println!(
        "captured {written} of {frames} depth frames from {}{replay} into {} ({dropped} dropped)",
        library,
        args.out.display()
    );
    if written < frames {
        return Err(format!(
            "the source ended after {written} of {frames} frames"
        ));
    }
    Ok(())
}

fn parse_args(mut args: impl Iterator<Item = String>) -> Result<Args, String> {
    let mut out = None;
    let mut parsed = Args {
        out: PathBuf::new(),
        frames: None,
        library: None,
        device: 0,
        wait: Duration::from_secs(10),
    };
    while let Some(arg) = args.next() {
        let mut value = |name: &str| {
            args.next()
                .ok_or_else(|| format!("{name} needs a value\n{USAGE}"))
        };
        let number = |name: &str, text: String| {
            text.parse::<u64>()
                .map_err(|_| format!("{name}: \"{text}\" is not a whole number\n{USAGE}"))
        };
        match arg.as_str() {
            "--frames" => parsed.frames = Some(number("--frames", value("--frames")?)?),
            "--library" => parsed.library = Some(PathBuf::from(value("--library")?)),
            "--device" => {
                let n = number("--device", value("--device")?)?;
                parsed.device = i32::try_from(n).map_err(|_| format!("--device {n}: too large"))?;
            }
            "--wait-s" => {
                parsed.wait = Duration::from_secs(number("--wait-s", value("--wait-s")?)?);
            }
            "-h" | "--help" => return Err(USAGE.into()),
            _ if arg.starts_with('-') => return Err(format!("unknown option {arg}\n{USAGE}")),
            _ if out.is_none() => out = Some(PathBuf::from(arg)),
            _ => {
                return Err(format!(
                    "one output folder expected, got another: {arg}\n{USAGE}"
                ));
            }
        }
    }
    parsed.out = out.ok_or_else(|| format!("no output folder\n{USAGE}"))?;
    Ok(parsed)
}
