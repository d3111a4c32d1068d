//! Garments given as meshes rather than patterns: Wavefront OBJ + MTL and glTF 2.0, modelled
//! around the MakeHuman body in model space (metres, +Y up, facing +Z).
//!
//! - **OBJ + MTL** (seed 000 §3.2.1): faces whose material name ends in `Free` are the
//!   simulated part; the other faces are the static part, skinned with the body. Vertices of
//!   static faces are attached (those shared with free faces are the attachment line). The
//!   OBJ's groups and materials are joined back into one mesh by vertex position.
//! - **glTF** (`.glb` or `.gltf` with its buffers embedded as data URIs or in `.bin` files
//!   next to it): every triangle primitive of the default scene, node transforms applied. A
//!   vertex is attached when its attachment weight is at least 0.5: the custom attribute
//!   `_ATTACH` (a float scalar) when present, else the red channel of `COLOR_0`
//!   (1 = attached). Attached vertices are the static, skinned part.
//!
//! Both give a [`GarmentMesh`] bound to the body; [`write_obj`] and [`write_glb`] write one
//! back (e.g. a pattern garment, for a 3D editor).

use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::Path;

use base64::Engine as _;
use glam::{Mat4, Vec2, Vec3};

use crate::binding::Binding;
use crate::body::BodySurface;
use crate::error::GarmentError;
use crate::garment::GarmentMesh;

/// The material suffix marking simulated faces (seed 000 §3.2.1).
pub const FREE_SUFFIX: &str = "Free";

/// Welds vertices by exact position (bit pattern).
#[derive(Default)]
struct Welder {
    index: HashMap<[u32; 3], u32>,
    positions: Vec<Vec3>,
}

impl Welder {
    fn add(&mut self, p: Vec3) -> u32 {
        let key = p.to_array().map(f32::to_bits);
        *self.index.entry(key).or_insert_with(|| {
            self.positions.push(p);
            (self.positions.len() - 1) as u32
        })
    }
}

fn mesh_error(file: &Path, problem: impl Into<String>) -> GarmentError {
    GarmentError::Mesh {
        file: file.display().to_string(),
        problem: problem.into(),
    }
}

/// Builds the garment from welded geometry and a per-vertex attached flag.
#[allow(clippy::too_many_arguments)]
fn finish(
    file: &Path,
    body: &BodySurface,
    fabric_name: &str,
    fabric: fitroom_cloth::Fabric,
    positions: Vec<Vec3>,
    triangles: Vec<[u32; 3]>,
    attached_mask: Vec<bool>,
    panels: Vec<String>,
    panel_of_vertex: Vec<u16>,
    uv_of: &HashMap<u32, Vec2>,
) -> Result<GarmentMesh, GarmentError> {
    // The texture coordinates, when every vertex has one.
    let n = positions.len();
    let rest_2d: Vec<Vec2> = if uv_of.len() == n {
        (0..n as u32)
            .filter_map(|v| uv_of.get(&v).copied())
            .collect()
    } else {
        Vec::new()
    };
    let name = file.file_stem().map_or_else(
        || "garment".to_owned(),
        |s| s.to_string_lossy().into_owned(),
    );
    if triangles.is_empty() {
        return Err(mesh_error(file, "has no triangles"));
    }
    if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
        return Err(mesh_error(file, format!("vertex {i} is not finite")));
    }
    // Drop unused vertices (points and lines, or a buffer shared with other meshes).
    let mut used = vec![false; positions.len()];
    for t in &triangles {
        for &v in t {
            used[v as usize] = true;
        }
    }
    let mut remap = vec![u32::MAX; positions.len()];
    let mut kept = 0u32;
    for (v, &u) in used.iter().enumerate() {
        if u {
            remap[v] = kept;
            kept += 1;
        }
    }
    // The values of the used vertices, in order.
    fn used_values<T: Copy>(values: &[T], used: &[bool]) -> Vec<T> {
        values
            .iter()
            .zip(used)
            .filter(|(_, u)| **u)
            .map(|(v, _)| *v)
            .collect()
    }
    let positions = used_values(&positions, &used);
    let attached_mask = used_values(&attached_mask, &used);
    let panel_of_vertex = used_values(&panel_of_vertex, &used);
    let rest_2d: Vec<Vec2> = if rest_2d.len() == used.len() {
        used_values(&rest_2d, &used)
    } else {
        Vec::new()
    };
    let triangles: Vec<[u32; 3]> = triangles
        .iter()
        .map(|t| t.map(|v| remap[v as usize]))
        .collect();
    let attached: Vec<u32> = (0..positions.len() as u32)
        .filter(|&v| attached_mask[v as usize])
        .collect();
    let points: Vec<Vec3> = attached.iter().map(|&v| positions[v as usize]).collect();
    let binding = Binding::bind(body, &attached, &points, &vec![None; attached.len()])?;
    Ok(GarmentMesh {
        name,
        size: String::new(),
        positions,
        triangles,
        attached,
        binding,
        seams: Vec::new(),
        seam_lines: Vec::new(),
        skinned: attached_mask,
        fabric,
        fabric_name: fabric_name.to_owned(),
        panels,
        panel_of_vertex,
        rest_2d,
        rows: Vec::new(),
        ignore_colliders: Vec::new(),
    })
}

