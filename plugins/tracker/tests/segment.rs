//! Person segmentation on synthetic Kinect frames (every part of the error model) of the
//! MakeHuman body in a room, against the camera's per-pixel ground truth: alone at several
//! distances, beside a box, with a second person behind, walking past, leaving and coming
//! back, the sensor tilted; and garbage frames.

use std::path::Path;

mod common;

use fitroom_body::BodyModel;
use fitroom_depth::synthetic::{
    Label, NoiseSettings, Scene, SceneMesh, SyntheticCamera, SyntheticFrame,
};
use fitroom_depth::{DepthCamera, DepthFrame, PIXELS, WIDTH};
use fitroom_tracker::{SegmentSettings, Segmenter};
use glam::{Quat, Vec3};

const SENSOR_HEIGHT: f32 = 0.8;

struct Body {
    /// Body vertices standing on the floor at the origin, facing the sensor (sensor axes).
    positions: Vec<Vec3>,
    triangles: Vec<[u32; 3]>,
}

fn body() -> Body {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/bodies/makehuman.fitbody");
    let model = BodyModel::read(&path).expect("the shipped body");
    let n = model.body_vertex_count as usize;
    let standing = model.standing_in_sensor_space(&model.positions);
    Body {
        positions: model.positions[..n]
            .iter()
            .map(|&p| standing.transform_point3(p))
            .collect(),
        triangles: model.triangles.clone(),
    }
}

/// The body standing at sensor-space `(x, z)` on the floor.
fn person(body: &Body, x: f32, z: f32, label: Label) -> SceneMesh {
    SceneMesh {
        positions: body
            .positions
            .iter()
            .map(|&p| p + Vec3::new(x, -SENSOR_HEIGHT, z))
            .collect(),
        triangles: body.triangles.clone(),
        label,
        closed: true,
    }
}

fn room() -> Scene {
    Scene::room(-SENSOR_HEIGHT, 3.9)
}

/// The room with a body of `skin` (sensor space) in it.
fn room_with(skin: Vec<Vec3>, triangles: &[[u32; 3]]) -> Scene {
    let mut scene = room();
    scene.meshes.push(SceneMesh {
        positions: skin,
        triangles: triangles.to_vec(),
        label: Label::Body,
        closed: true,
    });
    scene
}

/// Precision and recall of `mask` against the pixels that see the body and have a reading.
fn score(frame: &SyntheticFrame, mask: &[bool]) -> (f32, f32) {
    let truth: Vec<bool> = (0..PIXELS)
        .map(|k| frame.labels[k] == Label::Body as u8 && frame.frame.depth_mm[k] > 0)
        .collect();
    let both = (0..PIXELS).filter(|&k| mask[k] && truth[k]).count() as f32;
    let ours = mask.iter().filter(|&&m| m).count() as f32;
    let theirs = truth.iter().filter(|&&t| t).count() as f32;
    (both / ours.max(1.0), both / theirs.max(1.0))
}

fn camera(seed: u64) -> SyntheticCamera {
    SyntheticCamera::new(DepthCamera::default(), NoiseSettings::default(), seed)
}

#[test]
fn the_person_is_found_at_every_distance_of_the_range() {
    let body = body();
    for (seed, z) in [(1u64, 1.6f32), (2, 2.0), (3, 2.5), (4, 3.0), (5, 3.5)] {
        let mut scene = room();
        scene.meshes.push(person(&body, 0.1, z, Label::Body));
        let frame = camera(seed).render(&scene, 0.0);
        let mut segmenter = Segmenter::new(SegmentSettings::default());
        let found = segmenter.segment(&frame.frame).expect("a person");
        let (precision, recall) = score(&frame, &found.mask);
        println!(
            "| {z} m | precision {precision:.4} | recall {recall:.4} | top {:.2} m |",
            found.top_m
        );
        assert!(
            precision > 0.99 && recall > 0.95,
            "{z} m: {precision} {recall}"
        );
        assert!(
            (found.centroid.z - z).abs() < 0.3,
            "{z} m: {:?}",
            found.centroid
        );
        // The floor is where the scene put it.
        assert!(
            (found.floor.d - SENSOR_HEIGHT).abs() < 0.02,
            "{:?}",
            found.floor
        );
    }
}

