//! The tracker's estimate of the person's build with the measurement's body fit
//! ([`TrackedBuild`]), on bodies it was not tuned on (it was chosen on three ANSUR II builds
//! walking CMU clips; these are MakeHuman builds made from its sliders, standing as the
//! measurement's recordings film them): the body it gives has the person's stature, and the
//! trunk's joints come out nearer the truth than with the tracker's own search.

use std::sync::Arc;

/// The tracker's own test helpers: the shipped body posed by the body crate's skinning, filmed
/// in a room.
#[path = "../../tracker/tests/common/mod.rs"]
mod common;

use fitroom_body::{BodyModel, Shape};
use fitroom_depth::synthetic::{Label, NoiseSettings};
use fitroom_measure::ShapePrior;
use fitroom_measure::build::TrackedBuild;
use fitroom_measure::eval::{Filmed, Stance, record};
use fitroom_tracker::eval::TRUNK;
use fitroom_tracker::shape::{BuildFit, Snapshot};
use fitroom_tracker::{TrackBody, Tracker, TrackerSettings};

fn model() -> Arc<BodyModel> {
    Arc::new(common::model())
}

/// The stature (cm) of the body of `shape`.
fn stature_cm(model: &BodyModel, shape: &Shape) -> f32 {
    let body = model.shaped(shape).expect("a body");
    model.measure(&body.positions).expect("measured").stature_cm
}

/// The trunk's mean error (mm) from frame 10 on of `shape` filmed standing (noise and stance
/// from `seed`), tracked by `tracker`; and the build it found.
fn trunk_error_mm(
    model: &BodyModel,
    shape: &Shape,
    seed: u64,
    mut tracker: Tracker,
) -> (f32, Shape) {
    let rec = record(
        model,
        shape,
        &Stance::drawn(seed),
        30,
        NoiseSettings::default(),
        seed,
        None,
    )
    .expect("a recording");
    let (mut sum, mut n) = (0.0, 0);
    for (k, frame) in rec.frames.iter().enumerate() {
        let tracked = tracker.track(&frame.depth).expect("the person tracked");
        if k >= 10 {
            for j in TRUNK {
                sum += tracked.joints[j.index()]
                    .position
                    .distance(frame.joints[j.index()]);
                n += 1;
            }
        }
    }
    let found = tracker.person_shape().cloned().unwrap_or_else(|| {
        panic!(
            "the build not estimated within the first 10 frames: {:?}",
            tracker.shape_error
        )
    });
    (sum / n as f32 * 1000.0, found)
}

#[test]
fn the_body_fit_gives_the_tracker_the_persons_stature_and_a_nearer_trunk() {
    let model = model();
    let prior = Arc::new(ShapePrior::shipped().expect("the shipped prior"));
    let builds = [
        // A broad, heavy man; a slight, short woman; a tall, thin man (ANSUR II's range: the
        // prior the fit leans on is learnt from it).
        Shape {
            gender: 1.0,
            weight: 0.9,
            muscle: 0.7,
            height: 0.6,
            ..Shape::default()
        },
        Shape {
            gender: 0.0,
            weight: 0.3,
            muscle: 0.3,
            height: 0.2,
            ..Shape::default()
        },
        Shape {
            gender: 0.8,
            weight: 0.2,
            muscle: 0.5,
            height: 0.6,
            ..Shape::default()
        },
    ];
    let (mut own_sum, mut fit_sum, mut n) = (0.0, 0.0, 0.0);
    // Two stances and noise draws per build (a draw whose person the image cuts off at the
    // feet is never wholly in view, and no build is estimated).
    let draws = builds
        .iter()
        .enumerate()
        .flat_map(|(k, shape)| [(50 + k as u64, shape), (70 + k as u64, shape)]);
    for (seed, shape) in draws {
        let tracker =
            || Tracker::estimating(model.clone(), TrackerSettings::default()).expect("a tracker");
        let (own, _) = trunk_error_mm(&model, shape, seed, tracker());
        let with_fit = tracker().with_build_fit(Arc::new(TrackedBuild::new(prior.clone())));
        let (fit, found) = trunk_error_mm(&model, shape, seed, with_fit);
        let (truth_cm, found_cm) = (stature_cm(&model, shape), stature_cm(&model, &found));
        println!(
            "seed {seed}: trunk {own:.1} mm with the tracker's search, {fit:.1} with the body fit; stature {truth_cm:.1} cm, found {found_cm:.1}"
        );
        assert!(
            (found_cm - truth_cm).abs() < 2.0,
            "seed {seed}: stature {found_cm:.1} cm found, {truth_cm:.1} true"
        );
        own_sum += own;
        fit_sum += fit;
        n += 1.0;
    }
    let (own, fit) = (own_sum / n, fit_sum / n);
    println!("mean trunk: {fit:.1} mm against {own:.1}");
    // Standing still, the tracker's own search does well too (on the acceptance set's moving
    // people the gain is larger: docs/STATUS.md); when written, 14.2 against 16.5 mm.
    assert!(
        fit < 0.9 * own,
        "the body fit's trunk {fit:.1} mm, the tracker's search {own:.1}"
    );
}

