//! libfreenect's recording format, read and written in pure Rust: what its `fakenect-record`
//! tool writes and its `fakenect` library replays through libfreenect's own API.
//!
//! A recording is a folder. `INDEX.txt` names one file per line, in the order recorded
//! (libfreenect 0.5.3, `fakenect/record.c`, names them `"%c-%f-%u.%s"`):
//! - `d-<time>-<timestamp>.pgm`: depth, the header `P5 640 480 65535\n`, then 640x480 raw
//!   11-bit values as little-endian `u16` (2047: no reading; the bytes of libfreenect's
//!   buffer, so not the big-endian samples a PGM reader expects);
//! - `r-<time>-<timestamp>.ppm`: RGB, the header `P6 640 480 255\n`, then 640x480x3 bytes;
//! - `a-<time>-<timestamp>.dump`: the accelerometer and tilt state, the 12 bytes of
//!   `freenect_raw_tilt_state`.
//!
//! `<time>` is the recording machine's clock in seconds (six decimals), `<timestamp>` the
//! device's 32-bit frame timestamp.

use std::fs;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use crate::camera::{DepthCamera, HEIGHT, PIXELS, RAW_NO_VALUE, WIDTH};
use crate::frame::DepthFrame;

/// The index file of a recording.
pub const INDEX: &str = "INDEX.txt";

const DEPTH_HEADER: &str = "P5 640 480 65535\n";
const RGB_HEADER: &str = "P6 640 480 255\n";
const DEPTH_BYTES: usize = PIXELS * 2;
const RGB_BYTES: usize = PIXELS * 3;
/// `sizeof(freenect_raw_tilt_state)`: three `int16_t`, an `int8_t`, padding, an enum.
const ACCEL_BYTES: usize = 12;

/// What a recording's line holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EntryKind {
    Depth,
    Rgb,
    Accel,
}

impl EntryKind {
    fn prefix(self) -> char {
        match self {
            EntryKind::Depth => 'd',
            EntryKind::Rgb => 'r',
            EntryKind::Accel => 'a',
        }
    }

    fn extension(self) -> &'static str {
        match self {
            EntryKind::Depth => "pgm",
            EntryKind::Rgb => "ppm",
            EntryKind::Accel => "dump",
        }
    }
}

/// One line of `INDEX.txt`.
#[derive(Clone, Debug, PartialEq)]
pub struct Entry {
    pub kind: EntryKind,
    /// The recording machine's clock, seconds.
    pub time_s: f64,
    /// The device's timestamp.
    pub timestamp: u32,
    /// The file, relative to the folder.
    pub file: String,
    /// 1-based line in `INDEX.txt`.
    pub line: usize,
}

/// The accelerometer and tilt motor state (`freenect_raw_tilt_state`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct AccelState {
    /// Raw accelerometer counts (819 per g), x, y, z.
    pub accel: [i16; 3],
    /// The tilt motor's raw angle (half degrees).
    pub tilt_angle: i8,
    /// `freenect_tilt_status_code`: 0 stopped, 1 at limit, 4 moving.
    pub tilt_status: i32,
}

impl AccelState {
    fn to_bytes(self) -> [u8; ACCEL_BYTES] {
        let mut b = [0u8; ACCEL_BYTES];
        for (i, a) in self.accel.iter().enumerate() {
            b[2 * i..2 * i + 2].copy_from_slice(&a.to_le_bytes());
        }
        b[6] = self.tilt_angle.to_le_bytes()[0];
        b[8..12].copy_from_slice(&self.tilt_status.to_le_bytes());
        b
    }

    fn from_bytes(b: &[u8; ACCEL_BYTES]) -> Self {
        Self {
            accel: [0, 1, 2].map(|i| i16::from_le_bytes([b[2 * i], b[2 * i + 1]])),
            tilt_angle: i8::from_le_bytes([b[6]]),
            tilt_status: i32::from_le_bytes([b[8], b[9], b[10], b[11]]),
        }
    }
}

