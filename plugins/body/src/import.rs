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

use std::collections::{BTreeMap, HashMap};
use std::fs;
use std::io::Read;
use std::path::{Path, PathBuf};

use flate2::read::GzDecoder;
use glam::{Vec2, Vec3};
use serde::{Deserialize, Serialize};

use crate::model::{BodyModel, Bone, HelperGroup, JointPlacement, MorphTarget};

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

// ---------------------------------------------------------------------------------------------
// OBJ

struct ObjFace {
    /// (vertex, uv) per corner, 0-based.
    corners: Vec<(u32, Option<u32>)>,
    group: String,
}

struct Obj {
    positions: Vec<Vec3>,
    uvs: Vec<Vec2>,
    faces: Vec<ObjFace>,
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

/// Resolves an OBJ index (1-based, or negative = relative to the end so far).
fn obj_index(
    path: &Path,
    line: usize,
    what: &str,
    s: &str,
    count: usize,
) -> Result<u32, ImportError> {
    let i: i64 = s
        .parse()
        .map_err(|_| syntax(path, line, format!("{what} index '{s}' is not an integer")))?;
    let resolved = if i > 0 { i - 1 } else { count as i64 + i };
    if i == 0 || resolved < 0 || resolved >= count as i64 {
        return Err(syntax(
            path,
            line,
            format!("{what} index {i} is outside the {count} {what}s defined so far"),
        ));
    }
    Ok(resolved as u32)
}

fn parse_obj(path: &Path, text: &str) -> Result<Obj, ImportError> {
    let mut positions = Vec::new();
    let mut uvs = Vec::new();
    let mut faces = Vec::new();
    let mut group = String::new();
    for (k, raw) in text.lines().enumerate() {
        let line = k + 1;
        let mut it = raw.split_whitespace();
        match it.next() {
            Some("v") => {
                let x = parse_f32(path, line, "x", it.next())?;
                let y = parse_f32(path, line, "y", it.next())?;
                let z = parse_f32(path, line, "z", it.next())?;
                positions.push(Vec3::new(x, y, z) * DECIMETRE);
            }
            Some("vt") => {
                let u = parse_f32(path, line, "u", it.next())?;
                let v = parse_f32(path, line, "v", it.next())?;
                uvs.push(Vec2::new(u, v));
            }
            Some("g") => group = it.next().unwrap_or("").to_string(),
            Some("f") => {
                let mut corners = Vec::with_capacity(4);
                for token in it {
                    let mut parts = token.split('/');
                    let v = obj_index(
                        path,
                        line,
                        "vertex",
                        parts.next().unwrap_or(""),
                        positions.len(),
                    )?;
                    let t = match parts.next() {
                        Some(t) if !t.is_empty() => {
                            Some(obj_index(path, line, "texture coordinate", t, uvs.len())?)
                        }
                        _ => None,
                    };
                    corners.push((v, t));
                }
                if corners.len() < 3 {
                    return Err(syntax(
                        path,
                        line,
                        format!("a face needs at least 3 corners, found {}", corners.len()),
                    ));
                }
                faces.push(ObjFace {
                    corners,
                    group: group.clone(),
                });
            }
            _ => {}
        }
    }
    Ok(Obj {
        positions,
        uvs,
        faces,
    })
}

struct Mesh {
    triangles: Vec<[u32; 3]>,
    uvs: Vec<Vec2>,
    triangle_uvs: Vec<[Vec2; 3]>,
    helpers: Vec<HelperGroup>,
}

/// Triangulates faces as a fan from the first corner (quads: (a, b, c), (a, c, d)), which
/// keeps the OBJ's counter-clockwise winding.
fn build_mesh(
    obj: &Obj,
    body_vertex_count: u32,
    groups: &BTreeMap<String, Vec<[u32; 2]>>,
    report: &mut ImportReport,
) -> Mesh {
    let body = body_vertex_count as usize;
    let mut helpers: Vec<HelperGroup> = groups
        .iter()
        .filter(|(name, ranges)| name.starts_with("helper-") && !ranges.is_empty())
        .map(|(name, ranges)| HelperGroup {
            name: name.clone(),
            first_vertex: ranges.iter().map(|r| r[0]).min().unwrap_or(0),
            last_vertex: ranges.iter().map(|r| r[1]).max().unwrap_or(0),
            triangles: Vec::new(),
        })
        .collect();
    let helper_index: HashMap<String, usize> = helpers
        .iter()
        .enumerate()
        .map(|(i, h)| (h.name.clone(), i))
        .collect();

    let mut triangles = Vec::new();
    let mut triangle_uvs = Vec::new();
    let mut uvs: Vec<Option<Vec2>> = vec![None; body];
    let mut seam = vec![false; body];
    let uv_of = |t: Option<u32>| t.and_then(|t| obj.uvs.get(t as usize).copied());
    for face in &obj.faces {
        let c = &face.corners;
        let is_body = c.iter().all(|&(v, _)| (v as usize) < body);
        if is_body {
            for &(v, t) in c {
                if let Some(uv) = uv_of(t) {
                    match uvs[v as usize] {
                        None => uvs[v as usize] = Some(uv),
                        Some(old) if old != uv => seam[v as usize] = true,
                        Some(_) => {}
                    }
                }
            }
        }
        for k in 1..c.len() - 1 {
            let tri = [c[0].0, c[k].0, c[k + 1].0];
            if is_body {
                triangles.push(tri);
                triangle_uvs
                    .push([c[0].1, c[k].1, c[k + 1].1].map(|t| uv_of(t).unwrap_or_default()));
            } else if let Some(&h) = helper_index.get(&face.group) {
                helpers[h].triangles.push(tri);
                report.helper_triangles += 1;
            }
        }
        if !is_body && !helper_index.contains_key(&face.group) {
            report.skipped_faces += 1;
        }
    }
    report.body_triangles = triangles.len();
    report.uv_seam_vertices = seam.iter().filter(|&&s| s).count();
    report.vertices_without_uv = uvs.iter().filter(|u| u.is_none()).count();
    Mesh {
        triangles,
        uvs: uvs.into_iter().map(|u| u.unwrap_or_default()).collect(),
        triangle_uvs,
        helpers,
    }
}

// ---------------------------------------------------------------------------------------------
// Rig

#[derive(Deserialize)]
struct RigEndFile {
    strategy: String,
    #[serde(default)]
    cube_name: Option<String>,
    #[serde(default)]
    vertex_index: Option<u32>,
    #[serde(default)]
    vertex_indices: Option<Vec<u32>>,
}

#[derive(Deserialize)]
struct RigBoneFile {
    parent: String,
    head: RigEndFile,
    tail: RigEndFile,
    roll: f32,
}

fn placement(
    path: &Path,
    field: &str,
    end: &RigEndFile,
    groups: &BTreeMap<String, Vec<[u32; 2]>>,
    vertex_count: usize,
) -> Result<JointPlacement, ImportError> {
    let invalid = |message: String| ImportError::Invalid {
        path: path.to_path_buf(),
        field: field.to_string(),
        message,
    };
    let p = match end.strategy.as_str() {
        "CUBE" => {
            let name = end
                .cube_name
                .as_deref()
                .ok_or_else(|| invalid("strategy CUBE without `cube_name`".into()))?;
            let ranges = groups.get(name).ok_or_else(|| {
                invalid(format!(
                    "cube '{name}' is not a vertex group of the base mesh"
                ))
            })?;
            JointPlacement::Mean(expand(ranges))
        }
        "VERTEX" => JointPlacement::Vertex(
            end.vertex_index
                .ok_or_else(|| invalid("strategy VERTEX without `vertex_index`".into()))?,
        ),
        "MEAN" => JointPlacement::Mean(
            end.vertex_indices
                .clone()
                .ok_or_else(|| invalid("strategy MEAN without `vertex_indices`".into()))?,
        ),
        other => return Err(invalid(format!("unsupported strategy '{other}'"))),
    };
    let indices: Vec<u32> = match &p {
        JointPlacement::Mean(v) => v.clone(),
        JointPlacement::Vertex(i) => vec![*i],
        JointPlacement::Lerp { .. } => Vec::new(),
    };
    if indices.is_empty() {
        return Err(invalid("places the bone end on no vertex".into()));
    }
    if let Some(i) = indices.iter().find(|&&i| i as usize >= vertex_count) {
        return Err(invalid(format!(
            "vertex {i} is past the {vertex_count} vertices of the mesh"
        )));
    }
    Ok(p)
}

fn build_bones(
    path: &Path,
    rig: &BTreeMap<String, RigBoneFile>,
    groups: &BTreeMap<String, Vec<[u32; 2]>>,
    vertex_count: usize,
) -> Result<Vec<Bone>, ImportError> {
    // Name -> (parent name, bone with parent unresolved).
    let mut by_name: BTreeMap<String, (Option<String>, Bone)> = BTreeMap::new();
    for (name, b) in rig {
        let bone = Bone {
            name: name.clone(),
            parent: None,
            head_placement: placement(
                path,
                &format!("{name}.head"),
                &b.head,
                groups,
                vertex_count,
            )?,
            tail_placement: placement(
                path,
                &format!("{name}.tail"),
                &b.tail,
                groups,
                vertex_count,
            )?,
            roll: b.roll,
        };
        if !b.roll.is_finite() {
            return Err(ImportError::Invalid {
                path: path.to_path_buf(),
                field: format!("{name}.roll"),
                message: "not a finite number".into(),
            });
        }
        let parent = (!b.parent.is_empty()).then(|| b.parent.clone());
        by_name.insert(name.clone(), (parent, bone));
    }

    // Split the forearms.
    for (forearm, twist, hand) in SPLIT_FOREARMS {
        let missing = |bone: &str| ImportError::Invalid {
            path: path.to_path_buf(),
            field: bone.to_string(),
            message: format!("the rig has no bone '{bone}', which the forearm split needs"),
        };
        let (elbow, wrist, roll) = {
            let (_, f) = by_name.get(forearm).ok_or_else(|| missing(forearm))?;
            (f.head_placement.clone(), f.tail_placement.clone(), f.roll)
        };
        let middle = JointPlacement::Lerp {
            from: Box::new(elbow),
            to: Box::new(wrist.clone()),
            t: 0.5,
        };
        if by_name.contains_key(twist) {
            return Err(ImportError::Invalid {
                path: path.to_path_buf(),
                field: twist.to_string(),
                message: "the rig already has this bone; it cannot be split again".into(),
            });
        }
        {
            let (hand_parent, _) = by_name.get_mut(hand).ok_or_else(|| missing(hand))?;
            if hand_parent.as_deref() != Some(forearm) {
                return Err(ImportError::Invalid {
                    path: path.to_path_buf(),
                    field: format!("{hand}.parent"),
                    message: format!("expected '{forearm}', found {hand_parent:?}"),
                });
            }
            *hand_parent = Some(twist.to_string());
        }
        if let Some((_, f)) = by_name.get_mut(forearm) {
            f.tail_placement = middle.clone();
        }
        by_name.insert(
            twist.to_string(),
            (
                Some(forearm.to_string()),
                Bone {
                    name: twist.to_string(),
                    parent: None,
                    head_placement: middle,
                    tail_placement: wrist,
                    roll,
                },
            ),
        );
    }

    // Parents first: depth-first from the roots, children in name order.
    let mut children: BTreeMap<Option<String>, Vec<String>> = BTreeMap::new();
    for (name, (parent, _)) in &by_name {
        if let Some(p) = parent
            && !by_name.contains_key(p)
        {
            return Err(ImportError::Invalid {
                path: path.to_path_buf(),
                field: format!("{name}.parent"),
                message: format!("no bone is called '{p}'"),
            });
        }
        children
            .entry(parent.clone())
            .or_default()
            .push(name.clone());
    }
    let mut order: Vec<String> = Vec::with_capacity(by_name.len());
    let mut stack: Vec<String> = children.get(&None).cloned().unwrap_or_default();
    stack.reverse();
    while let Some(name) = stack.pop() {
        if let Some(kids) = children.get(&Some(name.clone())) {
            stack.extend(kids.iter().rev().cloned());
        }
        order.push(name);
    }
    if order.len() != by_name.len() {
        let unreachable: Vec<&String> = by_name.keys().filter(|n| !order.contains(n)).collect();
        return Err(ImportError::Invalid {
            path: path.to_path_buf(),
            field: "parent".into(),
            message: format!("bones in a parent cycle: {unreachable:?}"),
        });
    }
    let index: HashMap<&str, usize> = order
        .iter()
        .enumerate()
        .map(|(i, n)| (n.as_str(), i))
        .collect();
    let mut bones = Vec::with_capacity(order.len());
    for name in &order {
        if let Some((parent, bone)) = by_name.get(name) {
            let mut bone = bone.clone();
            bone.parent = parent.as_deref().and_then(|p| index.get(p).copied());
            bones.push(bone);
        }
    }
    if bones.len() > u16::MAX as usize {
        return Err(ImportError::Invalid {
            path: path.to_path_buf(),
            field: "bones".into(),
            message: format!("{} bones do not fit skin joint indices (u16)", bones.len()),
        });
    }
    Ok(bones)
}

// ---------------------------------------------------------------------------------------------
// Skin weights

#[derive(Deserialize)]
struct WeightsFile {
    weights: BTreeMap<String, Vec<(u32, f32)>>,
}

/// Distance from `p` to the segment `a`-`b`.
fn segment_distance(p: Vec3, a: Vec3, b: Vec3) -> f32 {
    let ab = b - a;
    let t = if ab.length_squared() > 0.0 {
        ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0)
    } else {
        0.0
    };
    p.distance(a + ab * t)
}

