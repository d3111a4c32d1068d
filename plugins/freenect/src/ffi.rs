//! The part of libfreenect 0.5.3's C API this crate calls (`include/libfreenect.h` at tag
//! v0.5.3), resolved at run time from the loaded library. Only declarations live here; the
//! rules for calling them are in the crate's private `device` and `callback` modules.
//!
//! Every C enum of the header is a 32-bit `int` (the header forces it with `*_DUMMY =
//! 2147483647` members), so they are passed as [`c_int`].

use std::ffi::{c_char, c_int, c_long, c_void};
use std::marker::{PhantomData, PhantomPinned};
use std::path::{Path, PathBuf};

use libloading::Library;

use crate::error::FreenectError;

/// The library's default name: libfreenect 0.5's soname, found through the loader's search
/// path, so `LD_LIBRARY_PATH=/usr/lib/x86_64-linux-gnu/fakenect` selects Debian's fakenect.
pub const DEFAULT_LIBRARY: &str = "libfreenect.so.0.5";

/// `freenect_context`: opaque, only handled by pointer.
#[repr(C)]
pub struct Context {
    _private: [u8; 0],
    _marker: PhantomData<(*mut u8, PhantomPinned)>,
}

/// `freenect_device`: opaque, only handled by pointer.
#[repr(C)]
pub struct Device {
    _private: [u8; 0],
    _marker: PhantomData<(*mut u8, PhantomPinned)>,
}

/// `freenect_frame_mode`, returned and passed by value: 24 bytes, 4-aligned.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct FrameMode {
    /// Internal id; passed back unchanged.
    pub reserved: u32,
    /// `freenect_resolution`.
    pub resolution: c_int,
    /// The union of `int32_t dummy`, `freenect_video_format` and `freenect_depth_format`:
    /// all 32-bit.
    pub format: i32,
    /// Bytes of one frame.
    pub bytes: i32,
    pub width: i16,
    pub height: i16,
    pub data_bits_per_pixel: i8,
    pub padding_bits_per_pixel: i8,
    pub framerate: i8,
    /// 0: the library does not support the mode asked for.
    pub is_valid: i8,
}

const _: () = assert!(size_of::<FrameMode>() == 24 && align_of::<FrameMode>() == 4);

/// `struct timeval` on 64-bit Linux (`time_t`, `suseconds_t`: both `long`).
#[repr(C)]
pub struct Timeval {
    pub tv_sec: c_long,
    pub tv_usec: c_long,
}

/// `FREENECT_RESOLUTION_MEDIUM`: 640x480.
pub const RESOLUTION_MEDIUM: c_int = 1;
/// `FREENECT_DEPTH_11BIT`: 11-bit raw values, one `uint16_t` per pixel.
pub const DEPTH_11BIT: c_int = 0;
/// `FREENECT_DEVICE_CAMERA`: the camera subdevice only (no motor, no audio firmware upload).
pub const DEVICE_CAMERA: c_int = 0x02;
/// `FREENECT_LOG_ERROR`.
pub const LOG_ERROR: c_int = 1;

/// `freenect_depth_cb`: called inside `freenect_process_events*` with the frame's buffer,
/// which is only valid during the call.
pub type DepthCb = unsafe extern "C" fn(dev: *mut Device, depth: *mut c_void, timestamp: u32);
/// `freenect_log_cb`: a formatted, NUL-terminated message.
pub type LogCb = unsafe extern "C" fn(ctx: *mut Context, level: c_int, msg: *const c_char);

type InitFn = unsafe extern "C" fn(*mut *mut Context, *mut c_void) -> c_int;
type CtxFn = unsafe extern "C" fn(*mut Context) -> c_int;
type CtxIntFn = unsafe extern "C" fn(*mut Context, c_int);
type SetLogCbFn = unsafe extern "C" fn(*mut Context, Option<LogCb>);
type OpenFn = unsafe extern "C" fn(*mut Context, *mut *mut Device, c_int) -> c_int;
type DevFn = unsafe extern "C" fn(*mut Device) -> c_int;
type FindModeFn = unsafe extern "C" fn(c_int, c_int) -> FrameMode;
type SetModeFn = unsafe extern "C" fn(*mut Device, FrameMode) -> c_int;
type SetDepthCbFn = unsafe extern "C" fn(*mut Device, Option<DepthCb>);
type EventsTimeoutFn = unsafe extern "C" fn(*mut Context, *mut Timeval) -> c_int;

