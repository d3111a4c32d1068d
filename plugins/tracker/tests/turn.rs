//! A person turning round on the spot, as a dancer spins (the acceptance set's CMU 05_06 turns
//! a full circle a second), and one first seen with their back to the sensor. A trunk seen
//! from the front or the back differs in depth by little more than the sensor's steps, so a
//! start tries both ways (`tracker/start.rs`), and a followed fit carries on the body's last
//! turn (`TrackerSettings::carry_turn`; on these clean spins the fit follows without it as
//! well: both are printed). Rendered with the body crate's own skinning, in poses the tracker
//! was not tuned on.

mod common;

use common::{Body, Turns, body, render, scene};
use fitroom_depth::synthetic::Label;
use fitroom_tracker::kinect::facing_degrees as facing;
use fitroom_tracker::{TrackBody, Tracker, TrackerSettings};
use glam::Vec3;

const POSE: Turns = &[
    ("upperarm_l", Vec3::Z, 15.0),
    ("upperarm_r", Vec3::Z, -20.0),
    ("lowerarm_r", Vec3::X, -40.0),
    ("thigh_l", Vec3::X, -20.0),
    ("calf_l", Vec3::X, 30.0),
];

fn angle_between(a: f32, b: f32) -> f32 {
    let d = (a - b).rem_euclid(360.0);
    d.min(360.0 - d)
}

struct Run {
    /// Mean joint error over the turn and after it, metres.
    mean_m: f32,
    /// Frames of the turn whose facing is more than 45° off.
    lost: usize,
    /// The facing's error once the turn is done, degrees.
    end_off: f32,
}

/// Half a second standing, a full turn at `degrees_per_frame`, half a second standing.
fn spin(body: &Body, settings: TrackerSettings, degrees_per_frame: f32, seed: u64) -> Run {
    let track = TrackBody::new(&body.model, &body.model.positions).expect("a trackable body");
    let mut tracker = Tracker::new(track, settings);
    let turn_frames = (360.0 / degrees_per_frame).round() as usize;
    let (mut sum, mut n, mut lost, mut end_off) = (0.0, 0, 0, 0.0);
    for i in 0..turn_frames + 30 {
        let turned = (i.saturating_sub(15).min(turn_frames)) as f32 * degrees_per_frame;
        let mut turns = vec![("pelvis", Vec3::Y, turned)];
        turns.extend_from_slice(POSE);
        let (skin, truth) = body.posed(&body.locals(&turns, 1.0), Vec3::new(0.0, -0.8, 2.7));
        let frame = render(
            &scene(vec![(skin, Label::Body)], &body.model.triangles),
            seed + i as u64,
            i as f64 / 30.0,
        );
        let Some(tracked) = tracker.track(&frame) else {
            panic!("frame {i}: no one tracked")
        };
        let found: Vec<Vec3> = tracked.joints.iter().map(|j| j.position).collect();
        assert!(
            found.iter().all(|p| p.is_finite()),
            "frame {i}: a NaN joint"
        );
        if i >= 15 {
            sum += found
                .iter()
                .zip(&truth)
                .map(|(a, b)| a.distance(*b))
                .sum::<f32>()
                / 20.0;
            n += 1;
        }
        let off = angle_between(facing(&found), facing(&truth));
        if (15..15 + turn_frames).contains(&i) && off > 45.0 {
            lost += 1;
        }
        end_off = off;
    }
    Run {
        mean_m: sum / n as f32,
        lost,
        end_off,
    }
}

#[test]
fn a_person_spinning_round_is_followed_through_the_turn() {
    let body = body();
    for (degrees, seed) in [(15.0f32, 40u64), (10.0, 90), (6.0, 20)] {
        let carried = spin(&body, TrackerSettings::default(), degrees, seed);
        let without = spin(
            &body,
            TrackerSettings {
                carry_turn: 0.0,
                ..TrackerSettings::default()
            },
            degrees,
            seed,
        );
        println!(
            "{degrees} deg per frame: mean error {:.0} mm, {} frames more than 45 deg off, {:.0} deg off at the end \
             (without carrying the turn: {:.0} mm, {} frames, {:.0} deg)",
            carried.mean_m * 1000.0,
            carried.lost,
            carried.end_off,
            without.mean_m * 1000.0,
            without.lost,
            without.end_off
        );
        assert_eq!(carried.lost, 0, "{degrees} deg per frame: the turn lost");
        assert!(
            carried.end_off < 30.0,
            "{degrees} deg per frame: facing {:.0} deg off after the turn",
            carried.end_off
        );
        assert!(
            carried.mean_m < 0.08,
            "{degrees} deg per frame: mean error {:.3} m",
            carried.mean_m
        );
    }
}