/// Position of `p` along `a`->`b` as a fraction, clamped to 0..1.
pub fn fraction_along(p: Vec3, a: Vec3, b: Vec3) -> f32 {
    let ab = b - a;
    if ab.length_squared() == 0.0 {
        return 0.0;
    }
    ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0)
}

type Skin = (Vec<[u16; 4]>, Vec<[f32; 4]>);

fn build_skin(
    path: &Path,
    file: &WeightsFile,
    bones: &[Bone],
    positions: &[Vec3],
    report: &mut ImportReport,
) -> Result<Skin, ImportError> {
    let n = positions.len();
    let index: HashMap<&str, usize> = bones
        .iter()
        .enumerate()
        .map(|(i, b)| (b.name.as_str(), i))
        .collect();
    // The split: forearm bone index -> (twist bone index, elbow, wrist) on the base mesh.
    let mut splits: HashMap<usize, (usize, Vec3, Vec3)> = HashMap::new();
    for (forearm, twist, _) in SPLIT_FOREARMS {
        if let (Some(&f), Some(&t)) = (index.get(forearm), index.get(twist)) {
            let elbow = bones[f].head_placement.resolve(positions);
            let wrist = bones[t].tail_placement.resolve(positions);
            splits.insert(f, (t, elbow, wrist));
        }
    }

    let mut influences: Vec<Vec<(usize, f32)>> = vec![Vec::new(); n];
    for (bone_name, list) in &file.weights {
        let &b = index
            .get(bone_name.as_str())
            .ok_or_else(|| ImportError::Invalid {
                path: path.to_path_buf(),
                field: format!("weights.{bone_name}"),
                message: "no bone of the rig has this name".into(),
            })?;
        for (k, &(v, w)) in list.iter().enumerate() {
            let field = || format!("weights.{bone_name}[{k}]");
            if v as usize >= n {
                return Err(ImportError::Invalid {
                    path: path.to_path_buf(),
                    field: field(),
                    message: format!("vertex {v} is past the {n} vertices of the mesh"),
                });
            }
            if !w.is_finite() || w < 0.0 {
                return Err(ImportError::Invalid {
                    path: path.to_path_buf(),
                    field: field(),
                    message: format!("weight {w} is not a finite non-negative number"),
                });
            }
            if w == 0.0 {
                continue;
            }
            let slot = &mut influences[v as usize];
            let mut add = |bone: usize, weight: f32| {
                if weight <= 0.0 {
                    return;
                }
                match slot.iter_mut().find(|(b, _)| *b == bone) {
                    Some((_, x)) => *x += weight,
                    None => slot.push((bone, weight)),
                }
            };
            match splits.get(&b) {
                Some(&(twist, elbow, wrist)) => {
                    let t = fraction_along(positions[v as usize], elbow, wrist);
                    add(b, w * (1.0 - t));
                    add(twist, w * t);
                }
                None => add(b, w),
            }
        }
    }

    // Bones that deform (carry weight somewhere): candidates for unweighted vertices.
    let mut deforming = vec![false; bones.len()];
    for inf in &influences {
        for &(b, _) in inf {
            deforming[b] = true;
        }
    }
    let rest_segments: Vec<(Vec3, Vec3)> = bones
        .iter()
        .map(|b| {
            (
                b.head_placement.resolve(positions),
                b.tail_placement.resolve(positions),
            )
        })
        .collect();

    let mut joints = Vec::with_capacity(n);
    let mut weights = Vec::with_capacity(n);
    for (v, mut inf) in influences.into_iter().enumerate() {
        if inf.is_empty() {
            report.unweighted_vertices += 1;
            let p = positions[v];
            let nearest = (0..bones.len())
                .filter(|&b| deforming[b] || !deforming.iter().any(|&d| d))
                .min_by(|&a, &b| {
                    let da = segment_distance(p, rest_segments[a].0, rest_segments[a].1);
                    let db = segment_distance(p, rest_segments[b].0, rest_segments[b].1);
                    da.total_cmp(&db)
                })
                .unwrap_or(0);
            inf.push((nearest, 1.0));
        }
        inf.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
        if inf.len() > 4 {
            report.truncated_vertices += 1;
            inf.truncate(4);
        }
        let total: f32 = inf.iter().map(|x| x.1).sum();
        let mut j = [0u16; 4];
        let mut w = [0f32; 4];
        for (k, &(b, x)) in inf.iter().enumerate() {
            j[k] = b as u16;
            w[k] = x / total;
        }
        joints.push(j);
        weights.push(w);
    }
    Ok((joints, weights))
}

