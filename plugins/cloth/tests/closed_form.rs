//! Checks against closed-form mechanics: a compliant spring's static stretch, a pendulum's
//! period, a compliant chain's sag, and the tilt of a pendulum in an accelerating frame.

mod common;

use common::*;
use fitroom_cloth::fabric::distance_compliance;
use fitroom_cloth::{ClothMesh, ClothSolver, Fabric, FrameInertia, RigidTransform, SolverSettings};
use glam::{Quat, Vec3};

/// A "swing": one free particle hanging from two pinned points on the x axis by two rods;
/// it can only swing about the x axis.
fn swing(half_width: f32, radius: f32, angle: f32) -> ClothMesh {
    ClothMesh::new(
        vec![
            Vec3::new(-half_width, 0.0, 0.0),
            Vec3::new(half_width, 0.0, 0.0),
            Vec3::new(0.0, -radius * angle.cos(), radius * angle.sin()),
        ],
        vec![[0, 1, 2]],
    )
    .unwrap()
}

fn bare_settings() -> SolverSettings {
    SolverSettings {
        threads: 1,
        air_density_kg_m3: 0.0,
        tethers_per_particle: 0,
        ..SolverSettings::default()
    }
}

fn fabric(stretch: f32, damping: f32) -> Fabric {
    Fabric {
        stretch_stiffness_n_m: stretch,
        shear_stiffness_n_m: 0.0,
        bend_stiffness_n_m: 0.0,
        damping_per_s: damping,
        ..Fabric::cotton()
    }
}

#[test]
fn a_pendulum_swings_with_the_analytic_period() {
    let (radius, angle) = (0.8f32, 5f32.to_radians());
    let mesh = swing(0.3, radius, angle);
    let mut cloth =
        ClothSolver::new(&mesh, fabric(f32::INFINITY, 0.0), &[0, 1], bare_settings()).unwrap();
    let g = 9.81f32;
    // Large-amplitude correction to second order.
    let expected = std::f32::consts::TAU * (radius / g).sqrt() * (1.0 + angle * angle / 16.0);
    let mut crossings = Vec::new();
    let mut last_z = cloth.positions()[2].z;
    let mut t = 0.0f64;
    while crossings.len() < 7 {
        cloth.step(DT).unwrap();
        t += DT as f64;
        let z = cloth.positions()[2].z;
        if last_z > 0.0 && z <= 0.0 || last_z < 0.0 && z >= 0.0 {
            // Linear interpolation of the crossing time.
            crossings.push(t - DT as f64 * (z as f64 / (z - last_z) as f64));
        }
        last_z = z;
        assert!(t < 20.0, "the pendulum stopped swinging");
    }
    // Three full periods between the first and seventh zero crossings.
    let period = (crossings[6] - crossings[0]) / 3.0;
    let error = (period as f32 - expected).abs() / expected;
    assert!(error < 0.005, "period {period} s vs {expected} s");
    // The rods stay rigid.
    let rod = (cloth.positions()[2] - cloth.positions()[0]).length();
    assert!((rod - (0.3f32 * 0.3 + radius * radius).sqrt()).abs() < 1e-4);
}

#[test]
fn a_compliant_spring_stretches_by_weight_times_compliance() {
    // Two springs from pins at x = ±d to one particle below; stiffness Y gives each spring the
    // compliance α = L²/(Y·A) (a lone triangle's edge stands for the whole triangle's area).
    let (d, length) = (0.05f32, 0.5f32);
    let mesh = swing(d, (length * length - d * d).sqrt(), 0.0);
    let stiffness = 4.0;
    let mut settings = bare_settings();
    settings.iterations = 4;
    let mut cloth = ClothSolver::new(&mesh, fabric(stiffness, 3.0), &[0, 1], settings).unwrap();
    for _ in 0..1200 {
        cloth.step(DT).unwrap();
    }
    let area = mesh.triangle_areas()[0];
    let alpha = distance_compliance(stiffness, length, area).unwrap();
    let weight = cloth.masses()[2] * 9.81;
    // Equilibrium depth y: 2·T·y/l = m·g with T = (l − L)/α and l = √(d² + y²) (Newton).
    let mut y = (length * length - d * d).sqrt();
    for _ in 0..50 {
        let l = (d * d + y * y).sqrt();
        let f = 2.0 * (l - length) / alpha * y / l - weight;
        let h = 1e-6;
        let l2 = (d * d + (y + h) * (y + h)).sqrt();
        let f2 = 2.0 * (l2 - length) / alpha * (y + h) / l2 - weight;
        y -= f * h / (f2 - f);
    }
    let stretch_expected = (d * d + y * y).sqrt() - length;
    let p = cloth.positions()[2];
    let stretch = (p - cloth.positions()[0]).length() - length;
    assert!(stretch_expected > 0.01, "the test wants a visible stretch");
    assert!(
        (stretch - stretch_expected).abs() < 0.01 * stretch_expected,
        "stretch {stretch} m vs {stretch_expected} m"
    );
    // Near the limit of small d, the closed form is m·g·α/2 per spring.
    assert!((stretch_expected - weight * alpha / 2.0).abs() < 0.02 * stretch_expected);
}