/// `shape` filmed standing (noise and stance from `seed`) with the skin of its trunk,
/// clavicles and upper arms `layer_m` out along the skin's normals (a shirt's surface), and
/// the frames the tracker kept for its build there.
fn clothed_snapshots(
    model: &Arc<BodyModel>,
    shape: &Shape,
    layer_m: f32,
    seed: u64,
) -> Vec<Snapshot> {
    let mut rest = model.shaped(shape).expect("a body").positions;
    let covered = fitroom_tracker::model::clothed_vertices(model);
    let normals = fitroom_body::compute_normals(&rest, &model.triangles);
    for ((v, n), &on) in rest.iter_mut().zip(&normals).zip(&covered) {
        if on {
            *v += *n * layer_m;
        }
    }
    let filmed = Filmed {
        shape,
        detailed: Some(&rest),
    };
    let rec = record(
        model,
        filmed,
        &Stance::drawn(seed),
        12,
        NoiseSettings::default(),
        seed,
        None,
    )
    .expect("a recording");
    let mut tracker = Tracker::new(
        TrackBody::new(model, &model.positions).expect("a body"),
        TrackerSettings::default(),
    );
    let mut kept = Vec::new();
    for (k, frame) in rec.frames.iter().enumerate() {
        let tracked = tracker.track(&frame.depth).expect("the person tracked");
        if k >= 9 {
            kept.push(Snapshot {
                frame: frame.depth.clone(),
                tracked,
            });
        }
    }
    kept
}

/// The body fit under a layer of clothing (`FitSettings::clothing_m`) finds the body under
/// it: on a person whose shirt stands 3 cm off the trunk and upper arms, the chest, waist and
/// hips of the body fitted under a 3 cm layer are nearer the person's than those of the body
/// fitted to the shirt's surface.
#[test]
fn the_body_fit_under_a_layer_of_clothing_finds_the_body_under_it() {
    let model = model();
    let prior = Arc::new(ShapePrior::shipped().expect("the shipped prior"));
    let fit = TrackedBuild::new(prior);
    let shape = Shape {
        gender: 0.8,
        weight: 0.6,
        ..Shape::default()
    };
    let girths = |s: &Shape| {
        let body = model.shaped(s).expect("a body");
        let m = model.measure(&body.positions).expect("measured");
        [m.bust_cm, m.waist_cm, m.hip_cm]
    };
    let truth = girths(&shape);
    for seed in [51, 71] {
        let kept = clothed_snapshots(&model, &shape, 0.03, seed);
        let off = |t: f32| -> f32 {
            let found = fit.fit(&model, &kept, t).expect("a build").shape;
            let g = girths(&found);
            println!("seed {seed}, layer {t}: bust, waist, hip {g:?} cm; true {truth:?}");
            g.iter()
                .zip(&truth)
                .map(|(a, b)| (a - b).abs())
                .sum::<f32>()
        };
        let (under, over) = (off(0.03), off(0.0));
        assert!(
            under < 0.5 * over,
            "seed {seed}: girths {under:.1} cm off under the layer, {over:.1} without"
        );
    }
}

/// The layer the tracker takes with the measurement's body fit (`estimate_with`, the app's and
/// the CLI's way): a person moving their arms in a 3 cm layer (the skin of the trunk,
/// clavicles and upper arms moved out along its normals, a shirt's surface) is found clothed,
/// the same person bare is not. (The tracker's own macro search is tested on the same scene in
/// `fitroom_tracker`'s `shape` tests.)
#[test]
fn the_tracker_with_the_body_fit_finds_a_layer_of_clothing_only_on_a_clothed_person() {
    let model = model();
    let prior = Arc::new(ShapePrior::shipped().expect("the shipped prior"));
    let layer_found = |layer_m: f32, seed: u64| -> f32 {
        let mut tracker = Tracker::estimating(model.clone(), TrackerSettings::default())
            .expect("a tracker")
            .with_build_fit(Arc::new(TrackedBuild::new(prior.clone())));
        for frame in common::arms_moving_in_a_layer(layer_m, seed) {
            tracker.track(&frame).expect("tracked");
        }
        tracker
            .shape
            .as_ref()
            .expect("the build estimated within a second")
            .clothing_m
    };
    for seed in [7, 107] {
        assert!(
            layer_found(0.03, seed) > 0.0,
            "seed {seed}: the clothed person found bare"
        );
        assert_eq!(
            layer_found(0.0, seed),
            0.0,
            "seed {seed}: the bare person found clothed"
        );
    }
}

