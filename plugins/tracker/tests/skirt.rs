//! A skirt found in the depth ([`fitroom_tracker::skirt`]): a flared tube from the hips down
//! around the standing body is found, its hem within a few centimetres of where it ends; the
//! same body bare, legs apart or pressed together (a heavy man's thighs meeting), wears none;
//! with the skirt's points left out of the fit the hips are held; legs walking under it
//! are held by their feet; and a skirt is still worn in the frames its cloth, drawn in
//! between the legs, hides the fork.

mod common;

use common::{Body, body, render, scene, shaped_body};
use fitroom_depth::synthetic::{Label, SceneMesh};
use fitroom_sensor::KinectJoint;
use fitroom_tracker::skirt::{SkirtSettings, SkirtZone, skirt_zone};
use fitroom_tracker::{SegmentSettings, Segmenter, TrackBody, Tracker, TrackerSettings};
use glam::Vec3;

/// An elliptic tube about the vertical through `centre`, open at both ends: its half-widths
/// sideways and in depth `top_m` at `top` (height), `hem_m` at `hem` (a hem in depth near
/// the shins, as cloth hangs: one 20 cm before them parted them from the person).
fn skirt_mesh(centre: Vec3, top: f32, hem: f32, top_m: [f32; 2], hem_m: [f32; 2]) -> SceneMesh {
    const AROUND: usize = 48;
    const DOWN: usize = 12;
    let mut positions = Vec::new();
    for i in 0..=DOWN {
        let t = i as f32 / DOWN as f32;
        let y = top + (hem - top) * t;
        let [rx, rz] = [0, 1].map(|i| top_m[i] + (hem_m[i] - top_m[i]) * t);
        for k in 0..AROUND {
            let a = k as f32 / AROUND as f32 * std::f32::consts::TAU;
            positions.push(Vec3::new(
                centre.x + rx * a.cos(),
                y,
                centre.z + rz * a.sin(),
            ));
        }
    }
    let mut triangles = Vec::new();
    for i in 0..DOWN {
        for k in 0..AROUND {
            let (a, b) = (
                (i * AROUND + k) as u32,
                (i * AROUND + (k + 1) % AROUND) as u32,
            );
            let (c, d) = (a + AROUND as u32, b + AROUND as u32);
            triangles.push([a, b, c]);
            triangles.push([b, d, c]);
        }
    }
    SceneMesh {
        positions,
        triangles,
        label: Label::Garment,
        closed: false,
    }
}

/// The skirt found on `body` posed by `turns`, 2.6 m away, in a tube reaching
/// `hem_below_m` under the hip joints (none: bare); and the hip joints' height.
fn found(
    body: &Body,
    turns: common::Turns,
    hem_below_m: Option<f32>,
    seed: u64,
) -> (Option<SkirtZone>, f32) {
    let (skin, joints) = body.posed(&body.locals(turns, 1.0), Vec3::new(0.0, -0.8, 2.6));
    let (left, right) = (
        joints[KinectJoint::HipLeft.index()],
        joints[KinectJoint::HipRight.index()],
    );
    let mid = (left + right) * 0.5;
    let mut the_scene = scene(vec![(skin, Label::Body)], &body.model.triangles);
    if let Some(below) = hem_below_m {
        the_scene.meshes.push(skirt_mesh(
            mid,
            mid.y + 0.08,
            mid.y - below,
            [0.2, 0.14],
            [0.25, 0.12],
        ));
    }
    let frame = render(&the_scene, seed, 0.0);
    let person = Segmenter::new(SegmentSettings::default())
        .segment(&frame)
        .expect("the person");
    let zone = skirt_zone(
        &frame,
        &person.mask,
        person.floor.normal,
        left,
        right,
        &SkirtSettings::default(),
    );
    (zone, person.floor.normal.dot(mid))
}

const TOGETHER: common::Turns = &[("thigh_l", Vec3::Z, 6.0), ("thigh_r", Vec3::Z, -6.0)];

