//! The device thread: opens the Kinect through libfreenect, streams depth, and on any failure
//! closes everything, reports [`SourceStatus::Disconnected`] and tries again a second later.
//!
//! libfreenect calls the depth callback from inside `freenect_process_events*`, on the thread
//! that called it; the callback reaches Rust state through a thread-local sink
//! ([`crate::callback`]) that this thread installs before any libfreenect call.

use std::ffi::c_int;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::Path;
use std::ptr;
use std::sync::Arc;
use std::time::{Duration, Instant};

use fitroom_depth::fakenect::Recording;
use fitroom_depth::{HEIGHT, PIXELS, WIDTH};

use crate::callback::{self, Progress, Sink, last_log, on_depth, on_log};
use crate::ffi::{self, Context, Device, Freenect, Timeval};
use crate::source::{KinectOptions, Shared, SourceStatus};

/// Wait between attempts to open the device.
const RETRY: Duration = Duration::from_secs(1);
/// A streaming device that sends no frame for this long is lost (a Kinect sends 30 a second).
const FRAME_TIMEOUT: Duration = Duration::from_secs(1);
/// A device just started gets longer for its first frame (the IR projector warms up).
const FIRST_FRAME_TIMEOUT: Duration = Duration::from_secs(2);
/// How long one `freenect_process_events_timeout` call may block, so that a stop request is
/// seen promptly.
const EVENTS_TIMEOUT_US: i64 = 100_000;

/// The thread's body: drives sessions until stopped or ended. Never panics out: a bug inside
/// becomes a `Disconnected` status naming it.
pub(crate) fn run(
    freenect: &Freenect,
    options: &KinectOptions,
    shared: &Arc<Shared>,
    opened: Instant,
) {
    let outcome = catch_unwind(AssertUnwindSafe(|| {
        callback::install(Some(Sink::new(
            Arc::clone(shared),
            options.camera,
            opened,
            options.max_frames,
        )));
        drive(freenect, options, shared);
    }));
    callback::install(None);
    if outcome.is_err() {
        shared.set_status(SourceStatus::Disconnected {
            reason: "the Kinect thread failed (a bug in fitroom_freenect: see the panic message \
                     in the log); reopen the source"
                .into(),
        });
    }
}

/// How a session ended.
enum End {
    /// The consumer dropped the source.
    Stopped,
    /// `max_frames` reached, or fakenect's recording is over.
    Ended,
    /// The device is missing or failed: why, for the status.
    Lost(String),
}

fn drive(freenect: &Freenect, options: &KinectOptions, shared: &Shared) {
    loop {
        if shared.stopping() {
            return;
        }
        if callback::progress().done {
            shared.set_status(SourceStatus::Ended);
            return;
        }
        match session(freenect, options, shared) {
            End::Stopped => return,
            End::Ended => {
                shared.set_status(SourceStatus::Ended);
                return;
            }
            End::Lost(reason) => {
                shared.set_status(SourceStatus::Disconnected { reason });
                if shared.wait_for_stop(RETRY) {
                    return;
                }
            }
        }
    }
}

/// A libfreenect context, shut down on drop.
struct Ctx<'a> {
    freenect: &'a Freenect,
    ptr: *mut Context,
}

impl Drop for Ctx<'_> {
    fn drop(&mut self) {
        // SAFETY: `ptr` came from a successful `freenect_init` and is shut down only here; every
        // device opened through it was closed first (its `Dev` guard is dropped earlier).
        unsafe { (self.freenect.shutdown)(self.ptr) };
    }
}

/// An open device, its depth stream stopped and the device closed on drop.
struct Dev<'a> {
    freenect: &'a Freenect,
    ptr: *mut Device,
    streaming: bool,
}

impl Drop for Dev<'_> {
    fn drop(&mut self) {
        // SAFETY: `ptr` came from a successful `freenect_open_device` and is closed only here,
        // before its context is shut down; stopping a stream libfreenect already stopped (a dead
        // device) only returns an error.
        unsafe {
            if self.streaming {
                (self.freenect.stop_depth)(self.ptr);
            }
            (self.freenect.close_device)(self.ptr);
        }
    }
}

