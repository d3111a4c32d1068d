//! The live Kinect v1 depth source: the system's libfreenect 0.5 driving the device on its own
//! thread, each frame copied out into a [`fitroom_depth::DepthFrame`].
//!
//! ```no_run
//! use std::time::Duration;
//! use fitroom_freenect::{KinectOptions, KinectSource};
//!
//! let mut kinect = KinectSource::open(KinectOptions::default())?;
//! if let Some(frame) = kinect.next_timeout(Duration::from_secs(2)) {
//!     println!("{:.0} % of pixels have depth", 100.0 * frame.valid_share());
//! } else {
//!     println!("no frame: {:?}", kinect.status());
//! }
//! # Ok::<(), fitroom_freenect::FreenectError>(())
//! ```
//!
//! **Loaded at run time.** libfreenect is opened with `dlopen` (the `libloading` crate) when a
//! source opens, not linked: building fitroom needs neither libfreenect nor its headers, and a
//! machine without it still runs everything else (only opening a [`KinectSource`] fails, with
//! [`FreenectError::NotFound`] saying how to install it). The default name,
//! `libfreenect.so.0.5`, goes through the loader's search path, so
//! `LD_LIBRARY_PATH=/usr/lib/x86_64-linux-gnu/fakenect FAKENECT_PATH=<recording>` swaps in
//! Debian's fakenect, which replays a recording through the same API; or
//! [`KinectOptions::library`] names a library file. [`ffi`] declares only the functions used.
//!
//! **Copy-out rule.** libfreenect lends the depth callback its own buffer, valid only during
//! the call (fakenect frees it right after). The callback copies all 640x480 raw values
//! (11-bit, 2047: no reading) into a new frame at once; no pointer into libfreenect's memory
//! ever leaves the callback. The callback is `extern "C"` and catches every panic, so none
//! unwinds into C.
//!
//! **The thread.** libfreenect calls back from inside `freenect_process_events*`, on the
//! calling thread; the source runs that loop on a thread of its own named `kinect`, and hands
//! frames over through a queue of [`source::QUEUE_FRAMES`] (the oldest dropped when a consumer
//! falls that far behind, so memory stays bounded). Dropping the source stops and joins it.
//!
//! **Disconnect and reconnect.** No Kinect, a failed open, an event-processing error or a
//! second without a frame sets [`SourceStatus::Disconnected`] with a reason for the screen;
//! the thread closes the device and the libfreenect context and tries again every second, so
//! a replugged Kinect streams again without a restart. Nothing here panics on the device's
//! account.
//!
//! **fakenect's limits** (libfreenect 0.5.3, `fakenect/fakenect.c`):
//! - each `freenect_process_events*` call reads one index line (depth, RGB or accelerometer)
//!   and calls at most one callback; the timeout is ignored, and it first sleeps the recorded
//!   gap since the previous line, so a replay runs at the recording's pace (12 frames at
//!   30 Hz: 0.4 s);
//! - past the last line it prints `Warning: No more lines` on stdout and returns -1, on every
//!   later call: set [`KinectOptions::max_frames`] to the recording's depth count to stop
//!   exactly at its end (a replay without it also ends, [`SourceStatus::Ended`], on that -1);
//! - it calls `exit(1)` if `FAKENECT_PATH` is unset or names a missing file: the source checks
//!   the recording ([`fitroom_depth::fakenect::Recording::open`]) before starting, and reports
//!   a bad one as `Disconnected`;
//! - its state is global and never rewinds: one replay per process, however many sources;
//! - RGB lines reach only a video callback, which this source does not install (depth only);
//!   accelerometer lines update state nobody asks for here. Both still take their turn, and
//!   their recorded gaps, in the pacing.

#![deny(clippy::undocumented_unsafe_blocks)]

mod callback;
mod device;
pub mod error;
pub mod ffi;
pub mod source;

pub use error::FreenectError;
pub use ffi::DEFAULT_LIBRARY;
pub use source::{KinectOptions, KinectSource, QUEUE_FRAMES, SourceStatus};
