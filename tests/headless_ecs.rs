//! The whole app, headless and without a renderer, stepped frame by frame with exact time.

mod common;

use fitroom::{AppOptions, Mode, headless};

/// Path length of the BVH root over `[t0, t1]` computed straight from the file's root position
/// channels at 120 Hz, in BVH units. Independent of the sensor source and the retargeter.
fn raw_root_path(text: &str, t0: f64, t1: f64) -> (f64, f64) {
    let mut lines = text.lines().map(str::trim);
    let mut frame_time = 0.0;
    for line in lines.by_ref() {
        if let Some(rest) = line.strip_prefix("Frame Time:") {
            frame_time = rest.trim().parse().expect("frame time");
            break;
        }
    }
    let roots: Vec<[f64; 3]> = lines
        .filter(|l| !l.is_empty())
        .map(|l| {
            let v: Vec<f64> = l
                .split_whitespace()
                .take(3)
                .map(|x| x.parse().expect("number"))
                .collect();
            [v[0], v[1], v[2]]
        })
        .collect();
    let first = (t0 / frame_time).round() as usize;
    let last = ((t1 / frame_time).round() as usize).min(roots.len() - 1);
    let mut length = 0.0;
    for w in roots[first..=last].windows(2) {
        let d: f64 = (0..3).map(|k| (w[1][k] - w[0][k]).powi(2)).sum();
        length += d.sqrt();
    }
    (length, frame_time)
}

#[test]
fn avatar_root_travels_the_clips_path() {
    let options =
        AppOptions::with_defaults(Mode::Headless { render: false }).expect("assets exist");
    let report = headless::run(&options, 120, None).expect("headless run works");

    // 120 frames of 1/60 s = 2 s of the clip, emitted at 30 Hz.
    assert!(
        (59..=61).contains(&report.sensor_frames),
        "sensor frames in 2 s: {}",
        report.sensor_frames
    );
    let scale = report
        .retarget_scale
        .expect("the retargeter calibrated on the first frame");

    // The clip as the sensor sees it: BVH units to metres by the leg length (0.82 m reference).
    let text = std::fs::read_to_string(&options.motion).expect("motion readable");
    let source = fitroom_sensor::bvh_source::BvhSource::load(&options.motion, Default::default())
        .expect("clip parses");
    let metres_per_unit = f64::from(source.mapping().metres_per_unit());
    // Playback starts after the DAZ T-pose blend-in; the first sensor frame is at t = 0.
    let skip = source.first_played_frame() as f64 * source.clip().frame_time_s();
    let last_frame_t = (report.sensor_frames - 1) as f64 / 30.0;
    let (units, _) = raw_root_path(&text, skip, skip + last_frame_t);
    let expected_m = units * metres_per_unit * f64::from(scale);
    let got = f64::from(report.root_path_m);
    let error = (got - expected_m).abs() / expected_m;
    println!(
        "root path: avatar {got:.3} m, clip {expected_m:.3} m (scale {scale:.3}), error {:.2}%",
        error * 100.0
    );
    assert!(
        expected_m > 1.0,
        "the walk clip should cover more than 1 m in 2 s: {expected_m}"
    );
    assert!(
        error < 0.05,
        "avatar path {got:.3} m vs clip {expected_m:.3} m"
    );

    // Every joint is reported, by name, and finite.
    assert!(report.joints.len() >= 55, "joints: {}", report.joints.len());
    for (name, p) in &report.joints {
        assert!(
            p.iter().all(|v| v.is_finite()),
            "{name} is not finite: {p:?}"
        );
    }
    // The avatar stands on the floor: its feet are near y = 0 in the world.
    let foot = report.joints["foot_l"][1].min(report.joints["foot_r"][1]);
    assert!((-0.05..0.25).contains(&foot), "lowest ankle height {foot}");
    for stage in ["sensor", "motion", "pose", "transform_propagate", "frame"] {
        assert_eq!(
            report.stages_ms[stage].samples, 120,
            "{stage} timed every frame"
        );
    }
}
