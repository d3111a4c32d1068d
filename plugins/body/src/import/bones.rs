//! The MPFB2 `game_engine` rig file (`rigs/standard/rig.game_engine.json.gz`) into the model's
//! bones, parents first, with each forearm split in two (seed 000 §4.4.3, the "split ulna").

use std::collections::{BTreeMap, HashMap};
use std::path::Path;

use serde::Deserialize;

use super::{ImportError, SPLIT_FOREARMS, expand};
use crate::model::{Bone, JointPlacement};

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
pub(super) struct RigBoneFile {
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

pub(super) fn build_bones(
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
