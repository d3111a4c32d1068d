//! The synthetic camera against its sources, measured on its own frames of a flat wall and of
//! a box in front of a wall: the axial spread against Nguyen et al. 2012, the depth steps
//! against the 11-bit raw scale, the projector's shadow against the geometry, the range, and
//! the seeding. The figures are printed for the docs' table (`-- --nocapture`).

use fitroom_depth::camera::raw_step_m;
use fitroom_depth::noise::axial_sigma_m;
use fitroom_depth::synthetic::{Label, NoiseSettings, Scene, SyntheticCamera};
use fitroom_depth::{DepthCamera, WIDTH};
use glam::Vec3;

fn wall(z: f32) -> Scene {
    let mut scene = Scene::default();
    scene.add_wall(z, 4.0, -3.0, 3.0);
    scene
}

/// Readings minus the exact depth, metres, over the central 200x200 pixels of `frames`
/// frames.
fn errors(camera: &mut SyntheticCamera, scene: &Scene, frames: usize) -> Vec<f64> {
    let mut out = Vec::new();
    for f in 0..frames {
        let frame = camera.render(scene, f as f64 / 30.0);
        for j in 140..340 {
            for i in 220..420 {
                let k = j * WIDTH + i;
                let mm = frame.frame.depth_mm[k];
                if mm > 0 {
                    out.push(f64::from(mm) / 1000.0 - f64::from(frame.true_depth_m[k]));
                }
            }
        }
    }
    out
}

fn std_dev(v: &[f64]) -> f64 {
    let mean = v.iter().sum::<f64>() / v.len() as f64;
    (v.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / v.len() as f64).sqrt()
}

#[test]
fn axial_spread_follows_nguyen_et_al() {
    // Everything but the quantisation, which would add its own step²/12 (a separate line).
    let noise = NoiseSettings {
        quantise: false,
        ..NoiseSettings::default()
    };
    for (seed, z) in [(11u64, 1.0f32), (12, 2.0), (13, 3.0), (14, 4.0)] {
        let mut camera = SyntheticCamera::new(DepthCamera::default(), noise, seed);
        let e = errors(&mut camera, &wall(z), 2);
        let measured = std_dev(&e) * 1000.0;
        let published = f64::from(axial_sigma_m(z, 0.0)) * 1000.0;
        println!(
            "| {z} m | {measured:.2} mm | {published:.2} mm | {} readings |",
            e.len()
        );
        assert!(
            (measured / published - 1.0).abs() < 0.2,
            "{z} m: {measured:.2} mm measured, {published:.2} mm published"
        );
    }
}

#[test]
fn depth_steps_follow_the_raw_scale() {
    // A wall seen through the whole pipeline: the distinct depths it reads near z are one
    // raw step apart (rounded to the millimetre of the depth image).
    for (seed, z) in [(21u64, 2.0f32), (22, 3.0), (23, 4.0)] {
        let mut camera =
            SyntheticCamera::new(DepthCamera::default(), NoiseSettings::default(), seed);
        let frame = camera.render(&wall(z), 0.0);
        let mut values: Vec<u16> = frame
            .frame
            .depth_mm
            .iter()
            .copied()
            .filter(|&d| d > 0)
            .collect();
        values.sort_unstable();
        values.dedup();
        let gaps: Vec<f64> = values
            .windows(2)
            .map(|w| f64::from(w[1] - w[0]))
            .filter(|g| *g > 0.0)
            .collect();
        // The gaps around the wall's depth (the middle of the values seen).
        let middle = &gaps[gaps.len() / 3..2 * gaps.len() / 3];
        let measured = middle.iter().sum::<f64>() / middle.len() as f64;
        let step = f64::from(raw_step_m(z)) * 1000.0;
        println!("| {z} m | step {measured:.2} mm | scale {step:.2} mm |");
        assert!(
            (measured / step - 1.0).abs() < 0.1,
            "{z} m: steps of {measured:.2} mm, the raw scale's {step:.2} mm"
        );
    }
}

#[test]
fn the_projector_shadow_lies_left_of_a_near_edge_with_the_predicted_width() {
    let (z1, z2) = (1.5f32, 3.0f32);
    let mut scene = wall(z2);
    // A box whose front face is at z1, centred on the optical axis.
    scene.add_box(
        Vec3::new(0.0, 0.0, z1 + 0.2),
        Vec3::new(0.3, 0.3, 0.2),
        Label::Other,
    );
    // Only the shadow: every other effect off, so the band is the projector's alone.
    let noise = NoiseSettings {
        shadow: true,
        ..NoiseSettings::exact()
    };
    let mut camera = SyntheticCamera::new(DepthCamera::default(), noise, 1);
    let frame = camera.render(&scene, 0.0);
    let cam = camera.camera;
    let row = cam.cy.round() as usize;
    let depth = |i: usize| frame.frame.depth_mm[row * WIDTH + i];
    // The box's edges in the image (+X is the image's left).
    let left_edge = cam.project(Vec3::new(0.3, 0.0, z1)).expect("in view").x;
    let right_edge = cam.project(Vec3::new(-0.3, 0.0, z1)).expect("in view").x;
    let box_left = (0..WIDTH)
        .find(|&i| (1400..1600).contains(&depth(i)))
        .expect("the box");
    assert!(
        (box_left as f32 - left_edge).abs() <= 1.0,
        "{box_left} vs {left_edge}"
    );
    let band = (0..box_left).rev().take_while(|&i| depth(i) == 0).count();
    let predicted = cam.fx * cam.baseline_m * (1.0 / z1 - 1.0 / z2);
    println!("| shadow band | {band} px | predicted {predicted:.2} px |");
    assert!(
        (band as f32 - predicted).abs() <= 1.0,
        "{band} px, predicted {predicted:.2}"
    );
    // The right side of the box: the wall reads right up to it.
    let box_right = (0..WIDTH)
        .rev()
        .find(|&i| (1400..1600).contains(&depth(i)))
        .expect("box");
    assert!((box_right as f32 - right_edge).abs() <= 1.0);
    assert!(depth(box_right + 1) > 2900, "no shadow on the right");
}

#[test]
fn nothing_is_read_outside_0_8_to_4_m() {
    for (z, expect) in [(0.7f32, false), (0.85, true), (3.9, true), (4.2, false)] {
        let mut camera = SyntheticCamera::new(DepthCamera::default(), NoiseSettings::default(), 5);
        let frame = camera.render(&wall(z), 0.0);
        let read = frame.frame.valid_share();
        assert_eq!(read > 0.5, expect, "{z} m: {read}");
        if !expect {
            assert_eq!(read, 0.0, "{z} m");
        }
        if let Some((lo, hi)) = frame.frame.depth_range_mm() {
            assert!(lo >= 700 && hi <= 4300, "{z} m: {lo}-{hi} mm");
        }
    }
}

#[test]
fn the_same_seed_gives_the_same_frames() {
    let mut scene = Scene::room(-0.8, 3.5);
    scene.add_box(Vec3::new(0.2, -0.3, 2.0), Vec3::splat(0.25), Label::Other);
    let render = |seed| {
        let mut camera =
            SyntheticCamera::new(DepthCamera::default(), NoiseSettings::default(), seed);
        (0..3)
            .map(|f| camera.render(&scene, f as f64).frame.depth_mm.to_vec())
            .collect::<Vec<_>>()
    };
    let (a, b, c) = (render(7), render(7), render(8));
    assert_eq!(a, b);
    assert_ne!(a, c);
    assert_ne!(a[0], a[1], "frames differ from each other");
}
