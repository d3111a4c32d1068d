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

/// The avatar's root path over a headless run of `frames` updates (1/60 s each) against the
/// clip's own root path over the same time, from the file; returns the report.
fn assert_root_path(
    options: &AppOptions,
    frames: u32,
    min_path_m: f64,
) -> headless::HeadlessReport {
    let report = headless::run(options, frames, None).expect("headless run works");
    let seconds = f64::from(frames) / 60.0;
    // The sensor's frames come at 30 Hz (the tracker's: one per depth frame it found the
    // person in, the first one a frame late at most).
    let expected_frames = (seconds * 30.0).round() as u64;
    assert!(
        (expected_frames - 2..=expected_frames + 1).contains(&report.sensor_frames),
        "sensor frames in {seconds} s: {}",
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
        "{}: root path: avatar {got:.3} m, clip {expected_m:.3} m (scale {scale:.3}), error {:.2}%",
        report.sensor_source,
        error * 100.0
    );
    assert!(
        expected_m > min_path_m,
        "the walk clip should cover more than {min_path_m} m in {seconds} s: {expected_m}"
    );
    assert!(
        error < 0.05,
        "avatar path {got:.3} m vs clip {expected_m:.3} m"
    );
    report
}

#[test]
fn avatar_root_travels_the_clips_path() {
    let options = common::clip_options(Mode::Headless { render: false });
    let report = assert_root_path(&options, 120, 1.0);

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

/// The walking skeleton's root-path check on the whole real chain: the synthetic Kinect films
/// the clip's performer, our tracker finds the skeleton in the depth, and the motion pipeline
/// drives the avatar from it. The walk comes towards the camera as recorded (no treadmill),
/// from 3.7 m (the camera reads to 4 m) for 1.2 s, i.e. to about 2.1 m, where the head leaves
/// the image's top edge.
#[test]
fn avatar_root_travels_the_clips_path_through_depth_and_the_tracker() {
    let mut options = AppOptions::with_defaults(Mode::Headless { render: false })
        .expect("the shipped assets read");
    assert_eq!(
        options.sensor,
        fitroom::sensors::SensorSpec::Performer(None)
    );
    options.treadmill = false;
    options.distance_m = 3.3;
    let report = assert_root_path(&options, 72, 1.0);
    assert!(
        report.sensor_source.starts_with("performer"),
        "{}",
        report.sensor_source
    );
    assert_eq!(
        report.rejected_frames, 0,
        "the gate kept no tracked frame out"
    );
}

/// The kiosk with the shipped default (the performer on a treadmill): a person is found and
/// tried on, and the avatar walks on the spot where the performer is. The performer never
/// stands still, so they are not measured (no measurement from a walking person: the kiosk
/// says so) and the kiosk goes on unmeasured after `measure_s` (1 s here, 8 s shipped).
#[test]
fn the_shipped_default_tracks_the_performer_into_try_on() {
    let (config, _) = common::kiosk_config_copy("walker", &[("measure_s: 12.0", "measure_s: 1.0")]);
    let options =
        AppOptions::with_config(Mode::Headless { render: false }, &config).expect("it reads");
    assert!(options.treadmill);
    let mut app = headless::headless_app(&options).expect("the app builds");
    let mut states = Vec::new();
    let mut hints = std::collections::BTreeSet::new();
    for _ in 0..200 {
        app.update();
        if let fitroom_measure::plugin::CalibrationStatus::Collecting(
            fitroom_measure::calibration::Collecting { hint: Some(h), .. },
        ) = &app
            .world()
            .resource::<fitroom_measure::plugin::Calibration>()
            .status
        {
            hints.insert(h.clone());
        }
        let state = *app
            .world()
            .resource::<bevy::prelude::State<fitroom::kiosk::KioskState>>()
            .get();
        if states.last() != Some(&state) {
            states.push(state);
        }
    }
    use fitroom::kiosk::KioskState::*;
    assert_eq!(
        states,
        [Attract, Calibrate, TryOn],
        "the kiosk's states in 3.3 s"
    );
    let tracked = app
        .world()
        .resource::<fitroom_tracker::plugin::TrackedSkeleton>();
    assert_eq!(tracked.starts, 1, "tracked from one start");
    assert!(
        !app.world()
            .contains_resource::<fitroom_measure::plugin::BodyMeasurements>(),
        "a walking person is not measured"
    );
    assert!(
        hints.iter().any(|h| h.contains("stand still")),
        "the kiosk asked them to stand still: {hints:?}"
    );
}

/// The person walks towards the camera and past it (no treadmill), out of its view: the kiosk
/// goes back to Attract; the clip starts again from 3.7 m and the tracker finds the person by
/// itself, the kiosk calibrates them again.
#[test]
fn the_kiosk_returns_to_attract_when_the_person_leaves_and_tracks_them_again() {
    use fitroom::kiosk::KioskState::{self, *};
    // The person is out of view about 1 s of each pass: Attract after half a second.
    let (config, _) = common::kiosk_config_copy("leave", &[("lost_s: 3.0", "lost_s: 0.5")]);
    let mut options =
        AppOptions::with_config(Mode::Headless { render: false }, &config).expect("it reads");
    options.treadmill = false;
    options.distance_m = 3.3;
    let mut app = headless::headless_app(&options).expect("the app builds");
    // (state, the update it began at)
    let mut states: Vec<(KioskState, u32)> = Vec::new();
    // The walk lasts 4.04 s and loops: two passes and the start of a third.
    for update in 0..560 {
        app.update();
        let state = *app
            .world()
            .resource::<bevy::prelude::State<KioskState>>()
            .get();
        if states.last().map(|s| s.0) != Some(state) {
            states.push((state, update));
        }
    }
    println!("states (state, update at 60 Hz): {states:?}");
    let sequence: Vec<KioskState> = states.iter().map(|s| s.0).collect();
    let back = sequence
        .windows(2)
        .position(|w| w[0] != Attract && w[1] == Attract)
        .expect("back to Attract when the person left");
    assert!(
        sequence[back + 1..].contains(&Calibrate),
        "the person found again after leaving: {sequence:?}"
    );
    // Each time the clip starts again the person stands 3.3 m away, wholly in view: found
    // within a second.
    let source = fitroom_sensor::bvh_source::BvhSource::load(&options.motion, Default::default())
        .expect("clip parses");
    let period_updates = source.played_frame_count() as f64 / source.clip_fps() * 60.0;
    for pair in states.windows(2) {
        if let [(Attract, _), (Calibrate, found)] = pair {
            let loop_start = (f64::from(*found) / period_updates).round() * period_updates;
            let late = f64::from(*found) - loop_start;
            assert!(
                late <= 60.0,
                "found {late:.0} updates after coming back into view (loop at {loop_start:.0})"
            );
        }
    }
    let tracked = app
        .world()
        .resource::<fitroom_tracker::plugin::TrackedSkeleton>();
    assert!(
        tracked.starts >= 2,
        "tracking restarted: {} starts",
        tracked.starts
    );
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
    let mut options = common::clip_options(Mode::Headless { render: false });
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
