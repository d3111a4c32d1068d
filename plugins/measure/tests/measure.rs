//! Measuring people from depth on ANSUR II subjects the shape prior never saw, filmed by the
//! synthetic Kinect v1 in the calibration pose: our fit against the filmed bodies' own
//! measurements, beside the seed's method; and bad calibrations refused with a reason.

use std::path::Path;
use std::sync::Arc;

use fitroom_body::ansur::{read_survey, sample};
use fitroom_body::{BodyModel, Measure, SizeChart};
use fitroom_depth::synthetic::NoiseSettings;
use fitroom_depth::{DepthCamera, DepthFrame, PIXELS};
use fitroom_measure::eval::{
    EvalOptions, MeasureReport, PoseSource, Stance, evaluate, held_out, record, training,
};
use fitroom_measure::person::STUCK_RMS_M;
use fitroom_measure::{
    AveragedView, CalibrationFrame, FitSettings, MeasureError, ShapePrior, ShapeSpace, ViewPose,
    fit_body, measure_person, seed,
};
use glam::Vec3;

fn root() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn model() -> BodyModel {
    BodyModel::read(&root().join("assets/bodies/makehuman.fitbody")).expect("the shipped body")
}

fn chart(name: &str) -> SizeChart {
    SizeChart::load(root().join("assets/sizecharts").join(name)).expect("a shipped chart")
}

/// `count` held-out subjects measured with the pose from `pose`.
fn run(count: usize, seed: u64, pose: PoseSource) -> MeasureReport {
    let model = model();
    let [women, men] = read_survey(&fitroom_testdata::data_dir().join("ansur2")).expect("ANSUR II");
    let all: Vec<_> = women.into_iter().chain(men).collect();
    let subjects = sample(&held_out(&all), count, seed);
    let prior = ShapePrior::shipped().expect("the shipped prior");
    let (w, m) = (
        chart("en13402-female-seed002.ron"),
        chart("en13402-male-seed002.ron"),
    );
    let report = evaluate(
        &model,
        &subjects,
        &prior,
        (&w, &m),
        &FitSettings::default(),
        &EvalOptions {
            pose,
            seed,
            ..EvalOptions::default()
        },
        &|_, _| {},
    );
    for r in &report.results {
        assert!(r.error.is_none(), "subject {}: {:?}", r.id, r.error);
    }
    report
}

fn stats(r: &MeasureReport, m: Measure) -> f64 {
    r.ours
        .iter()
        .find(|s| s.measure == m)
        .map(|s| s.mean_abs_cm)
        .expect("evaluated")
}

fn seed_stats(r: &MeasureReport, m: Measure) -> f64 {
    r.seed_method
        .iter()
        .find(|s| s.measure == m)
        .map(|s| s.mean_abs_cm)
        .expect("evaluated")
}

/// Prints each subject's errors and the summary.
fn report(r: &MeasureReport) {
    for s in &r.results {
        println!(
            "{} truth {:.2} ours {:.2} female {} at {:.2} m: stature {:+.2}, shoulder {:+.2}, bust {:+.2}, hip {:+.2} cm",
            s.id,
            s.truth[&Measure::Stature],
            s.ours[&Measure::Stature],
            s.female,
            s.stance.distance_m,
            s.ours[&Measure::Stature] - s.truth[&Measure::Stature],
            s.ours[&Measure::ShoulderWidth] - s.truth[&Measure::ShoulderWidth],
            s.ours[&Measure::Bust] - s.truth[&Measure::Bust],
            s.ours[&Measure::Hip] - s.truth[&Measure::Hip]
        );
    }
    println!(
        "{}",
        serde_json::to_string_pretty(&(&r.ours, &r.seed_method)).unwrap_or_default()
    );
    println!(
        "stature {:.2} % (seed {:.2} %), sizes {:.1} %, genders {:.1} %, fit {:.0} ms mean",
        r.stature_percent_ours,
        r.stature_percent_seed,
        r.size_agreement * 100.0,
        r.gender_agreement * 100.0,
        r.mean_fit_ms
    );
}

