//! `fitroom body measure|fit|size|export` as a user runs them: re-measuring the exported OBJ
//! gives the figures of the JSON report, a fitted shape file gives the fit's body, the glb
//! holds the OBJ's body; bad shape files and fit requests are clear errors.

mod common;

use std::process::Command;

use glam::Vec3;

fn fitroom() -> Command {
    Command::new(env!("CARGO_BIN_EXE_fitroom"))
}

/// The `v` lines of an OBJ, read independently of the exporter.
fn obj_vertices(text: &str) -> Vec<Vec3> {
    text.lines()
        .filter_map(|l| l.strip_prefix("v "))
        .map(|rest| {
            let v: Vec<f32> = rest
                .split_whitespace()
                .map(|x| x.parse().expect("number"))
                .collect();
            Vec3::new(v[0], v[1], v[2])
        })
        .collect()
}

#[test]
fn an_exported_obj_measures_like_the_json_report() {
    let dir = common::out_dir();
    let shape = dir.join("heavy_female.ron");
    std::fs::write(
        &shape,
        "(gender: 0.0, weight: 0.8, measures: {\"waist-circ\": -0.3})",
    )
    .expect("write");
    let out = fitroom()
        .args(["body", "measure", "--json", "--shape"])
        .arg(&shape)
        .output()
        .expect("runs");
    common::assert_succeeded(&out, "");
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");

    let obj = dir.join("heavy_female.obj");
    let out = fitroom()
        .args(["body", "export", "--shape"])
        .arg(&shape)
        .arg("--out")
        .arg(&obj)
        .output()
        .expect("runs");
    common::assert_succeeded(&out, "");

    let body_path = fitroom::assets::assets_dir()
        .expect("assets")
        .join(fitroom::assets::DEFAULT_BODY);
    let model = fitroom_body::BodyModel::read(&body_path).expect("body");
    let positions = obj_vertices(&std::fs::read_to_string(&obj).expect("obj"));
    let again = model.measure(&positions).expect("the OBJ measures");
    let again = serde_json::to_value(&again).expect("JSON");
    for field in [
        "stature_cm",
        "crotch_height_cm",
        "arm_length_cm",
        "shoulder_width_cm",
        "neck_cm",
        "bust_cm",
        "underbust_cm",
        "waist_cm",
        "navel_waist_cm",
        "hip_cm",
        "thigh_cm",
        "calf_cm",
    ] {
        let a = report["measurements"][field].as_f64().expect(field);
        let b = again[field].as_f64().expect(field);
        assert!(
            (a - b).abs() < 0.01,
            "{field}: report {a}, re-measured OBJ {b}"
        );
    }
    // A heavier body than the default has a larger waist.
    let default = fitroom()
        .args(["body", "measure", "--json"])
        .output()
        .expect("runs");
    let default: serde_json::Value = serde_json::from_slice(&default.stdout).expect("JSON");
    assert!(
        report["measurements"]["hip_cm"].as_f64() > default["measurements"]["hip_cm"].as_f64(),
        "weight 0.8 should widen the hips"
    );
}

#[test]
fn bad_shape_files_name_the_file_field_and_range() {
    let dir = common::out_dir();
    for (name, text, expect) in [
        ("absurd.ron", "(weight: 2.0)", "weight"),
        (
            "unknown.ron",
            "(measures: {\"tail-length\": 0.5})",
            "tail-length",
        ),
        ("broken.ron", "(gender: 0.0,, )", "broken.ron:1:"),
    ] {
        let path = dir.join(name);
        std::fs::write(&path, text).expect("write");
        let out = fitroom()
            .args(["body", "measure", "--shape"])
            .arg(&path)
            .output()
            .expect("runs");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{name} was accepted");
        assert!(stderr.contains(expect), "{name}: {stderr}");
        assert!(!stderr.contains("panicked"), "{name}: {stderr}");
    }
}

fn run_ok(args: &[&str]) -> Vec<u8> {
    let out = fitroom().args(args).output().expect("runs");
    common::assert_succeeded(&out, format!("{args:?}"));
    out.stdout
}

