//! `fitroom body measure` and `fitroom body export` as a user runs them: re-measuring the
//! exported OBJ gives the figures of the JSON report; bad shape files are clear errors.

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
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");

    let obj = dir.join("heavy_female.obj");
    let out = fitroom()
        .args(["body", "export", "--shape"])
        .arg(&shape)
        .arg("--out")
        .arg(&obj)
        .output()
        .expect("runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );

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