/// The acceptance lines, on `r`.
fn assert_goals(r: &MeasureReport, size_share: f64) {
    report(r);
    assert!(
        r.stature_percent_ours <= 1.0,
        "stature {:.2} %",
        r.stature_percent_ours
    );
    let shoulder = stats(r, Measure::ShoulderWidth);
    assert!(shoulder <= 1.5, "shoulder width {shoulder:.2} cm");
    for m in [Measure::Bust, Measure::Waist, Measure::Hip] {
        let e = stats(r, m);
        assert!(e <= 2.0, "{m} {e:.2} cm");
    }
    assert!(
        r.size_agreement >= size_share,
        "recommended size equal to the true one for {:.1} %",
        r.size_agreement * 100.0
    );
    assert!(stats(r, Measure::Stature) < seed_stats(r, Measure::Stature));
    assert!(shoulder < seed_stats(r, Measure::ShoulderWidth));
}

/// A dozen subjects in the filmed pose (the measurement alone): the goals' error lines hold
/// (the size share, a coarse figure on 12 people, is checked at 75 %; the 200-subject run
/// below checks 90 %).
#[test]
fn held_out_subjects_are_measured_within_the_goals() {
    let r = run(12, 3, PoseSource::Truth);
    assert_goals(&r, 0.75);
    assert!(
        r.gender_agreement >= 0.9,
        "genders {:.2}",
        r.gender_agreement
    );
}

/// Through the kiosk's chain (our tracker's pose, pixels and skeleton): within a few
/// centimetres, and far better than the seed's method. (The goals are not met on this path
/// yet: `docs/measure.md`.)
#[test]
fn held_out_subjects_through_the_tracker_are_measured_within_centimetres() {
    let r = run(8, 4, PoseSource::Tracker);
    report(&r);
    assert!(
        r.stature_percent_ours <= 1.5,
        "stature {:.2} %",
        r.stature_percent_ours
    );
    for m in [
        Measure::ShoulderWidth,
        Measure::Bust,
        Measure::Waist,
        Measure::Hip,
    ] {
        let e = stats(&r, m);
        assert!(e <= 3.5, "{m} {e:.2} cm");
    }
    assert!(stats(&r, Measure::Stature) < seed_stats(&r, Measure::Stature));
}

/// The acceptance run: 200 held-out subjects (fixed seed), through the kiosk's chain (our
/// tracker). About ten minutes on two cores: `cargo test --release -p fitroom_measure
/// --no-default-features --test measure -- --ignored`.
#[test]
#[ignore]
fn two_hundred_subjects_meet_the_acceptance_lines() {
    let r = run(200, 1, PoseSource::Tracker);
    assert_goals(&r, 0.90);
}

/// The prior and the evaluation never share a subject.
#[test]
fn the_prior_learns_from_other_subjects_than_the_evaluation_measures() {
    let [women, men] = read_survey(&fitroom_testdata::data_dir().join("ansur2")).expect("ANSUR II");
    let all: Vec<_> = women.into_iter().chain(men).collect();
    let train: std::collections::HashSet<String> =
        training(&all).into_iter().map(|s| s.id).collect();
    let test = held_out(&all);
    assert!(test.len() > 3000);
    assert!(test.iter().all(|s| !train.contains(&s.id)));
}

fn still_frames(
    count: usize,
) -> (
    BodyModel,
    Vec<CalibrationFrame>,
    fitroom_measure::eval::Recording,
) {
    let model = model();
    let shape = fitroom_body::Shape::default();
    let rec = record(
        &model,
        &shape,
        &Stance::drawn(5),
        count,
        NoiseSettings::default(),
        5,
        None,
    )
    .expect("a recording");
    (model, rec.frames.clone(), rec)
}

#[test]
fn too_few_frames_are_refused() {
    let (_, frames, _) = still_frames(3);
    assert!(matches!(
        AveragedView::new(&frames),
        Err(MeasureError::TooFewFrames { got: 3, .. })
    ));
    assert!(matches!(
        seed::measure(&frames),
        Err(MeasureError::TooFewFrames { .. })
    ));
}

