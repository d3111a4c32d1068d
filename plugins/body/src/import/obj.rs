//! The MakeHuman hm08 base mesh as a Wavefront OBJ file (`3dobjs/base.obj`, decimetres, CC0): its
//! parser, and the body triangles, UVs and helper groups built from its faces, triangulated as fans
//! that keep the OBJ's counter-clockwise winding.

use std::collections::{BTreeMap, HashMap};
use std::path::Path;

use glam::{Vec2, Vec3};

use super::{DECIMETRE, ImportError, ImportReport, parse_f32, syntax};
use crate::model::HelperGroup;

struct ObjFace {
    /// (vertex, uv) per corner, 0-based.
    corners: Vec<(u32, Option<u32>)>,
    group: String,
}

pub(super) struct Obj {
    pub(super) positions: Vec<Vec3>,
    uvs: Vec<Vec2>,
    faces: Vec<ObjFace>,
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

pub(super) fn parse_obj(path: &Path, text: &str) -> Result<Obj, ImportError> {
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

pub(super) struct Mesh {
    pub(super) triangles: Vec<[u32; 3]>,
    pub(super) uvs: Vec<Vec2>,
    pub(super) triangle_uvs: Vec<[Vec2; 3]>,
    pub(super) helpers: Vec<HelperGroup>,
}

/// Triangulates faces as a fan from the first corner (quads: (a, b, c), (a, c, d)), which
/// keeps the OBJ's counter-clockwise winding.
pub(super) fn build_mesh(
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
}
