//! The measurement in an app: depth frames of a filmed calibration go through the tracker
//! plugin into the measurement plugin, which measures the person off the main schedule and
//! reshapes the avatar; bad calibrations (two people, a person who walks away) publish
//! nothing and say why.

use std::path::Path;
use std::sync::Arc;
use std::time::{Duration, Instant};

use bevy::prelude::*;
use fitroom_body::plugin::{AvatarBody, AvatarShape};
use fitroom_body::{BodyModel, Shape};
use fitroom_depth::DepthFrame;
use fitroom_depth::plugin::DepthFeed;
use fitroom_depth::synthetic::NoiseSettings;
use fitroom_measure::calibration::{Collecting, TURN_HINT};
use fitroom_measure::eval::{Recording, Stance, TURN_DEG, record};
use fitroom_measure::plugin::{BodyMeasurements, Calibration, CalibrationStatus, MeasurePlugin};
use fitroom_sensor::plugin::SensorFeed;
use fitroom_tracker::plugin::TrackerPlugin;

fn model() -> BodyModel {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/bodies/makehuman.fitbody");
    BodyModel::read(&path).expect("the shipped body")
}

fn app(model: &BodyModel) -> App {
    let mut app = App::new();
    app.add_plugins(MinimalPlugins)
        .insert_resource(AvatarBody::unshaped(Arc::new(model.clone())))
        .init_resource::<AvatarShape>()
        .init_resource::<SensorFeed>()
        .init_resource::<DepthFeed>()
        .add_plugins((TrackerPlugin, MeasurePlugin));
    app.world_mut().resource_mut::<Calibration>().start();
    app
}

fn feed(app: &mut App, frame: &DepthFrame) {
    {
        let mut depth = app.world_mut().resource_mut::<DepthFeed>();
        depth.latest = Some(frame.clone());
        depth.frames_received += 1;
    }
    app.update();
}

/// Updates until the fit under way ends (at most 30 s).
fn settle(app: &mut App) {
    let began = Instant::now();
    while app.world().resource::<Calibration>().status == CalibrationStatus::Fitting {
        assert!(
            began.elapsed() < Duration::from_secs(30),
            "the fit never ended"
        );
        std::thread::sleep(Duration::from_millis(20));
        app.update();
    }
}

fn hint(app: &App) -> Option<String> {
    match &app.world().resource::<Calibration>().status {
        CalibrationStatus::Collecting(c) => c.hint.clone(),
        _ => None,
    }
}

fn filmed(model: &BodyModel, shape: &Shape, stance: Stance, seed: u64) -> Recording {
    record(
        model,
        shape,
        &stance,
        40,
        NoiseSettings::default(),
        seed,
        None,
    )
    .expect("a recording")
}

/// A broad man stands still facing the mirror, then turned halfway to his side: measured,
/// the avatar takes his shape. (Through the tracker,
/// whose own build estimate runs on a thread of its own and lands when it lands: the bounds
/// are the tracker path's 95th percentiles over 200 subjects, stature 3.5 cm, chest 2.7 cm.)
#[test]
fn a_person_standing_still_is_measured_and_the_avatar_takes_their_shape() {
    let model = model();
    let man = Shape {
        gender: 1.0,
        weight: 0.8,
        height: 0.55,
        ..Shape::default()
    };
    let stance = Stance::drawn(11);
    let rec = filmed(&model, &man, stance, 11);
    let turned = filmed(&model, &man, stance.turned(TURN_DEG), 12);
    let truth = model.measure(&rec.body.positions).expect("measurable");
    let mut app = app(&model);
    for f in &rec.frames {
        feed(&mut app, &f.depth);
    }
    // The front view is collected: the person is asked to turn.
    assert!(!app.world().contains_resource::<BodyMeasurements>());
    assert_eq!(hint(&app).as_deref(), Some(TURN_HINT));
    for f in &turned.frames {
        feed(&mut app, &f.depth);
        settle(&mut app);
        if app.world().contains_resource::<BodyMeasurements>() {
            break;
        }
    }
    let measured = app
        .world()
        .get_resource::<BodyMeasurements>()
        .expect("measured within the recording");
    let m = &measured.measurements;
    println!(
        "stature {:.1} / {:.1}, chest {:.1} / {:.1}, waist {:.1} / {:.1}, hip {:.1} / {:.1} cm; {:.0} ms after the last frame",
        m.stature_cm,
        truth.stature_cm,
        m.bust_cm,
        truth.bust_cm,
        m.waist_cm,
        truth.waist_cm,
        m.hip_cm,
        truth.hip_cm,
        measured.latency_ms
    );
    assert!((m.stature_cm - truth.stature_cm).abs() < 4.0);
    assert!((m.bust_cm - truth.bust_cm).abs() < 4.0);
    assert!(!measured.female, "a man's prior explains him better");
    assert_eq!(measured.frames, 60, "a second facing, a second turned");
    assert!(
        measured
            .uncertainty_cm
            .iter()
            .all(|(_, s)| s.is_finite() && *s > 0.0)
    );
    assert_eq!(app.world().resource::<AvatarShape>().0, measured.shape);
    assert_eq!(
        app.world().resource::<Calibration>().status,
        CalibrationStatus::Done
    );
}