#[test]
fn a_fitted_shape_file_measures_like_the_fit_report() {
    let dir = common::out_dir();
    let shape = dir.join("fitted.ron");
    let shape_s = shape.to_str().expect("utf-8 path");
    let report: serde_json::Value = serde_json::from_slice(&run_ok(&[
        "body",
        "fit",
        "--gender",
        "female",
        "--stature",
        "165",
        "--bust",
        "92",
        "--waist",
        "72",
        "--hip",
        "100",
        "--thigh",
        "58",
        "--json",
        "--out",
        shape_s,
    ]))
    .expect("JSON");
    for key in [
        "achieved",
        "residuals_cm",
        "reachable",
        "outer_iterations",
        "iterations",
        "time_ms",
    ] {
        assert!(report.get(key).is_some(), "no `{key}` in {report}");
    }
    assert!(
        report["achieved"]["landmarks"]["waist_cm"]
            .as_f64()
            .is_some()
    );
    assert_eq!(report["reachable"], true, "{}", report["residuals_cm"]);
    for (k, target) in [
        ("stature", 165.0),
        ("bust", 92.0),
        ("waist", 72.0),
        ("hip", 100.0),
    ] {
        let r = report["residuals_cm"][k].as_f64().expect(k);
        assert!(r.abs() <= 0.5, "{k}: residual {r} (target {target})");
    }
    // The saved shape gives the same body.
    let measured: serde_json::Value =
        serde_json::from_slice(&run_ok(&["body", "measure", "--json", "--shape", shape_s]))
            .expect("JSON");
    for field in ["stature_cm", "bust_cm", "waist_cm", "hip_cm", "thigh_cm"] {
        let a = report["achieved"][field].as_f64().expect(field);
        let b = measured["measurements"][field].as_f64().expect(field);
        assert!((a - b).abs() < 0.01, "{field}: fit {a}, shape file {b}");
    }
    // And a size from the seed's women's chart, with its reasons.
    let chart = fitroom::assets::assets_dir()
        .expect("assets")
        .join("sizecharts/en13402-female-seed002.ron");
    let size: serde_json::Value = serde_json::from_slice(&run_ok(&[
        "body",
        "size",
        "--json",
        "--chart",
        chart.to_str().expect("utf-8"),
        "--shape",
        shape_s,
    ]))
    .expect("JSON");
    let text = size.to_string();
    assert!(text.contains("bust 92."), "{text}");
    assert!(size["recommendation"]["size"].is_string(), "{text}");
}

#[test]
fn bad_fit_requests_fail_with_the_field_and_range() {
    for (args, expect) in [
        (vec!["--waist", "300"], "45..=170"),
        (vec!["--hip", "0"], "`hip`"),
        (vec!["--wasit", "70"], "--waist"),
        (vec!["--stature", "abc"], "stature"),
        (vec![], "at least one measurement"),
    ] {
        let out = fitroom()
            .args(["body", "fit", "--gender", "female"])
            .args(&args)
            .output()
            .expect("runs");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?} was accepted");
        assert!(stderr.contains(expect), "{args:?}: {stderr}");
        assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
    }
    let out = fitroom()
        .args(["body", "fit", "--gender", "robot", "--waist", "70"])
        .output()
        .expect("runs");
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("[possible values: female, male]"));
}

#[test]
fn a_glb_export_holds_the_body_of_the_obj_export() {
    let dir = common::out_dir();
    let (obj, glb) = (dir.join("same.obj"), dir.join("same.glb"));
    run_ok(&["body", "export", "--out", obj.to_str().expect("utf-8")]);
    run_ok(&["body", "export", "--out", glb.to_str().expect("utf-8")]);
    let obj = obj_vertices(&std::fs::read_to_string(&obj).expect("obj"));
    // Read the glb by its specification: 12-byte header, JSON chunk, BIN chunk.
    let bytes = std::fs::read(&glb).expect("glb");
    let u32_at = |i: usize| u32::from_le_bytes(bytes[i..i + 4].try_into().expect("4 bytes"));
    assert_eq!(&bytes[0..4], b"glTF");
    assert_eq!(u32_at(4), 2);
    assert_eq!(u32_at(8) as usize, bytes.len());
    let json_len = u32_at(12) as usize;
    assert_eq!(&bytes[16..20], b"JSON");
    let json: serde_json::Value =
        serde_json::from_slice(&bytes[20..20 + json_len]).expect("glTF JSON");
    let bin = &bytes[20 + json_len + 8..];
    let accessor = &json["accessors"][json["meshes"][0]["primitives"][0]["attributes"]["POSITION"]
        .as_u64()
        .expect("POSITION") as usize];
    let view = &json["bufferViews"][accessor["bufferView"].as_u64().expect("view") as usize];
    let offset = view["byteOffset"].as_u64().unwrap_or(0) as usize;
    let count = accessor["count"].as_u64().expect("count") as usize;
    assert_eq!(count, 13_380, "the body's vertices");
    let f = |i: usize| f32::from_le_bytes(bin[i..i + 4].try_into().expect("4 bytes"));
    for v in (0..count).step_by(97) {
        let p = Vec3::new(
            f(offset + v * 12),
            f(offset + v * 12 + 4),
            f(offset + v * 12 + 8),
        );
        assert!(
            p.distance(obj[v]) < 2e-6,
            "vertex {v}: glb {p} obj {}",
            obj[v]
        );
    }
    let indices = &json["accessors"][json["meshes"][0]["primitives"][0]["indices"]
        .as_u64()
        .expect("indices") as usize];
    assert_eq!(indices["count"].as_u64().expect("count") % 3, 0);
    // Y up: the body is taller than wide.
    let (min, max) = (&accessor["min"], &accessor["max"]);
    let extent = |k: usize| max[k].as_f64().expect("max") - min[k].as_f64().expect("min");
    assert!(extent(1) > 1.5 && extent(1) > 1.5 * extent(0));
}