/// One attempt: open the context and the device, stream until stopped, ended or lost.
fn session(freenect: &Freenect, options: &KinectOptions, shared: &Shared) -> End {
    if freenect.replay
        && let Err(reason) = check_recording()
    {
        return End::Lost(reason);
    }
    callback::begin_session();
    let mut ctx = ptr::null_mut();
    // SAFETY: `freenect_init` writes a context pointer through `&mut ctx`; a null USB context
    // asks libfreenect to make its own.
    let r = unsafe { (freenect.init)(&mut ctx, ptr::null_mut()) };
    if r < 0 || ctx.is_null() {
        return End::Lost(format!(
            "no Kinect reachable: libfreenect could not start USB (freenect_init returned \
             {r}{}); is USB available to this process (in a container, pass /dev/bus/usb)?",
            last_log()
        ));
    }
    let ctx = Ctx { freenect, ptr: ctx };
    // SAFETY: `ctx.ptr` is a live context; `on_log` has `freenect_log_cb`'s signature and
    // stays valid (a plain function).
    let count = unsafe {
        (freenect.set_log_level)(ctx.ptr, ffi::LOG_ERROR);
        (freenect.set_log_callback)(ctx.ptr, Some(on_log));
        (freenect.select_subdevices)(ctx.ptr, ffi::DEVICE_CAMERA);
        (freenect.num_devices)(ctx.ptr)
    };
    let index = options.device_index;
    if count < 0 {
        return End::Lost(format!(
            "no Kinect: cannot list USB devices (freenect_num_devices returned {count}{})",
            last_log()
        ));
    }
    if count == 0 {
        return End::Lost(
            "no Kinect connected: plug in a Kinect v1 (its USB cable and its power supply)".into(),
        );
    }
    if index < 0 || index >= count {
        return End::Lost(format!(
            "no Kinect #{index}: {count} connected (device_index counts from 0)"
        ));
    }
    let mut dev = ptr::null_mut();
    // SAFETY: `ctx.ptr` is live; `freenect_open_device` writes a device pointer through
    // `&mut dev`.
    let r = unsafe { (freenect.open_device)(ctx.ptr, &mut dev, index) };
    if r < 0 || dev.is_null() {
        return End::Lost(format!(
            "cannot open Kinect #{index} (freenect_open_device returned {r}{}): another program \
             may hold it, or this user may not access it (install libfreenect's udev rules or \
             join the plugdev group)",
            last_log()
        ));
    }
    let mut dev = Dev {
        freenect,
        ptr: dev,
        streaming: false,
    };
    if let Err(reason) = start_depth(freenect, &dev) {
        return End::Lost(reason);
    }
    dev.streaming = true;
    stream(freenect, &ctx, shared)
}

/// Selects 640x480 11-bit depth, installs the callback and starts the stream.
fn start_depth(freenect: &Freenect, dev: &Dev<'_>) -> Result<(), String> {
    let mode = freenect.depth_mode_11bit();
    let expected_bytes = i32::try_from(PIXELS * 2).unwrap_or(i32::MAX);
    if mode.is_valid == 0
        || usize::try_from(mode.width) != Ok(WIDTH)
        || usize::try_from(mode.height) != Ok(HEIGHT)
        || mode.bytes != expected_bytes
    {
        return Err(format!(
            "{} offers no 640x480 11-bit depth mode (it answered {mode:?}): not libfreenect 0.5?",
            freenect.name
        ));
    }
    // SAFETY: `dev.ptr` is an open device; `mode` came from libfreenect itself; `on_depth` has
    // `freenect_depth_cb`'s signature and copies the buffer out before returning, as the
    // callback contract requires (the buffer holds `mode.bytes`, checked above).
    let (set, start) = unsafe {
        let set = (freenect.set_depth_mode)(dev.ptr, mode);
        (freenect.set_depth_callback)(dev.ptr, Some(on_depth));
        (set, (freenect.start_depth)(dev.ptr))
    };
    if set < 0 || start < 0 {
        return Err(format!(
            "the Kinect refused the depth stream (freenect_set_depth_mode returned {set}, \
             freenect_start_depth {start}{}): replug it",
            last_log()
        ));
    }
    Ok(())
}

/// Processes events until stopped, ended or lost.
fn stream(freenect: &Freenect, ctx: &Ctx<'_>, shared: &Shared) -> End {
    let started = Instant::now();
    loop {
        if shared.stopping() {
            return End::Stopped;
        }
        let r = process_events(freenect, ctx);
        let Progress {
            done,
            last_frame,
            failed,
        } = callback::progress();
        if done {
            return End::Ended;
        }
        if failed {
            return End::Lost("the frame callback failed (a bug in fitroom_freenect)".into());
        }
        if r < 0 {
            if freenect.replay {
                // fakenect returns -1 past its index's last line (and prints a warning).
                return End::Ended;
            }
            return End::Lost(format!(
                "the Kinect stopped answering (freenect_process_events returned {r}{}): \
                 unplugged, or its power supply disconnected?",
                last_log()
            ));
        }
        let silent = last_frame.map_or(started.elapsed(), |t| t.elapsed());
        let limit = last_frame.map_or(FIRST_FRAME_TIMEOUT, |_| FRAME_TIMEOUT);
        if silent > limit {
            return End::Lost(format!(
                "no depth frame for {:.1} s: the Kinect was unplugged or lost its power supply",
                silent.as_secs_f64()
            ));
        }
    }
}

/// One round of libfreenect's event processing: at most 0.1 s on a Kinect; with fakenect, one
/// index line, after sleeping to the recording's pace.
fn process_events(freenect: &Freenect, ctx: &Ctx<'_>) -> c_int {
    match freenect.process_events_timeout {
        Some(process) => {
            let mut timeout = Timeval {
                tv_sec: 0,
                tv_usec: EVENTS_TIMEOUT_US,
            };
            // SAFETY: `ctx.ptr` is live; `timeout` outlives the call. Callbacks run on this
            // thread, inside the call, with no borrow of the sink held here.
            unsafe { process(ctx.ptr, &mut timeout) }
        }
        // SAFETY: as above.
        None => unsafe { (freenect.process_events)(ctx.ptr) },
    }
}

/// fakenect calls `exit(1)` when `FAKENECT_PATH` is unset or names a missing file: check the
/// recording first so that a bad one is a status, not the end of the process.
fn check_recording() -> Result<(), String> {
    let Some(dir) = std::env::var_os("FAKENECT_PATH") else {
        return Err(
            "fakenect is loaded but FAKENECT_PATH is not set: set it to a recording \
                    folder before starting the program"
                .into(),
        );
    };
    Recording::open(Path::new(&dir))
        .map(|_| ())
        .map_err(|e| format!("fakenect cannot replay FAKENECT_PATH: {e}"))
}
