//! Opening the source against the libraries found (or not) on the machine: a missing library
//! and one that is not libfreenect are clear errors; the real libfreenect with no Kinect
//! attached (as on CI machines) reports why, never panics, and drops promptly.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use fitroom_freenect::ffi::Freenect;
use fitroom_freenect::{FreenectError, KinectOptions, KinectSource, SourceStatus};

/// Debian 12's libfreenect and fakenect (package libfreenect0.5).
const LIB_DIR: &str = "/usr/lib/x86_64-linux-gnu";

fn installed(path: PathBuf) -> PathBuf {
    assert!(
        path.exists(),
        "{} is missing: install libfreenect with scripts/deps.sh or `sudo apt install \
         libfreenect-dev` (Debian 12)",
        path.display()
    );
    path
}

fn real_library() -> PathBuf {
    installed(Path::new(LIB_DIR).join("libfreenect.so.0.5"))
}

fn fakenect_library() -> PathBuf {
    installed(Path::new(LIB_DIR).join("fakenect/libfreenect.so.0.5"))
}

fn open_with(library: PathBuf) -> Result<KinectSource, FreenectError> {
    KinectSource::open(KinectOptions {
        library: Some(library),
        ..KinectOptions::default()
    })
}

#[test]
fn a_missing_library_is_a_clear_error() {
    let Err(error) = open_with(PathBuf::from("/nonexistent/libfreenect.so.0.5")) else {
        panic!("opened a library that does not exist");
    };
    let message = error.to_string();
    println!("{message}");
    assert!(matches!(error, FreenectError::NotFound { .. }), "{error:?}");
    assert!(message.contains("libfreenect not found"), "{message}");
    assert!(message.contains("apt install libfreenect-dev"), "{message}");
    assert!(
        message.contains("/nonexistent/libfreenect.so.0.5"),
        "{message}"
    );
}

#[test]
fn a_library_without_freenect_is_a_clear_error() {
    // libusb is there whenever libfreenect is (its one dependency), and exports no freenect_*.
    let libusb = installed(Path::new(LIB_DIR).join("libusb-1.0.so.0"));
    let Err(error) = open_with(libusb) else {
        panic!("libusb taken for libfreenect");
    };
    println!("{error}");
    assert!(
        matches!(
            error,
            FreenectError::MissingSymbol {
                symbol: "freenect_init",
                ..
            }
        ),
        "{error:?}"
    );
    let Err(error) = open_with(PathBuf::from("/etc/hostname")) else {
        panic!("a text file taken for a library");
    };
    assert!(
        matches!(error, FreenectError::LoadFailed { .. }),
        "{error:?}"
    );
}

/// The by-value `freenect_frame_mode` comes back as the header lays it out, from both
/// libraries; and only fakenect is taken for a replay.
#[test]
fn the_depth_mode_reads_back_from_both_libraries() {
    for (library, replay) in [(real_library(), false), (fakenect_library(), true)] {
        let freenect = Freenect::load(Some(&library)).expect("load");
        let mode = freenect.depth_mode_11bit();
        let what = library.display();
        assert_eq!(freenect.replay, replay, "{what}");
        assert!(freenect.process_events_timeout.is_some(), "{what}");
        assert_eq!(mode.is_valid, 1, "{what}: {mode:?}");
        assert_eq!((mode.width, mode.height), (640, 480), "{what}: {mode:?}");
        assert_eq!(mode.bytes, 640 * 480 * 2, "{what}: {mode:?}");
        assert_eq!(mode.resolution, 1, "{what}: {mode:?}");
        assert_eq!(mode.format, 0, "{what}: 11-bit: {mode:?}");
        assert_eq!(
            (mode.data_bits_per_pixel, mode.padding_bits_per_pixel),
            (11, 5),
            "{what}: {mode:?}"
        );
        assert_eq!(mode.framerate, 30, "{what}: {mode:?}");
    }
}

/// Assumes no Kinect is attached (none is on CI machines): unplug one to run this test.
#[test]
fn no_kinect_is_reported_as_disconnected_and_drops_cleanly() {
    let mut source = open_with(real_library()).expect("the real libfreenect loads");
    assert!(!source.is_replay());
    let started = Instant::now();
    let status = loop {
        let status = source.status();
        if matches!(status, SourceStatus::Disconnected { .. })
            || started.elapsed() > Duration::from_secs(2)
        {
            break status;
        }
        std::thread::sleep(Duration::from_millis(10));
    };
    println!("after {:.2?}: {status:?}", started.elapsed());
    let SourceStatus::Disconnected { reason } = status else {
        panic!("expected Disconnected within 2 s (is a Kinect attached?), got {status:?}");
    };
    assert!(reason.contains("no Kinect"), "{reason}");
    assert!(source.try_next().is_none());
    assert!(source.next_timeout(Duration::from_millis(50)).is_none());
    // It keeps retrying (once a second) and still reports the same.
    std::thread::sleep(Duration::from_millis(1200));
    assert!(
        matches!(source.status(), SourceStatus::Disconnected { .. }),
        "{:?}",
        source.status()
    );
    let dropping = Instant::now();
    drop(source);
    let took = dropping.elapsed();
    println!("dropped in {took:.2?}");
    assert!(took < Duration::from_secs(1), "drop took {took:.2?}");
}