/// A jump's crouch: thighs raised, knees bent deep, the trunk bowed forward.
const CROUCH: common::Turns = &[
    ("thigh_l", glam::Vec3::X, -100.0),
    ("thigh_r", glam::Vec3::X, -100.0),
    ("calf_l", glam::Vec3::X, 130.0),
    ("calf_r", glam::Vec3::X, 130.0),
    ("spine_01", glam::Vec3::X, 25.0),
    ("spine_02", glam::Vec3::X, 20.0),
    ("neck_01", glam::Vec3::X, -20.0),
];

/// The stature (cm) of the build the tracker with the measurement's body fit gives a man
/// first seen crouching, who then rises and stands moving his arms (noise seed `seed`), when
/// it looks at his build `looks` times.
fn stature_after_a_crouch_cm(
    model: &Arc<BodyModel>,
    shape: &Shape,
    seed: u64,
    looks: usize,
) -> f32 {
    let person = common::shaped_body(shape);
    let prior = Arc::new(ShapePrior::shipped().expect("the shipped prior"));
    let mut settings = TrackerSettings::default();
    settings.shape.looks = looks;
    let mut tracker = Tracker::estimating(model.clone(), settings)
        .expect("a tracker")
        .with_build_fit(Arc::new(TrackedBuild::new(prior)));
    let floor_y = -0.8;
    for k in 0..75u32 {
        // Crouched for 12 frames, up by frame 20, then the arms rise and fall.
        let crouch = (1.0 - (k as f32 - 12.0) / 8.0).clamp(0.0, 1.0);
        let mut locals = person.locals(CROUCH, crouch);
        let arms = person.locals(common::ARMS_OUT, 0.4 + 0.3 * (k as f32 / 15.0).sin());
        for (name, _, _) in common::ARMS_OUT {
            let b = person.bone(name);
            locals[b] = arms[b];
        }
        // The soles on the floor.
        let spot = glam::Vec3::new(0.05, 0.0, 2.8);
        let (skin, _) = person.posed(&locals, spot);
        let low = skin.iter().map(|p| p.y).fold(f32::INFINITY, f32::min);
        let (skin, _) = person.posed(&locals, spot + glam::Vec3::Y * (floor_y - low));
        let frame = common::render(
            &common::scene_at(floor_y, vec![(skin, Label::Body)], &person.model.triangles),
            seed + u64::from(k),
            f64::from(k) / 30.0,
        );
        tracker.track(&frame);
    }
    let found = tracker
        .person_shape()
        .cloned()
        .unwrap_or_else(|| panic!("no build estimated: {:?}", tracker.shape_error));
    stature_cm(model, &found)
}

/// A man first seen crouching (a jump's start) is started on a body sized to the crouch, and
/// the build fitted to those first frames kept him short for good (the acceptance set's
/// T-shirt recordings of CMU 02_04 and 13_39: 175.5 cm men measured 157-162 cm); the second
/// look, from frames of him standing, gives his stature. (Until session 42 the first look alone
/// was 7-8 cm short with both noise seeds; since a data point's rows stay with the capsule it
/// was matched on, it is right with one of them and 32 cm short with the other.)
#[test]
fn a_man_first_seen_crouching_is_given_his_standing_stature() {
    let model = model();
    let shape = Shape {
        gender: 0.9,
        weight: 0.6,
        height: 0.6,
        ..Shape::default()
    };
    let truth = stature_cm(&model, &shape);
    let mut gain = f32::NEG_INFINITY;
    for seed in [300, 500] {
        let first = stature_after_a_crouch_cm(&model, &shape, seed, 1);
        let second = stature_after_a_crouch_cm(&model, &shape, seed, 2);
        println!("seed {seed}: stature {truth:.1} cm; first look {first:.1}, second {second:.1}");
        assert!(
            (second - truth).abs() < 3.0,
            "seed {seed}: the second look's stature {second:.1} cm, true {truth:.1}"
        );
        gain = gain.max((first - truth).abs() - (second - truth).abs());
    }
    assert!(
        gain > 3.0,
        "the first look alone is no worse than both ({gain:.1} cm)"
    );
}