#[test]
fn a_skirt_is_found_to_its_hem_and_bare_legs_wear_none() {
    let body = body();
    for (seed, below) in [(1u64, 0.45f32), (2, 0.6)] {
        let (zone, hips) = found(&body, &[], Some(below), seed);
        let zone = zone.unwrap_or_else(|| panic!("seed {seed}: no skirt found {below} m long"));
        let hem = hips - zone.hem;
        println!("a skirt to {below} m below the hip joints: hem found {hem:.2} m below");
        assert!(
            (hem - below).abs() <= 0.06,
            "seed {seed}: hem {hem:.2} m below the hip joints, the skirt's {below}"
        );
        assert!(zone.hides(Vec3::new(0.0, hips - below * 0.5, 2.5)));
    }
    // A heavy man's thighs meet below the crotch: no gap, a crease.
    let heavy = shaped_body(&fitroom_body::Shape {
        gender: 1.0,
        weight: 1.0,
        muscle: 0.3,
        ..Default::default()
    });
    for (seed, who, turns, what) in [
        (3u64, &body, &[][..], "apart"),
        (4, &body, TOGETHER, "together"),
        (5, &heavy, TOGETHER, "together (a heavy man)"),
    ] {
        let (zone, _) = found(who, turns, None, seed);
        assert_eq!(
            zone, None,
            "seed {seed}: bare legs {what} taken for a skirt"
        );
    }
}

/// Frame `k` (at 30 Hz) of `skin` in a skirt about its hip joints (from `truth`) reaching
/// `below` metres under them, its half-widths `top_m` at the top and `hem_m` at the hem
/// ([`skirt_mesh`]).
fn skirted(
    person: &Body,
    skin: Vec<Vec3>,
    truth: &[Vec3],
    (below, top_m, hem_m): (f32, [f32; 2], [f32; 2]),
    seed: u64,
    k: u64,
) -> fitroom_depth::DepthFrame {
    use KinectJoint::*;
    let mid = (truth[HipLeft.index()] + truth[HipRight.index()]) * 0.5;
    let mut the_scene = scene(vec![(skin, Label::Body)], &person.model.triangles);
    the_scene
        .meshes
        .push(skirt_mesh(mid, mid.y + 0.08, mid.y - below, top_m, hem_m));
    render(&the_scene, seed, k as f64 / 30.0)
}

/// The mean error (mm) of the hips' joints over the last 10 of 30 frames of a man moving
/// his arms inside a skirt reaching 0.55 m below his hip joints, tracked with `skirt` (the
/// default, or none looked for).
fn hips_error_mm(skirt: SkirtSettings, seed: u64) -> f32 {
    use KinectJoint::*;
    let person = shaped_body(&fitroom_body::Shape {
        gender: 1.0,
        weight: 0.6,
        ..Default::default()
    });
    let settings = TrackerSettings {
        skirt,
        ..TrackerSettings::default()
    };
    let track = TrackBody::new(&person.model, &person.positions).expect("body");
    let mut tracker = Tracker::new(track, settings);
    let (mut sum, mut n, mut found) = (0.0, 0, 0);
    for k in 0..30 {
        let share = 0.3 + 0.3 * (k as f32 / 10.0).sin();
        let (skin, truth) = person.posed(
            &person.locals(common::ARMS_OUT, share),
            Vec3::new(0.0, -0.8, 2.8),
        );
        let frame = skirted(
            &person,
            skin,
            &truth,
            (0.55, [0.22, 0.16], [0.3, 0.15]),
            seed + k,
            k,
        );
        let tracked = tracker.track(&frame).expect("tracked");
        if k >= 20 {
            for j in [HipCenter, HipLeft, HipRight] {
                sum += tracked.joints[j.index()]
                    .position
                    .distance(truth[j.index()]);
                n += 1;
            }
            found += usize::from(tracked.skirt.as_ref().is_some_and(|z| z.seen));
        }
    }
    let looked = skirt.fork_m > 0.0;
    assert_eq!(
        found,
        if looked { 10 } else { 0 },
        "seed {seed}: the skirt found in {found} of the last 10 frames (looked for: {looked})"
    );
    sum / n as f32 * 1000.0
}