/// Someone who walks into view with their back to the sensor (or turned it while no one was
/// tracked) is started facing away, not fitted as a person facing the sensor with left and
/// right swapped.
#[test]
fn a_person_first_seen_with_their_back_turned_is_found_so() {
    let body = body();
    for (name, turns, seed) in [
        ("arms bent, a knee bent", POSE, 5u64),
        ("reach and step", common::REACH_AND_STEP, 6),
        ("at rest", &[][..], 7),
    ] {
        let mut all = vec![("pelvis", Vec3::Y, 180.0f32)];
        all.extend_from_slice(turns);
        let (skin, truth) = body.posed(&body.locals(&all, 1.0), Vec3::new(0.1, -0.8, 2.7));
        let frame = render(
            &scene(vec![(skin, Label::Body)], &body.model.triangles),
            seed,
            0.0,
        );
        let first = |settings: TrackerSettings| {
            let track =
                TrackBody::new(&body.model, &body.model.positions).expect("a trackable body");
            let tracked = Tracker::new(track, settings)
                .track(&frame)
                .unwrap_or_else(|| panic!("{name}: no one found"));
            let found: Vec<Vec3> = tracked.joints.iter().map(|j| j.position).collect();
            let error = found
                .iter()
                .zip(&truth)
                .map(|(a, b)| a.distance(*b))
                .sum::<f32>()
                / 20.0;
            (error, angle_between(facing(&found), facing(&truth)))
        };
        let (error, off) = first(TrackerSettings::default());
        // Only ever started facing the sensor (the other way would have to be infinitely better).
        let (facing_only, facing_only_off) = first(TrackerSettings {
            turn_margin: f32::INFINITY,
            ..TrackerSettings::default()
        });
        println!(
            "{name}: mean error {:.0} mm, facing {off:.0} deg off (started facing the sensor only: {:.0} mm, {facing_only_off:.0} deg)",
            error * 1000.0,
            facing_only * 1000.0
        );
        assert!(off < 30.0, "{name}: facing {off:.0} deg off");
        assert!(error < 0.06, "{name}: mean error {error:.3} m");
        assert!(
            facing_only > 2.0 * error,
            "{name}: the test does not tell the two starts apart"
        );
    }
}

/// A body followed with its back to the sensor is checked every `turn_check_every` frames
/// against a start facing it (`tracker/start.rs`, `check_turn`): a fit that took a person
/// facing the sensor for one turned away (the acceptance set's CMU 02_01, the small woman in
/// the T-shirt, was followed so for all 150 frames) is turned back, and a person who really
/// stands with their back to the sensor stays so. The wrong start is forced here by a start
/// that always takes the other way round (`turn_margin` -inf).
#[test]
fn a_body_followed_the_wrong_way_round_is_turned_back() {
    let body = body();
    let track = || TrackBody::new(&body.model, &body.model.positions).expect("a trackable body");
    for (name, turned, seed) in [
        ("facing the sensor", 0.0f32, 11u64),
        ("back turned", 180.0, 12),
    ] {
        // One second of a person swaying a little on the spot.
        let frames: Vec<_> = (0..30)
            .map(|i| {
                let sway = 10.0 * (i as f32 / 30.0 * std::f32::consts::TAU).sin();
                let mut turns = vec![("pelvis", Vec3::Y, turned + sway)];
                turns.extend_from_slice(POSE);
                let (skin, truth) =
                    body.posed(&body.locals(&turns, 1.0), Vec3::new(0.0, -0.8, 2.7));
                let frame = render(
                    &scene(vec![(skin, Label::Body)], &body.model.triangles),
                    seed + i as u64,
                    i as f64 / 30.0,
                );
                (frame, truth)
            })
            .collect();
        let run = |settings: TrackerSettings| {
            let mut tracker = Tracker::new(track(), settings);
            let mut offs = Vec::new();
            for (i, (frame, truth)) in frames.iter().enumerate() {
                let tracked = tracker
                    .track(frame)
                    .unwrap_or_else(|| panic!("{name}, frame {i}: no one tracked"));
                let found: Vec<Vec3> = tracked.joints.iter().map(|j| j.position).collect();
                offs.push(angle_between(facing(&found), facing(truth)));
            }
            offs
        };
        let wrong_start = TrackerSettings {
            turn_margin: f32::NEG_INFINITY,
            ..TrackerSettings::default()
        };
        let checked = run(wrong_start);
        let unchecked = run(TrackerSettings {
            turn_check_every: 0,
            ..wrong_start
        });
        let right = run(TrackerSettings::default());
        let wrong_after = |offs: &[f32]| offs[15..].iter().filter(|&&o| o > 90.0).count();
        println!(
            "{name}: frames after the first half second the wrong way round: checked {}, unchecked {}, \
             started right {} (first frame {:.0} / {:.0} / {:.0} deg off)",
            wrong_after(&checked),
            wrong_after(&unchecked),
            wrong_after(&right),
            checked[0],
            unchecked[0],
            right[0]
        );
        if turned == 0.0 {
            assert!(checked[0] > 90.0, "{name}: the forced start was not wrong");
            assert!(
                wrong_after(&unchecked) > 10,
                "{name}: the test does not need the check"
            );
            assert_eq!(wrong_after(&checked), 0, "{name}: not turned back");
        } else {
            // Really turned away: a check must not turn the body round.
            assert_eq!(wrong_after(&right), 0, "{name}: turned round wrongly");
        }
    }
}
