//! One 120 Hz step (10 substeps) of a skirt-like garment: a cylinder pinned at its waist ring
//! with stretch, shear, isometric bending and tethers, around a moving body of 28 colliders
//! (14 tapered capsules and 14 spheres) with continuous collision. Sizes 1k, 4k (the goal:
//! ≤ 0.6 ms per step on 2 cores), 16k and 64k particles.
//!
//! `rapier-cloth-core` 0.3 (crates.io) steps the identical mesh, pins, gravity and substeps
//! (10 × 1 iteration, edge-length + dihedral bending). It has no built-in sphere or capsule
//! collider (a caller implements its `ContactSource`), so the comparison is made without
//! colliders, for both solvers.
//!
//! Steps run back to back, except in `…_one_step_per_frame`, which idles 2 ms before each
//! step as the kiosk does between frames (the worker threads have gone to sleep and must be
//! woken). On a machine shared with other busy processes the 2-thread cases fall back to the
//! caller's thread for a while after a stalled step (see `fitroom_cloth::solver`), so they
//! then measure about the 1-thread time: note the load (`uptime`) with the results.
//!
//! Run: `cargo bench -p fitroom_cloth --bench step` (add `-- --quick` for a short run).

use std::hint::black_box;
use std::time::Duration;

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use fitroom_cloth::{ClothMesh, ClothSolver, Fabric, Plane, SolverSettings, Sphere};
use glam::{Quat, Vec3};

const DT: f32 = 1.0 / 120.0;
const SUBSTEPS: u32 = 10;

/// A skirt: `around` vertices per ring, `around` rings (so `around²` particles), radius 0.3 m,
/// from y = 0.4 to the waist at y = 1.0; returns the mesh and the waist ring.
fn skirt(around: u32) -> (ClothMesh, Vec<u32>) {
    let rows = around - 1;
    let mesh = ClothMesh::cylinder(Vec3::new(0.0, 0.4, 0.0), 0.3, 0.6, around, rows)
        .expect("a valid skirt");
    let waist = ClothMesh::cylinder_ring(around, rows).collect();
    (mesh, waist)
}

/// 31 spheres and 14 capsules; the 14 spheres no capsule uses collide on their own:
/// 28 colliders. The legs swing by `swing` radians.
fn body(swing: f32) -> (Vec<Sphere>, Vec<[u32; 2]>) {
    let mut spheres = Vec::new();
    let mut capsules = Vec::new();
    let mut chain = |points: &[(Vec3, f32)], spheres: &mut Vec<Sphere>| {
        let first = spheres.len() as u32;
        for &(c, r) in points {
            spheres.push(Sphere::new(c, r));
        }
        for k in 0..points.len() as u32 - 1 {
            capsules.push([first + k, first + k + 1]);
        }
    };
    // Torso: pelvis, waist, chest, neck, head (4 capsules).
    chain(
        &[
            (Vec3::new(0.0, 0.95, 0.0), 0.17),
            (Vec3::new(0.0, 1.1, 0.0), 0.14),
            (Vec3::new(0.0, 1.3, 0.0), 0.16),
            (Vec3::new(0.0, 1.5, 0.0), 0.06),
            (Vec3::new(0.0, 1.62, 0.0), 0.1),
        ],
        &mut spheres,
    );
    // Legs: hip, knee, ankle (2 capsules each), swinging in opposition.
    for (side, sign) in [(-0.1f32, 1.0f32), (0.1, -1.0)] {
        let hip = Vec3::new(side, 0.9, 0.0);
        let rot = Quat::from_rotation_x(sign * swing);
        chain(
            &[
                (hip, 0.1),
                (hip + rot * Vec3::new(0.0, -0.45, 0.0), 0.06),
                (hip + rot * Vec3::new(0.0, -0.85, 0.0), 0.045),
            ],
            &mut spheres,
        );
    }
    // Arms: shoulder, elbow, wrist (2 capsules each).
    for side in [-1.0f32, 1.0] {
        chain(
            &[
                (Vec3::new(0.2 * side, 1.42, 0.0), 0.06),
                (Vec3::new(0.25 * side, 1.15, 0.02), 0.045),
                (Vec3::new(0.27 * side, 0.9, 0.08), 0.035),
            ],
            &mut spheres,
        );
    }
    // Two more capsules: the buttocks.
    chain(
        &[
            (Vec3::new(-0.08, 0.92, -0.08), 0.1),
            (Vec3::new(0.08, 0.92, -0.08), 0.1),
        ],
        &mut spheres,
    );
    // The shoulder girdle joins the two shoulders (spheres 11 and 14): 14 capsules.
    capsules.push([11, 14]);
    // 14 lone spheres: hands, feet, belly, breasts, knees' caps, hips' sides, elbows.
    for (c, r) in [
        (Vec3::new(-0.27, 0.82, 0.1), 0.05),
        (Vec3::new(0.27, 0.82, 0.1), 0.05),
        (Vec3::new(-0.1, 0.05, 0.06), 0.05),
        (Vec3::new(0.1, 0.05, 0.06), 0.05),
        (Vec3::new(0.0, 1.02, 0.07), 0.1),
        (Vec3::new(-0.08, 1.3, 0.08), 0.08),
        (Vec3::new(0.08, 1.3, 0.08), 0.08),
        (Vec3::new(-0.1, 0.47, 0.04), 0.05),
        (Vec3::new(0.1, 0.47, 0.04), 0.05),
        (Vec3::new(-0.16, 0.9, 0.0), 0.08),
        (Vec3::new(0.16, 0.9, 0.0), 0.08),
        (Vec3::new(-0.26, 1.15, -0.02), 0.04),
        (Vec3::new(0.26, 1.15, -0.02), 0.04),
        (Vec3::new(0.0, 1.2, -0.1), 0.1),
    ] {
        spheres.push(Sphere::new(c, r));
    }
    let used: std::collections::BTreeSet<u32> = capsules.iter().flatten().copied().collect();
    assert_eq!(
        capsules.len() + spheres.len() - used.len(),
        28,
        "28 colliders"
    );
    (spheres, capsules)
}

