//! A garment written as binary glTF (GLB), for a 3D editor: one mesh, one triangle
//! primitive, attachment weight 1 on the static part (seed 000 §3.2.1: the skinned part).

use std::path::Path;

use fitroom_body::export;

use crate::error::GarmentError;
use crate::garment::GarmentMesh;

/// Which attribute [`write_glb`] stores the attachment weight in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AttachChannel {
    /// The red channel of `COLOR_0` (RGBA float; green and blue 1, alpha 1).
    Color0,
    /// The custom attribute `_ATTACH`.
    Custom,
    /// Both.
    Both,
}

/// The garment as a binary glTF (GLB): one mesh, one triangle primitive, attachment weight 1
/// on the static (skinned) vertices.
pub fn glb_bytes(garment: &GarmentMesh, channel: AttachChannel) -> Vec<u8> {
    let n = garment.positions.len();
    let mut bin: Vec<u8> = Vec::new();
    let mut views: Vec<(usize, usize)> = Vec::new();
    let mut push = |bin: &mut Vec<u8>, bytes: Vec<u8>| {
        while !bin.len().is_multiple_of(4) {
            bin.push(0);
        }
        views.push((bin.len(), bytes.len()));
        bin.extend_from_slice(&bytes);
    };
    let pos = export::vec3_bytes(&garment.positions);
    push(&mut bin, pos);
    let idx = export::index_bytes(&garment.triangles);
    push(&mut bin, idx);
    let weight = |v: usize| {
        if garment.skinned.get(v).copied().unwrap_or(false) {
            1.0f32
        } else {
            0.0
        }
    };
    let colour: Vec<u8> = (0..n)
        .flat_map(|v| [weight(v), 1.0, 1.0, 1.0])
        .flat_map(f32::to_le_bytes)
        .collect();
    push(&mut bin, colour);
    let attach: Vec<u8> = (0..n).map(weight).flat_map(f32::to_le_bytes).collect();
    push(&mut bin, attach);
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let (lo, hi) = export::bounds(&garment.positions);
    let mut attributes = vec!["\"POSITION\":0".to_owned()];
    if matches!(channel, AttachChannel::Color0 | AttachChannel::Both) {
        attributes.push("\"COLOR_0\":2".to_owned());
    }
    if matches!(channel, AttachChannel::Custom | AttachChannel::Both) {
        attributes.push("\"_ATTACH\":3".to_owned());
    }
    let view_json: Vec<String> = views
        .iter()
        .map(|(offset, len)| {
            format!("{{\"buffer\":0,\"byteOffset\":{offset},\"byteLength\":{len}}}")
        })
        .collect();
    let json = format!(
        concat!(
            "{{\"asset\":{{\"version\":\"2.0\",\"generator\":\"fitroom_garment\"}},",
            "\"scene\":0,\"scenes\":[{{\"nodes\":[0]}}],\"nodes\":[{{\"mesh\":0,\"name\":\"{name}\"}}],",
            "\"meshes\":[{{\"name\":\"{name}\",\"primitives\":[{{\"attributes\":{{{attrs}}},\"indices\":1,\"mode\":4}}]}}],",
            "\"buffers\":[{{\"byteLength\":{blen}}}],\"bufferViews\":[{views}],",
            "\"accessors\":[",
            "{{\"bufferView\":0,\"componentType\":5126,\"count\":{n},\"type\":\"VEC3\",\"min\":[{l0},{l1},{l2}],\"max\":[{h0},{h1},{h2}]}},",
            "{{\"bufferView\":1,\"componentType\":5125,\"count\":{ni},\"type\":\"SCALAR\"}},",
            "{{\"bufferView\":2,\"componentType\":5126,\"count\":{n},\"type\":\"VEC4\"}},",
            "{{\"bufferView\":3,\"componentType\":5126,\"count\":{n},\"type\":\"SCALAR\"}}]}}"
        ),
        name = garment.name.replace('"', "'"),
        attrs = attributes.join(","),
        blen = bin.len(),
        views = view_json.join(","),
        n = n,
        ni = garment.triangles.len() * 3,
        l0 = lo.x,
        l1 = lo.y,
        l2 = lo.z,
        h0 = hi.x,
        h1 = hi.y,
        h2 = hi.z,
    );
    export::glb(json.into_bytes(), bin)
}

/// Writes [`glb_bytes`] to `path`.
pub fn write_glb(
    garment: &GarmentMesh,
    path: impl AsRef<Path>,
    channel: AttachChannel,
) -> Result<(), GarmentError> {
    let path = path.as_ref();
    std::fs::write(path, glb_bytes(garment, channel)).map_err(|source| GarmentError::Write {
        path: path.to_owned(),
        source,
    })
}
