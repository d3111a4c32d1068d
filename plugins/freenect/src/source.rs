//! [`KinectSource`]: the public face of the device thread. The thread and the consumer share
//! one small queue of frames and the status, behind a mutex; a condition variable wakes a
//! consumer waiting for a frame and the thread waiting to retry.

use std::collections::VecDeque;
use std::path::PathBuf;
use std::sync::{Arc, Condvar, Mutex, MutexGuard, PoisonError};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use fitroom_depth::{DepthCamera, DepthFrame};

use crate::device;
use crate::error::FreenectError;
use crate::ffi::Freenect;

/// Frames kept for a consumer that has not taken them yet. When the queue is full the oldest
/// frame is dropped ([`KinectSource::dropped_frames`] counts them), so a stalled consumer costs
/// at most this many frames of memory (8 x 1.2 MB). Eight frames are 0.27 s at 30 Hz: a
/// consumer that keeps up on average, with hiccups shorter than that, loses none, which the
/// fakenect replay test relies on.
pub const QUEUE_FRAMES: usize = 8;

/// How the source is opened. The default: the first Kinect through `libfreenect.so.0.5`, no
/// frame limit, [`DepthCamera::default`].
#[derive(Clone, Debug, Default)]
pub struct KinectOptions {
    /// The libfreenect library to load; `None`: `libfreenect.so.0.5` through the loader's
    /// search path (so `LD_LIBRARY_PATH=/usr/lib/x86_64-linux-gnu/fakenect` replays the
    /// recording in `FAKENECT_PATH`).
    pub library: Option<PathBuf>,
    /// Which Kinect, in libfreenect's bus order (0: the first).
    pub device_index: i32,
    /// Stop after this many depth frames and report [`SourceStatus::Ended`]. Needed with
    /// fakenect: set it to the recording's depth count, because fakenect cannot tell "end of
    /// recording" from an error (see the crate docs).
    pub max_frames: Option<u64>,
    /// The camera model stamped on every frame.
    pub camera: DepthCamera,
}

/// What the device thread is doing.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum SourceStatus {
    /// Opening the device; no frame yet.
    Connecting,
    /// Frames are arriving.
    Streaming,
    /// No device, or it stopped answering; the thread retries every second. `reason` says what
    /// happened and what would fix it, for the screen.
    Disconnected { reason: String },
    /// `max_frames` frames were delivered, or fakenect's recording is over: no more frames.
    Ended,
}

/// State shared by the device thread and the consumer.
pub(crate) struct Shared {
    state: Mutex<State>,
    changed: Condvar,
}

struct State {
    frames: VecDeque<DepthFrame>,
    status: SourceStatus,
    stop: bool,
    dropped: u64,
}

impl Shared {
    fn lock(&self) -> MutexGuard<'_, State> {
        // A panic elsewhere while holding the lock leaves consistent data (every update is one
        // assignment or push), so a poisoned lock is used as is.
        self.state.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// Queues a frame (dropping the oldest when full) and marks the source streaming.
    pub(crate) fn push(&self, frame: DepthFrame) {
        let mut state = self.lock();
        if state.frames.len() >= QUEUE_FRAMES {
            state.frames.pop_front();
            state.dropped += 1;
        }
        state.frames.push_back(frame);
        state.status = SourceStatus::Streaming;
        self.changed.notify_all();
    }

    pub(crate) fn set_status(&self, status: SourceStatus) {
        self.lock().status = status;
        self.changed.notify_all();
    }

    pub(crate) fn stopping(&self) -> bool {
        self.lock().stop
    }

    /// Waits up to `timeout` for a stop request; true if one came.
    pub(crate) fn wait_for_stop(&self, timeout: Duration) -> bool {
        let state = self.lock();
        let (state, _) = self
            .changed
            .wait_timeout_while(state, timeout, |s| !s.stop)
            .unwrap_or_else(PoisonError::into_inner);
        state.stop
    }
}

/// The live Kinect depth stream: libfreenect's device driven on its own thread, frames copied
/// out into a small queue. Dropping it stops the thread and closes the device.
pub struct KinectSource {
    shared: Arc<Shared>,
    thread: Option<JoinHandle<()>>,
    replay: bool,
    library: String,
}

impl KinectSource {
    /// Loads libfreenect and starts the device thread. Fails only if the library cannot be
    /// loaded or lacks a function; a missing Kinect is reported by [`Self::status`], and the
    /// thread keeps looking for one.
    pub fn open(options: KinectOptions) -> Result<Self, FreenectError> {
        let freenect = Freenect::load(options.library.as_deref())?;
        let (replay, library) = (freenect.replay, freenect.name.clone());
        let shared = Arc::new(Shared {
            state: Mutex::new(State {
                frames: VecDeque::with_capacity(QUEUE_FRAMES),
                status: SourceStatus::Connecting,
                stop: false,
                dropped: 0,
            }),
            changed: Condvar::new(),
        });
        let thread_shared = Arc::clone(&shared);
        let started = Instant::now();
        let thread = std::thread::Builder::new()
            .name("kinect".into())
            .spawn(move || device::run(&freenect, &options, &thread_shared, started))
            .map_err(FreenectError::Thread)?;
        Ok(Self {
            shared,
            thread: Some(thread),
            replay,
            library,
        })
    }

    /// The oldest queued frame, without waiting; `None` if none is queued.
    pub fn try_next(&mut self) -> Option<DepthFrame> {
        self.shared.lock().frames.pop_front()
    }

    /// The newest queued frame, discarding older ones (for a consumer that only wants the
    /// present, such as a screen).
    pub fn try_latest(&mut self) -> Option<DepthFrame> {
        let mut state = self.shared.lock();
        let newest = state.frames.pop_back();
        state.frames.clear();
        newest
    }

    /// The oldest queued frame, waiting up to `timeout` for one. Returns `None` at once when
    /// the source has [`SourceStatus::Ended`] and the queue is empty.
    pub fn next_timeout(&mut self, timeout: Duration) -> Option<DepthFrame> {
        let state = self.shared.lock();
        let (mut state, _) = self
            .shared
            .changed
            .wait_timeout_while(state, timeout, |s| {
                s.frames.is_empty() && s.status != SourceStatus::Ended
            })
            .unwrap_or_else(PoisonError::into_inner);
        state.frames.pop_front()
    }

    /// What the device thread is doing.
    pub fn status(&self) -> SourceStatus {
        self.shared.lock().status.clone()
    }

    /// Frames dropped because the queue was full (the consumer fell [`QUEUE_FRAMES`] behind).
    pub fn dropped_frames(&self) -> u64 {
        self.shared.lock().dropped
    }

    /// True when the loaded library is fakenect (a replay), not a real libfreenect.
    pub fn is_replay(&self) -> bool {
        self.replay
    }

    /// The library loaded (its name or path as given).
    pub fn library(&self) -> &str {
        &self.library
    }
}

impl Drop for KinectSource {
    /// Asks the thread to stop and waits for it: it closes the device and the libfreenect
    /// context first. Takes at most one `freenect_process_events_timeout` call (0.1 s on a
    /// Kinect; with fakenect, the recording's gap to its next line).
    fn drop(&mut self) {
        self.shared.lock().stop = true;
        self.shared.changed.notify_all();
        if let Some(thread) = self.thread.take() {
            // The thread catches its own panics; a join error has nothing left to clean up.
            let _ = thread.join();
        }
    }
}
