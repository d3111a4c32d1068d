//! The MPFB2 skin weights (`rigs/standard/weights.game_engine.json.gz`) into four influences per
//! vertex: the forearm's weight shared with its twist bone along the elbow->wrist axis (seed 000
//! §4.4.3), unweighted vertices given to the nearest bone, the smallest influences dropped and the
//! rest renormalised (GPU skinning in Bevy takes 4).

use std::collections::{BTreeMap, HashMap};
use std::path::Path;

use glam::Vec3;
use serde::Deserialize;

use super::{ImportError, ImportReport, SPLIT_FOREARMS};
use crate::model::Bone;

#[derive(Deserialize)]
pub(super) struct WeightsFile {
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

pub(super) fn build_skin(
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fraction_along_clamps() {
        let (a, b) = (Vec3::ZERO, Vec3::new(0.0, 0.0, 2.0));
        assert_eq!(fraction_along(Vec3::new(1.0, 0.0, 1.0), a, b), 0.5);
        assert_eq!(fraction_along(Vec3::new(0.0, 0.0, -1.0), a, b), 0.0);
        assert_eq!(fraction_along(Vec3::new(0.0, 0.0, 3.0), a, b), 1.0);
    }
}
