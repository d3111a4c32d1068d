//! Collision: cloth dropped on a sphere and on a tapered capsule, and capsules swept fast
//! through a hanging cloth (a 720°/s swing and a 2 m teleport). After every step no particle
//! may be inside a collider by more than 5 mm (checked with an independent distance function),
//! nothing may be NaN and no tether may be stretched beyond 110 %.

mod common;

use common::*;
use fitroom_cloth::{ClothSolver, Fabric, Plane, SolverSettings, Sphere};
use glam::{Quat, Vec3};

const TOLERANCE: f32 = 0.005;

fn check_outside(cloth: &ClothSolver, step: usize, distance: impl Fn(Vec3) -> f32) -> f32 {
    assert!(all_finite(cloth.positions()), "step {step}: NaN");
    let mut deepest = f32::INFINITY;
    for (i, p) in cloth.positions().iter().enumerate() {
        let d = distance(Vec3::from(*p));
        deepest = deepest.min(d);
        assert!(d > -TOLERANCE, "step {step}: particle {i} is {d} m inside");
    }
    deepest
}

#[test]
fn a_cloth_dropped_on_a_sphere_stays_outside_it() {
    let mesh = horizontal_cloth(1.0, 40, 0.6);
    let mut cloth = solver(&mesh, Fabric::cotton(), &[], settings(2));
    let sphere = Sphere::new(Vec3::new(0.05, 0.3, 0.0), 0.2);
    cloth.set_colliders(&[sphere], &[]).unwrap();
    cloth.set_planes(&[Plane::floor(0.0)]).unwrap();
    let mut contact = false;
    for step in 0..240 {
        cloth.step(DT).unwrap();
        let deepest = check_outside(&cloth, step, |p| sphere.signed_distance(p));
        contact |= deepest < 0.01;
        let floor = cloth
            .positions()
            .iter()
            .map(|p| p.y)
            .fold(f32::INFINITY, f32::min);
        assert!(
            floor > -TOLERANCE,
            "step {step}: through the floor at {floor}"
        );
    }
    assert!(contact, "the cloth never reached the sphere");
    // It drapes: the centre rests on top of the sphere, the corners hang lower.
    let centre = cloth.positions()[20 * 41 + 20];
    assert!(centre.y > 0.49 && centre.y < 0.52, "centre at {centre}");
}

/// A sheet dropped off-centre on a sphere slides down its side: farther on a frictionless
/// sphere (a share of 0 of the fabric's friction) than on one with the fabric's friction,
/// and outside it either way.
#[test]
fn a_cloth_slides_farther_off_a_frictionless_sphere() {
    let slide = |share: f32| {
        let mesh = horizontal_cloth(0.5, 20, 0.56);
        let fabric = Fabric {
            friction: 0.8,
            ..Fabric::denim()
        };
        let mut cloth = solver(&mesh, fabric, &[], settings(2));
        // The sheet's centre 9 cm to the left of the sphere's top.
        let sphere = Sphere::new(Vec3::new(0.09, 0.3, 0.0), 0.25).with_friction(share);
        cloth.set_colliders(&[sphere], &[]).unwrap();
        for step in 0..90 {
            cloth.step(DT).unwrap();
            check_outside(&cloth, step, |p| sphere.signed_distance(p));
        }
        cloth.positions()[10 * 21 + 10].x
    };
    let (held, free) = (slide(1.0), slide(0.0));
    println!("the sheet's centre after 0.75 s: x = {held} with friction, {free} without");
    assert!(free < held - 0.01, "{free} against {held}");
}

#[test]
fn a_cloth_dropped_on_a_tapered_capsule_stays_outside_it() {
    let mesh = horizontal_cloth(1.0, 40, 0.7);
    let mut cloth = solver(&mesh, Fabric::silk(), &[], settings(2));
    let (a, ra) = (Vec3::new(-0.35, 0.35, 0.05), 0.14);
    let (b, rb) = (Vec3::new(0.4, 0.25, -0.05), 0.05);
    cloth
        .set_colliders(&[Sphere::new(a, ra), Sphere::new(b, rb)], &[[0, 1]])
        .unwrap();
    let mut contact = false;
    for step in 0..240 {
        cloth.step(DT).unwrap();
        let deepest = check_outside(&cloth, step, |p| round_cone_distance(a, ra, b, rb, p));
        contact |= deepest < 0.01;
    }
    assert!(contact, "the cloth never reached the capsule");
}