/// Reads an OBJ + MTL garment: faces with a material ending in `Free` are simulated, the rest
/// is the static, skinned part.
pub fn load_obj(
    path: impl AsRef<Path>,
    body: &BodySurface,
    fabric_name: &str,
    fabric: fitroom_cloth::Fabric,
) -> Result<GarmentMesh, GarmentError> {
    let path = path.as_ref();
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ignore_points: true,
        ignore_lines: true,
    };
    let (models, materials) = tobj::load_obj(path, &options)
        .map_err(|e| mesh_error(path, format!("cannot read the OBJ: {e}")))?;
    let materials = materials.map_err(|e| {
        mesh_error(
            path,
            format!("cannot read its MTL file ({e}); the material names mark the simulated part (suffix `{FREE_SUFFIX}`)"),
        )
    })?;
    let mut welder = Welder::default();
    let mut triangles = Vec::new();
    let mut face_free = Vec::new();
    let mut face_panel = Vec::new();
    let mut panels: Vec<String> = Vec::new();
    let mut uv_of: HashMap<u32, Vec2> = HashMap::new();
    for model in &models {
        let mesh = &model.mesh;
        let material = mesh
            .material_id
            .and_then(|m| materials.get(m))
            .map(|m| m.name.clone())
            .ok_or_else(|| {
                mesh_error(
                    path,
                    format!(
                        "object \"{}\" has no material (`usemtl`) defined in the MTL file; give every face a material",
                        model.name
                    ),
                )
            })?;
        let panel = match panels.iter().position(|p| *p == material) {
            Some(i) => i,
            None => {
                panels.push(material.clone());
                panels.len() - 1
            }
        };
        let free = material.ends_with(FREE_SUFFIX);
        let local: Vec<u32> = mesh
            .positions
            .chunks_exact(3)
            .map(|c| welder.add(Vec3::new(c[0], c[1], c[2])))
            .collect();
        if mesh.indices.len() % 3 != 0 {
            return Err(mesh_error(
                path,
                format!("object \"{}\" is not triangulated", model.name),
            ));
        }
        for (f, tri) in mesh.indices.chunks_exact(3).enumerate() {
            let mut t = [0u32; 3];
            for k in 0..3 {
                let i = tri[k] as usize;
                t[k] = *local.get(i).ok_or_else(|| {
                    mesh_error(
                        path,
                        format!("object \"{}\" indexes past its vertices", model.name),
                    )
                })?;
                if let Some(&ti) = mesh.texcoord_indices.get(3 * f + k)
                    && let Some(uv) = mesh.texcoords.get(2 * ti as usize..2 * ti as usize + 2)
                {
                    uv_of.entry(t[k]).or_insert(Vec2::new(uv[0], uv[1]));
                }
            }
            if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
                continue;
            }
            triangles.push(t);
            face_free.push(free);
            face_panel.push(panel as u16);
        }
    }
    let n = welder.positions.len();
    if !face_free.iter().any(|&f| f) {
        return Err(mesh_error(
            path,
            format!(
                "no material name ends in `{FREE_SUFFIX}`, so nothing would be simulated; name the simulated part's material e.g. `Skirt{FREE_SUFFIX}`"
            ),
        ));
    }
    let mut attached = vec![false; n];
    let mut panel_of_vertex = vec![u16::MAX; n];
    for ((t, &free), &panel) in triangles.iter().zip(&face_free).zip(&face_panel) {
        for &v in t {
            if !free {
                attached[v as usize] = true;
            }
            if panel_of_vertex[v as usize] == u16::MAX || !free {
                panel_of_vertex[v as usize] = panel;
            }
        }
    }
    finish(
        path,
        body,
        fabric_name,
        fabric,
        welder.positions,
        triangles,
        attached,
        panels,
        panel_of_vertex
            .into_iter()
            .map(|p| if p == u16::MAX { 0 } else { p })
            .collect(),
        &uv_of,
    )
}

