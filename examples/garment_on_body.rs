//! A garment on a body without a window: the MakeHuman body shaped as a woman, the skirt of
//! `assets/garments/` built in its middle size (graded, placed, sewn), then settled by the
//! cloth solver on the body standing still. The same calls the kiosk and `fitroom cloth fit`
//! make.
//!
//! `cargo run --release --example garment_on_body [-- path/to/garment.ron SIZE]`

use std::path::PathBuf;

use fitroom_body::{BodyModel, Shape};
use fitroom_cloth::SolverSettings;
use fitroom_garment::sim::{GarmentSim, SimGarment};
use fitroom_garment::{BodySurface, GarmentSource};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let mut args = std::env::args().skip(1);
    let garment = args
        .next()
        .map_or_else(|| root.join("assets/garments/skirt.ron"), PathBuf::from);
    let size = args.next();

    let model = BodyModel::read(&root.join("assets/bodies/makehuman.fitbody"))?;
    let shape = Shape {
        gender: 0.0,
        ..Shape::default()
    };
    let shaped = model.shaped(&shape)?;
    let body = BodySurface::new(&model, &shaped)?;
    let measured = model.measure(&shaped.positions)?;
    println!(
        "body: stature {:.1} cm, waist {:.1} cm, hip {:.1} cm",
        measured.stature_cm, measured.waist_cm, measured.hip_cm
    );

    // Any garment file: a pattern (.ron), an OBJ + MTL or a glTF.
    let source = GarmentSource::load(&garment)?;
    println!(
        "{}: sizes {}",
        source.name(),
        source.size_labels().join(", ")
    );
    let mesh = source.build(&body, size.as_deref())?;
    println!(
        "{} size {}: {} particles, {} attached to the body",
        mesh.name,
        mesh.size,
        mesh.positions.len(),
        mesh.attached.len()
    );

    // Settle it for a second and a half on the body at rest.
    let mut sim = GarmentSim::new(
        &model,
        &shaped.positions,
        &shaped.rest_pose,
        &SimGarment::from_mesh(&mesh),
        SolverSettings::default(),
    )?;
    // The skinning transforms of the body standing in its rest pose: identities.
    let rest = vec![glam::Affine3A::IDENTITY; model.bones.len()];
    sim.set_floor(Some(0.0))?;
    sim.reset(&rest)?;
    for _ in 0..180 {
        sim.step(&rest, 1.0 / 120.0)?;
    }
    // Per vertex, its most stretched edge (negative: all its edges slack).
    let strain = sim.strain_pct();
    let largest = strain.iter().copied().fold(f32::NEG_INFINITY, f32::max);
    let slack = strain.iter().filter(|&&s| s < 0.0).count();
    println!(
        "settled: largest edge strain {largest:+.1} %, {slack} of {} vertices with every edge slack",
        strain.len()
    );
    Ok(())
}