fn garment_solver(around: u32, threads: usize, colliders: bool) -> ClothSolver {
    let (mesh, waist) = skirt(around);
    let settings = SolverSettings {
        substeps: SUBSTEPS,
        threads,
        ..SolverSettings::default()
    };
    let mut cloth =
        ClothSolver::new(&mesh, Fabric::cotton(), &waist, settings).expect("a valid garment");
    if colliders {
        let (spheres, capsules) = body(0.0);
        cloth
            .set_colliders(&spheres, &capsules)
            .expect("valid colliders");
        cloth
            .set_planes(&[Plane::floor(0.0)])
            .expect("a valid floor");
    }
    // Let it settle onto the body.
    for _ in 0..30 {
        cloth.step(DT).expect("a valid step");
    }
    cloth
}

fn bench_fitroom(c: &mut Criterion) {
    let mut group = c.benchmark_group("fitroom_cloth_step_120hz_10_substeps");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3));
    for (around, threads) in [(32u32, 2usize), (64, 1), (64, 2), (128, 2), (256, 2)] {
        let mut cloth = garment_solver(around, threads, true);
        let mut t = 0.0f32;
        let id = format!(
            "{}_particles_28_colliders_{threads}_threads",
            around * around
        );
        group.bench_function(BenchmarkId::from_parameter(id), |b| {
            b.iter(|| {
                t += DT;
                let (spheres, capsules) = body(0.5 * (6.0 * t).sin());
                cloth
                    .set_colliders(&spheres, &capsules)
                    .expect("valid colliders");
                black_box(cloth.step(DT).expect("a valid step"));
            })
        });
    }
    // As in the kiosk: one step per 120 Hz frame, the rest of the frame spent elsewhere (the
    // workers have gone to sleep by the next step, which pays for waking them). Only the
    // steps are timed.
    {
        let mut cloth = garment_solver(64, 2, true);
        let mut t = 0.0f32;
        group.bench_function(
            BenchmarkId::from_parameter("4096_particles_28_colliders_2_threads_one_step_per_frame"),
            |b| {
                b.iter_custom(|steps| {
                    let mut total = Duration::ZERO;
                    for _ in 0..steps {
                        std::thread::sleep(Duration::from_millis(2));
                        t += DT;
                        let (spheres, capsules) = body(0.5 * (6.0 * t).sin());
                        let start = std::time::Instant::now();
                        cloth
                            .set_colliders(&spheres, &capsules)
                            .expect("valid colliders");
                        black_box(cloth.step(DT).expect("a valid step"));
                        total += start.elapsed();
                    }
                    total
                })
            },
        );
    }
    for threads in [1usize, 2] {
        let mut cloth = garment_solver(64, threads, false);
        let id = format!("4096_particles_no_colliders_{threads}_threads");
        group.bench_function(BenchmarkId::from_parameter(id), |b| {
            b.iter(|| black_box(cloth.step(DT).expect("a valid step")))
        });
    }
    group.finish();
}

fn bench_rapier(c: &mut Criterion) {
    use rapier_cloth_core as rc;
    let mut group = c.benchmark_group("rapier_cloth_core_step_120hz_10_substeps");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3));
    let (mesh, waist) = skirt(64);
    let positions = mesh
        .positions()
        .iter()
        .map(|p| rc::Vec3::new(p.x, p.y, p.z))
        .collect();
    let rmesh = rc::ClothMesh::new(positions, mesh.triangles().to_vec()).expect("valid mesh");
    let fabric = Fabric::cotton();
    let material = rc::ClothMaterial {
        surface_density: fabric.areal_density_kg_m2,
        damping: fabric.damping_per_s,
        friction: fabric.friction,
        ..rc::ClothMaterial::default()
    };
    let mut cloth = rc::Cloth::new(rmesh, material).expect("valid cloth");
    for &v in &waist {
        let p = cloth.positions()[v as usize];
        cloth.pin(v, p).expect("valid pin");
    }
    let mut solver = rc::Solver::new();
    let settings = rc::SolverSettings {
        iterations: 1,
        ..rc::SolverSettings::default()
    };
    let h = DT / SUBSTEPS as f32;
    let gravity = rc::Vec3::new(0.0, -9.81, 0.0);
    let mut step = |cloth: &mut rc::Cloth| {
        for _ in 0..SUBSTEPS {
            solver
                .step(cloth, h, gravity, &settings)
                .expect("a valid substep");
        }
    };
    for _ in 0..30 {
        step(&mut cloth);
    }
    group.bench_function(
        BenchmarkId::from_parameter("4096_particles_no_colliders_1_thread"),
        |b| b.iter(|| step(black_box(&mut cloth))),
    );
    group.finish();
}

criterion_group!(benches, bench_fitroom, bench_rapier);
criterion_main!(benches);
