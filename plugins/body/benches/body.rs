//! The speed goals for the parametric body (release): applying a full shape (morph
//! targets, normals, skeleton rest pose) to the 13,380-vertex body in at most 2 ms, and one
//! 9-measurement fit in at most 100 ms. Also the full measurement and the fast probe the fit
//! uses.

use std::collections::BTreeMap;
use std::hint::black_box;
use std::path::Path;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use fitroom_body::{BodyModel, FitOptions, FitRequest, Measure, Shape, fit};

fn model() -> BodyModel {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../assets/bodies/makehuman.fitbody"
    );
    BodyModel::read(Path::new(path)).expect("body asset")
}

/// A full shape: every macro slider off its default and twelve measure sliders.
fn full_shape() -> Shape {
    let measures = [
        ("bust-circ", 0.3),
        ("underbust-circ", -0.2),
        ("waist-circ", 0.4),
        ("hips-circ", -0.3),
        ("neck-circ", 0.2),
        ("thigh-circ", 0.5),
        ("calf-circ", -0.4),
        ("shoulder-dist", 0.3),
        ("upperleg-height", 0.2),
        ("lowerleg-height", -0.1),
        ("upperarm-length", 0.3),
        ("lowerarm-length", 0.2),
    ];
    Shape {
        gender: 0.3,
        age: 0.6,
        muscle: 0.6,
        weight: 0.7,
        height: 0.55,
        proportions: 0.6,
        african: 0.2,
        asian: 0.3,
        caucasian: 0.5,
        measures: measures
            .iter()
            .map(|&(k, v)| (k.to_owned(), v))
            .collect::<BTreeMap<_, _>>(),
        regions: BTreeMap::new(),
    }
}

/// The nine ANSUR II measures of the survey's median woman (cm; ANSUR II female medians).
fn median_woman() -> FitRequest {
    FitRequest {
        gender: 0.0,
        age_years: None,
        targets: BTreeMap::from([
            (Measure::Stature, 162.6),
            (Measure::Bust, 94.0),
            (Measure::NavelWaist, 85.2),
            (Measure::Hip, 101.9),
            (Measure::Neck, 37.0),
            (Measure::Thigh, 61.3),
            (Measure::Calf, 37.2),
            (Measure::ShoulderWidth, 36.5),
            (Measure::InsideLeg, 78.0),
        ]),
    }
}

/// The survey's median man.
fn median_man() -> FitRequest {
    FitRequest {
        gender: 1.0,
        age_years: None,
        targets: BTreeMap::from([
            (Measure::Stature, 175.5),
            (Measure::Bust, 105.6),
            (Measure::NavelWaist, 93.7),
            (Measure::Hip, 101.7),
            (Measure::Neck, 43.3),
            (Measure::Thigh, 62.4),
            (Measure::Calf, 39.2),
            (Measure::ShoulderWidth, 41.5),
            (Measure::InsideLeg, 84.5),
        ]),
    }
}

fn bench_body(c: &mut Criterion) {
    let model = model();
    let shape = full_shape();
    c.bench_function("shape_apply_full_13k_vertices", |b| {
        b.iter(|| black_box(model.shaped(black_box(&shape)).expect("shape")))
    });
    let positions = model.shaped(&shape).expect("shape").positions;
    let mut g = c.benchmark_group("measure");
    g.sample_size(20);
    g.bench_function("full_measurement", |b| {
        b.iter(|| black_box(model.measure(black_box(&positions)).expect("measure")))
    });
    let (_, probe) = model.measure_with_probe(&positions).expect("measure");
    g.bench_function("probe_remeasurement", |b| {
        b.iter(|| black_box(probe.measure(black_box(&positions), &model.triangles)))
    });
    g.finish();

    let mut g = c.benchmark_group("fit");
    g.sample_size(10).measurement_time(Duration::from_secs(8));
    for (name, request) in [
        ("median_woman", median_woman()),
        ("median_man", median_man()),
    ] {
        let report = fit(&model, &request, &FitOptions::default()).expect("fit");
        assert!(report.reachable, "{name}: {:?}", report.residuals_cm);
        g.bench_function(format!("nine_measurements_{name}"), |b| {
            b.iter(|| black_box(fit(&model, black_box(&request), &FitOptions::default())))
        });
    }
    g.finish();
}

criterion_group!(benches, bench_body);
criterion_main!(benches);
