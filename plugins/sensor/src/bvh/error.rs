//! Why a BVH file could not be read: every error names the file and, where it has one, the
//! 1-based line, and says what was found and what was expected (the BVH format of the CMU
//! motion-capture database, see the [module docs](super)).

/// Why a BVH file could not be read. Every variant names the file; all but `Io` and
/// `InvalidOptions` name the 1-based line, and the message says what was expected.
#[derive(Debug, thiserror::Error)]
pub enum BvhError {
    #[error("{file}: cannot read the file: {source}")]
    Io {
        file: String,
        #[source]
        source: std::io::Error,
    },
    /// A keyword or structure other than the one the format requires at this point.
    #[error("{file}:{line}: found {found}; expected {expected}")]
    Syntax {
        file: String,
        line: usize,
        found: String,
        expected: String,
    },
    /// A token that should be a number is not one (or is not finite).
    #[error("{file}:{line}: '{value}' is not a valid number; expected {expected}")]
    NotANumber {
        file: String,
        line: usize,
        value: String,
        expected: String,
    },
    /// A motion line with a different number of values than the hierarchy has channels.
    #[error(
        "{file}:{line}: frame index {frame} has {found} values; expected {expected} (one per channel declared in HIERARCHY)"
    )]
    ChannelCount {
        file: String,
        line: usize,
        /// 0-based frame index.
        frame: usize,
        found: usize,
        expected: usize,
    },
    /// The motion block ends before the number of frames given by `Frames:`.
    #[error(
        "{file}:{line}: motion data ends after {found} frame lines; expected {declared} frame lines as declared by 'Frames: {declared}' (truncated file?)"
    )]
    Truncated {
        file: String,
        /// The line where the next frame was expected.
        line: usize,
        found: usize,
        declared: usize,
    },
    /// More frame lines than `Frames:` declares.
    #[error(
        "{file}:{line}: extra frame line; expected only {declared} frame lines as declared by 'Frames: {declared}'"
    )]
    ExtraFrames {
        file: String,
        line: usize,
        declared: usize,
    },
    /// `Frames: 0`.
    #[error("{file}:{line}: 'Frames: 0' declares an empty clip; expected at least one frame")]
    NoFrames { file: String, line: usize },
    /// A well-formed file whose skeleton cannot be mapped onto the Kinect joints (an unknown
    /// root name, a missing joint, a degenerate leg).
    #[error("{file}:{line}: {message}")]
    Skeleton {
        file: String,
        line: usize,
        message: String,
    },
    /// Options given to a BVH source that cannot work (non-positive frame rate...).
    #[error("{file}: invalid BVH source options: {message}")]
    InvalidOptions { file: String, message: String },
}

impl BvhError {
    /// The file name or path the error is about.
    pub fn file(&self) -> &str {
        match self {
            BvhError::Io { file, .. }
            | BvhError::Syntax { file, .. }
            | BvhError::NotANumber { file, .. }
            | BvhError::ChannelCount { file, .. }
            | BvhError::Truncated { file, .. }
            | BvhError::ExtraFrames { file, .. }
            | BvhError::NoFrames { file, .. }
            | BvhError::Skeleton { file, .. }
            | BvhError::InvalidOptions { file, .. } => file,
        }
    }

    /// The 1-based line the error is about, if it is about one.
    pub fn line(&self) -> Option<usize> {
        match self {
            BvhError::Io { .. } | BvhError::InvalidOptions { .. } => None,
            BvhError::Syntax { line, .. }
            | BvhError::NotANumber { line, .. }
            | BvhError::ChannelCount { line, .. }
            | BvhError::Truncated { line, .. }
            | BvhError::ExtraFrames { line, .. }
            | BvhError::NoFrames { line, .. }
            | BvhError::Skeleton { line, .. } => Some(*line),
        }
    }
}