#[test]
fn the_person_is_chosen_over_a_box_beside_and_a_person_behind() {
    let body = body();
    let mut scene = room();
    scene.meshes.push(person(&body, 0.0, 2.4, Label::Body));
    scene.meshes.push(person(&body, 1.0, 3.4, Label::Other));
    scene.add_box(
        Vec3::new(-0.9, -SENSOR_HEIGHT + 0.55, 2.3),
        Vec3::new(0.25, 0.55, 0.25),
        Label::Other,
    );
    let frame = camera(7).render(&scene, 0.0);
    let found = Segmenter::new(SegmentSettings::default())
        .segment(&frame.frame)
        .expect("a person");
    let (precision, recall) = score(&frame, &found.mask);
    assert!(precision > 0.99 && recall > 0.95, "{precision} {recall}");
    // By size alone a 1.1 m box could be a child: the choice, not the count, is what matters.
    assert!(found.people >= 2, "{} people", found.people);
}

#[test]
fn the_person_is_kept_while_another_walks_past_behind_and_found_again_after_leaving() {
    let body = body();
    let mut segmenter = Segmenter::new(SegmentSettings::default());
    let mut camera = camera(11);
    // Someone walks behind, across the whole view, nearer the interaction area's centre than
    // the person is at the start.
    for step in 0..12 {
        let mut scene = room();
        scene.meshes.push(person(&body, 0.6, 2.2, Label::Body));
        let x = -1.6 + 0.28 * step as f32;
        scene.meshes.push(person(&body, x, 2.9, Label::Other));
        let frame = camera.render(&scene, step as f64 / 30.0);
        let found = segmenter.segment(&frame.frame).expect("a person");
        let (precision, recall) = score(&frame, &found.mask);
        assert!(
            precision > 0.99 && recall > 0.9,
            "step {step} (walker at x = {x}): {precision} {recall}"
        );
    }
    // The room alone: nobody.
    let empty = camera.render(&room(), 0.5);
    assert!(segmenter.segment(&empty.frame).is_none());
    // Back, elsewhere: found again.
    let mut scene = room();
    scene.meshes.push(person(&body, -0.4, 2.7, Label::Body));
    let frame = camera.render(&scene, 0.6);
    let found = segmenter.segment(&frame.frame).expect("found again");
    let (precision, recall) = score(&frame, &found.mask);
    assert!(precision > 0.99 && recall > 0.95, "{precision} {recall}");
}

#[test]
fn a_tilted_sensor_still_finds_floor_and_person() {
    let body = body();
    // The sensor pitched 12° down: the scene turns 12° up about the sensor's x axis.
    let pitch = Quat::from_rotation_x(-12f32.to_radians());
    let mut scene = room();
    scene.meshes.push(person(&body, 0.0, 2.6, Label::Body));
    for mesh in &mut scene.meshes {
        for p in &mut mesh.positions {
            *p = pitch * *p;
        }
    }
    let frame = camera(13).render(&scene, 0.0);
    let found = Segmenter::new(SegmentSettings::default())
        .segment(&frame.frame)
        .expect("a person");
    let (precision, recall) = score(&frame, &found.mask);
    assert!(precision > 0.99 && recall > 0.95, "{precision} {recall}");
    let tilt = found
        .floor
        .normal
        .angle_between(pitch * Vec3::Y)
        .to_degrees();
    assert!(tilt < 1.0, "floor normal off by {tilt}°");
}

#[test]
fn garbage_frames_give_no_person_and_no_panic() {
    let camera = DepthCamera::default();
    let zeros = DepthFrame::from_raw(vec![0; PIXELS], 0.0, 0, camera);
    let none = DepthFrame::from_raw(vec![2047; PIXELS], 0.0, 0, camera);
    let mut state = 12345u32;
    let noise: Vec<u16> = (0..PIXELS)
        .map(|_| {
            state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (state >> 21) as u16
        })
        .collect();
    let garbage = DepthFrame::from_raw(noise, 0.0, 0, camera);
    let mut segmenter = Segmenter::new(SegmentSettings::default());
    for frame in [&zeros, &none, &garbage] {
        assert!(segmenter.segment(frame).is_none());
    }
}

