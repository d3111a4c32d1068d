//! Mesh garments: the shipped OBJ + MTL tube skirt splits into the static `Waistband` and the
//! simulated `SkirtFree` (seed 000 §3.2.1); the same garment as glTF carries its attachment
//! in `_ATTACH` or `COLOR_0`; broken files are refused with the file named.

mod common;

use common::default_body;
use fitroom_cloth::Fabric;
use fitroom_garment::mesh_garment::glb_bytes;
use fitroom_garment::{AttachChannel, GarmentError, GarmentMesh, load_gltf, load_obj};

const AROUND: usize = 48;
const ROWS: usize = 22;

fn tube_obj() -> GarmentMesh {
    let path = common::assets().join("garments/tube_skirt.obj");
    load_obj(&path, &default_body().surface, "cotton", Fabric::cotton())
        .unwrap_or_else(|e| panic!("{e}"))
}

fn temp_file(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("fitroom_garment_test_{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir.join(name)
}

#[test]
fn shipped_assets_are_small() {
    for f in ["tube_skirt.obj", "tube_skirt.mtl", "tube_skirt.glb"] {
        let len = std::fs::metadata(common::assets().join("garments").join(f))
            .expect("shipped")
            .len();
        assert!(len <= 200 * 1024, "{f}: {len} bytes");
    }
}

#[test]
fn obj_free_material_is_simulated_and_the_rest_is_static() {
    let g = tube_obj();
    assert_eq!(
        g.positions.len(),
        AROUND * ROWS,
        "materials' vertices joined back by position"
    );
    assert_eq!(g.triangles.len(), 2 * AROUND * (ROWS - 1));
    assert_eq!(g.panels, ["Waistband", "SkirtFree"]);
    // The static part is the two top rings (the waistband's faces); the ring shared with the
    // free faces is the attachment line.
    let skinned = g.skinned.iter().filter(|&&s| s).count();
    assert_eq!(skinned, 2 * AROUND);
    assert_eq!(g.attached.len(), 2 * AROUND);
    assert_eq!(g.free_vertices().len(), AROUND * (ROWS - 2));
    let top = g
        .positions
        .iter()
        .map(|p| p.y)
        .fold(f32::NEG_INFINITY, f32::max);
    for &v in &g.attached {
        assert!(
            g.positions[v as usize].y > top - 0.03,
            "attached vertices are the top rings"
        );
    }
    // Faces touching a free vertex came from `SkirtFree`.
    for t in &g.triangles {
        if t.iter().any(|&v| !g.skinned[v as usize]) {
            assert!(
                t.iter()
                    .any(|&v| g.panels[g.panel_of_vertex[v as usize] as usize] == "SkirtFree")
            );
        }
    }
    // Bound to the body, outside it, and a valid cloth.
    let body = &default_body().surface;
    let rest: Vec<_> = g
        .attached
        .iter()
        .map(|&v| g.positions[v as usize])
        .collect();
    let got = g.binding.positions(&body.positions, &body.normals);
    for (a, b) in got.iter().zip(&rest) {
        assert!(a.distance(*b) < 2e-6);
    }
    assert!(g.positions.iter().all(|&p| body.signed_distance(p) > 0.0));
    g.cloth_mesh().expect("valid cloth");
    assert_eq!(g.rest_2d.len(), 0, "the OBJ has no texture coordinates");
}

#[test]
fn gltf_attachment_from_custom_attribute_and_colour() {
    let obj = tube_obj();
    let body = &default_body().surface;
    // The shipped .glb has both `_ATTACH` and COLOR_0; `_ATTACH` is read first.
    let shipped = load_gltf(
        common::assets().join("garments/tube_skirt.glb"),
        body,
        "cotton",
        Fabric::cotton(),
    )
    .unwrap_or_else(|e| panic!("{e}"));
    // The readers number vertices differently (OBJ by material group): match by position
    // (the OBJ holds 5 decimals).
    let same = |g: &GarmentMesh| {
        assert_eq!(g.positions.len(), obj.positions.len());
        assert_eq!(g.attached.len(), obj.attached.len());
        assert_eq!(g.triangles.len(), obj.triangles.len());
        for (v, &p) in g.positions.iter().enumerate() {
            let twin = obj
                .positions
                .iter()
                .position(|q| q.distance(p) < 2e-5)
                .unwrap_or_else(|| panic!("no OBJ vertex at {p}"));
            assert_eq!(obj.skinned[twin], g.skinned[v], "vertex at {p}");
        }
    };
    same(&shipped);
    assert_eq!(shipped.panels, ["tube_skirt"]);
    // Only one of the two attributes: both are read.
    for channel in [AttachChannel::Color0, AttachChannel::Custom] {
        let path = temp_file(&format!("tube_{channel:?}.glb"));
        std::fs::write(&path, glb_bytes(&obj, channel)).expect("writes");
        let g = load_gltf(&path, body, "cotton", Fabric::cotton())
            .unwrap_or_else(|e| panic!("{channel:?}: {e}"));
        same(&g);
    }
}

#[test]
fn broken_mesh_garments_are_refused_with_the_file_named() {
    let body = &default_body().surface;
    let obj_text =
        std::fs::read_to_string(common::assets().join("garments/tube_skirt.obj")).expect("shipped");
    // No `Free` material: nothing to simulate.
    let path = temp_file("no_free.obj");
    std::fs::write(
        &path,
        obj_text
            .replace("SkirtFree", "Skirt")
            .replace("mtllib tube_skirt.mtl", "mtllib no_free.mtl"),
    )
    .expect("writes");
    std::fs::write(
        path.with_extension("mtl"),
        "newmtl Waistband\nKd 1 1 1\nnewmtl Skirt\nKd 1 1 1\n",
    )
    .expect("writes");
    let msg = load_obj(&path, body, "cotton", Fabric::cotton())
        .expect_err("refused")
        .to_string();
    assert!(msg.contains("no_free.obj") && msg.contains("Free"), "{msg}");
    // A missing MTL file.
    let path = temp_file("no_mtl.obj");
    std::fs::write(
        &path,
        obj_text.replace("mtllib tube_skirt.mtl", "mtllib missing.mtl"),
    )
    .expect("writes");
    let msg = load_obj(&path, body, "cotton", Fabric::cotton())
        .expect_err("refused")
        .to_string();
    assert!(msg.contains("no_mtl.obj") && msg.contains("MTL"), "{msg}");
    // A glTF that is not one, and one without attachment weights.
    let path = temp_file("garbage.glb");
    std::fs::write(&path, b"glTF\x02\0\0\0 not really").expect("writes");
    let err = load_gltf(&path, body, "cotton", Fabric::cotton()).expect_err("refused");
    assert!(
        matches!(err, GarmentError::Mesh { .. }) && err.to_string().contains("garbage.glb"),
        "{err}"
    );
    let mut plain = tube_obj();
    plain.skinned.iter_mut().for_each(|s| *s = false);
    let bytes = glb_bytes(&plain, AttachChannel::Custom);
    let path = temp_file("unattached.glb");
    std::fs::write(&path, bytes).expect("writes");
    // Weights all 0 are allowed (everything simulated); a file without either attribute is not.
    let g = load_gltf(&path, body, "cotton", Fabric::cotton()).expect("all free");
    assert!(g.attached.is_empty());
    let json = r#"{"asset":{"version":"2.0"},"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],"meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],"buffers":[{"byteLength":36,"uri":"data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA"}],"bufferViews":[{"buffer":0,"byteLength":36}],"accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}]}"#;
    let path = temp_file("no_weights.gltf");
    std::fs::write(&path, json).expect("writes");
    let msg = load_gltf(&path, body, "cotton", Fabric::cotton())
        .expect_err("refused")
        .to_string();
    assert!(
        msg.contains("no_weights.gltf") && msg.contains("_ATTACH"),
        "{msg}"
    );
}