/// The skirt is found on a person moving their arms out (their points kept: a hand beside
/// it is not the skirt's) and its points left out of the fit hold the hips as well as
/// fitted as skin: a rigid tube does not draw the legs as a dress's cloth does (29-30 mm
/// either way here; the dresses' figures are in docs/STATUS.md, session 53).
#[test]
fn hips_under_a_skirt_are_held_with_its_points_left_out() {
    let off = SkirtSettings {
        fork_m: 0.0,
        ..SkirtSettings::default()
    };
    for seed in [11, 31] {
        let (with, without) = (
            hips_error_mm(SkirtSettings::default(), seed),
            hips_error_mm(off, seed),
        );
        println!("seed {seed}: hips {with:.1} mm, {without:.1} with the skirt fitted as skin");
        assert!(
            with <= 40.0 && with <= without + 5.0,
            "seed {seed}: hips {with:.1} against {without:.1} mm"
        );
    }
}

/// The mean error (mm) of the knees and ankles over frames 20-39 of a man walking on the
/// spot in a skirt reaching 0.5 m below his hip joints (his legs swinging 20° forward and
/// back at the hips, a stride every 20 frames), tracked with the legs tried at the feet seen
/// below the hem or not ([`TrackerSettings::recover_by_feet`]).
fn walking_legs_error_mm(by_feet: bool, seed: u64) -> f32 {
    use KinectJoint::*;
    let person = body();
    let settings = TrackerSettings {
        recover_by_feet: by_feet,
        ..TrackerSettings::default()
    };
    let track = TrackBody::new(&person.model, &person.positions).expect("body");
    let mut tracker = Tracker::new(track, settings);
    let (mut sum, mut n) = (0.0, 0);
    for k in 0..40 {
        let swing = 20.0 * (k as f32 * std::f32::consts::TAU / 20.0).sin();
        let turns = [("thigh_l", Vec3::X, -swing), ("thigh_r", Vec3::X, swing)];
        let (skin, truth) = person.posed(&person.locals(&turns, 1.0), Vec3::new(0.0, -0.8, 2.6));
        let frame = skirted(
            &person,
            skin,
            &truth,
            (0.5, [0.2, 0.14], [0.3, 0.22]),
            seed + k,
            k,
        );
        let tracked = tracker.track(&frame).expect("tracked");
        if k >= 20 {
            for j in [KneeLeft, AnkleLeft, KneeRight, AnkleRight] {
                sum += tracked.joints[j.index()]
                    .position
                    .distance(truth[j.index()]);
                n += 1;
            }
        }
    }
    sum / n as f32 * 1000.0
}

/// Walking in a skirt, a leg the fit followed from the last frame slips (knees and ankles
/// 37-45 mm off under noise seeds 61, 3 and 13; 13-22 mm under five others) and nothing
/// else brings it back: the thighs are hidden and the shins' few points below the hem are
/// not enough. Pulled to the feet seen below the hem, the legs are held under every seed
/// (13-22 mm).
#[test]
fn legs_walking_under_a_skirt_are_held_by_their_feet() {
    for seed in [61, 3, 13] {
        let (with, without) = (
            walking_legs_error_mm(true, seed),
            walking_legs_error_mm(false, seed),
        );
        println!("seed {seed}: knees and ankles {with:.0} mm, {without:.0} without the feet");
        assert!(
            without > 30.0,
            "seed {seed}: the case should lose a leg without the feet: {without:.0} mm"
        );
        assert!(
            with < 25.0,
            "seed {seed}: the legs not held by the feet: {with:.0} mm"
        );
    }
}

/// `mesh` (a [`skirt_mesh`] about `centre`) with its front drawn in `depth_m` at the middle,
/// tapering to nothing 6 cm to either side: cloth drawn in between walking legs, a crease
/// as deep as the one between bare legs.
fn creased(mut mesh: SceneMesh, centre: Vec3, depth_m: f32) -> SceneMesh {
    for p in &mut mesh.positions {
        let side = (p.x - centre.x).abs();
        if p.z < centre.z && side < 0.06 {
            p.z += depth_m * (1.0 - side / 0.06);
        }
    }
    mesh
}