// ---------------------------------------------------------------------------------------------
// Morph targets

/// Whether a target is one of the body-region scale targets that help fitting
/// (`neck/neck-scale-horiz-decr`, `legs/l-upperleg-scale-depth-incr`, ...): the `*-scale-*`
/// targets of the neck, torso, hip, legs and arms (not the face's or the feet's).
fn is_region_scale(root: &Path, dir: &Path, stem: &str) -> bool {
    let top = dir
        .strip_prefix(root)
        .ok()
        .and_then(|p| p.components().next())
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .unwrap_or_default();
    matches!(top.as_str(), "neck" | "torso" | "hip" | "legs" | "arms")
        && stem.contains("-scale-")
        && (stem.ends_with("-decr") || stem.ends_with("-incr"))
        && !stem.contains("foot")
        && !stem.contains("hand")
}

/// Collects `(name, path)` of the targets to import: everything under `macrodetails/`, every
/// `measure-*` target anywhere and the region scale targets ([`is_region_scale`]).
fn collect_targets(
    root: &Path,
    dir: &Path,
    in_macrodetails: bool,
    out: &mut Vec<(String, PathBuf)>,
) -> Result<(), ImportError> {
    let io = |source| ImportError::Io {
        path: dir.to_path_buf(),
        source,
    };
    let mut entries: Vec<PathBuf> = fs::read_dir(dir)
        .map_err(io)?
        .map(|e| e.map(|e| e.path()))
        .collect::<Result<_, _>>()
        .map_err(io)?;
    entries.sort();
    for path in entries {
        let file_name = path
            .file_name()
            .and_then(|n| n.to_str())
            .unwrap_or_default()
            .to_string();
        if path.is_dir() {
            let macro_dir = in_macrodetails || (dir == root && file_name == "macrodetails");
            collect_targets(root, &path, macro_dir, out)?;
        } else if let Some(stem) = file_name.strip_suffix(".target.gz")
            && (in_macrodetails || stem.starts_with("measure-") || is_region_scale(root, dir, stem))
        {
            let rel = path.strip_prefix(root).unwrap_or(&path);
            let mut name: Vec<String> = rel
                .parent()
                .map(|p| {
                    p.components()
                        .map(|c| c.as_os_str().to_string_lossy().into_owned())
                        .collect()
                })
                .unwrap_or_default();
            name.push(stem.to_string());
            out.push((name.join("/"), path));
        }
    }
    Ok(())
}