/// The loaded library and the functions this crate calls. The pointers stay valid as long as
/// `_library` is loaded, which is as long as this struct lives.
pub struct Freenect {
    pub init: InitFn,
    pub shutdown: CtxFn,
    pub set_log_level: CtxIntFn,
    pub set_log_callback: SetLogCbFn,
    pub select_subdevices: CtxIntFn,
    pub num_devices: CtxFn,
    pub open_device: OpenFn,
    pub close_device: DevFn,
    pub find_depth_mode: FindModeFn,
    pub set_depth_mode: SetModeFn,
    pub set_depth_callback: SetDepthCbFn,
    pub start_depth: DevFn,
    pub stop_depth: DevFn,
    /// Absent in some builds: then [`Self::process_events`] (which blocks up to 60 s on a
    /// real device) is the fallback.
    pub process_events_timeout: Option<EventsTimeoutFn>,
    pub process_events: CtxFn,
    /// The library is fakenect, which replays a recording: it lacks
    /// `freenect_list_device_attributes`, which every real libfreenect 0.5 exports.
    pub replay: bool,
    /// What was loaded, for messages.
    pub name: String,
    _library: Library,
}

impl Freenect {
    /// Loads `library`, or [`DEFAULT_LIBRARY`] through the loader's search path, and resolves
    /// every function.
    pub fn load(library: Option<&Path>) -> Result<Self, FreenectError> {
        let name = library.map_or_else(|| DEFAULT_LIBRARY.to_owned(), |p| p.display().to_string());
        if let Some(path) = library.filter(|p| !p.exists()) {
            return Err(FreenectError::NotFound {
                library: name,
                detail: format!("no file {}", path.display()),
            });
        }
        let target = library.map_or_else(|| PathBuf::from(DEFAULT_LIBRARY), Path::to_path_buf);
        // SAFETY: loading runs the library's ELF initialisers. libfreenect 0.5 and fakenect
        // have none of their own (only the C runtime's and libusb's, which set no process
        // state Rust relies on), and the library stays loaded while `Freenect` lives.
        let loaded = unsafe { Library::new(&target) };
        let lib = loaded.map_err(|e| match library {
            Some(path) => FreenectError::LoadFailed {
                library: path.to_owned(),
                detail: e.to_string(),
            },
            None => FreenectError::NotFound {
                library: name.clone(),
                detail: e.to_string(),
            },
        })?;
        let replay = {
            // SAFETY: only the symbol's presence is asked; the pointer is never called.
            let found =
                unsafe { lib.get::<unsafe extern "C" fn()>(b"freenect_list_device_attributes") };
            found.is_err()
        };
        let n = name.as_str();
        // SAFETY: each field's type is the C declaration of the same name in libfreenect.h
        // v0.5.3 (fakenect defines them with the same signatures), transcribed above; the
        // pointers are only called while `_library`, stored alongside, keeps them mapped.
        unsafe {
            Ok(Self {
                init: resolve(&lib, n, "freenect_init")?,
                shutdown: resolve(&lib, n, "freenect_shutdown")?,
                set_log_level: resolve(&lib, n, "freenect_set_log_level")?,
                set_log_callback: resolve(&lib, n, "freenect_set_log_callback")?,
                select_subdevices: resolve(&lib, n, "freenect_select_subdevices")?,
                num_devices: resolve(&lib, n, "freenect_num_devices")?,
                open_device: resolve(&lib, n, "freenect_open_device")?,
                close_device: resolve(&lib, n, "freenect_close_device")?,
                find_depth_mode: resolve(&lib, n, "freenect_find_depth_mode")?,
                set_depth_mode: resolve(&lib, n, "freenect_set_depth_mode")?,
                set_depth_callback: resolve(&lib, n, "freenect_set_depth_callback")?,
                start_depth: resolve(&lib, n, "freenect_start_depth")?,
                stop_depth: resolve(&lib, n, "freenect_stop_depth")?,
                process_events_timeout: resolve(&lib, n, "freenect_process_events_timeout").ok(),
                process_events: resolve(&lib, n, "freenect_process_events")?,
                replay,
                name: name.clone(),
                _library: lib,
            })
        }
    }
}

impl Freenect {
    /// `freenect_find_depth_mode(FREENECT_RESOLUTION_MEDIUM, FREENECT_DEPTH_11BIT)`: the mode
    /// this crate streams (valid, 640x480, 614,400 bytes on libfreenect 0.5 and fakenect).
    pub fn depth_mode_11bit(&self) -> FrameMode {
        // SAFETY: a lookup in libfreenect's static mode table (fakenect: a constant), needing
        // no context; the arguments are the ones fakenect asserts.
        unsafe { (self.find_depth_mode)(RESOLUTION_MEDIUM, DEPTH_11BIT) }
    }
}

/// `symbol` from `lib`, copied out of libloading's borrow.
///
/// # Safety
/// `T` must be the C type of `symbol`, and the pointer must not be called after `lib` is
/// dropped.
unsafe fn resolve<T: Copy>(
    lib: &Library,
    library: &str,
    symbol: &'static str,
) -> Result<T, FreenectError> {
    // SAFETY: the caller guarantees that `T` is the symbol's type.
    let found = unsafe { lib.get::<T>(symbol.as_bytes()) };
    found.map(|s| *s).map_err(|e| FreenectError::MissingSymbol {
        library: library.to_owned(),
        symbol,
        detail: e.to_string(),
    })
}
