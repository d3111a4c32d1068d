//! `fitroom cloth fit`: the garment settled on the body in its rest pose.

use std::path::Path;

use anyhow::Result;
use fitroom_body::{BodyModel, Shape};
use fitroom_cloth::SolverSettings;
use fitroom_garment::{
    ease::{Ease, trunk_ease},
    sim::{GarmentSim, SimGarment},
};
use glam::Affine3A;
use serde::Serialize;

use super::{STEP_HZ, load_garment};

/// The JSON of `fitroom cloth fit`.
#[derive(Debug, Serialize)]
pub struct FitMapReport {
    pub garment: String,
    pub size: String,
    pub fabric: String,
    pub particles: usize,
    pub settle_s: f32,
    pub max_strain_pct: f32,
    pub mean_strain_pct: f32,
    /// Mean distance of the garment from the body colliders, mm (positive outside).
    pub mean_gap_mm: f32,
    pub max_penetration_mm: f32,
    pub ease: Vec<Ease>,
}

/// `fitroom cloth fit`: the garment settles on the body in its rest pose.
pub fn fit_map(
    model: &BodyModel,
    shape: &Shape,
    garment: &Path,
    size: Option<&str>,
    settle_s: f32,
) -> Result<(FitMapReport, GarmentSim)> {
    let (shaped, mesh) = load_garment(model, shape, garment, size)?;
    let mut sim = GarmentSim::new(
        model,
        &shaped.positions,
        &shaped.rest_pose,
        &SimGarment::from_mesh(&mesh),
        SolverSettings::default(),
    )?;
    let body = &shaped.positions[..model.body_vertex_count as usize];
    let floor = body.iter().map(|p| p.y).fold(f32::INFINITY, f32::min);
    sim.set_floor(Some(floor))?;
    let identity = vec![Affine3A::IDENTITY; model.bones.len()];
    sim.reset(&identity)?;
    let steps = (settle_s * STEP_HZ).round().max(1.0) as usize;
    let mut max_pen = 0.0f32;
    for _ in 0..steps {
        let s = sim.step(&identity, 1.0 / STEP_HZ)?;
        max_pen = max_pen.max(s.max_penetration_m);
    }
    let strain = sim.strain_pct();
    let gap = sim.gap_m(&identity);
    let measured = model.measure(&shaped.positions)?;
    let ease = trunk_ease(&sim.positions(), sim.triangles(), &measured, floor);
    let n = strain.len().max(1) as f32;
    let report = FitMapReport {
        garment: mesh.name.clone(),
        size: mesh.size.clone(),
        fabric: mesh.fabric_name.clone(),
        particles: mesh.positions.len(),
        settle_s,
        max_strain_pct: strain.iter().copied().fold(0.0, f32::max),
        mean_strain_pct: strain.iter().sum::<f32>() / n,
        mean_gap_mm: gap.iter().sum::<f32>() / gap.len().max(1) as f32 * 1e3,
        max_penetration_mm: max_pen * 1e3,
        ease,
    };
    Ok((report, sim))
}

pub(super) fn print_fit(r: &FitMapReport) {
    println!(
        "{} size {} ({}), settled {} s: strain max {:.1}% mean {:.2}%, mean gap {:.1} mm, max penetration {:.2} mm",
        r.garment,
        r.size,
        r.fabric,
        r.settle_s,
        r.max_strain_pct,
        r.mean_strain_pct,
        r.mean_gap_mm,
        r.max_penetration_mm
    );
    for e in &r.ease {
        match (e.garment_girth_cm, e.ease_cm) {
            (Some(g), Some(ease)) => println!(
                "  {:<6} body {:.1} cm, garment {:.1} cm: ease {:+.1} cm",
                e.landmark, e.body_girth_cm, g, ease
            ),
            _ => println!(
                "  {:<6} body {:.1} cm: the garment does not go round the body there",
                e.landmark, e.body_girth_cm
            ),
        }
    }
}
