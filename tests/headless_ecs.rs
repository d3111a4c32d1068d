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

/// The avatar shaped from a shape file at start, then reshaped live (what the body panel's
/// sliders do): the body, its measurements, the joints and the motion skeleton all follow.
#[test]
fn the_avatar_takes_a_shape_and_reshapes_live() {
    use bevy::prelude::*;
    use fitroom_body::{
        Shape,
        plugin::{AvatarBody, AvatarJoint, AvatarMeasurements, AvatarShape},
    };
    use fitroom_motion::plugin::AvatarMotion;

    let tall = Shape {
        gender: 1.0,
        height: 0.8,
        ..Shape::default()
    };
    let mut options =
        AppOptions::with_defaults(Mode::Headless { render: false }).expect("assets exist");
    options.shape = Some(tall.clone());
    let mut app = fitroom::build_app(&options).expect("app");
    for _ in 0..10 {
        app.update();
    }
    let model = app.world().resource::<AvatarBody>().model.clone();
    let expected = model
        .measure(&model.shaped(&tall).expect("shape").positions)
        .expect("measure");
    let measured = app
        .world()
        .resource::<AvatarMeasurements>()
        .measurements
        .clone()
        .expect("the avatar is measured");
    assert!((measured.stature_cm - expected.stature_cm).abs() < 1e-3);
    let thigh = model.bone_index("thigh_l").expect("thigh_l");
    let calf = model.bone_index("calf_l").expect("calf_l");
    let leg = |app: &App| {
        let motion = app.world().resource::<AvatarMotion>();
        motion.pipeline.skeleton().bones[calf]
            .local_translation
            .length()
    };
    let tall_leg = leg(&app);
    let tall_thigh_rest = app.world().resource::<AvatarBody>().rest.heads[thigh];

    // Reshape to a short woman, as the panel does.
    let short = Shape {
        gender: 0.0,
        height: 0.2,
        ..Shape::default()
    };
    app.world_mut().resource_mut::<AvatarShape>().0 = short.clone();
    for _ in 0..5 {
        app.update();
    }
    let short_measured = app
        .world()
        .resource::<AvatarMeasurements>()
        .measurements
        .clone()
        .expect("measured");
    let expected = model
        .measure(&model.shaped(&short).expect("shape").positions)
        .expect("measure");
    assert!((short_measured.stature_cm - expected.stature_cm).abs() < 1e-3);
    assert!(short_measured.stature_cm < measured.stature_cm - 15.0);
    // The motion pipeline runs on the new, shorter skeleton.
    let short_leg = leg(&app);
    assert!(
        short_leg < tall_leg - 0.03,
        "thigh {tall_leg} -> {short_leg}"
    );
    assert_ne!(
        app.world().resource::<AvatarBody>().rest.heads[thigh],
        tall_thigh_rest
    );
    // The joints still move (the pipeline recalibrated and drives them).
    let mut q = app.world_mut().query::<(&AvatarJoint, &Transform)>();
    let before: Vec<Transform> = q.iter(app.world()).map(|(_, t)| *t).collect();
    for _ in 0..30 {
        app.update();
    }
    let mut q = app.world_mut().query::<(&AvatarJoint, &Transform)>();
    let after: Vec<Transform> = q.iter(app.world()).map(|(_, t)| *t).collect();
    assert!(before.iter().zip(&after).any(|(a, b)| a != b));
    assert!(after.iter().all(|t| t.translation.is_finite()));

    // A shape out of range keeps the body and says why.
    app.world_mut().resource_mut::<AvatarShape>().0 = Shape {
        weight: 3.0,
        ..Shape::default()
    };
    app.update();
    let m = app.world().resource::<AvatarMeasurements>();
    assert!(
        m.error.as_deref().is_some_and(|e| e.contains("weight")),
        "{:?}",
        m.error
    );
    let still = app.world().resource::<AvatarBody>().rest.heads[thigh];
    assert_eq!(
        still,
        model.shaped(&short).expect("shape").rest_pose.heads[thigh]
    );
}