#[test]
fn a_compliant_chain_sags_by_the_sum_of_its_link_extensions() {
    // A ladder two vertices wide, pinned at its top two vertices, with no shear and no
    // bending: each side is a vertical chain whose link k carries the weight below it.
    let (width, rows, link) = (0.02f32, 10u32, 0.05f32);
    let mesh = ClothMesh::grid(
        Vec3::ZERO,
        Vec3::X * width,
        -Vec3::Y * (link * rows as f32),
        1,
        rows,
    )
    .unwrap();
    let stiffness = 5.0;
    let mut settings = bare_settings();
    settings.iterations = 8;
    let mut cloth = ClothSolver::new(&mesh, fabric(stiffness, 4.0), &[0, 1], settings).unwrap();
    for _ in 0..1800 {
        cloth.step(DT).unwrap();
    }
    // A vertical boundary edge belongs to one quad: it stands for half the quad's area.
    let alpha = distance_compliance(stiffness, link, 0.5 * width * link).unwrap();
    for side in 0..2u32 {
        let column: Vec<usize> = (0..=rows).map(|j| (j * 2 + side) as usize).collect();
        let mut sag = 0.0f32;
        for k in 1..=rows as usize {
            let below: f32 = column[k..].iter().map(|&v| cloth.masses()[v]).sum();
            sag += alpha * below * 9.81;
        }
        let bottom = cloth.positions()[column[rows as usize]];
        let expected_y = -(link * rows as f32) - sag;
        assert!(sag > 0.02, "the test wants a visible sag, got {sag}");
        assert!(
            (bottom.y - expected_y).abs() < 0.02 * sag,
            "side {side}: bottom at {} vs {expected_y} (sag {sag})",
            bottom.y
        );
    }
}

#[test]
fn a_pendulum_in_an_accelerating_frame_tilts_by_the_felt_acceleration() {
    let mesh = swing(0.2, 0.5, 0.0);
    let acceleration = 3.0f32;
    for scale in [1.0f32, 0.5] {
        let settings = SolverSettings {
            frame_inertia: FrameInertia {
                linear: scale,
                ..FrameInertia::FULL
            },
            ..bare_settings()
        };
        let mut cloth =
            ClothSolver::new(&mesh, fabric(f32::INFINITY, 3.0), &[0, 1], settings).unwrap();
        cloth.reset_body_frame(RigidTransform::IDENTITY).unwrap();
        let mut t = 0.0f32;
        for _ in 0..600 {
            t += DT;
            // The body accelerates along +z; the pins are fixed in its frame.
            let pose = RigidTransform::new(Quat::IDENTITY, Vec3::Z * (0.5 * acceleration * t * t));
            cloth.set_body_frame(pose).unwrap();
            cloth.step(DT).unwrap();
        }
        let p = cloth.positions()[2];
        // It trails behind (−z) at tan θ = s·a/g.
        let tilt = (-p.z).atan2(-p.y);
        let expected = (scale * acceleration / 9.81).atan();
        assert!(
            (tilt - expected).abs() < 0.01,
            "scale {scale}: tilt {tilt} rad vs {expected} rad"
        );
    }
}
