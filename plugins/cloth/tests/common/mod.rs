//! Helpers shared by the cloth integration tests.
#![allow(dead_code)]

use fitroom_cloth::{ClothMesh, ClothSolver, Fabric, SolverSettings};
use glam::{Vec3, Vec3A};

pub const DT: f32 = 1.0 / 120.0;

/// A square cloth of side `size` metres in the x-y plane, top edge at `top_y`, hanging from its
/// two top corners; returns the mesh and the indices of the two pinned corners.
pub fn hanging_cloth(size: f32, cells: u32, top_y: f32) -> (ClothMesh, [u32; 2]) {
    let mesh = ClothMesh::grid(
        Vec3::new(-size / 2.0, top_y, 0.0),
        Vec3::X * size,
        -Vec3::Y * size,
        cells,
        cells,
    )
    .expect("a valid grid");
    (mesh, [0, cells])
}

/// A horizontal square cloth of side `size` centred above the origin at height `y`.
pub fn horizontal_cloth(size: f32, cells: u32, y: f32) -> ClothMesh {
    ClothMesh::grid(
        Vec3::new(-size / 2.0, y, -size / 2.0),
        Vec3::X * size,
        Vec3::Z * size,
        cells,
        cells,
    )
    .expect("a valid grid")
}

pub fn settings(threads: usize) -> SolverSettings {
    SolverSettings {
        threads,
        ..SolverSettings::default()
    }
}

pub fn solver(
    mesh: &ClothMesh,
    fabric: Fabric,
    pins: &[u32],
    settings: SolverSettings,
) -> ClothSolver {
    ClothSolver::new(mesh, fabric, pins, settings).expect("a valid cloth")
}

pub fn all_finite(points: &[Vec3A]) -> bool {
    points.iter().all(|p| p.is_finite())
}

/// Signed distance to the convex hull of two spheres, computed independently of the crate by
/// sampling the union of the linearly interpolated spheres along the axis.
pub fn round_cone_distance(a: Vec3, ra: f32, b: Vec3, rb: f32, p: Vec3) -> f32 {
    let samples = 2000;
    (0..=samples)
        .map(|k| {
            let t = k as f32 / samples as f32;
            (p - a.lerp(b, t)).length() - (ra + (rb - ra) * t)
        })
        .fold(f32::INFINITY, f32::min)
}

/// Total mechanical energy (kinetic + gravitational potential, g along −Y) of the free
/// particles, J.
pub fn mechanical_energy(cloth: &ClothSolver, g: f32) -> f64 {
    let potential: f64 = cloth
        .positions()
        .iter()
        .zip(cloth.masses())
        .zip(cloth.inverse_masses())
        .filter(|(_, w)| **w > 0.0)
        .map(|((p, m), _)| *m as f64 * g as f64 * p.y as f64)
        .sum();
    potential + cloth.kinetic_energy()
}
