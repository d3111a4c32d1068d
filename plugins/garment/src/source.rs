//! One way to read a garment, whatever its file: a sewing pattern (`.ron`, [`crate::pattern`]),
//! an OBJ + MTL or a glTF mesh garment ([`crate::mesh_garment`]). The command line, the kiosk
//! and the designer all read garments through [`GarmentSource`] and dress a body with
//! [`GarmentSource::build`], so a garment that works in one works in all.
//!
//! Reading a garment reads every file it names (fabric, size chart, MTL, glTF buffers) through
//! a [`GarmentFiles`]; the source keeps what it read, so building it on a body later needs no
//! file access (the asset loader reads once; a reshaped avatar is dressed again from memory).

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use crate::body::BodySurface;
use crate::error::GarmentError;
use crate::fabric::FabricSpec;
use crate::files::{DiskFiles, GarmentFiles};
use crate::garment::{BuildOptions, GarmentMesh};
use crate::mesh_garment::{load_gltf_with, load_obj_with};
use crate::pattern::{Pattern, fabric_path};

/// The fabric of a mesh garment, which names none: `<folder>/../fabrics/cotton.ron`.
pub const MESH_GARMENT_FABRIC: &str = "cotton";

/// The size label of a mesh garment (it has one size: the mesh as modelled).
pub const ONE_SIZE: &str = "one size";

/// What kind of garment a file is, by its extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GarmentFormat {
    /// A sewing pattern, `.ron`.
    Pattern,
    /// Wavefront OBJ + MTL, `.obj`.
    Obj,
    /// glTF 2.0, `.glb` or `.gltf`.
    Gltf,
}

impl GarmentFormat {
    /// The extensions garment files have.
    pub const EXTENSIONS: [&str; 4] = ["ron", "obj", "glb", "gltf"];

    pub fn of(path: &Path) -> Result<Self, GarmentError> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .unwrap_or_default();
        match ext.as_str() {
            "ron" => Ok(Self::Pattern),
            "obj" => Ok(Self::Obj),
            "glb" | "gltf" => Ok(Self::Gltf),
            _ => Err(GarmentError::Mesh {
                file: path.display().to_string(),
                problem: "a garment is a pattern (.ron) or a mesh (.obj, .glb, .gltf)".into(),
            }),
        }
    }
}

/// A garment file read with everything it names, ready to be built on a body.
#[derive(Clone, Debug)]
pub struct GarmentSource {
    path: PathBuf,
    kind: SourceKind,
}

#[derive(Clone, Debug)]
enum SourceKind {
    Pattern(Box<Pattern>),
    Mesh {
        format: GarmentFormat,
        fabric: FabricSpec,
        /// The mesh file and the files it names, as read.
        files: HashMap<PathBuf, Vec<u8>>,
    },
}

impl GarmentSource {
    /// Reads a garment file and the files it names from the file system.
    pub fn load(path: impl AsRef<Path>) -> Result<Self, GarmentError> {
        Self::read(path.as_ref(), &DiskFiles)
    }

    /// Reads a garment file and the files it names from `files`.
    pub fn read(path: &Path, files: &dyn GarmentFiles) -> Result<Self, GarmentError> {
        let format = GarmentFormat::of(path)?;
        let kind = match format {
            GarmentFormat::Pattern => {
                SourceKind::Pattern(Box::new(Pattern::load_with(path, files)?))
            }
            GarmentFormat::Obj | GarmentFormat::Gltf => {
                let dir = path.parent().unwrap_or(Path::new("."));
                let fabric_file = fabric_path(dir, MESH_GARMENT_FABRIC);
                let fabric = FabricSpec::from_ron_str(
                    &files.read_text(&fabric_file)?,
                    &fabric_file.display().to_string(),
                )?;
                let bytes = files.read(path)?;
                let mut read = HashMap::new();
                for named in named_files(format, &bytes) {
                    let named = dir.join(named);
                    let named_bytes = files.read(&named)?;
                    read.insert(crate::files::normalize(&named), named_bytes);
                }
                read.insert(crate::files::normalize(path), bytes);
                SourceKind::Mesh {
                    format,
                    fabric,
                    files: read,
                }
            }
        };
        Ok(Self {
            path: path.to_owned(),
            kind,
        })
    }

