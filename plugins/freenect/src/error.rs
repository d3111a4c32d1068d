//! [`FreenectError`]: why a [`crate::KinectSource`] cannot start. Only the library itself can
//! stop it from starting; a missing or unplugged Kinect is a status
//! ([`crate::SourceStatus::Disconnected`]), not an error, because it can come back.

use std::path::PathBuf;

/// The install command the messages give (Debian 12; `libfreenect0.5` holds both the library
/// and fakenect, `libfreenect-dev` depends on it).
pub const INSTALL_HINT: &str = "`sudo apt install libfreenect-dev` (Debian 12)";

/// Why the libfreenect library cannot be used. Each names the library and says what would fix it.
#[derive(Debug, thiserror::Error)]
pub enum FreenectError {
    /// The dynamic loader found no such library (the default name through the loader's search
    /// path and `LD_LIBRARY_PATH`, or an explicit path that does not exist).
    #[error(
        "libfreenect not found ({library}): install it with {INSTALL_HINT}, or name the \
         library's path (KinectOptions::library) [{detail}]"
    )]
    NotFound { library: String, detail: String },
    /// The file exists but the loader refused it (wrong architecture, not a shared library, a
    /// dependency such as libusb-1.0 missing).
    #[error(
        "cannot load {}: {detail} (is it a libfreenect 0.5 for this machine? reinstall it with \
         {INSTALL_HINT})",
        library.display()
    )]
    LoadFailed { library: PathBuf, detail: String },
    /// The library loaded but lacks a function this crate calls: not libfreenect 0.5.
    #[error(
        "{library} lacks `{symbol}`: it is not libfreenect 0.5 (or fakenect 0.5); install it \
         with {INSTALL_HINT} [{detail}]"
    )]
    MissingSymbol {
        library: String,
        symbol: &'static str,
        detail: String,
    },
    /// The operating system refused the device thread.
    #[error("cannot start the Kinect thread: {0} (out of memory or threads?)")]
    Thread(#[source] std::io::Error),
}