#[test]
fn the_far_arm_seen_past_the_back_is_the_persons() {
    // Turned halfway to the side, the arms a little away from the body (the calibration's
    // second view): the far arm shows past the back, 20-30 cm deeper than the body beside
    // it, its shoulder hidden, so the labelling makes it a component of its own.
    let body = common::body();
    let arms: common::Turns = &[
        ("upperarm_l", Vec3::Z, -15.0),
        ("upperarm_r", Vec3::Z, 15.0),
    ];
    let spot = Vec3::new(0.0, -SENSOR_HEIGHT, 2.7);
    let mut worst = (f32::INFINITY, f32::INFINITY);
    for (seed, yaw) in [(11u64, 45f32), (12, -50.0), (13, 60.0)] {
        let (skin, _) = body.posed(&body.locals(arms, 1.0), spot);
        let turn = Quat::from_rotation_y(yaw.to_radians());
        let skin = skin.into_iter().map(|p| spot + turn * (p - spot)).collect();
        let scene = room_with(skin, &body.model.triangles);
        let frame = camera(seed).render(&scene, 0.0);
        let segment = |join_parts| {
            let settings = SegmentSettings {
                join_parts,
                ..SegmentSettings::default()
            };
            let found = Segmenter::new(settings)
                .segment(&frame.frame)
                .expect("a person");
            score_above_feet(&frame, &found.mask)
        };
        let ((precision, recall), (_, without)) = (segment(true), segment(false));
        println!(
            "turned {yaw}°: precision {precision:.4}, recall {recall:.4} ({without:.4} without the parts)"
        );
        assert!(precision > 0.99, "turned {yaw}°: precision {precision}");
        worst = (worst.0.min(recall), worst.1.min(without));
    }
    assert!(worst.0 > 0.98, "recall {}", worst.0);
    // The scenes do show the case: without the parts, an arm is missing.
    assert!(worst.1 < worst.0 - 0.03, "{worst:?}");
}

/// [`score`] over the pixels above the feet (the floor band takes the soles: not the case
/// tested).
fn score_above_feet(frame: &SyntheticFrame, mask: &[bool]) -> (f32, f32) {
    let camera = frame.frame.camera;
    let above: Vec<bool> = (0..PIXELS)
        .map(|k| {
            let z = f32::from(frame.frame.depth_mm[k]) * 0.001;
            let p = camera.unproject((k % WIDTH) as f32, (k / WIDTH) as f32, z);
            p.y > -SENSOR_HEIGHT + 0.15
        })
        .collect();
    let kept: Vec<bool> = (0..PIXELS).map(|k| mask[k] && above[k]).collect();
    let mut truth_above = frame.clone();
    truth_above.labels = (0..PIXELS)
        .map(|k| match above[k] {
            true => frame.labels[k],
            false => Label::Other as u8,
        })
        .collect();
    score(&truth_above, &kept)
}

#[test]
fn a_foot_stretched_back_to_the_wall_does_not_join_the_person_to_it() {
    // A leg lifted behind (a dancer's arabesque, as in CMU 05_06), the body turned 45° so
    // that the leg shows beside it, the foot 4 cm from the back wall: at 3.9 m the sensor's
    // steps are 4.5 cm and its noise 2.5 cm, so foot and wall read as one surface, and the
    // person joined to the wall is no longer a person.
    let body = common::body();
    let wall_z = 3.9;
    let turn = Quat::from_rotation_y(45f32.to_radians());
    let origin = Vec3::new(0.0, -SENSOR_HEIGHT, 0.0);
    let posed = |degrees: f32| -> Vec<Vec3> {
        let leg: common::Turns = &[("thigh_r", Vec3::X, degrees)];
        let (skin, _) = body.posed(&body.locals(leg, 1.0), origin);
        skin.into_iter()
            .map(|p| origin + turn * (p - origin))
            .collect()
    };
    let deepest = |skin: &[Vec3]| skin.iter().map(|p| p.z).fold(f32::MIN, f32::max);
    // The turn that lifts the leg behind the body reaches deepest.
    let skin = [posed(90.0), posed(-90.0)]
        .into_iter()
        .max_by(|a, b| deepest(a).total_cmp(&deepest(b)))
        .expect("two poses");
    let shift = Vec3::new(0.0, 0.0, wall_z - 0.04 - deepest(&skin));
    let scene = room_with(
        skin.iter().map(|&p| p + shift).collect(),
        &body.model.triangles,
    );
    let frame = camera(21).render(&scene, 0.0);
    let segment = |wall| {
        let settings = SegmentSettings {
            wall,
            ..SegmentSettings::default()
        };
        Segmenter::new(settings)
            .segment(&frame.frame)
            .map(|found| score_above_feet(&frame, &found.mask))
    };
    let (precision, recall) = segment(true).expect("the person, the wall taken out");
    println!(
        "pelvis at {:.2} m: precision {precision:.4}, recall {recall:.4}; without the wall: {:?}",
        shift.z,
        segment(false)
    );
    assert!(precision > 0.99 && recall > 0.95, "{precision} {recall}");
    // The scene does show the case: without the wall taken out, no person.
    assert!(segment(false).is_none());
}