/// Reads one `.target.gz` (lines `vertex dx dy dz` in decimetres, `#` comments) into a
/// quantised sparse target.
fn parse_target(
    path: &Path,
    name: &str,
    vertex_count: usize,
    report: &mut ImportReport,
) -> Result<MorphTarget, ImportError> {
    let bytes = read_gz(path)?;
    let text = String::from_utf8(bytes).map_err(|e| ImportError::Invalid {
        path: path.to_path_buf(),
        field: "text".into(),
        message: format!("not UTF-8: {e}"),
    })?;
    let mut entries: BTreeMap<u32, Vec3> = BTreeMap::new();
    for (k, raw) in text.lines().enumerate() {
        let line = k + 1;
        let s = raw.trim();
        if s.is_empty() || s.starts_with('#') {
            continue;
        }
        let mut it = s.split_whitespace();
        let index_str = it.next().unwrap_or("");
        let index: u32 = index_str.parse().map_err(|_| {
            syntax(
                path,
                line,
                format!("vertex index '{index_str}' is not an integer"),
            )
        })?;
        if index as usize >= vertex_count {
            return Err(syntax(
                path,
                line,
                format!("vertex index {index} is past the {vertex_count} vertices of the mesh"),
            ));
        }
        let dx = parse_f32(path, line, "dx", it.next())?;
        let dy = parse_f32(path, line, "dy", it.next())?;
        let dz = parse_f32(path, line, "dz", it.next())?;
        if it.next().is_some() {
            return Err(syntax(path, line, "more than 4 fields (vertex dx dy dz)"));
        }
        let d = Vec3::new(dx, dy, dz);
        if d == Vec3::ZERO {
            report.zero_deltas_dropped += 1;
            continue;
        }
        // A vertex listed twice moves by the sum.
        *entries.entry(index).or_insert(Vec3::ZERO) += d * DECIMETRE;
    }
    Ok(quantise(name, &entries, report))
}

