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
//!
//! The readers share the welding of vertices and the building of the garment here; `obj`
//! reads and writes OBJ + MTL, `gltf_read` reads glTF and `glb_write` writes binary glTF.

mod glb_write;
mod gltf_read;
mod obj;

use std::collections::HashMap;
use std::path::Path;

use glam::{Vec2, Vec3};

use crate::binding::Binding;
use crate::body::BodySurface;
use crate::error::GarmentError;
use crate::garment::GarmentMesh;

pub use glb_write::{AttachChannel, glb_bytes, write_glb};
pub use gltf_read::{load_gltf, load_gltf_with};
pub use obj::{load_obj, load_obj_with, write_obj};

/// The material suffix marking simulated faces (seed 000 §3.2.1).
pub const FREE_SUFFIX: &str = "Free";

/// Welds vertices by exact position (bit pattern).
#[derive(Default)]
pub(super) struct Welder {
    pub(super) index: HashMap<[u32; 3], u32>,
    pub(super) positions: Vec<Vec3>,
}

impl Welder {
    pub(super) fn add(&mut self, p: Vec3) -> u32 {
        let key = p.to_array().map(f32::to_bits);
        *self.index.entry(key).or_insert_with(|| {
            self.positions.push(p);
            (self.positions.len() - 1) as u32
        })
    }
}

pub(super) fn mesh_error(file: &Path, problem: impl Into<String>) -> GarmentError {
    GarmentError::Mesh {
        file: file.display().to_string(),
        problem: problem.into(),
    }
}

/// Builds the garment from welded geometry and a per-vertex attached flag.
#[allow(clippy::too_many_arguments)]
pub(super) fn finish(
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
