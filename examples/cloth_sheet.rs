//! A cloth sheet hanging from two corners, stepped by the XPBD solver core alone (no Bevy, no
//! body): the smallest use of `fitroom_cloth`.
//!
//! `cargo run --release --example cloth_sheet`

use fitroom_cloth::{ClothMesh, ClothSolver, Fabric, SolverSettings};
use glam::Vec3;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    // A 1 m square of 32 x 32 cells in the x-y plane, its top edge 1.5 m above the floor.
    let cells = 32;
    let mesh = ClothMesh::grid(
        Vec3::new(-0.5, 1.5, 0.0),
        Vec3::X,
        Vec3::NEG_Y,
        cells,
        cells,
    )?;
    // Pinned at the two top corners: the first and the last vertex of the top row.
    let pins = [0, cells];
    let mut cloth = ClothSolver::new(&mesh, Fabric::cotton(), &pins, SolverSettings::default())?;
    let dt = 1.0 / 120.0;
    for second in 1..=3 {
        for _ in 0..120 {
            let report = cloth.step(dt)?;
            if report.health != fitroom_cloth::Health::Ok {
                eprintln!("step health: {:?}", report.health);
            }
        }
        let lowest = cloth
            .positions()
            .iter()
            .map(|p| p.y)
            .fold(f32::INFINITY, f32::min);
        println!(
            "after {second} s: lowest point {lowest:.3} m, largest stretch {:.3}",
            cloth.max_stretch_ratio()
        );
    }
    Ok(())
}
