//! Where a garment's files come from. A garment file names other files (its fabric, its size
//! chart, an OBJ's MTL file, a glTF's buffers) relative to itself; the readers ask a
//! [`GarmentFiles`] for them, so that the same code reads from the file system
//! ([`DiskFiles`]) or from bytes an asset loader fetched beforehand ([`FetchedFiles`], which
//! also records what was asked for and is missing, so that the loader can fetch it and read
//! again).

use std::cell::RefCell;
use std::collections::HashMap;
use std::path::{Component, Path, PathBuf};

use crate::error::GarmentError;

/// A source of the files a garment names.
pub trait GarmentFiles {
    /// The bytes of the file at `path`.
    fn read(&self, path: &Path) -> Result<Vec<u8>, GarmentError>;

    /// The file at `path` as UTF-8 text.
    fn read_text(&self, path: &Path) -> Result<String, GarmentError> {
        String::from_utf8(self.read(path)?).map_err(|e| GarmentError::Read {
            path: path.to_owned(),
            source: std::io::Error::new(std::io::ErrorKind::InvalidData, e),
        })
    }
}

/// The file system.
#[derive(Clone, Copy, Debug, Default)]
pub struct DiskFiles;

impl GarmentFiles for DiskFiles {
    fn read(&self, path: &Path) -> Result<Vec<u8>, GarmentError> {
        std::fs::read(path).map_err(|source| GarmentError::Read {
            path: path.to_owned(),
            source,
        })
    }
}

/// Files fetched beforehand, by normalised path; a file not there is recorded in
/// [`FetchedFiles::missing`] and read as "not found".
#[derive(Debug, Default)]
pub struct FetchedFiles {
    files: HashMap<PathBuf, Result<Vec<u8>, String>>,
    missing: RefCell<Vec<PathBuf>>,
}

impl FetchedFiles {
    /// Adds a fetched file, or the reason it could not be fetched (then reading it fails
    /// with that reason instead of being recorded as missing).
    pub fn insert(&mut self, path: &Path, bytes: Result<Vec<u8>, String>) {
        self.files.insert(normalize(path), bytes);
    }

    /// The paths asked for that have not been fetched yet (and forgets them).
    pub fn take_missing(&self) -> Vec<PathBuf> {
        std::mem::take(&mut *self.missing.borrow_mut())
    }

    /// Every file fetched (path, bytes), for a later [`GarmentFiles`] use.
    pub fn into_fetched(self) -> HashMap<PathBuf, Vec<u8>> {
        self.files
            .into_iter()
            .filter_map(|(p, b)| b.ok().map(|b| (p, b)))
            .collect()
    }
}

impl GarmentFiles for FetchedFiles {
    fn read(&self, path: &Path) -> Result<Vec<u8>, GarmentError> {
        let key = normalize(path);
        let not_found = |message: String| GarmentError::Read {
            path: path.to_owned(),
            source: std::io::Error::new(std::io::ErrorKind::NotFound, message),
        };
        match self.files.get(&key) {
            Some(Ok(bytes)) => Ok(bytes.clone()),
            Some(Err(reason)) => Err(not_found(reason.clone())),
            None => {
                self.missing.borrow_mut().push(key);
                Err(not_found("not fetched yet".into()))
            }
        }
    }
}

impl GarmentFiles for HashMap<PathBuf, Vec<u8>> {
    fn read(&self, path: &Path) -> Result<Vec<u8>, GarmentError> {
        self.get(&normalize(path))
            .cloned()
            .ok_or_else(|| GarmentError::Read {
                path: path.to_owned(),
                source: std::io::Error::new(std::io::ErrorKind::NotFound, "not fetched"),
            })
    }
}

/// `a/b/../c/./d` -> `a/c/d`, lexically (no file system access; a `..` above the start is
/// kept).
pub fn normalize(path: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for c in path.components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir => {
                let last = out.components().next_back();
                if matches!(last, Some(Component::Normal(_))) {
                    out.pop();
                } else {
                    out.push("..");
                }
            }
            other => out.push(other.as_os_str()),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normalize_resolves_dots_lexically() {
        assert_eq!(
            normalize(Path::new("assets/garments/../fabrics/./denim.ron")),
            PathBuf::from("assets/fabrics/denim.ron")
        );
        assert_eq!(normalize(Path::new("/a/b/../../c")), PathBuf::from("/c"));
        assert_eq!(normalize(Path::new("../x/../y")), PathBuf::from("../y"));
    }

    #[test]
    fn fetched_files_record_what_is_missing() {
        let mut files = FetchedFiles::default();
        files.insert(Path::new("a/b.ron"), Ok(b"x".to_vec()));
        assert_eq!(
            files.read(Path::new("a/./c/../b.ron")).ok(),
            Some(b"x".to_vec())
        );
        assert!(files.read(Path::new("a/d.ron")).is_err());
        assert_eq!(files.take_missing(), vec![PathBuf::from("a/d.ron")]);
        assert!(files.take_missing().is_empty());
        files.insert(Path::new("a/d.ron"), Err("no such file".into()));
        let e = files
            .read(Path::new("a/d.ron"))
            .expect_err("a file that does not exist");
        assert!(e.to_string().contains("no such file"), "{e}");
        assert!(files.take_missing().is_empty());
    }
}