/// Reads a glTF garment (`.glb`, or `.gltf` with embedded or neighbouring buffers).
pub fn load_gltf(
    path: impl AsRef<Path>,
    body: &BodySurface,
    fabric_name: &str,
    fabric: fitroom_cloth::Fabric,
) -> Result<GarmentMesh, GarmentError> {
    let path = path.as_ref();
    let bytes = std::fs::read(path).map_err(|source| GarmentError::Read {
        path: path.to_owned(),
        source,
    })?;
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
                    let file = dir.join(uri);
                    std::fs::read(&file)
                        .map_err(|source| GarmentError::Read { path: file, source })?
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

/// Writes a garment as OBJ + MTL (next to it, same stem): faces with every vertex in the
/// static part get the material `<panel>`, the others `<panel>Free`.
pub fn write_obj(garment: &GarmentMesh, path: impl AsRef<Path>) -> Result<(), GarmentError> {
    let path = path.as_ref();
    let mtl = path.with_extension("mtl");
    let mtl_name = mtl.file_name().map_or_else(
        || "garment.mtl".to_owned(),
        |s| s.to_string_lossy().into_owned(),
    );
    let skinned = |v: u32| garment.skinned.get(v as usize).copied().unwrap_or(false);
    let material_of = |t: &[u32; 3]| {
        // A free face takes the panel of its first free vertex, a static face its first's.
        let free = t.iter().copied().find(|&v| !skinned(v));
        let v = free.unwrap_or(t[0]);
        let panel = garment
            .panels
            .get(
                garment
                    .panel_of_vertex
                    .get(v as usize)
                    .copied()
                    .unwrap_or(0) as usize,
            )
            .cloned()
            .unwrap_or_else(|| "garment".to_owned());
        let panel: String = panel
            .chars()
            .map(|c| if c.is_alphanumeric() { c } else { '_' })
            .collect();
        match free {
            None => panel,
            Some(_) => format!("{panel}{FREE_SUFFIX}"),
        }
    };
    let mut groups: Vec<(String, Vec<[u32; 3]>)> = Vec::new();
    for t in &garment.triangles {
        let m = material_of(t);
        match groups.iter_mut().find(|(name, _)| *name == m) {
            Some((_, list)) => list.push(*t),
            None => groups.push((m, vec![*t])),
        }
    }
    let mut obj = String::new();
    let size = if garment.size.is_empty() {
        String::new()
    } else {
        format!(" (size {})", garment.size)
    };
    let _ = writeln!(obj, "# {}{size}, written by fitroom_garment", garment.name);
    let _ = writeln!(
        obj,
        "# model space, metres, +Y up, facing +Z; materials ending in `Free` are simulated"
    );
    let _ = writeln!(obj, "mtllib {mtl_name}");
    let _ = writeln!(obj, "o {}", garment.name.replace(char::is_whitespace, "_"));
    for p in &garment.positions {
        let _ = writeln!(obj, "v {:.5} {:.5} {:.5}", p.x, p.y, p.z);
    }
    let mut mtl_text = String::from(
        "# materials of a fitroom garment: the suffix `Free` marks the simulated part\n",
    );
    for (name, list) in &groups {
        let _ = writeln!(obj, "usemtl {name}");
        for t in list {
            let _ = writeln!(obj, "f {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1);
        }
        let colour = if name.ends_with(FREE_SUFFIX) {
            "0.80 0.30 0.20"
        } else {
            "0.20 0.30 0.80"
        };
        let _ = writeln!(mtl_text, "newmtl {name}\nKd {colour}\n");
    }
    let write = |p: &Path, text: &str| {
        std::fs::write(p, text).map_err(|source| GarmentError::Write {
            path: p.to_owned(),
            source,
        })
    };
    write(path, &obj)?;
    write(&mtl, &mtl_text)
}

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
    let pos: Vec<u8> = garment
        .positions
        .iter()
        .flat_map(|p| p.to_array())
        .flat_map(f32::to_le_bytes)
        .collect();
    push(&mut bin, pos);
    let idx: Vec<u8> = garment
        .triangles
        .iter()
        .flatten()
        .flat_map(|v| v.to_le_bytes())
        .collect();
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
    let (lo, hi) = garment.positions.iter().fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(lo, hi), &p| (lo.min(p), hi.max(p)),
    );
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
    let mut json = json.into_bytes();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(&0x4E4F_534Au32.to_le_bytes());
    out.extend_from_slice(&json);
    out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    out.extend_from_slice(&0x004E_4942u32.to_le_bytes());
    out.extend_from_slice(&bin);
    out
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