/// A hanging cloth and a settings with tethers at their rest length.
fn curtain(threads: usize) -> (fitroom_cloth::ClothMesh, ClothSolver) {
    let (mesh, pins) = hanging_cloth(1.0, 32, 1.5);
    let settings = SolverSettings {
        threads,
        ..SolverSettings::default()
    };
    let mut cloth = solver(&mesh, Fabric::cotton(), &pins, settings);
    // Let it settle first.
    for _ in 0..120 {
        cloth.step(DT).unwrap();
    }
    (mesh, cloth)
}

#[test]
fn an_arm_swinging_at_720_degrees_per_second_does_not_pass_through() {
    let (_, mut cloth) = curtain(2);
    // An "arm" (tapered capsule) hanging from a shoulder 25 cm behind the cloth swings about
    // the x axis, ±1 rad at 2 Hz: 720°/s through the bottom of the swing, where the hand
    // crosses the cloth's plane and goes 17 cm beyond it, pushing the cloth ahead of it.
    let shoulder = Vec3::new(0.1, 1.2, -0.25);
    let (r_shoulder, r_hand, length) = (0.06, 0.04, 0.5);
    let omega = 4.0 * std::f32::consts::PI;
    let amplitude = 1.0;
    assert!((amplitude * omega - 720f32.to_radians()).abs() < 1e-3);
    let arm = |t: f32| {
        let angle = -amplitude * (omega * t).sin();
        let dir = Quat::from_rotation_x(angle) * Vec3::NEG_Y;
        [
            Sphere::new(shoulder, r_shoulder),
            Sphere::new(shoulder + length * dir, r_hand),
        ]
    };
    cloth.set_colliders(&arm(0.0), &[[0, 1]]).unwrap();
    cloth.teleport_colliders();
    let mut pushed = false;
    for step in 1..=240 {
        let t = step as f32 * DT;
        let spheres = arm(t);
        cloth.set_colliders(&spheres, &[[0, 1]]).unwrap();
        let report = cloth.step(DT).unwrap();
        assert!(report.is_healthy(), "step {step}: {report:?}");
        let deepest = check_outside(&cloth, step, |p| {
            round_cone_distance(spheres[0].center, r_shoulder, spheres[1].center, r_hand, p)
        });
        pushed |= deepest < 0.01;
        let tether = cloth.max_tether_ratio();
        assert!(tether <= 1.1, "step {step}: tether at {tether}");
    }
    assert!(pushed, "the arm never touched the cloth");
}

#[test]
fn a_capsule_teleported_two_metres_through_the_cloth_does_not_leave_particles_inside() {
    let (_, mut cloth) = curtain(2);
    let (ra, rb) = (0.06, 0.05);
    let capsule_at = |z: f32| {
        [
            Sphere::new(Vec3::new(-0.3, 1.0, z), ra),
            Sphere::new(Vec3::new(0.3, 1.0, z), rb),
        ]
    };
    cloth.set_colliders(&capsule_at(-1.0), &[[0, 1]]).unwrap();
    cloth.teleport_colliders();
    cloth.step(DT).unwrap();
    let before: Vec<Vec3> = cloth.positions().iter().map(|&p| p.into()).collect();
    // Forward through the cloth, back again, forward again: 2 m per step.
    for (step, z) in [1.0f32, -1.0, 1.0, 1.0, 1.0, 1.0].into_iter().enumerate() {
        let spheres = capsule_at(z);
        cloth.set_colliders(&spheres, &[[0, 1]]).unwrap();
        cloth.step(DT).unwrap();
        check_outside(&cloth, step, |p| {
            round_cone_distance(spheres[0].center, ra, spheres[1].center, rb, p)
        });
        let tether = cloth.max_tether_ratio();
        assert!(tether <= 1.1, "step {step}: tether at {tether}");
    }
    // The capsule hit the cloth: something moved by more than a centimetre.
    let moved = cloth
        .positions()
        .iter()
        .zip(&before)
        .map(|(p, q)| (Vec3::from(*p) - *q).length())
        .fold(0.0, f32::max);
    assert!(moved > 0.01, "the capsule missed the cloth ({moved} m)");
}
