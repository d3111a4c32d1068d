//! Shape fitting (calibration to measurements): recovering the measurements of bodies the
//! model can make, honest reports of bodies it cannot, clear errors for bad input, and the
//! issue's acceptance over ANSUR II subjects.

mod common;

use std::collections::BTreeMap;

use fitroom_body::ansur::{self, ANSUR_MEASURES};
use fitroom_body::{BodyModel, FitError, FitOptions, FitRequest, Measure, Shape, fit};

fn model() -> &'static BodyModel {
    common::asset_model()
}

/// The nine ANSUR measures of a body the model itself makes: fitting them must find a body
/// with those measurements (not necessarily the same sliders: many shapes share them).
#[test]
fn recovers_the_measurements_of_bodies_the_model_makes() {
    let m = model();
    let shapes = [
        Shape {
            gender: 0.0,
            weight: 0.7,
            height: 0.6,
            measures: BTreeMap::from([
                ("hips-circ".to_owned(), 0.4),
                ("neck-circ".to_owned(), 0.3),
            ]),
            ..Shape::default()
        },
        Shape {
            gender: 1.0,
            weight: 0.3,
            muscle: 0.7,
            height: 0.4,
            measures: BTreeMap::from([("waist-circ".to_owned(), -0.4)]),
            ..Shape::default()
        },
    ];
    for shape in shapes {
        let truth = m
            .measure(&m.shaped(&shape).expect("shape").positions)
            .expect("measure");
        let targets: BTreeMap<Measure, f32> = ANSUR_MEASURES
            .iter()
            .map(|&(_, q)| (q, q.of(&truth)))
            .collect();
        let report = fit(
            m,
            &FitRequest {
                gender: shape.gender,
                age_years: None,
                targets: targets.clone(),
            },
            &FitOptions::default(),
        )
        .expect("fit");
        println!(
            "gender {}: {} full measurements, {} steps, {:.0} ms, residuals {:?}",
            shape.gender,
            report.outer_iterations,
            report.iterations,
            report.time_ms,
            report.residuals_cm
        );
        assert!(report.reachable, "{:?}", report.residuals_cm);
        // The reported measurements are a full re-measurement of the fitted shape.
        let again = m
            .measure(&m.shaped(&report.shape).expect("shape").positions)
            .expect("measure");
        for (q, t) in &targets {
            assert!(
                (q.of(&again) - t).abs() <= 0.5,
                "{q}: {} vs {t}",
                q.of(&again)
            );
            assert!((q.of(&again) - q.of(&report.achieved)).abs() < 1e-3);
        }
    }
}

#[test]
fn an_unreachable_body_is_reported_with_the_closest_body() {
    // 215 cm tall with 62 cm of inside leg: legs far shorter than the model's proportions
    // allow at that height.
    let report = fit(
        model(),
        &FitRequest {
            gender: 1.0,
            age_years: None,
            targets: BTreeMap::from([(Measure::Stature, 215.0), (Measure::InsideLeg, 62.0)]),
        },
        &FitOptions::default(),
    )
    .expect("fit");
    println!("{:?} at bounds {:?}", report.residuals_cm, report.at_bounds);
    assert!(!report.reachable);
    assert!(report.residuals_cm.values().any(|r| r.abs() > 0.5));
    assert!(!report.at_bounds.is_empty());
    // The shape is still valid and is the body that was measured.
    report.shape.validate().expect("a valid shape");
}