/// Why a recording cannot be read or written. Each names the file (and for the index, the
/// line) and says what would fix it.
#[derive(Debug, thiserror::Error)]
pub enum FakenectError {
    #[error(
        "'{}' has no {INDEX}: not a fakenect recording (make one with `fitroom sensor record` \
         or libfreenect's `fakenect-record`)",
        dir.display()
    )]
    NoIndex { dir: PathBuf },
    #[error("{}: {action}: {source}", path.display())]
    Io {
        path: PathBuf,
        action: &'static str,
        source: std::io::Error,
    },
    #[error("{}:{line}: {problem} (in \"{text}\"; lines are `d-TIME-TIMESTAMP.pgm`, `r-….ppm` or `a-….dump`)", index.display())]
    BadLine {
        index: PathBuf,
        line: usize,
        text: String,
        problem: String,
    },
    #[error("{}: lists no frame", index.display())]
    Empty { index: PathBuf },
    #[error("{}:{line}: names '{file}', which is not in the folder", index.display())]
    MissingFile {
        index: PathBuf,
        line: usize,
        file: String,
    },
    #[error("{} (line {line} of {INDEX}): {problem}", file.display())]
    BadFile {
        file: PathBuf,
        line: usize,
        problem: String,
    },
    #[error("'{}' already holds a recording ({INDEX}); choose an empty folder", dir.display())]
    NotEmpty { dir: PathBuf },
    #[error("a frame of {found} values was given; a recording holds {expected}")]
    FrameSize { found: usize, expected: usize },
    #[error(
        "{}: lists no depth frame (only RGB or accelerometer lines); record with the depth \
         stream on",
        index.display()
    )]
    NoDepth { index: PathBuf },
}

/// A recording opened for reading: its index, checked against the folder.
#[derive(Clone, Debug)]
pub struct Recording {
    dir: PathBuf,
    entries: Vec<Entry>,
}

impl Recording {
    /// Reads and checks `dir/INDEX.txt`: every line parses and names a file in the folder, and
    /// there is at least one frame.
    pub fn open(dir: &Path) -> Result<Self, FakenectError> {
        let index = dir.join(INDEX);
        if !index.is_file() {
            return Err(FakenectError::NoIndex {
                dir: dir.to_owned(),
            });
        }
        let bytes = fs::read(&index).map_err(|source| FakenectError::Io {
            path: index.clone(),
            action: "cannot read",
            source,
        })?;
        let text = String::from_utf8_lossy(&bytes);
        let mut entries = Vec::new();
        for (i, raw_line) in text.lines().enumerate() {
            let line = i + 1;
            let text = raw_line.trim_end_matches('\r');
            if text.trim().is_empty() {
                continue;
            }
            let entry = parse_line(text, line).map_err(|problem| FakenectError::BadLine {
                index: index.clone(),
                line,
                // Printable whatever the file holds.
                text: text.chars().take(80).flat_map(char::escape_debug).collect(),
                problem,
            })?;
            if !dir.join(&entry.file).is_file() {
                return Err(FakenectError::MissingFile {
                    index: index.clone(),
                    line,
                    file: entry.file,
                });
            }
            entries.push(entry);
        }
        if !entries
            .iter()
            .any(|e| matches!(e.kind, EntryKind::Depth | EntryKind::Rgb))
        {
            return Err(FakenectError::Empty { index });
        }
        Ok(Self {
            dir: dir.to_owned(),
            entries,
        })
    }

    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Every line of the index, in order.
    pub fn entries(&self) -> &[Entry] {
        &self.entries
    }

    /// The depth lines, in order.
    pub fn depth_entries(&self) -> impl Iterator<Item = &Entry> {
        self.entries.iter().filter(|e| e.kind == EntryKind::Depth)
    }

    /// Number of depth frames.
    pub fn depth_count(&self) -> usize {
        self.depth_entries().count()
    }

    /// Reads a depth line's frame; its time counts from the recording's first line.
    pub fn read_depth(
        &self,
        entry: &Entry,
        camera: DepthCamera,
    ) -> Result<DepthFrame, FakenectError> {
        let payload = self.read_payload(entry, DEPTH_HEADER, DEPTH_BYTES)?;
        let raw: Vec<u16> = payload
            .chunks_exact(2)
            .map(|b| u16::from_le_bytes([b[0], b[1]]))
            .collect();
        let start = self.entries.first().map_or(entry.time_s, |e| e.time_s);
        Ok(DepthFrame::from_raw(
            raw,
            entry.time_s - start,
            entry.timestamp,
            camera,
        ))
    }

    /// Reads an RGB line's image (640x480x3 bytes).
    pub fn read_rgb(&self, entry: &Entry) -> Result<Vec<u8>, FakenectError> {
        self.read_payload(entry, RGB_HEADER, RGB_BYTES)
    }

