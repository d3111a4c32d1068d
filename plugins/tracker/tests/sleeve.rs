//! A short sleeve's end seen in the outline of a hanging upper arm (`fitroom_tracker::sleeve`):
//! bodies rendered from the body crate's own skinning, bare and with sleeves made by pushing
//! the skin of each upper arm's top half out along its normals (a tube standing off the arm,
//! ending in a step, as a T-shirt's sleeve does; the root test `track_clothing` sees the
//! shipped T-shirt's, simulated).

mod common;

use common::{Body, Turns, body, render, scene};
use fitroom_depth::synthetic::Label;
use fitroom_tracker::sleeve::{self, Sleeves};
use fitroom_tracker::{TrackBody, Tracker, TrackerSettings};
use glam::Vec3;

const HANGING: Turns = &[
    ("upperarm_l", Vec3::Z, -40.0),
    ("upperarm_r", Vec3::Z, 40.0),
];

/// Vertex normals of the body's skin (area-weighted face normals).
fn normals(person: &Body) -> Vec<Vec3> {
    let mut n = vec![Vec3::ZERO; person.positions.len()];
    for t in &person.model.triangles {
        let [a, b, c] = t.map(|i| person.positions[i as usize]);
        let face = (b - a).cross(c - a);
        for i in t {
            n[*i as usize] += face;
        }
    }
    n.iter().map(|v| v.normalize_or_zero()).collect()
}

/// `person` with sleeves `stand_off` metres off the skin of each upper arm's top half.
fn sleeved(mut person: Body, stand_off: f32) -> Body {
    let normals = normals(&person);
    for name in ["upperarm_l", "upperarm_r"] {
        let b = person.bone(name);
        let (head, tail) = (person.rest.heads[b], person.rest.tails[b]);
        let axis = tail - head;
        let owned: Vec<usize> = (0..person.model.body_vertex_count as usize)
            .filter(|&v| {
                let (j, w) = (person.model.skin_joints[v], person.model.skin_weights[v]);
                usize::from(j[0]) == b && w[0] > 0.5
            })
            .collect();
        for v in owned {
            let along = (person.positions[v] - head).dot(axis) / axis.length_squared();
            if along < 0.5 {
                person.positions[v] += normals[v] * stand_off;
            }
        }
    }
    person
}

/// The steps measured over 8 frames of `person` standing `z` metres away in `turns`.
fn steps(person: &Body, turns: Turns, z: f32, seed: u64) -> Vec<f32> {
    let track = TrackBody::new(&person.model, &person.model.positions).expect("body");
    let mut tracker = Tracker::new(track, TrackerSettings::default());
    let (skin, _) = person.posed(&person.locals(turns, 1.0), Vec3::new(0.0, -0.8, z));
    let the_scene = scene(vec![(skin, Label::Body)], &person.model.triangles);
    let mut out = Vec::new();
    for f in 0..8 {
        let frame = render(&the_scene, seed + f, f as f64 / 30.0);
        let tracked = tracker.track(&frame).expect("tracked");
        let joints: Vec<_> = tracked
            .joints
            .iter()
            .map(|j| (j.position, j.pixel))
            .collect();
        out.extend(sleeve::steps(&frame, &tracked.person.mask, &joints));
    }
    out
}

#[test]
fn sleeves_are_seen_on_hanging_arms_and_bare_arms_are_bare() {
    let settings = TrackerSettings::default();
    let judge = |s: &[f32]| sleeve::judge(s, settings.sleeve_seen_m, settings.sleeve_bare_m);
    for (z, seed) in [(2.2, 3u64), (3.0, 19)] {
        let bare = steps(&body(), HANGING, z, seed);
        let shirt = steps(&sleeved(body(), 0.03), HANGING, z, seed);
        let mm = |s: &[f32]| sleeve::median_step(s).map(|m| (m * 1000.0).round());
        println!(
            "at {z} m: bare {:?} mm, sleeved {:?} mm ({} and {} arms measured)",
            mm(&bare),
            mm(&shirt),
            bare.len(),
            shirt.len()
        );
        assert_eq!(judge(&bare), Sleeves::Bare, "bare at {z} m: {bare:?}");
        assert_eq!(judge(&shirt), Sleeves::Seen, "sleeved at {z} m: {shirt:?}");
    }
}

#[test]
fn raised_arms_say_nothing() {
    let raised: Turns = &[
        ("upperarm_l", Vec3::Z, 60.0),
        ("upperarm_r", Vec3::Z, -60.0),
    ];
    let shirt = steps(&sleeved(body(), 0.03), raised, 2.5, 7);
    assert!(shirt.is_empty(), "{shirt:?}");
}