/// A third of a second of the empty room (the person stepped out of view).
fn nobody_in_view(app: &mut App, model: &BodyModel) {
    let mut room = Stance::drawn(8);
    room.offset_m = 6.0; // out of the camera's view
    let empty = filmed(model, &Shape::default(), room, 9);
    for f in &empty.frames[..10] {
        feed(app, &f.depth);
        settle(app);
    }
}

/// A person stands in the middle, still, facing and then turned (the calibration's two
/// views), until the app has measured them.
fn stand_in_the_middle_until_measured(app: &mut App, model: &BodyModel) {
    let rec = filmed(model, &Shape::default(), Stance::drawn(8), 8);
    let turned = filmed(
        model,
        &Shape::default(),
        Stance::drawn(8).turned(TURN_DEG),
        10,
    );
    for f in rec.frames.iter().chain(&turned.frames) {
        feed(app, &f.depth);
        settle(app);
        if app.world().contains_resource::<BodyMeasurements>() {
            break;
        }
    }
}

/// Two people in view: nothing is measured, and the kiosk is told why.
#[test]
fn two_people_in_view_are_not_measured() {
    let model = model();
    let mut left = Stance::drawn(3);
    left.offset_m = -0.45;
    let mut right = Stance::drawn(4);
    right.offset_m = 0.5;
    right.distance_m = left.distance_m + 0.1;
    let a = filmed(&model, &Shape::default(), left, 3);
    let b = filmed(
        &model,
        &Shape {
            gender: 0.0,
            ..Shape::default()
        },
        right,
        4,
    );
    let mut app = app(&model);
    let mut hints = Vec::new();
    for (fa, fb) in a.frames.iter().zip(&b.frames) {
        // Both people in one frame: the nearer reading of the two films.
        let both: Vec<u16> = fa
            .depth
            .depth_mm
            .iter()
            .zip(fb.depth.depth_mm.iter())
            .map(|(&x, &y)| match (x, y) {
                (0, v) | (v, 0) => v,
                (x, y) => x.min(y),
            })
            .collect();
        let frame = DepthFrame {
            depth_mm: both.into(),
            raw: None,
            ..fa.depth.clone()
        };
        feed(&mut app, &frame);
        settle(&mut app);
        hints.extend(hint(&app));
    }
    assert!(!app.world().contains_resource::<BodyMeasurements>());
    assert!(
        hints.iter().any(|h| h.contains("Two people")),
        "hints: {hints:?}"
    );
}

/// The person walks away half-way through: no measurement from the frames before; when
/// they are back, still, and turned for the second view, they are measured.
#[test]
fn a_calibration_interrupted_by_leaving_starts_again() {
    let model = model();
    let rec = filmed(&model, &Shape::default(), Stance::drawn(8), 8);
    let mut app = app(&model);
    for f in &rec.frames[..20] {
        feed(&mut app, &f.depth);
    }
    nobody_in_view(&mut app, &model);
    assert!(!app.world().contains_resource::<BodyMeasurements>());
    let h = hint(&app).expect("a hint while nobody is there");
    assert!(h.contains("Step in front"), "{h}");
    stand_in_the_middle_until_measured(&mut app, &model);
    assert!(app.world().contains_resource::<BodyMeasurements>());
}

/// A person partly out of view (standing so far aside that an arm and a shoulder leave the
/// picture): no measurement from those frames, and they are told why; back in the middle,
/// still, and turned, they are measured. (The recording moves a person too near for the picture
/// back until they fit, so "too near" is not filmed here; the head and feet checks are the
/// same bounding-box test as the side's.)
#[test]
fn a_person_partly_out_of_view_is_not_measured_and_told_why() {
    let model = model();
    let mut aside = Stance::drawn(12);
    aside.offset_m = 1.4;
    let aside = filmed(&model, &Shape::default(), aside, 13);
    let mut app = app(&model);
    let mut hints = std::collections::BTreeSet::new();
    for f in &aside.frames {
        feed(&mut app, &f.depth);
        settle(&mut app);
        hints.extend(hint(&app));
        if let CalibrationStatus::Collecting(Collecting { view, frames, .. }) =
            &app.world().resource::<Calibration>().status
        {
            let (view, frames) = (*view, *frames);
            assert_eq!(
                (view, frames),
                (0, 0),
                "frames of a person half out of view kept"
            );
        }
    }
    assert!(!app.world().contains_resource::<BodyMeasurements>());
    assert!(
        hints.iter().any(|h| h.contains("step to the middle")),
        "hints: {hints:?}"
    );
    // They step out and come back into the middle. (Put in the middle from one frame to the
    // next, the tracker carried its aside pose over and the calibration kept restarting.)
    nobody_in_view(&mut app, &model);
    stand_in_the_middle_until_measured(&mut app, &model);
    assert!(
        app.world().contains_resource::<BodyMeasurements>(),
        "measured once in view; hints before: {hints:?}"
    );
}
