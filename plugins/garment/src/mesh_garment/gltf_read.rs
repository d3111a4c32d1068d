//! glTF 2.0 garments (`.glb`, or `.gltf` with embedded or neighbouring buffers): every
//! triangle primitive of the default scene, a vertex attached (the static, skinned part of
//! seed 000 §3.2.1) when its attachment weight (`_ATTACH`, else the red of `COLOR_0`) is at
//! least 0.5.

use std::collections::HashMap;
use std::path::Path;

use base64::Engine as _;
use glam::{Mat4, Vec2, Vec3};

use crate::body::BodySurface;
use crate::error::GarmentError;
use crate::files::{DiskFiles, GarmentFiles};
use crate::garment::GarmentMesh;

use super::{Welder, finish, mesh_error};

/// Reads a glTF garment (`.glb`, or `.gltf` with embedded or neighbouring buffers).
pub fn load_gltf(
    path: impl AsRef<Path>,
    body: &BodySurface,
    fabric_name: &str,
    fabric: fitroom_cloth::Fabric,
) -> Result<GarmentMesh, GarmentError> {
    load_gltf_with(path.as_ref(), &DiskFiles, body, fabric_name, fabric)
}

/// [`load_gltf`] with the file and its `.bin` buffers read from `files`.
pub fn load_gltf_with(
    path: &Path,
    files: &dyn GarmentFiles,
    body: &BodySurface,
    fabric_name: &str,
    fabric: fitroom_cloth::Fabric,
) -> Result<GarmentMesh, GarmentError> {
    let bytes = files.read(path)?;
    let dir = path.parent().unwrap_or(Path::new("."));
    let doc = gltf::Gltf::from_slice(&bytes)
        .map_err(|e| mesh_error(path, format!("not a valid glTF: {e}")))?;
    let mut buffers: Vec<Vec<u8>> = Vec::new();
    for buffer in doc.buffers() {
        let data = match buffer.source() {
            gltf::buffer::Source::Bin => doc.blob.clone().ok_or_else(|| {
                mesh_error(
                    path,
                    "buffer refers to the GLB binary chunk, which is missing",
                )
            })?,
            gltf::buffer::Source::Uri(uri) => {
                if let Some(rest) = uri.strip_prefix("data:") {
                    let b64 = rest
                        .split_once(";base64,")
                        .map(|(_, d)| d)
                        .ok_or_else(|| mesh_error(path, "a data URI buffer is not base64"))?;
                    base64::engine::general_purpose::STANDARD
                        .decode(b64)
                        .map_err(|e| {
                            mesh_error(path, format!("a data URI buffer is not valid base64: {e}"))
                        })?
                } else {
                    files.read(&dir.join(uri))?
                }
            }
        };
        if data.len() < buffer.length() {
            return Err(mesh_error(
                path,
                format!(
                    "buffer {} has {} bytes, the file says {}",
                    buffer.index(),
                    data.len(),
                    buffer.length()
                ),
            ));
        }
        buffers.push(data);
    }
    let get = |b: gltf::Buffer| buffers.get(b.index()).map(|d| d.as_slice());

    let mut welder = Welder::default();
    let mut triangles: Vec<[u32; 3]> = Vec::new();
    let mut weight_of: HashMap<u32, f32> = HashMap::new();
    let mut panel_of: HashMap<u32, u16> = HashMap::new();
    let mut uv_of: HashMap<u32, Vec2> = HashMap::new();
    let mut panels: Vec<String> = Vec::new();
    let mut any_weights = false;

    let scene = doc.default_scene().or_else(|| doc.scenes().next());
    let mut stack: Vec<(gltf::Node, Mat4)> = match &scene {
        Some(s) => s.nodes().map(|n| (n, Mat4::IDENTITY)).collect(),
        None => doc.nodes().map(|n| (n, Mat4::IDENTITY)).collect(),
    };
    let mut depth_guard = 0usize;
    while let Some((node, parent)) = stack.pop() {
        depth_guard += 1;
        if depth_guard > 100_000 {
            return Err(mesh_error(
                path,
                "the node hierarchy is cyclic or too large",
            ));
        }
        let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        for child in node.children() {
            stack.push((child, world));
        }
        let Some(mesh) = node.mesh() else { continue };
        let panel_name = mesh
            .name()
            .map_or_else(|| format!("mesh{}", mesh.index()), str::to_owned);
        let panel = match panels.iter().position(|p| *p == panel_name) {
            Some(i) => i,
            None => {
                panels.push(panel_name);
                panels.len() - 1
            }
        } as u16;
        for prim in mesh.primitives() {
            if prim.mode() != gltf::mesh::Mode::Triangles {
                continue;
            }
            let reader = prim.reader(get);
            let positions: Vec<Vec3> = reader
                .read_positions()
                .ok_or_else(|| {
                    mesh_error(
                        path,
                        format!("mesh {} has a primitive without POSITION", mesh.index()),
                    )
                })?
                .map(|p| world.transform_point3(Vec3::from_array(p)))
                .collect();
            let weights: Option<Vec<f32>> = match prim.get(&gltf::Semantic::Extras("ATTACH".into())) {
                Some(accessor) => Some(read_scalar(accessor, get).ok_or_else(|| {
                    mesh_error(path, "`_ATTACH` must be a SCALAR float (or normalised unsigned byte/short) accessor")
                })?),
                None => reader.read_colors(0).map(|c| c.into_rgba_f32().map(|c| c[0]).collect()),
            };
            if let Some(w) = &weights {
                any_weights = true;
                if w.len() != positions.len() {
                    return Err(mesh_error(
                        path,
                        "the attachment weights and positions differ in count",
                    ));
                }
            }
            let uvs: Option<Vec<[f32; 2]>> =
                reader.read_tex_coords(0).map(|t| t.into_f32().collect());
            let local: Vec<u32> = positions.iter().map(|&p| welder.add(p)).collect();
            for (i, &v) in local.iter().enumerate() {
                let w = weights.as_ref().map_or(0.0, |w| w[i]);
                let e = weight_of.entry(v).or_insert(w);
                *e = e.max(w);
                panel_of.entry(v).or_insert(panel);
                if let Some(uv) = uvs.as_ref().and_then(|u| u.get(i)) {
                    uv_of.entry(v).or_insert(Vec2::from_array(*uv));
                }
            }
            let indices: Vec<u32> = match reader.read_indices() {
                Some(ix) => ix.into_u32().collect(),
                None => (0..positions.len() as u32).collect(),
            };
            for tri in indices.chunks_exact(3) {
                let mut t = [0u32; 3];
                for k in 0..3 {
                    t[k] = *local.get(tri[k] as usize).ok_or_else(|| {
                        mesh_error(path, "an index points past the primitive's vertices")
                    })?;
                }
                if t[0] != t[1] && t[1] != t[2] && t[0] != t[2] {
                    triangles.push(t);
                }
            }
        }
    }
    if !any_weights {
        return Err(mesh_error(
            path,
            "no attachment weights: give each vertex `_ATTACH` (float, 1 = attached) or COLOR_0 (red = 1 attached)",
        ));
    }
    let n = welder.positions.len();
    let attached = (0..n as u32)
        .map(|v| weight_of.get(&v).copied().unwrap_or(0.0) >= 0.5)
        .collect();
    finish(
        path,
        body,
        fabric_name,
        fabric,
        welder.positions,
        triangles,
        attached,
        panels,
        (0..n as u32)
            .map(|v| panel_of.get(&v).copied().unwrap_or(0))
            .collect(),
        &uv_of,
    )
}

/// Reads a scalar accessor as floats (float, or normalised unsigned byte/short).
fn read_scalar<'a, 's>(
    accessor: gltf::Accessor<'a>,
    get: impl Clone + Fn(gltf::Buffer<'a>) -> Option<&'s [u8]>,
) -> Option<Vec<f32>> {
    use gltf::accessor::{DataType, Dimensions, Iter};
    if accessor.dimensions() != Dimensions::Scalar {
        return None;
    }
    match accessor.data_type() {
        DataType::F32 => Iter::<f32>::new(accessor, get).map(|i| i.collect()),
        DataType::U8 if accessor.normalized() => {
            Iter::<u8>::new(accessor, get).map(|i| i.map(|v| v as f32 / 255.0).collect())
        }
        DataType::U16 if accessor.normalized() => {
            Iter::<u16>::new(accessor, get).map(|i| i.map(|v| v as f32 / 65535.0).collect())
        }
        _ => None,
    }
}
