//! The speed goal's case as a criterion bench: the sun dress meshed to about 4,000 particles
//! (as `fitroom cloth bench` meshes it), on the default body walking the embedded clip, one
//! 120 Hz step (10 substeps; stretch, shear, isometric bending, tethers; the body's colliders
//! with continuous collision; the attached particles skinned and the colliders posed and
//! fitted every step; the skinned bodice's inside, which shares no constraint with the free
//! cloth, is skinned where the dress is drawn, as in seed 000 §3.2.1), 2 threads and 1. The walk's 120 Hz poses are made beforehand and played
//! forwards and backwards (no jump at the clip's end), so only the garment's step is timed.
//!
//! `rapier-cloth-core` 0.3 (crates.io) steps the identical mesh with the identical pins,
//! gravity and substeps (10 × 1 iteration). It has no built-in sphere or capsule collider (a
//! caller implements its `ContactSource`), so the peer comparison is made without colliders
//! and without motion, for both solvers, on one thread.
//!
//! Run: `cargo bench --bench dress` (add `-- --quick` for a short run).

use std::hint::black_box;
use std::path::Path;
use std::time::Duration;

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use fitroom::cli::cloth::{dress_4k, garment_on_walk};
use fitroom_body::BodyModel;
use fitroom_cloth::{ClothSolver, Fabric, SolverSettings};
use fitroom_garment::GarmentMesh;
use fitroom_motion::walk::{STEP_HZ, Walk};
use glam::Affine3A;

const DT: f32 = 1.0 / STEP_HZ;
/// Frames of the walk played (30 Hz; 4 steps each).
const FRAMES: usize = 120;

fn assets() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("assets")
}

fn settings(threads: usize) -> SolverSettings {
    SolverSettings {
        threads,
        ..SolverSettings::default()
    }
}

fn bench_dress(c: &mut Criterion) {
    let assets = assets();
    let model = BodyModel::read(&assets.join(fitroom::assets::DEFAULT_BODY)).expect("the body");
    let (shaped, mesh) =
        dress_4k(&model, &assets.join("garments/sundress.ron")).expect("the 4,000-particle dress");
    let motion = assets.join(fitroom::assets::DEFAULT_MOTION);
    let mut walk = Walk::new(&model, &shaped, &motion).expect("the walk");
    // Up to the clip's last frame (the next would wrap to its first, a jump).
    let frames = FRAMES.min(walk.frames());
    let poses: Vec<Vec<Affine3A>> = (1..frames).flat_map(|_| walk.next_frame()).collect();
    // Forwards, then backwards: the body never jumps.
    let order: Vec<usize> = (0..poses.len()).chain((0..poses.len()).rev()).collect();

    let mut group = c.benchmark_group("sundress_4k_step_120hz_10_substeps");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3));
    for threads in [2usize, 1] {
        let mut sim = garment_on_walk(&model, &shaped, &mesh, &walk, settings(threads))
            .expect("the dress on the walk");
        // As the app runs it: no penetration and strain measurement after each step.
        sim.set_measuring(false);
        let mut at = 0usize;
        let id = format!(
            "{}_vertices_{}_simulated_{}_colliders_walking_{threads}_threads",
            mesh.positions.len(),
            sim.simulated_particles(),
            sim.collider_count()
        );
        group.bench_function(BenchmarkId::from_parameter(id), |b| {
            b.iter(|| {
                let pose = &poses[order[at % order.len()]];
                at += 1;
                black_box(sim.step(pose, DT).expect("a valid step"));
            })
        });
        assert_eq!(sim.resets(), 0, "the dress blew up in the bench");
        assert_eq!(sim.teleports(), 0, "the body jumped in the bench");
    }
    group.finish();

    peers(c, &mesh);
}

/// Both solvers on the dress's mesh without colliders or motion, one thread.
fn peers(c: &mut Criterion, mesh: &GarmentMesh) {
    use rapier_cloth_core as rc;
    let mut group = c.benchmark_group("sundress_4k_no_colliders_1_thread");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3));
    let cloth_mesh = fitroom_cloth::ClothMesh::new(mesh.positions.clone(), mesh.triangles.clone())
        .expect("a valid mesh");
    let mut ours = ClothSolver::new(&cloth_mesh, mesh.fabric, &mesh.attached, settings(1))
        .expect("a valid garment");
    for _ in 0..30 {
        ours.step(DT).expect("a valid step");
    }
    let id = format!("fitroom_cloth_{}_particles", mesh.positions.len());
    group.bench_function(BenchmarkId::from_parameter(id), |b| {
        b.iter(|| black_box(ours.step(DT).expect("a valid step")))
    });

    let positions = mesh
        .positions
        .iter()
        .map(|p| rc::Vec3::new(p.x, p.y, p.z))
        .collect();
    let rmesh = rc::ClothMesh::new(positions, mesh.triangles.clone()).expect("a valid mesh");
    let fabric: Fabric = mesh.fabric;
    let material = rc::ClothMaterial {
        surface_density: fabric.areal_density_kg_m2,
        damping: fabric.damping_per_s,
        friction: fabric.friction,
        ..rc::ClothMaterial::default()
    };
    let mut cloth = rc::Cloth::new(rmesh, material).expect("a valid cloth");
    for &v in &mesh.attached {
        let p = cloth.positions()[v as usize];
        cloth.pin(v, p).expect("a valid pin");
    }
    let mut solver = rc::Solver::new();
    let rc_settings = rc::SolverSettings {
        iterations: 1,
        ..rc::SolverSettings::default()
    };
    let substeps = SolverSettings::default().substeps;
    let h = DT / substeps as f32;
    let gravity = rc::Vec3::new(0.0, -9.81, 0.0);
    let mut step = |cloth: &mut rc::Cloth| {
        for _ in 0..substeps {
            solver
                .step(cloth, h, gravity, &rc_settings)
                .expect("a valid substep");
        }
    };
    for _ in 0..30 {
        step(&mut cloth);
    }
    let id = format!("rapier_cloth_core_{}_particles", mesh.positions.len());
    group.bench_function(BenchmarkId::from_parameter(id), |b| {
        b.iter(|| step(black_box(&mut cloth)))
    });
    group.finish();
}

criterion_group!(benches, bench_dress);
criterion_main!(benches);
