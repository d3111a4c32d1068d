//! A reading's noise averaged out over its surface ([`fitroom_tracker::denoise`]), against the
//! depth the renderer knows each pixel sees: nearer the truth than the readings, as near on
//! average (no pull forward or back), and a forearm held before the chest not blended into it.

mod common;

use common::{body, scene};
use fitroom_depth::synthetic::{Label, NoiseSettings, SyntheticCamera};
use fitroom_depth::{DepthCamera, HEIGHT, WIDTH};
use fitroom_tracker::denoise::{denoised, surface_depth_m};
use glam::Vec3;

/// Per pixel of the body read on its own surface, (reading's error, denoised error, whether
/// the body is seen 10 cm or more behind it within the window: the rim of the arm held before
/// the chest), mm; the body standing `z` metres away, a forearm held across the chest.
fn errors(z: f32, seed: u64) -> Vec<(f32, f32, bool)> {
    let body = body();
    let (skin, _) = body.posed(&body.locals(&[], 0.0), Vec3::new(0.0, 0.0, z));
    let mut scene = scene(vec![(skin, Label::Body)], &body.model.triangles);
    // A forearm held across the chest, a hand's breadth before it.
    scene.add_box(
        Vec3::new(0.0, 0.35, z - 0.35),
        Vec3::new(0.2, 0.04, 0.04),
        Label::Body,
    );
    let shot = SyntheticCamera::new(DepthCamera::default(), NoiseSettings::default(), seed)
        .render(&scene, 0.0);
    let mask: Vec<bool> = shot
        .labels
        .iter()
        .map(|&l| l == Label::Body as u8)
        .collect();
    let clean = denoised(&shot.frame, &mask, 2);
    let truth_mm = |x: usize, y: usize| shot.true_depth_m[y * WIDTH + x] * 1000.0;
    let mut out = Vec::new();
    for (k, &mm) in shot.frame.depth_mm.iter().enumerate() {
        let (x, y) = (k % WIDTH, k / WIDTH);
        let truth = truth_mm(x, y);
        // Pixels read on their own surface: the sensor's lateral error makes a pixel at an
        // edge read the surface beside it (the wall, the chest past the arm) now and then.
        if !mask[k] || mm == 0 || !truth.is_finite() || (f32::from(mm) - truth).abs() > 50.0 {
            continue;
        }
        let one = surface_depth_m(&shot.frame.depth_mm, &mask, x, y, 2)
            .expect("a pixel with a reading has a depth");
        assert_eq!(
            (one * 1000.0).round() as u16,
            clean.depth_mm[k],
            "the frame's pixel {k} and the pixel's own"
        );
        let rim = (y.saturating_sub(2)..=(y + 2).min(HEIGHT - 1)).any(|yy| {
            (x.saturating_sub(2)..=(x + 2).min(WIDTH - 1))
                .any(|xx| mask[yy * WIDTH + xx] && truth_mm(xx, yy) > truth + 100.0)
        });
        out.push((f32::from(mm) - truth, one * 1000.0 - truth, rim));
    }
    out
}

fn rms(v: impl Iterator<Item = f32>) -> f32 {
    let (s, n) = v.fold((0.0, 0), |(s, n), e| (s + e * e, n + 1));
    (s / n.max(1) as f32).sqrt()
}

#[test]
fn readings_averaged_on_their_surface_are_nearer_the_truth_and_not_moved() {
    for (z, seed) in [(2.0f32, 3u64), (3.0, 4)] {
        let e = errors(z, seed);
        assert!(e.len() > 5_000, "{} body pixels at {z} m", e.len());
        let raw = rms(e.iter().map(|x| x.0));
        let smooth = rms(e.iter().map(|x| x.1));
        let bias = e.iter().map(|x| x.1).sum::<f32>() / e.len() as f32;
        let raw_bias = e.iter().map(|x| x.0).sum::<f32>() / e.len() as f32;
        println!(
            "{z} m: {} pixels, RMS error {raw:.1} mm as read, {smooth:.1} averaged; mean {raw_bias:+.2} / {bias:+.2} mm",
            e.len()
        );
        // At 3 m the readings are 14 mm off (the sensor's published error, with its
        // quantisation); 25 of them averaged would be 3 mm, the edges and the window's
        // curvature add to it.
        assert!(
            smooth < 0.5 * raw,
            "{z} m: RMS {smooth:.1} against {raw:.1} mm"
        );
        assert!(bias.abs() < 2.0, "{z} m: the surface moved {bias:+.2} mm");
    }
}

#[test]
fn a_forearm_before_the_chest_is_not_blended_into_it() {
    let e = errors(2.5, 7);
    let rim: Vec<_> = e.iter().filter(|x| x.2).collect();
    let raw = rms(rim.iter().map(|x| x.0));
    let smooth = rms(rim.iter().map(|x| x.1));
    let bias = rim.iter().map(|x| x.1).sum::<f32>() / rim.len().max(1) as f32;
    println!(
        "{} pixels with the body 10 cm or more behind them nearby: RMS {raw:.1} mm as read, {smooth:.1} averaged, mean {bias:+.2}",
        rim.len()
    );
    assert!(rim.len() > 50, "{} rim pixels", rim.len());
    // Blended with the surface behind, their readings would move back by centimetres.
    assert!(
        smooth < raw && bias.abs() < 3.0,
        "RMS {smooth:.1} against {raw:.1} mm, moved {bias:+.2} mm"
    );
}
