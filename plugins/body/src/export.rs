//! Meshes written for other tools: Wavefront OBJ text and binary glTF 2.0 (GLB) of positions,
//! normals and triangles. The body export uses them whole; the garment writers build on the
//! pieces (vertex and face lines, buffers, the GLB container).

use std::fmt::Write as _;

use glam::Vec3;

use crate::{BodyModel, ShapedBody};

/// Appends `v x y z` lines with `decimals` decimals.
pub fn obj_vertices(out: &mut String, positions: &[Vec3], decimals: usize) {
    for p in positions {
        let _ = writeln!(
            out,
            "v {:.*} {:.*} {:.*}",
            decimals, p.x, decimals, p.y, decimals, p.z
        );
    }
}

/// Appends `vn x y z` lines with `decimals` decimals.
pub fn obj_normals(out: &mut String, normals: &[Vec3], decimals: usize) {
    for n in normals {
        let _ = writeln!(
            out,
            "vn {:.*} {:.*} {:.*}",
            decimals, n.x, decimals, n.y, decimals, n.z
        );
    }
}

/// Appends `f` lines of 0-based `triangles` (OBJ counts from 1); with `normals`, each corner
/// names the normal of the same index (`f a//a b//b c//c`).
pub fn obj_faces(out: &mut String, triangles: &[[u32; 3]], normals: bool) {
    for t in triangles {
        let [a, b, c] = t.map(|i| i + 1);
        let _ = if normals {
            writeln!(out, "f {a}//{a} {b}//{b} {c}//{c}")
        } else {
            writeln!(out, "f {a} {b} {c}")
        };
    }
}

/// The smallest and largest coordinates of `positions` (infinite for none).
pub fn bounds(positions: &[Vec3]) -> (Vec3, Vec3) {
    positions.iter().fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(lo, hi), &p| (lo.min(p), hi.max(p)),
    )
}

/// The little-endian `f32` bytes of `vectors`, component after component.
pub fn vec3_bytes(vectors: &[Vec3]) -> Vec<u8> {
    vectors
        .iter()
        .flat_map(|v| v.to_array())
        .flat_map(f32::to_le_bytes)
        .collect()
}

/// The little-endian `u32` bytes of `triangles`' indices.
pub fn index_bytes(triangles: &[[u32; 3]]) -> Vec<u8> {
    triangles
        .iter()
        .flatten()
        .flat_map(|i| i.to_le_bytes())
        .collect()
}

/// A binary glTF 2.0 file: the 12-byte header, the JSON chunk (padded with spaces to 4 bytes)
/// and the BIN chunk (padded with zeros).
pub fn glb(mut json: Vec<u8>, mut bin: Vec<u8>) -> Vec<u8> {
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut out: Vec<u8> = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json);
    out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(&bin);
    out
}

/// A mesh of positions, normals (one per position) and triangles as GLB: one node and mesh
/// named `name`, one triangle primitive.
pub fn mesh_glb(
    name: &str,
    generator: &str,
    positions: &[Vec3],
    normals: &[Vec3],
    triangles: &[[u32; 3]],
) -> Vec<u8> {
    let n = positions.len();
    let (lo, hi) = bounds(positions);
    let mut bin: Vec<u8> = Vec::with_capacity(n * 24 + triangles.len() * 12);
    bin.extend(vec3_bytes(positions));
    bin.extend(vec3_bytes(&normals[..n]));
    bin.extend(index_bytes(triangles));
    let (pos_len, idx_len) = (n * 12, triangles.len() * 12);
    let json = serde_json::json!({
        "asset": {"version": "2.0", "generator": generator},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0, "name": name}],
        "meshes": [{"name": name, "primitives": [{
            "attributes": {"POSITION": 0, "NORMAL": 1}, "indices": 2, "mode": 4
        }]}],
        "buffers": [{"byteLength": bin.len()}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": pos_len, "target": 34962},
            {"buffer": 0, "byteOffset": pos_len, "byteLength": pos_len, "target": 34962},
            {"buffer": 0, "byteOffset": 2 * pos_len, "byteLength": idx_len, "target": 34963}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": n, "type": "VEC3",
             "min": lo.to_array(), "max": hi.to_array()},
            {"bufferView": 1, "componentType": 5126, "count": n, "type": "VEC3"},
            {"bufferView": 2, "componentType": 5125, "count": triangles.len() * 3, "type": "SCALAR"}
        ]
    });
    // A `Value` always serialises.
    let json = serde_json::to_vec(&json).unwrap_or_default();
    glb(json, bin)
}

/// The shaped body as OBJ text: every vertex of the model in its order (metres, +Y up, rest
/// pose), the body's normals, and the body's triangles in group `body`. Helper vertices
/// (tights, joint cubes...) come after the body's and no face uses them; they keep the file
/// re-measurable, since landmarks use the rig's joint cubes.
pub fn body_obj(model: &BodyModel, body: &ShapedBody) -> String {
    let mut text = String::with_capacity(body.positions.len() * 40 + model.triangles.len() * 30);
    let _ = writeln!(
        text,
        "# fitroom body export: MakeHuman hm08 (CC0), metres, +Y up, rest pose\n\
         # {} vertices ({} body, then helpers), {} triangles",
        body.positions.len(),
        model.body_vertex_count,
        model.triangles.len()
    );
    obj_vertices(&mut text, &body.positions, 6);
    obj_normals(&mut text, &body.normals, 5);
    text.push_str("g body\n");
    obj_faces(&mut text, &model.triangles, true);
    text
}

/// The shaped body as GLB: one mesh with positions (metres, +Y up, rest pose) and normals of
/// the body vertices and its triangles.
pub fn body_glb(model: &BodyModel, body: &ShapedBody) -> Vec<u8> {
    let n = model.body_vertex_count as usize;
    mesh_glb(
        "body",
        "fitroom body export (MakeHuman hm08, CC0)",
        &body.positions[..n],
        &body.normals[..n],
        &model.triangles,
    )
}