/// A man moving his arms in a skirt reaching 0.5 m below his hip joints, its front drawn in
/// 8 cm in every third frame: whether each of frames 50-59 shows the skirt found
/// ([`skirt_zone`] about the true hip joints), the tracker's zone in it and its hip centre's
/// error, metres.
fn worn_through_creases(settings: SkirtSettings, seed: u64) -> Vec<(bool, Option<SkirtZone>, f32)> {
    use KinectJoint::*;
    let person = body();
    let track = TrackBody::new(&person.model, &person.positions).expect("body");
    let mut tracker = Tracker::new(
        track,
        TrackerSettings {
            skirt: settings,
            ..TrackerSettings::default()
        },
    );
    let mut out = Vec::new();
    for k in 0..60u64 {
        let share = 0.3 + 0.3 * (k as f32 / 10.0).sin();
        let (skin, truth) = person.posed(
            &person.locals(common::ARMS_OUT, share),
            Vec3::new(0.0, -0.8, 2.7),
        );
        let (left, right) = (truth[HipLeft.index()], truth[HipRight.index()]);
        let mid = (left + right) * 0.5;
        let mut the_scene = scene(vec![(skin, Label::Body)], &person.model.triangles);
        let tube = skirt_mesh(mid, mid.y + 0.08, mid.y - 0.5, [0.2, 0.14], [0.3, 0.2]);
        let drawn_in = if k % 3 == 2 { 0.08 } else { 0.0 };
        the_scene.meshes.push(creased(tube, mid, drawn_in));
        let frame = render(&the_scene, seed + k, k as f64 / 30.0);
        let tracked = tracker.track(&frame).expect("tracked");
        if k >= 50 {
            let mask = &tracked.person.mask;
            let up = tracked.person.floor.normal;
            let seen = skirt_zone(&frame, mask, up, left, right, &settings).is_some();
            let hips = tracked.joints[HipCenter.index()]
                .position
                .distance(truth[HipCenter.index()]);
            out.push((seen, tracked.skirt.clone(), hips));
        }
    }
    out
}

/// Cloth drawn in between the legs makes a crease like the one between bare legs, and that
/// frame alone shows no skirt; one found in the frames before is still worn there, its
/// points weighed as a skirt's, not fitted as skin. Without the memory, those frames have
/// none. A rigid tube does not draw the legs as a dress's cloth does, so the hips are only
/// checked to be held no worse (the dresses' gain: docs/STATUS.md, session 55).
#[test]
fn a_skirt_is_worn_through_the_frames_a_crease_hides_it() {
    let off = SkirtSettings {
        memory_s: 0.0,
        ..SkirtSettings::default()
    };
    let seed = 71;
    let with = worn_through_creases(SkirtSettings::default(), seed);
    let without = worn_through_creases(off, seed);
    let creased_hips = |run: &[(bool, Option<SkirtZone>, f32)]| {
        let errors: Vec<f32> = run.iter().filter(|r| !r.0).map(|r| r.2).collect();
        errors.iter().sum::<f32>() / errors.len().max(1) as f32 * 1000.0
    };
    let (hips, hips_off) = (creased_hips(&with), creased_hips(&without));
    println!("hip centre in the creased frames: {hips:.1} mm worn, {hips_off:.1} mm without");
    assert!(
        hips <= hips_off + 5.0 && hips < 40.0,
        "hip centre {hips:.1} mm with the skirt worn, {hips_off:.1} without"
    );
    for (k, ((seen, zone, _), (_, zone_off, _))) in with.iter().zip(&without).enumerate() {
        let frame = 50 + k;
        let creased = frame % 3 == 2;
        assert_eq!(!seen, creased, "frame {frame}: the skirt seen {seen}");
        let zone = zone
            .as_ref()
            .unwrap_or_else(|| panic!("frame {frame}: no skirt"));
        assert_eq!(
            zone.seen, !creased,
            "frame {frame}: found in the frame or worn"
        );
        assert!(
            (zone.drop_m() - 0.5).abs() < 0.08,
            "frame {frame}: hem {:.2} m below the hips",
            zone.drop_m()
        );
        assert_eq!(
            zone_off.is_some(),
            !creased,
            "frame {frame}: without the memory"
        );
    }
}
