//! The C callbacks and the thread-local state they reach. libfreenect calls them from inside
//! `freenect_process_events*`, on the device thread: the depth callback copies the frame out
//! of libfreenect's buffer at once into the thread's [`Sink`], and both catch every panic so
//! that none unwinds into C.

use std::cell::RefCell;
use std::ffi::{CStr, c_char, c_int, c_void};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::ptr;
use std::sync::Arc;
use std::time::Instant;

use fitroom_depth::{DepthCamera, DepthFrame, PIXELS};

use crate::ffi::{Context, Device};
use crate::source::Shared;

/// Where the depth callback puts frames. Lives in [`SINK`] on the device thread.
pub(crate) struct Sink {
    shared: Arc<Shared>,
    camera: DepthCamera,
    /// When the source opened: frames' `time_s` counts from here.
    opened: Instant,
    max_frames: Option<u64>,
    /// Frames delivered since the source opened, over all sessions.
    delivered: u64,
    /// The last frame of the current session.
    last_frame: Option<Instant>,
    /// A callback panicked (a bug): the session ends.
    failed: bool,
}

/// What the callbacks did so far, read between `freenect_process_events*` calls.
pub(crate) struct Progress {
    /// `max_frames` frames delivered.
    pub done: bool,
    /// The last frame of the current session.
    pub last_frame: Option<Instant>,
    /// A callback failed (or no sink is installed).
    pub failed: bool,
}

impl Sink {
    pub(crate) fn new(
        shared: Arc<Shared>,
        camera: DepthCamera,
        opened: Instant,
        max_frames: Option<u64>,
    ) -> Self {
        Self {
            shared,
            camera,
            opened,
            max_frames,
            delivered: 0,
            last_frame: None,
            failed: false,
        }
    }

    fn done(&self) -> bool {
        self.max_frames.is_some_and(|max| self.delivered >= max)
    }

    fn deliver(&mut self, raw: Vec<u16>, timestamp: u32) {
        if self.done() {
            return;
        }
        self.delivered += 1;
        self.last_frame = Some(Instant::now());
        let time_s = self.opened.elapsed().as_secs_f64();
        let frame = DepthFrame::from_raw(raw, time_s, timestamp, self.camera);
        self.shared.push(frame);
    }
}

thread_local! {
    static SINK: RefCell<Option<Sink>> = const { RefCell::new(None) };
    /// libfreenect's last log message (level error or worse), for the disconnect reason.
    static LAST_LOG: RefCell<String> = const { RefCell::new(String::new()) };
}

/// Installs (or with `None`, removes) this thread's sink.
pub(crate) fn install(sink: Option<Sink>) {
    SINK.set(sink);
}

/// Starts a session: no frame yet, no log message yet.
pub(crate) fn begin_session() {
    SINK.with_borrow_mut(|s| {
        if let Some(s) = s {
            s.last_frame = None;
        }
    });
    LAST_LOG.with_borrow_mut(String::clear);
}

/// The callbacks' progress. Must not be called from inside a callback.
pub(crate) fn progress() -> Progress {
    SINK.with_borrow(|s| match s {
        Some(s) => Progress {
            done: s.done(),
            last_frame: s.last_frame,
            failed: s.failed,
        },
        None => Progress {
            done: false,
            last_frame: None,
            failed: true,
        },
    })
}

/// `"; libfreenect: <message>"`, or nothing if it logged none.
pub(crate) fn last_log() -> String {
    LAST_LOG.with_borrow(|m| {
        if m.is_empty() {
            String::new()
        } else {
            format!("; libfreenect: {m}")
        }
    })
}

/// `freenect_depth_cb`: copies the frame out of libfreenect's buffer into the sink.
///
/// # Safety
/// `depth` must be null or point to a readable depth frame of the 640x480 11-bit mode
/// (`PIXELS * 2` bytes, any alignment), valid for the duration of the call: libfreenect's
/// contract for the callback in that mode.
pub(crate) unsafe extern "C" fn on_depth(_dev: *mut Device, depth: *mut c_void, timestamp: u32) {
    let outcome = catch_unwind(AssertUnwindSafe(|| {
        if depth.is_null() {
            return;
        }
        let mut raw = vec![0u16; PIXELS];
        // SAFETY: the caller's contract: `depth` holds `PIXELS * 2` readable bytes for this
        // call. fakenect's pointer is just past the PGM header (an odd address), so the copy is
        // bytewise into the aligned `Vec`; u16 samples are native-endian in both.
        unsafe {
            ptr::copy_nonoverlapping(
                depth.cast::<u8>(),
                raw.as_mut_ptr().cast::<u8>(),
                PIXELS * 2,
            );
        }
        SINK.with_borrow_mut(|sink| {
            if let Some(sink) = sink {
                sink.deliver(raw, timestamp);
            }
        });
    }));
    if outcome.is_err() {
        let _ = SINK.try_with(|s| {
            if let Ok(mut s) = s.try_borrow_mut()
                && let Some(s) = s.as_mut()
            {
                s.failed = true;
            }
        });
    }
}

/// `freenect_log_cb`: keeps the last message for the disconnect reason.
///
/// # Safety
/// `msg` must be null or a NUL-terminated string valid for the call (libfreenect passes its
/// formatting buffer, terminated explicitly).
pub(crate) unsafe extern "C" fn on_log(_ctx: *mut Context, _level: c_int, msg: *const c_char) {
    let _ = catch_unwind(|| {
        if msg.is_null() {
            return;
        }
        // SAFETY: the caller's contract: a NUL-terminated string valid during the call.
        let text = unsafe { CStr::from_ptr(msg) }.to_string_lossy();
        let text: String = text.trim().chars().take(200).collect();
        let _ = LAST_LOG.try_with(|m| {
            if let Ok(mut m) = m.try_borrow_mut() {
                *m = text;
            }
        });
    });
}