    /// Reads an accelerometer line's state.
    pub fn read_accel(&self, entry: &Entry) -> Result<AccelState, FakenectError> {
        let path = self.dir.join(&entry.file);
        let bytes = read(&path)?;
        let b: &[u8; ACCEL_BYTES] =
            bytes
                .as_slice()
                .try_into()
                .map_err(|_| FakenectError::BadFile {
                    file: path.clone(),
                    line: entry.line,
                    problem: format!(
                        "{} bytes; an accelerometer record has {ACCEL_BYTES}",
                        bytes.len()
                    ),
                })?;
        Ok(AccelState::from_bytes(b))
    }

    /// The depth frames in order, each with the RGB image recorded last before it (if any).
    pub fn depth_frames(
        &self,
        camera: DepthCamera,
    ) -> impl Iterator<Item = Result<DepthFrame, FakenectError>> + '_ {
        let mut last_rgb: Option<&Entry> = None;
        self.entries.iter().filter_map(move |e| match e.kind {
            EntryKind::Rgb => {
                last_rgb = Some(e);
                None
            }
            EntryKind::Accel => None,
            EntryKind::Depth => Some(self.read_depth(e, camera).and_then(|mut frame| {
                if let Some(rgb) = last_rgb {
                    frame.rgb = Some(self.read_rgb(rgb)?.into());
                }
                Ok(frame)
            })),
        })
    }

    /// A file's payload after its one-line header, checked against the expected header and
    /// size.
    fn read_payload(
        &self,
        entry: &Entry,
        header: &str,
        size: usize,
    ) -> Result<Vec<u8>, FakenectError> {
        let path = self.dir.join(&entry.file);
        let mut bytes = read(&path)?;
        let bad = |problem: String| FakenectError::BadFile {
            file: path.clone(),
            line: entry.line,
            problem,
        };
        let Some(end) = bytes.iter().take(64).position(|&b| b == b'\n') else {
            return Err(bad(format!(
                "no header line (expected \"{}\")",
                header.trim_end()
            )));
        };
        let found = String::from_utf8_lossy(&bytes[..end]).into_owned();
        if !same_header(&found, header) {
            return Err(bad(format!(
                "header \"{}\", expected \"{}\"",
                found.chars().take(40).collect::<String>(),
                header.trim_end()
            )));
        }
        let payload = bytes.len() - end - 1;
        if payload != size {
            return Err(bad(format!(
                "{payload} bytes of image after the header, expected {size} ({WIDTH}x{HEIGHT}{}): \
                 the file is {}",
                if size == DEPTH_BYTES { " x 2" } else { " x 3" },
                if payload < size {
                    "truncated"
                } else {
                    "too long"
                }
            )));
        }
        bytes.drain(..=end);
        Ok(bytes)
    }
}

/// The header's tokens equal the expected ones (a writer may separate them differently).
fn same_header(found: &str, expected: &str) -> bool {
    found
        .split_ascii_whitespace()
        .eq(expected.split_ascii_whitespace())
}

fn read(path: &Path) -> Result<Vec<u8>, FakenectError> {
    fs::read(path).map_err(|source| FakenectError::Io {
        path: path.to_owned(),
        action: "cannot read",
        source,
    })
}

/// `d-1290113250.123456-123456789.pgm` (fakenect's `sscanf("%c-%lf-%u-%*s")`, with the
/// extension checked against the prefix).
fn parse_line(text: &str, line: usize) -> Result<Entry, String> {
    if text.contains('/') || text.contains('\\') {
        return Err("a file name, not a path, is expected".into());
    }
    let kind = match text.chars().next() {
        Some('d') => EntryKind::Depth,
        Some('r') => EntryKind::Rgb,
        Some('a') => EntryKind::Accel,
        Some(c) => return Err(format!("unknown prefix '{}'", c.escape_debug())),
        None => return Err("empty line".into()),
    };
    let rest = text
        .get(1..)
        .and_then(|r| r.strip_prefix('-'))
        .ok_or("no '-' after the prefix")?;
    let (time, rest) = rest.split_once('-').ok_or("no '-' after the time")?;
    let (timestamp, extension) = rest.split_once('.').ok_or("no file extension")?;
    let time_s: f64 = time
        .parse()
        .ok()
        .filter(|t: &f64| t.is_finite())
        .ok_or_else(|| format!("time \"{time}\" is not a number of seconds"))?;
    let timestamp: u32 = timestamp
        .parse()
        .map_err(|_| format!("timestamp \"{timestamp}\" is not a 32-bit unsigned number"))?;
    if extension != kind.extension() {
        return Err(format!(
            "a '{}' line names a .{extension} file, expected .{}",
            kind.prefix(),
            kind.extension()
        ));
    }
    Ok(Entry {
        kind,
        time_s,
        timestamp,
        file: text.to_owned(),
        line,
    })
}