/// A person is as deep as they are tall at most: leaning forward, arms reaching ahead and a
/// leg stretched back (an arabesque, a dancer's walkover), turned 30° from the sensor, spans
/// 1.5 m along the view. (The limit was 1.2 m: this scene had no person, and CMU 05_06's walkover was no
/// one in 8 of its 150 frames.)
#[test]
fn a_person_stretched_along_the_view_is_a_person() {
    let body = common::body();
    let pose: common::Turns = &[
        ("upperarm_l", Vec3::X, -90.0),
        ("upperarm_r", Vec3::X, -90.0),
        ("thigh_r", Vec3::X, 90.0),
        ("spine_01", Vec3::X, 40.0),
    ];
    let spot = Vec3::new(0.0, -SENSOR_HEIGHT, 2.6);
    // Turned a little from the sensor: the stretch lies near the view, the leg seen past the
    // body (facing the sensor, the body hides the leg, and the old limit kept them too).
    let (skin, _) = body.posed(&body.locals(pose, 1.0), spot);
    let turn = Quat::from_rotation_y(30f32.to_radians());
    let skin: Vec<Vec3> = skin.into_iter().map(|p| spot + turn * (p - spot)).collect();
    let (near, far) = skin
        .iter()
        .fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), p| {
            (a.min(p.z), b.max(p.z))
        });
    println!(
        "the body spans {:.2} m along the view ({near:.2}..{far:.2})",
        far - near
    );
    assert!(
        far - near > 1.3,
        "the scene shows the case: {:.2} m",
        far - near
    );
    let scene = room_with(skin, &body.model.triangles);
    let frame = camera(21).render(&scene, 0.0);
    let found = Segmenter::default()
        .segment(&frame.frame)
        .expect("a person");
    let (precision, recall) = score_above_feet(&frame, &found.mask);
    println!("precision {precision:.4}, recall {recall:.4}");
    assert!(precision > 0.99 && recall > 0.97, "{precision} {recall}");
}

/// Bowing deep towards the sensor, the trunk comes in front of the thighs and depth edges
/// part it from the legs, the head from the trunk, the legs from each other: no piece looks
/// like a person by itself (the legs reach up to the hips only, the trunk not down to the
/// floor; CMU 05_06's dancer at 0.9 s), and the piece that did (the legs) dropped the rest.
/// They were the person's a frame ago, so they still are. A small person bowed deeper is
/// lower than a person first seen may be (0.9 m): followed, they are still a person.
#[test]
fn the_upper_body_parted_from_the_legs_by_a_deep_bow_is_the_persons() {
    let spot = Vec3::new(0.0, -SENSOR_HEIGHT, 2.6);
    // The shipped body bowing to 79°, and one 0.88 its size to 89°.
    for (size, steps) in [(1.0, 24), (0.88, 27)] {
        let body = common::scaled_body(size);
        let frame_at = |bow: f32, seed: u64| {
            // The arms turned back as far as the trunk bows: they hang down.
            let pose: common::Turns = &[
                ("spine_01", Vec3::X, bow),
                ("spine_03", Vec3::X, 0.3 * bow),
                ("upperarm_l", Vec3::X, -1.3 * bow),
                ("upperarm_r", Vec3::X, -1.3 * bow),
            ];
            let (skin, _) = body.posed(&body.locals(pose, 1.0), spot);
            camera(seed).render(&room_with(skin, &body.model.triangles), 0.0)
        };
        // Followed at 30 frames a second through a bow of 100°/s.
        let mut segmenter = Segmenter::default();
        let mut worst = f32::INFINITY;
        let bows: Vec<f32> = (0..=steps).map(|k| k as f32 * 3.3).collect();
        for (k, &bow) in bows.iter().enumerate() {
            let frame = frame_at(bow, 40 + k as u64);
            let found = segmenter.segment(&frame.frame).expect("a person");
            let (precision, recall) = score_above_feet(&frame, &found.mask);
            assert!(precision > 0.99, "bowed {bow:.0}°: precision {precision}");
            worst = worst.min(recall);
        }
        // The deepest bow seen afresh: a piece of the person at most.
        let last = frame_at(bows[bows.len() - 1], 40 + bows.len() as u64);
        let afresh = Segmenter::default()
            .segment(&last.frame)
            .map_or(0.0, |found| score_above_feet(&last, &found.mask).1);
        println!(
            "size {size}: recall followed through the bow at least {worst:.4}; the deepest bow afresh {afresh:.4}"
        );
        assert!(worst > 0.97, "size {size}: recall {worst}");
        assert!(
            afresh < 0.8,
            "size {size}: the scene shows the case: {afresh}"
        );
    }
}
