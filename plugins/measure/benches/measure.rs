//! The measurement's speed: from the last calibration frame to the measured body (the frames
//! of both views averaged, both genders' fits on the app's two threads, the fitted body measured), on one
//! filmed calibration of an ANSUR II-like body. The goal: at most 1 s on these 2 cores.
//! `cargo bench -p fitroom_measure --no-default-features --bench measure`.

use std::path::Path;

use criterion::{Criterion, criterion_group, criterion_main};
use fitroom_body::{BodyModel, Shape};
use fitroom_depth::synthetic::NoiseSettings;
use fitroom_measure::eval::{Stance, TURN_DEG, record};
use fitroom_measure::tracked::tracked_views;
use fitroom_measure::{FitSettings, ShapePrior, ViewPose, measure_person};

fn bench(c: &mut Criterion) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/bodies/makehuman.fitbody");
    let model = BodyModel::read(&path).expect("the shipped body");
    let prior = ShapePrior::shipped().expect("the shipped prior");
    let shape = Shape {
        gender: 1.0,
        weight: 0.6,
        ..Shape::default()
    };
    // The calibration's two views: facing the sensor, then turned to the side. The kiosk's
    // chain: the tracker's pose, refined.
    let stance = Stance::drawn(2);
    let seen: Vec<_> = [stance, stance.turned(TURN_DEG)]
        .iter()
        .enumerate()
        .map(|(i, st)| {
            let rec = record(
                &model,
                &shape,
                st,
                30,
                NoiseSettings::default(),
                2 + i as u64,
                None,
            )
            .expect("a recording");
            fitroom_measure::eval::tracked(&model, &rec.frames).expect("tracked")
        })
        .collect();
    let settings = FitSettings::default();
    let mut group = c.benchmark_group("measure");
    group.sample_size(10);
    group.bench_function("calibration_to_body", |b| {
        b.iter(|| {
            let views = tracked_views(&model, &seen).expect("averaged");
            let views: Vec<ViewPose> = views.iter().map(|v| v.as_view_pose()).collect();
            measure_person(&model, &views, &prior, &settings).expect("measured")
        })
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
