//! `fitroom cloth bench`: the cloth step's cost on the walking avatar and its growth with the
//! particle count.

use std::path::Path;

use anyhow::{Context, Result};
use fitroom_body::{BodyModel, Shape, ShapedBody};
use fitroom_cloth::SolverSettings;
use fitroom_garment::sim::{GarmentSim, SimGarment};
use fitroom_garment::{BodySurface, GarmentMesh, Pattern};
use glam::{Affine3A, Vec3};
use serde::Serialize;

use super::{STEP_HZ, SimReport, Stats, mesh_garment, sim_mesh};

/// The JSON of `fitroom cloth bench`.
#[derive(Debug, Serialize)]
pub struct BenchReport {
    /// The dress on the walking avatar.
    pub dress: SimReport,
    /// The same dress meshed again, to about [`DRESS_PARTICLES`] particles (the size of the
    /// goal's dress, seed 000's 4,088-vertex dress), on the same walk; `None` for a mesh
    /// garment (it cannot be meshed again).
    pub dress_4k: Option<SimReport>,
    /// The edge length `dress_4k` was meshed at, cm.
    pub dress_4k_edge_cm: Option<f32>,
    /// Per particle count (cylinders around the body's colliders, 10 substeps, 120 Hz): one
    /// step's cost, ms.
    pub scaling: Vec<(usize, Stats)>,
    pub threads: usize,
    pub goal_ms: f64,
}

/// The particle count of the speed goal's dress.
pub const DRESS_PARTICLES: usize = 4_000;

/// The pattern garment `dress` (in its middle size), meshed as its file says to `meshed`
/// particles, meshed again to about `particles`: the mesh and its edge length, cm.
fn remesh(
    body: &BodySurface,
    dress: &Path,
    meshed: usize,
    particles: usize,
) -> Result<(GarmentMesh, f32)> {
    // The particle count grows as the inverse square of the edge length (kept within what a
    // pattern file may ask for).
    let edge_cm = (Pattern::load(dress)?.target_edge_cm
        * (meshed as f32 / particles as f32).sqrt())
    .clamp(0.5, 20.0);
    let mesh = mesh_garment(body, dress, None, Some(edge_cm)).with_context(|| {
        format!(
            "cannot mesh '{}' again at {edge_cm:.2} cm edges for the {particles}-particle bench",
            dress.display()
        )
    })?;
    Ok((mesh, edge_cm))
}

/// The goal's dress: the pattern garment `dress` meshed to about [`DRESS_PARTICLES`]
/// particles (as `fitroom cloth bench` does) on the default body, which it returns too.
pub fn dress_4k(model: &BodyModel, dress: &Path) -> Result<(ShapedBody, GarmentMesh)> {
    let (shaped, body, base) = dress_on_default_body(model, dress)?;
    let (mesh, _) = remesh(&body, dress, base.positions.len(), DRESS_PARTICLES)?;
    Ok((shaped, mesh))
}

/// The default body, its surface, and `dress` (middle size, as its file meshes it) on it.
fn dress_on_default_body(
    model: &BodyModel,
    dress: &Path,
) -> Result<(ShapedBody, BodySurface, GarmentMesh)> {
    let shaped = model.shaped(&Shape::default())?;
    let body = BodySurface::new(model, &shaped)?;
    let mesh = mesh_garment(&body, dress, None, None)?;
    Ok((shaped, body, mesh))
}

/// `fitroom cloth bench`.
pub fn bench(model: &BodyModel, dress: &Path, motion: &Path, frames: usize) -> Result<BenchReport> {
    let (shaped, body, mesh) = dress_on_default_body(model, dress)?;
    let (report, _, _) = sim_mesh(model, &shaped, &mesh, motion, frames, None, true)?;
    let pattern = dress
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("ron"));
    let (dress_4k, edge_cm) = if pattern {
        let (fine, edge_cm) = remesh(&body, dress, report.particles, DRESS_PARTICLES)?;
        let (fine, _, _) = sim_mesh(model, &shaped, &fine, motion, frames, None, true)?;
        (Some(fine), Some(edge_cm))
    } else {
        (None, None)
    };
    let dress = report;
    let mut scaling = Vec::new();
    for (around, rows) in [(32u32, 32u32), (64, 64), (128, 128), (256, 256)] {
        // A tube around the hips and legs: a skirt-like cloth of around × rows particles.
        // Around the hips (model space: the hips at about y = 0), hanging to the knees.
        let mesh =
            fitroom_cloth::ClothMesh::cylinder(Vec3::new(0.0, -0.45, 0.0), 0.2, 0.5, around, rows)?;
        let positions: Vec<Vec3> = mesh.positions().to_vec();
        let attached: Vec<u32> =
            fitroom_cloth::ClothMesh::cylinder_ring(around, rows - 1).collect();
        let garment = SimGarment {
            positions,
            triangles: mesh.triangles().to_vec(),
            attached,
            fabric: fitroom_cloth::Fabric::cotton(),
            ignore_colliders: Vec::new(),
        };
        let mut s = GarmentSim::new(
            model,
            &shaped.positions,
            &shaped.rest_pose,
            &garment,
            SolverSettings::default(),
        )?;
        let identity = vec![Affine3A::IDENTITY; model.bones.len()];
        s.reset(&identity)?;
        let mut times = Vec::new();
        let n = if around >= 256 { 10 } else { 40 };
        for _ in 0..n {
            times.push(s.step(&identity, 1.0 / STEP_HZ)?.solve_ms);
        }
        scaling.push(((around * rows) as usize, Stats::of(&times)));
    }
    Ok(BenchReport {
        dress,
        dress_4k,
        dress_4k_edge_cm: edge_cm,
        scaling,
        threads: SolverSettings::default().threads,
        goal_ms: 0.6,
    })
}

pub(super) fn print_bench(r: &BenchReport) {
    println!(
        "{} ({} particles, {} colliders, {} substeps, {} threads): {:.2} ms per 120 Hz step (p95 {:.2}); goal {} ms",
        r.dress.garment,
        r.dress.particles,
        r.dress.colliders,
        r.dress.substeps,
        r.threads,
        r.dress.step_ms.mean,
        r.dress.step_ms.p95,
        r.goal_ms
    );
    if let (Some(fine), Some(edge)) = (&r.dress_4k, r.dress_4k_edge_cm) {
        println!(
            "  re-meshed ({edge:.2} cm edges, {} particles): {:.2} ms per step (p95 {:.2})",
            fine.particles, fine.step_ms.mean, fine.step_ms.p95,
        );
    }
    for (n, s) in &r.scaling {
        println!(
            "  {n:>6} particles: {:.2} ms per step (p95 {:.2})",
            s.mean, s.p95
        );
    }
}
