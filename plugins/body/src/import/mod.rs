//! Import of the MakeHuman hm08 body from the MPFB2 asset layout into a [`BodyModel`].
//!
//! Sources (all CC0, MakeHuman 1.x / MPFB2): `3dobjs/base.obj` (the hm08 base mesh in
//! decimetres), `mesh_metadata/basemesh_vertex_groups.json` (body, helper and `joint-*` vertex
//! groups), `rigs/standard/rig.game_engine.json.gz` and `weights.game_engine.json.gz` (the
//! 53-bone game-engine skeleton and its skin weights), and the macro (`targets/macrodetails/**`)
//! and measurement (`targets/*/measure-*`) morph targets.
//!
//! Two things are changed on the way in:
//! - each forearm is split in two (seed 000 §4.4.3, the "split ulna"): `lowerarm_l`/`_r` keep
//!   the proximal half (elbow to mid-forearm) and a new child `lowerarm_twist_l`/`_r` takes the
//!   distal half (mid-forearm to wrist) and becomes the hand's parent. The forearm's skin weight
//!   is shared between the two along the elbow->wrist axis (linear in the vertex's projection),
//!   so that a wrist twist can be spread over the forearm instead of collapsing at one joint;
//! - skin weights are reduced to the 4 largest influences per vertex and renormalised (GPU
//!   skinning in Bevy takes 4).
//!
//! Morph targets are stored sparse and quantised to `i16` with a per-target scale (see
//! [`MorphTarget`]).
//!
//! # Where things are
//!
//! - this module: the import itself ([`import_makehuman`]) and the file readers it shares;
//! - `obj`: the base mesh (OBJ) and its body, helper and UV tables;
//! - `bones`: the rig file and the forearm split;
//! - `skin`: the skin weights (split forearms, 4 influences);
//! - `targets`: which morph targets are imported, and their quantisation.
//!
//! [`MorphTarget`]: crate::model::MorphTarget

mod bones;
mod obj;
mod skin;
mod targets;

pub use skin::fraction_along;

use std::collections::BTreeMap;
use std::fs;
use std::io::Read;
use std::path::{Path, PathBuf};

use flate2::read::GzDecoder;
use serde::{Deserialize, Serialize};

use self::bones::{RigBoneFile, build_bones};
use self::obj::{build_mesh, parse_obj};
use self::skin::{WeightsFile, build_skin};
use self::targets::{collect_targets, parse_target};
use crate::model::BodyModel;

/// MakeHuman mesh units (decimetres) to metres.
pub const DECIMETRE: f32 = 0.1;

/// The rig imported (MPFB2 `rigs/standard/rig.<RIG_NAME>.json.gz`).
pub const RIG_NAME: &str = "game_engine";

/// The split forearms: (original forearm bone, new twist bone, hand bone).
pub const SPLIT_FOREARMS: [(&str, &str, &str); 2] = [
    ("lowerarm_l", "lowerarm_twist_l", "hand_l"),
    ("lowerarm_r", "lowerarm_twist_r", "hand_r"),
];

/// Why the MakeHuman data could not be imported. Every variant names the file.
#[derive(Debug, thiserror::Error)]
pub enum ImportError {
    #[error("{path}: cannot read the file: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{path}, line {line}: {message}")]
    Syntax {
        path: PathBuf,
        line: usize,
        message: String,
    },
    #[error("{path}: invalid JSON: {source}")]
    Json {
        path: PathBuf,
        #[source]
        source: serde_json::Error,
    },
    #[error("{path}: {field}: {message}")]
    Invalid {
        path: PathBuf,
        field: String,
        message: String,
    },
}

/// What the importer did, for logs and tests.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ImportReport {
    pub vertices: usize,
    pub body_vertices: usize,
    pub body_triangles: usize,
    pub helper_triangles: usize,
    /// Faces neither body nor in a helper group (the joint cubes), not kept as triangles.
    pub skipped_faces: usize,
    /// Body vertices with more than one UV in the OBJ (the first one is kept in `uvs`).
    pub uv_seam_vertices: usize,
    /// Body vertices that no face gives a UV (their UV is zero).
    pub vertices_without_uv: usize,
    /// Bones after the forearm split.
    pub bones: usize,
    /// Vertices without any weight in the weights file, given weight 1 on the nearest bone.
    pub unweighted_vertices: usize,
    /// Vertices that had more than 4 influences (after the forearm split) and lost the smallest.
    pub truncated_vertices: usize,
    pub targets: usize,
    /// Sum over targets of stored (non-zero) entries.
    pub target_entries: usize,
    /// Target lines whose displacement is exactly zero (dropped).
    pub zero_deltas_dropped: usize,
    /// Non-zero displacements below half a quantisation step (dropped: they would be zero).
    pub quantised_to_zero_dropped: usize,
    /// Targets with no displacement at all (kept, with no entries).
    pub empty_targets: Vec<String>,
}

/// Imports the MakeHuman body from `dir` (the MPFB2 data folder, e.g.
/// `shared/data/makehuman`). `progress` is called with a stage name and how much of it is done.
pub fn import_makehuman(
    dir: &Path,
    progress: &mut dyn FnMut(&str, usize, usize),
) -> Result<BodyModel, ImportError> {
    import_makehuman_with_report(dir, progress).map(|(model, _)| model)
}

