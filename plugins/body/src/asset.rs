//! The `.fitbody` file: a [`BodyModel`] converted once from the MakeHuman data, shipped in
//! `assets/bodies/`. The layout is documented in the crate docs (`fitroom_body`, "The
//! `.fitbody` format").

use std::fs;
use std::io::{Read, Write};
use std::path::{Path, PathBuf};

use flate2::Compression;
use flate2::read::DeflateDecoder;
use flate2::write::DeflateEncoder;

use crate::model::BodyModel;

/// The first 8 bytes of every `.fitbody` file.
pub const MAGIC: [u8; 8] = *b"FITBODY\0";

/// The format version this build writes and reads.
pub const FORMAT_VERSION: u32 = 1;

/// Bytes before the compressed payload: magic, version, payload length, CRC-32.
pub const HEADER_LEN: usize = 8 + 4 + 8 + 4;

/// Largest uncompressed payload accepted (guards against a corrupt length field).
const MAX_PAYLOAD: u64 = 1 << 32;

/// Why a `.fitbody` file could not be written or read. Every variant names the file.
#[derive(Debug, thiserror::Error)]
pub enum AssetError {
    #[error("{path}: {action}: {source}")]
    Io {
        path: PathBuf,
        action: &'static str,
        #[source]
        source: std::io::Error,
    },
    #[error(
        "{path}: not a fitroom body file (it does not start with the bytes `FITBODY\\0`); \
         convert the MakeHuman data with the body importer"
    )]
    BadMagic { path: PathBuf },
    #[error(
        "{path}: body format version {found} is not supported (this build reads version \
         {supported}); convert the MakeHuman data again with this build's importer"
    )]
    UnsupportedVersion {
        path: PathBuf,
        found: u32,
        supported: u32,
    },
    #[error("{path}: corrupt body file: {reason}")]
    Corrupt { path: PathBuf, reason: String },
    #[error("{path}: cannot encode the body model: {reason}")]
    Encode { path: PathBuf, reason: String },
}

impl BodyModel {
    /// Encodes the model in the `.fitbody` format.
    pub fn to_bytes(&self) -> Result<Vec<u8>, AssetError> {
        self.to_bytes_named(Path::new("<memory>"))
    }

    fn to_bytes_named(&self, path: &Path) -> Result<Vec<u8>, AssetError> {
        let payload = postcard::to_stdvec(self).map_err(|e| AssetError::Encode {
            path: path.to_path_buf(),
            reason: e.to_string(),
        })?;
        let mut crc = flate2::Crc::new();
        crc.update(&payload);
        let mut out = Vec::with_capacity(payload.len() / 2 + HEADER_LEN);
        out.extend_from_slice(&MAGIC);
        out.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
        out.extend_from_slice(&(payload.len() as u64).to_le_bytes());
        out.extend_from_slice(&crc.sum().to_le_bytes());
        let io = |source| AssetError::Io {
            path: path.to_path_buf(),
            action: "cannot compress",
            source,
        };
        let mut encoder = DeflateEncoder::new(out, Compression::best());
        encoder.write_all(&payload).map_err(io)?;
        encoder.finish().map_err(io)
    }

    /// Writes the model to `path` (through a temporary file renamed into place, so a reader
    /// never sees half a file).
    pub fn write(&self, path: &Path) -> Result<(), AssetError> {
        let bytes = self.to_bytes_named(path)?;
        let mut tmp = path.as_os_str().to_owned();
        tmp.push(".part");
        let tmp = PathBuf::from(tmp);
        fs::write(&tmp, &bytes).map_err(|source| AssetError::Io {
            path: tmp.clone(),
            action: "cannot write",
            source,
        })?;
        fs::rename(&tmp, path).map_err(|source| AssetError::Io {
            path: path.to_path_buf(),
            action: "cannot move the written file into place",
            source,
        })
    }

    /// Reads a `.fitbody` file.
    pub fn read(path: &Path) -> Result<Self, AssetError> {
        let bytes = fs::read(path).map_err(|source| AssetError::Io {
            path: path.to_path_buf(),
            action: "cannot read",
            source,
        })?;
        Self::from_bytes_named(&bytes, path)
    }

    /// Decodes a `.fitbody` file already in memory.
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, AssetError> {
        Self::from_bytes_named(bytes, Path::new("<memory>"))
    }

    /// Decodes a `.fitbody` file already in memory; `path` names it in errors (e.g. the asset
    /// path a Bevy loader was given).
    pub fn from_bytes_named(bytes: &[u8], path: &Path) -> Result<Self, AssetError> {
        let corrupt = |reason: String| AssetError::Corrupt {
            path: path.to_path_buf(),
            reason,
        };
        if bytes.len() < MAGIC.len() || bytes[..MAGIC.len()] != MAGIC {
            if bytes.len() < MAGIC.len() && MAGIC.starts_with(bytes) {
                return Err(corrupt(format!(
                    "truncated: {} bytes, the header alone needs {HEADER_LEN}",
                    bytes.len()
                )));
            }
            return Err(AssetError::BadMagic {
                path: path.to_path_buf(),
            });
        }
        if bytes.len() < HEADER_LEN {
            return Err(corrupt(format!(
                "truncated: {} bytes, the header alone needs {HEADER_LEN}",
                bytes.len()
            )));
        }
        let u32_at = |at: usize| {
            let mut b = [0u8; 4];
            b.copy_from_slice(&bytes[at..at + 4]);
            u32::from_le_bytes(b)
        };
        let version = u32_at(8);
        if version != FORMAT_VERSION {
            return Err(AssetError::UnsupportedVersion {
                path: path.to_path_buf(),
                found: version,
                supported: FORMAT_VERSION,
            });
        }
        let mut len_bytes = [0u8; 8];
        len_bytes.copy_from_slice(&bytes[12..20]);
        let payload_len = u64::from_le_bytes(len_bytes);
        let expected_crc = u32_at(20);
        if payload_len > MAX_PAYLOAD {
            return Err(corrupt(format!(
                "the header gives a payload of {payload_len} bytes, more than the {MAX_PAYLOAD} \
                 allowed"
            )));
        }
        let mut payload = Vec::with_capacity((payload_len as usize).min(64 << 20));
        DeflateDecoder::new(&bytes[HEADER_LEN..])
            .take(payload_len + 1)
            .read_to_end(&mut payload)
            .map_err(|e| corrupt(format!("the compressed data does not inflate: {e}")))?;
        if payload.len() as u64 != payload_len {
            return Err(corrupt(format!(
                "the data inflates to {} bytes, the header says {payload_len} (truncated or damaged file)",
                payload.len()
            )));
        }
        let mut crc = flate2::Crc::new();
        crc.update(&payload);
        if crc.sum() != expected_crc {
            return Err(corrupt(format!(
                "CRC-32 mismatch: the data has {:08x}, the header says {expected_crc:08x}",
                crc.sum()
            )));
        }
        let model: BodyModel = postcard::from_bytes(&payload)
            .map_err(|e| corrupt(format!("the model does not decode: {e}")))?;
        model
            .validate()
            .map_err(|e| corrupt(format!("the model is inconsistent: {e}")))?;
        Ok(model)
    }
}
