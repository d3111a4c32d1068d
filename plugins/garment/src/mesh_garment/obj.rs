//! Wavefront OBJ + MTL garments (seed 000 §3.2.1: faces whose material name ends in `Free`
//! are the simulated part, the others the static part skinned with the body): reading one
//! onto the body, and writing a garment back.

use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::Path;

use fitroom_body::export;
use glam::{Vec2, Vec3};

use crate::body::BodySurface;
use crate::error::GarmentError;
use crate::files::{DiskFiles, GarmentFiles};
use crate::garment::GarmentMesh;

use super::{FREE_SUFFIX, Welder, finish, mesh_error};

/// Reads an OBJ + MTL garment: faces with a material ending in `Free` are simulated, the rest
/// is the static, skinned part.
pub fn load_obj(
    path: impl AsRef<Path>,
    body: &BodySurface,
    fabric_name: &str,
    fabric: fitroom_cloth::Fabric,
) -> Result<GarmentMesh, GarmentError> {
    load_obj_with(path.as_ref(), &DiskFiles, body, fabric_name, fabric)
}

/// [`load_obj`] with the OBJ and its MTL files read from `files`.
pub fn load_obj_with(
    path: &Path,
    files: &dyn GarmentFiles,
    body: &BodySurface,
    fabric_name: &str,
    fabric: fitroom_cloth::Fabric,
) -> Result<GarmentMesh, GarmentError> {
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ignore_points: true,
        ignore_lines: true,
    };
    let bytes = files.read(path)?;
    let dir = path.parent().unwrap_or(Path::new("."));
    let (models, materials) =
        tobj::load_obj_buf(&mut std::io::Cursor::new(bytes), &options, |mtl| {
            let mtl = files
                .read(&dir.join(mtl))
                .map_err(|_| tobj::LoadError::OpenFileFailed)?;
            tobj::load_mtl_buf(&mut std::io::Cursor::new(mtl))
        })
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
    export::obj_vertices(&mut obj, &garment.positions, 5);
    let mut mtl_text = String::from(
        "# materials of a fitroom garment: the suffix `Free` marks the simulated part\n",
    );
    for (name, list) in &groups {
        let _ = writeln!(obj, "usemtl {name}");
        export::obj_faces(&mut obj, list, false);
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