/// [`import_makehuman`], also returning what the importer did.
pub fn import_makehuman_with_report(
    dir: &Path,
    progress: &mut dyn FnMut(&str, usize, usize),
) -> Result<(BodyModel, ImportReport), ImportError> {
    let mut report = ImportReport::default();
    const STAGES: usize = 5;

    progress("vertex groups", 0, STAGES);
    let groups_path = dir.join("mesh_metadata/basemesh_vertex_groups.json");
    let groups: BTreeMap<String, Vec<[u32; 2]>> = serde_json::from_slice(&read_file(&groups_path)?)
        .map_err(|source| ImportError::Json {
            path: groups_path.clone(),
            source,
        })?;
    let body_range = groups.get("body").ok_or_else(|| ImportError::Invalid {
        path: groups_path.clone(),
        field: "body".into(),
        message: "no `body` vertex group".into(),
    })?;
    let body_vertex_count = match body_range.as_slice() {
        [[0, last]] => last + 1,
        _ => {
            return Err(ImportError::Invalid {
                path: groups_path,
                field: "body".into(),
                message: format!("expected one range starting at 0, found {body_range:?}"),
            });
        }
    };

    progress("mesh", 1, STAGES);
    let obj_path = dir.join("3dobjs/base.obj");
    let obj = parse_obj(&obj_path, &read_text(&obj_path)?)?;
    let vertex_count = obj.positions.len();
    if (body_vertex_count as usize) > vertex_count {
        return Err(ImportError::Invalid {
            path: groups_path,
            field: "body".into(),
            message: format!(
                "the body group ends at vertex {} but {} has {vertex_count} vertices",
                body_vertex_count - 1,
                obj_path.display()
            ),
        });
    }
    for (name, ranges) in &groups {
        if let Some(&[_, last]) = ranges.iter().find(|r| r[1] as usize >= vertex_count) {
            return Err(ImportError::Invalid {
                path: groups_path,
                field: name.clone(),
                message: format!(
                    "range ends at vertex {last}, past the {vertex_count} vertices of the mesh"
                ),
            });
        }
    }
    let mesh = build_mesh(&obj, body_vertex_count, &groups, &mut report);

    progress("rig", 2, STAGES);
    let rig_path = dir.join(format!("rigs/standard/rig.{RIG_NAME}.json.gz"));
    let rig: BTreeMap<String, RigBoneFile> =
        serde_json::from_slice(&read_gz(&rig_path)?).map_err(|source| ImportError::Json {
            path: rig_path.clone(),
            source,
        })?;
    let bones = build_bones(&rig_path, &rig, &groups, vertex_count)?;
    report.bones = bones.len();

    progress("weights", 3, STAGES);
    let weights_path = dir.join(format!("rigs/standard/weights.{RIG_NAME}.json.gz"));
    let weights: WeightsFile =
        serde_json::from_slice(&read_gz(&weights_path)?).map_err(|source| ImportError::Json {
            path: weights_path.clone(),
            source,
        })?;
    let (mut skin_joints, mut skin_weights) =
        build_skin(&weights_path, &weights, &bones, &obj.positions, &mut report)?;
    let helper_skin_joints = skin_joints.split_off(body_vertex_count as usize);
    let helper_skin_weights = skin_weights.split_off(body_vertex_count as usize);

    progress("targets", 4, STAGES);
    let targets_dir = dir.join("targets");
    let mut files = Vec::new();
    collect_targets(&targets_dir, &targets_dir, false, &mut files)?;
    files.sort();
    let mut targets = Vec::with_capacity(files.len());
    for (k, (name, path)) in files.iter().enumerate() {
        progress("targets", k, files.len());
        let target = parse_target(path, name, vertex_count, &mut report)?;
        if target.indices.is_empty() {
            report.empty_targets.push(name.clone());
        }
        report.target_entries += target.indices.len();
        targets.push(target);
    }
    progress("targets", files.len(), files.len());
    report.targets = targets.len();

    let model = BodyModel {
        positions: obj.positions,
        body_vertex_count,
        triangles: mesh.triangles,
        uvs: mesh.uvs,
        triangle_uvs: mesh.triangle_uvs,
        helpers: mesh.helpers,
        bones,
        skin_joints,
        skin_weights,
        helper_skin_joints,
        helper_skin_weights,
        targets,
    };
    model.validate().map_err(|message| ImportError::Invalid {
        path: dir.to_path_buf(),
        field: "model".into(),
        message,
    })?;
    report.vertices = model.positions.len();
    report.body_vertices = body_vertex_count as usize;
    progress("done", STAGES, STAGES);
    Ok((model, report))
}

fn read_file(path: &Path) -> Result<Vec<u8>, ImportError> {
    fs::read(path).map_err(|source| ImportError::Io {
        path: path.to_path_buf(),
        source,
    })
}

fn read_text(path: &Path) -> Result<String, ImportError> {
    fs::read_to_string(path).map_err(|source| ImportError::Io {
        path: path.to_path_buf(),
        source,
    })
}

fn read_gz(path: &Path) -> Result<Vec<u8>, ImportError> {
    let file = fs::File::open(path).map_err(|source| ImportError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let mut out = Vec::new();
    GzDecoder::new(file)
        .read_to_end(&mut out)
        .map_err(|source| ImportError::Io {
            path: path.to_path_buf(),
            source,
        })?;
    Ok(out)
}

/// Expands inclusive index ranges.
fn expand(ranges: &[[u32; 2]]) -> Vec<u32> {
    ranges.iter().flat_map(|&[a, b]| a..=b).collect()
}

fn syntax(path: &Path, line: usize, message: impl Into<String>) -> ImportError {
    ImportError::Syntax {
        path: path.to_path_buf(),
        line,
        message: message.into(),
    }
}

fn parse_f32(path: &Path, line: usize, field: &str, s: Option<&str>) -> Result<f32, ImportError> {
    let s = s.ok_or_else(|| syntax(path, line, format!("missing {field}")))?;
    s.parse::<f32>()
        .ok()
        .filter(|v| v.is_finite())
        .ok_or_else(|| syntax(path, line, format!("{field} '{s}' is not a finite number")))
}
