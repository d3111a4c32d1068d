//! Writes the mesh-garment examples shipped in `assets/garments/`: a tube skirt around the
//! default MakeHuman body, as OBJ + MTL (`tube_skirt.obj`: material `Waistband` static and
//! skinned, `SkirtFree` simulated, seed 000 §3.2.1) and as binary glTF (`tube_skirt.glb`: the
//! attachment weight in both `COLOR_0` red and `_ATTACH`).
//!
//! Run from the workspace root:
//! `cargo run -p fitroom_garment --example write_mesh_garments [output folder]`.

use std::path::PathBuf;

use fitroom_body::{BodyModel, Shape};
use fitroom_garment::body::{Landmark, Region};
use fitroom_garment::placement::tube_ring;
use fitroom_garment::{AttachChannel, BodySurface, GarmentMesh, write_glb, write_obj};
use glam::Vec2;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let assets = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../assets"));
    let out = std::env::args()
        .nth(1)
        .map_or_else(|| assets.join("garments"), PathBuf::from);
    let model = BodyModel::read(&assets.join("bodies/makehuman.fitbody"))?;
    let shaped = model.shaped(&Shape::default())?;
    let body = BodySurface::new(&model, &shaped)?;

    // Rings from 3 cm above the waist down to 50 cm below it, every 2.5 cm; the skirt flares
    // from 1 cm to 6 cm off the body's hull. The top two rings are the static waistband.
    const AROUND: usize = 48;
    const ROWS: usize = 22;
    const STATIC_ROWS: usize = 2;
    let waist = body.landmark_y(Landmark::Waist);
    let mut positions = Vec::with_capacity(AROUND * ROWS);
    let mut rest_2d = Vec::with_capacity(AROUND * ROWS);
    for row in 0..ROWS {
        let t = row as f32 / (ROWS - 1) as f32;
        let y = waist + 0.03 - 0.53 * t;
        let ring = tube_ring(&body, Region::Trunk, y, 0.01 + 0.05 * t, AROUND);
        if ring.len() != AROUND {
            return Err(format!("no body section at y = {y}").into());
        }
        positions.extend_from_slice(&ring);
        rest_2d.extend((0..AROUND).map(|i| Vec2::new(i as f32 / AROUND as f32, 1.0 - t)));
    }
    let mut triangles = Vec::new();
    for row in 0..ROWS - 1 {
        for i in 0..AROUND {
            let a = (row * AROUND + i) as u32;
            let b = (row * AROUND + (i + 1) % AROUND) as u32;
            let c = b + AROUND as u32;
            let d = a + AROUND as u32;
            // Outward facing: around runs front -> left (+X), rows run down.
            triangles.push([a, d, c]);
            triangles.push([a, c, b]);
        }
    }
    let n = positions.len();
    let skinned: Vec<bool> = (0..n).map(|v| v / AROUND < STATIC_ROWS).collect();
    let garment = GarmentMesh {
        name: "tube_skirt".into(),
        size: String::new(),
        positions,
        triangles,
        attached: (0..n as u32).filter(|&v| skinned[v as usize]).collect(),
        binding: Default::default(),
        seams: Vec::new(),
        seam_lines: Vec::new(),
        panel_of_vertex: skinned.iter().map(|&s| if s { 0 } else { 1 }).collect(),
        skinned,
        fabric: fitroom_cloth::Fabric::cotton(),
        fabric_name: "cotton".into(),
        panels: vec!["Waistband".into(), "Skirt".into()],
        rest_2d,
        rows: Vec::new(),
        ignore_colliders: Vec::new(),
    };
    std::fs::create_dir_all(&out)?;
    write_obj(&garment, out.join("tube_skirt.obj"))?;
    write_glb(&garment, out.join("tube_skirt.glb"), AttachChannel::Both)?;
    println!("wrote tube_skirt.obj, .mtl and .glb to {}", out.display());
    Ok(())
}