    /// The garment file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The garment's name: the pattern's, or the mesh file's stem.
    pub fn name(&self) -> String {
        match &self.kind {
            SourceKind::Pattern(p) => p.name.clone(),
            SourceKind::Mesh { .. } => self
                .path
                .file_stem()
                .map_or_else(String::new, |s| s.to_string_lossy().into_owned()),
        }
    }

    /// The fabric it is made of.
    pub fn fabric(&self) -> &FabricSpec {
        match &self.kind {
            SourceKind::Pattern(p) => &p.fabric,
            SourceKind::Mesh { fabric, .. } => fabric,
        }
    }

    /// The pattern, for a pattern garment.
    pub fn pattern(&self) -> Option<&Pattern> {
        match &self.kind {
            SourceKind::Pattern(p) => Some(p),
            SourceKind::Mesh { .. } => None,
        }
    }

    /// The pattern, for a pattern garment, to change before building (e.g. its mesh size).
    pub fn pattern_mut(&mut self) -> Option<&mut Pattern> {
        match &mut self.kind {
            SourceKind::Pattern(p) => Some(p),
            SourceKind::Mesh { .. } => None,
        }
    }

    /// The sizes it comes in, smallest first ([`ONE_SIZE`] for a mesh garment).
    pub fn size_labels(&self) -> Vec<String> {
        match &self.kind {
            SourceKind::Pattern(p) => p.size_labels().iter().map(|s| s.to_string()).collect(),
            SourceKind::Mesh { .. } => vec![ONE_SIZE.to_owned()],
        }
    }

    /// `size` if the garment has it, else an error listing its sizes; without a size, the
    /// middle one.
    pub fn resolve_size(&self, size: Option<&str>) -> Result<String, GarmentError> {
        let labels = self.size_labels();
        let invalid = |problem: String| GarmentError::Invalid {
            file: self.path.display().to_string(),
            line: 1,
            field: "sizes".into(),
            problem,
        };
        match size {
            Some(s) if labels.iter().any(|l| l == s) => Ok(s.to_owned()),
            Some(s) => Err(invalid(format!(
                "no size `{s}`; its sizes: {}",
                labels.join(", ")
            ))),
            None => labels
                .get(labels.len() / 2)
                .cloned()
                .ok_or_else(|| invalid("no sizes".into())),
        }
    }

    /// The garment in `size` (default: the middle one) on `body`: a pattern is graded, placed,
    /// sewn and welded; a mesh garment is bound to the body as modelled.
    pub fn build(
        &self,
        body: &BodySurface,
        size: Option<&str>,
    ) -> Result<GarmentMesh, GarmentError> {
        let size = self.resolve_size(size)?;
        match &self.kind {
            SourceKind::Pattern(pattern) => pattern
                .build(body, &size, &BuildOptions::default())?
                .welded(body),
            SourceKind::Mesh {
                format,
                fabric,
                files,
            } => {
                let mut mesh = match format {
                    GarmentFormat::Obj => {
                        load_obj_with(&self.path, files, body, &fabric.name, fabric.fabric)?
                    }
                    _ => load_gltf_with(&self.path, files, body, &fabric.name, fabric.fabric)?,
                };
                mesh.size = size;
                Ok(mesh)
            }
        }
    }
}

/// The files a mesh garment names, relative to its folder: an OBJ's `mtllib` files, a glTF's
/// buffers that are neither embedded nor data URIs. A file that does not parse names none
/// (building it then says why).
fn named_files(format: GarmentFormat, bytes: &[u8]) -> Vec<PathBuf> {
    match format {
        GarmentFormat::Obj => String::from_utf8_lossy(bytes)
            .lines()
            .filter_map(|l| l.trim().strip_prefix("mtllib"))
            .flat_map(|rest| {
                rest.split_whitespace()
                    .map(PathBuf::from)
                    .collect::<Vec<_>>()
            })
            .collect(),
        GarmentFormat::Gltf => gltf::Gltf::from_slice(bytes)
            .map(|doc| {
                doc.buffers()
                    .filter_map(|b| match b.source() {
                        gltf::buffer::Source::Uri(uri) if !uri.starts_with("data:") => {
                            Some(PathBuf::from(uri))
                        }
                        _ => None,
                    })
                    .collect()
            })
            .unwrap_or_default(),
        GarmentFormat::Pattern => Vec::new(),
    }
}