/// Quantises displacements (metres) to `i16` with `scale = max |component| / 32767`.
fn quantise(name: &str, entries: &BTreeMap<u32, Vec3>, report: &mut ImportReport) -> MorphTarget {
    let max = entries
        .values()
        .map(|d| d.abs().max_element())
        .fold(0.0f32, f32::max);
    let scale = max / i16::MAX as f32;
    let mut indices = Vec::with_capacity(entries.len());
    let mut deltas = Vec::with_capacity(entries.len());
    if scale > 0.0 {
        for (&i, &d) in entries {
            let q = (d / scale).round().clamp(
                Vec3::splat(-(i16::MAX as f32)),
                Vec3::splat(i16::MAX as f32),
            );
            let q = [q.x as i16, q.y as i16, q.z as i16];
            if q == [0, 0, 0] {
                report.quantised_to_zero_dropped += 1;
                continue;
            }
            indices.push(i);
            deltas.push(q);
        }
    }
    MorphTarget {
        name: name.to_string(),
        indices,
        deltas,
        scale_m: scale,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn obj_errors_name_the_line() {
        let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n";
        let err = parse_obj(Path::new("x.obj"), text)
            .err()
            .map(|e| e.to_string());
        let err = err.unwrap_or_default();
        assert!(err.contains("x.obj, line 4"), "{err}");
        assert!(err.contains("vertex index 4"), "{err}");
        let err = parse_obj(Path::new("x.obj"), "v 0 nan 0\n")
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default();
        assert!(err.contains("line 1") && err.contains('y'), "{err}");
    }

    #[test]
    fn quantisation_keeps_the_largest_exact_and_drops_zeroes() {
        let mut report = ImportReport::default();
        let mut e = BTreeMap::new();
        e.insert(3, Vec3::new(0.1, -0.05, 0.0));
        e.insert(7, Vec3::new(1e-9, 0.0, 0.0));
        let t = quantise("t", &e, &mut report);
        assert_eq!(t.indices, vec![3]);
        assert_eq!(t.deltas[0][0], i16::MAX);
        assert!((t.deltas[0][1] as f32 * t.scale_m + 0.05).abs() <= 0.51 * t.scale_m);
        assert_eq!(report.quantised_to_zero_dropped, 1);
    }

    #[test]
    fn fraction_along_clamps() {
        let (a, b) = (Vec3::ZERO, Vec3::new(0.0, 0.0, 2.0));
        assert_eq!(fraction_along(Vec3::new(1.0, 0.0, 1.0), a, b), 0.5);
        assert_eq!(fraction_along(Vec3::new(0.0, 0.0, -1.0), a, b), 0.0);
        assert_eq!(fraction_along(Vec3::new(0.0, 0.0, 3.0), a, b), 1.0);
    }
}
