//! The command line as a user runs it.

mod common;

use std::process::Command;

fn fitroom() -> Command {
    Command::new(env!("CARGO_BIN_EXE_fitroom"))
}

#[test]
fn sensor_inspect_prints_json_for_every_clip() {
    for (file, frames) in common::cmu_index() {
        let out = fitroom()
            .args(["sensor", "inspect"])
            .arg(fitroom_testdata::clip_path(&file))
            .arg("--json")
            .output()
            .expect("fitroom runs");
        common::assert_succeeded(&out, &file);
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("valid JSON");
        assert_eq!(v["frames"].as_u64(), Some(frames as u64), "{file}");
        assert!(
            (v["fps"].as_f64().expect("fps") - 120.0).abs() < 0.1,
            "{file}"
        );
        let duration = v["duration_s"].as_f64().expect("duration");
        assert!(
            (duration - frames as f64 / 120.0).abs() < 0.02,
            "{file}: {duration}"
        );
        let joints = v["joints"].as_u64().expect("joints");
        let skeleton = v["skeleton"].as_str().expect("skeleton");
        assert!(
            (joints == 43 && skeleton == "cgspeed-daz")
                || (joints == 31 && skeleton == "motionbuilder"),
            "{file}: {joints} joints, {skeleton}"
        );
    }
}

#[test]
fn a_broken_clip_fails_with_file_and_line_and_no_panic() {
    let text = fitroom_testdata::clip_text("07_01.bvh");
    let broken = text.replacen("Frame Time:", "Frame Time: x", 1);
    let path = common::out_dir().join("broken_frame_time.bvh");
    std::fs::write(&path, broken).expect("write");
    let out = fitroom()
        .args(["sensor", "inspect"])
        .arg(&path)
        .output()
        .expect("runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    let line = text
        .lines()
        .position(|l| l.starts_with("Frame Time:"))
        .expect("the clip has a Frame Time line")
        + 1;
    assert!(
        stderr.contains(&format!("broken_frame_time.bvh:{line}:")),
        "{stderr}"
    );
    assert!(!stderr.contains("backtrace"), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
}

#[test]
fn headless_run_reports_json_without_a_display() {
    let report = common::out_dir().join("run.json");
    let out = fitroom()
        .args(["run", "--headless", "--frames", "30", "--report"])
        .arg(&report)
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .expect("fitroom runs");
    common::assert_succeeded(&out, "");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&report).expect("report written"))
            .expect("JSON");
    assert_eq!(v["frames"], 30);
    for stage in ["sensor", "motion", "pose", "frame"] {
        assert!(
            v["stages_ms"][stage]["p95_ms"].as_f64().is_some(),
            "{stage}"
        );
    }
    assert!(v["joints"]["head"].as_array().map(|a| a.len()) == Some(3));
}