#[test]
fn a_frame_of_the_wrong_size_or_with_nan_joints_is_named() {
    let (_, mut frames, _) = still_frames(6);
    frames[2].mask = vec![true; 100].into();
    let e = AveragedView::new(&frames).expect_err("refused");
    assert!(e.to_string().contains("frame 2"), "{e}");
    let (_, mut frames, _) = still_frames(6);
    frames[4].joints[3] = Vec3::NAN;
    let e = AveragedView::new(&frames).expect_err("refused");
    assert!(e.to_string().contains("frame 4"), "{e}");
}

/// Frames without depth (a sensor that shows nothing) give an error, not a body.
#[test]
fn frames_without_depth_are_refused() {
    let (model, mut frames, rec) = still_frames(6);
    for f in &mut frames {
        f.depth = DepthFrame {
            depth_mm: Arc::from(vec![0u16; PIXELS]),
            raw: None,
            rgb: None,
            time_s: 0.0,
            timestamp: 0,
            camera: DepthCamera::default(),
        };
    }
    let view = AveragedView::new(&frames).expect("averaged");
    let prior = ShapePrior::shipped().expect("the shipped prior");
    let views = [ViewPose {
        view: &view,
        locals: &rec.locals,
        placement: rec.placement,
    }];
    let e = fit_body(
        &model,
        &views,
        &fitroom_body::Shape::default(),
        Some(prior.of(true)),
        &FitSettings::default(),
    )
    .expect_err("no body from no depth");
    assert!(matches!(e, MeasureError::TooFewPoints { .. }), "{e}");
    assert!(seed::measure(&frames).is_err());
}

/// A start the fit cannot recover from (both arms folded onto the chest, as the tracker
/// reports them for some small women) is detected by the points left far from the skin and
/// fitted again from the pose the calibration asks for: the person is measured anyway.
#[test]
fn a_fit_stuck_on_a_wrong_start_is_made_again() {
    let model = model();
    let shape = fitroom_body::Shape {
        gender: 0.0,
        weight: 0.4,
        ..fitroom_body::Shape::default()
    };
    let rec = record(
        &model,
        &shape,
        &Stance::drawn(11),
        12,
        NoiseSettings::default(),
        11,
        None,
    )
    .expect("a recording");
    let truth = model.measure(&rec.body.positions).expect("measured");
    let view = AveragedView::new(&rec.frames).expect("averaged");
    // Each upper arm turned 110° from the filmed pose, towards the body's middle.
    let mut folded = rec.locals.clone();
    for (bone, sign) in [("upperarm_l", 1.0f32), ("upperarm_r", -1.0)] {
        let b = model.bone_index(bone).expect("an upper arm");
        folded[b] *= glam::Quat::from_rotation_z(sign * 110f32.to_radians());
    }
    let views = [ViewPose {
        view: &view,
        locals: &folded,
        placement: rec.placement,
    }];
    let prior = ShapePrior::shipped().expect("the shipped prior");
    let settings = FitSettings::default();
    let worst =
        |e: &fitroom_measure::BodyEstimate| e.view_rms_m.iter().copied().fold(0.0f32, f32::max);
    // The premise: from this start, the fit alone stays stuck.
    let start = ShapeSpace::full().shape(&prior.female.mean);
    let alone = fit_body(&model, &views, &start, Some(&prior.female), &settings).expect("a fit");
    assert!(
        worst(&alone) > STUCK_RMS_M,
        "the folded start did not trap the fit ({:.1} mm): the test shows nothing",
        worst(&alone) * 1e3
    );
    let person = measure_person(&model, &views, &prior, &settings).expect("measured");
    let e = &person.estimate;
    let err = |m: Measure| m.of(&e.measurements) - m.of(&truth);
    assert!(
        worst(e) < STUCK_RMS_M,
        "still stuck: {:.1} mm",
        worst(e) * 1e3
    );
    for m in [Measure::Stature, Measure::Bust, Measure::Hip] {
        assert!(err(m).abs() < 2.0, "{m:?}: {:+.1} cm", err(m));
    }
}