#[test]
fn bad_requests_are_clear_errors() {
    let m = model();
    let ask = |targets: BTreeMap<Measure, f32>, gender: f32, age: Option<f32>| {
        fit(
            m,
            &FitRequest {
                gender,
                age_years: age,
                targets,
            },
            &FitOptions::default(),
        )
    };
    let e = ask(BTreeMap::from([(Measure::Waist, 300.0)]), 0.0, None).unwrap_err();
    assert!(matches!(e, FitError::OutOfRange { .. }), "{e}");
    let text = e.to_string();
    assert!(
        text.contains("waist") && text.contains("300") && text.contains("45..=170"),
        "{text}"
    );
    let e = ask(BTreeMap::from([(Measure::Hip, -5.0)]), 0.0, None).unwrap_err();
    assert!(e.to_string().contains("`hip`"), "{e}");
    let e = ask(BTreeMap::from([(Measure::Hip, f32::NAN)]), 0.0, None).unwrap_err();
    assert!(e.to_string().contains("`hip`"), "{e}");
    let e = ask(BTreeMap::new(), 0.0, None).unwrap_err();
    assert!(matches!(e, FitError::NoTargets), "{e}");
    let e = ask(BTreeMap::from([(Measure::Hip, 100.0)]), 2.0, None).unwrap_err();
    assert!(e.to_string().contains("gender"), "{e}");
    let e = ask(BTreeMap::from([(Measure::Hip, 100.0)]), 0.0, Some(5.0)).unwrap_err();
    assert!(e.to_string().contains("age"), "{e}");
    assert_eq!(Measure::from_name("chest"), Some(Measure::Bust));
    let e = "wiast".parse::<Measure>().unwrap_err();
    assert!(e.contains("wiast") && e.contains("navel-waist"), "{e}");
}

/// The acceptance: 200 random subjects of each sex (seed 1), the nine measures:
/// |error| <= 0.5 cm for at least 90% of the (subject, measurement) pairs. The whole survey
/// is evaluated by `fitroom body ansur` (docs/STATUS.md).
#[test]
fn ansur_ii_subjects_are_fitted_within_half_a_centimetre() {
    let survey =
        ansur::read_survey(&fitroom_testdata::ansur_dir()).unwrap_or_else(|e| panic!("{e}"));
    let mut subjects = Vec::new();
    for all in &survey {
        assert!(all.len() > 1900, "{} subjects", all.len());
        subjects.extend(ansur::sample(all, 200, 1));
    }
    let report = ansur::evaluate(model(), &subjects, &FitOptions::default(), 2, &|_, _| {});
    println!(
        "{} subjects, {:.1}% of {} pairs within 0.5 cm, {} subjects fully reached, mean fit {:.0} ms",
        report.subjects,
        100.0 * report.pairs_within_tolerance,
        report.pairs,
        report.subjects_reachable,
        report.mean_fit_ms
    );
    for m in &report.per_measure {
        println!(
            "  {:<15} {:5.1}%  median {:.2}  p90 {:.2}  max {:.1} cm",
            m.measure.name(),
            100.0 * m.within_tolerance,
            m.median_abs_cm,
            m.p90_abs_cm,
            m.max_abs_cm
        );
    }
    assert_eq!(report.failed_fits, 0);
    assert!(
        report.pairs_within_tolerance >= 0.90,
        "{:.1}% of pairs within 0.5 cm",
        100.0 * report.pairs_within_tolerance
    );
}

#[test]
fn a_corrupt_ansur_file_is_a_clear_error() {
    let dir = std::env::temp_dir().join(format!("fitroom-ansur-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join("broken.csv");
    let header = "subjectid,Age,weightkg,stature,chestcircumference,waistcircumference,\
                  buttockcircumference,neckcircumferencebase,thighcircumference,\
                  calfcircumference,biacromialbreadth,crotchheight";
    std::fs::write(
        &path,
        format!("{header}\n1,30,700,1650,900,800,1000,350,600,370,360,780\n2,31,x,1650,900,800,1000,350,600,370,360,780\n"),
    )
    .expect("write");
    let e = ansur::read_ansur(&path, true).unwrap_err().to_string();
    assert!(
        e.contains("broken.csv") && e.contains("line 3") && e.contains("weightkg"),
        "{e}"
    );
    std::fs::write(&path, "subjectid,Age\n1,30\n").expect("write");
    let e = ansur::read_ansur(&path, true).unwrap_err().to_string();
    assert!(e.contains("weightkg") && e.contains("ANSUR"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}