/// Writes a recording into an empty folder, line by line; the index is flushed after every
/// file, so an interrupted recording is readable up to its last whole frame.
pub struct RecordingWriter {
    dir: PathBuf,
    index: BufWriter<fs::File>,
    lines: usize,
}

impl RecordingWriter {
    /// Creates `dir` if needed; refuses a folder that already holds a recording.
    pub fn create(dir: &Path) -> Result<Self, FakenectError> {
        fs::create_dir_all(dir).map_err(|source| FakenectError::Io {
            path: dir.to_owned(),
            action: "cannot create the folder",
            source,
        })?;
        let path = dir.join(INDEX);
        if path.exists() {
            return Err(FakenectError::NotEmpty {
                dir: dir.to_owned(),
            });
        }
        let file = fs::File::create(&path).map_err(|source| FakenectError::Io {
            path: path.clone(),
            action: "cannot create",
            source,
        })?;
        Ok(Self {
            dir: dir.to_owned(),
            index: BufWriter::new(file),
            lines: 0,
        })
    }

    /// Writes a depth frame of raw values ([`PIXELS`] of them, 2047 for no reading).
    pub fn write_depth(
        &mut self,
        time_s: f64,
        timestamp: u32,
        raw: &[u16],
    ) -> Result<(), FakenectError> {
        if raw.len() != PIXELS {
            return Err(FakenectError::FrameSize {
                found: raw.len(),
                expected: PIXELS,
            });
        }
        let mut bytes = Vec::with_capacity(DEPTH_HEADER.len() + DEPTH_BYTES);
        bytes.extend_from_slice(DEPTH_HEADER.as_bytes());
        for &r in raw {
            bytes.extend_from_slice(&r.min(RAW_NO_VALUE).to_le_bytes());
        }
        self.write_entry(EntryKind::Depth, time_s, timestamp, &bytes)
    }

    /// Writes an RGB image (640x480x3 bytes).
    pub fn write_rgb(
        &mut self,
        time_s: f64,
        timestamp: u32,
        rgb: &[u8],
    ) -> Result<(), FakenectError> {
        if rgb.len() != RGB_BYTES {
            return Err(FakenectError::FrameSize {
                found: rgb.len(),
                expected: RGB_BYTES,
            });
        }
        let mut bytes = Vec::with_capacity(RGB_HEADER.len() + RGB_BYTES);
        bytes.extend_from_slice(RGB_HEADER.as_bytes());
        bytes.extend_from_slice(rgb);
        self.write_entry(EntryKind::Rgb, time_s, timestamp, &bytes)
    }

    /// Writes an accelerometer record.
    pub fn write_accel(
        &mut self,
        time_s: f64,
        timestamp: u32,
        state: AccelState,
    ) -> Result<(), FakenectError> {
        self.write_entry(EntryKind::Accel, time_s, timestamp, &state.to_bytes())
    }

    /// Lines written so far.
    pub fn lines(&self) -> usize {
        self.lines
    }

    fn write_entry(
        &mut self,
        kind: EntryKind,
        time_s: f64,
        timestamp: u32,
        bytes: &[u8],
    ) -> Result<(), FakenectError> {
        let name = format!(
            "{}-{time_s:.6}-{timestamp}.{}",
            kind.prefix(),
            kind.extension()
        );
        let path = self.dir.join(&name);
        fs::write(&path, bytes).map_err(|source| FakenectError::Io {
            path,
            action: "cannot write",
            source,
        })?;
        let index = self.dir.join(INDEX);
        writeln!(self.index, "{name}")
            .and_then(|()| self.index.flush())
            .map_err(|source| FakenectError::Io {
                path: index,
                action: "cannot write",
                source,
            })?;
        self.lines += 1;
        Ok(())
    }
}
