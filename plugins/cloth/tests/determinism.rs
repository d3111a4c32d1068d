//! The result of a step does not depend on the number of threads: 1, 2 and 4 threads give
//! bit-for-bit the same positions in a scene that exercises every phase (wind gusts, drag and
//! lift, moving attachments, moving colliders, a moving body frame, several iterations), on a
//! mesh of two blocks (one seam) and one of four (seams and corners).

mod common;

use common::*;
use fitroom_cloth::{
    ClothMesh, ClothSolver, Fabric, Plane, RigidTransform, SolverSettings, Sphere, Wind,
};
use glam::{Quat, Vec3};

fn run(threads: usize, (around, rows): (u32, u32)) -> Vec<[u32; 3]> {
    let mesh = ClothMesh::cylinder(Vec3::new(0.0, 0.4, 0.0), 0.25, 0.6, around, rows).unwrap();
    let top: Vec<u32> = ClothMesh::cylinder_ring(around, rows).collect();
    let settings = SolverSettings {
        threads,
        iterations: 2,
        ..SolverSettings::default()
    };
    let mut cloth = ClothSolver::new(&mesh, Fabric::silk(), &top, settings).unwrap();
    cloth.set_wind(Some(Wind::new(Vec3::new(2.0, 0.0, 1.0), 1.5, 0.3, 42)));
    cloth.set_planes(&[Plane::floor(0.0)]).unwrap();
    cloth.reset_body_frame(RigidTransform::IDENTITY).unwrap();
    let rest: Vec<Vec3> = top.iter().map(|&v| mesh.positions()[v as usize]).collect();
    for step in 0..60 {
        let t = step as f32 * DT;
        // The hips sway; the waist ring follows; legs swing inside the skirt.
        let pose = RigidTransform::new(
            Quat::from_rotation_y(0.5 * t.sin()),
            Vec3::new(0.1 * t, 0.0, 0.0),
        );
        cloth.set_body_frame(pose).unwrap();
        let waist: Vec<Vec3> = rest
            .iter()
            .map(|p| *p * (1.0 + 0.05 * (3.0 * t).sin()))
            .collect();
        cloth.set_attachment_targets(&waist).unwrap();
        let swing = 0.6 * (6.0 * t).sin();
        let knee = |side: f32, sign: f32| {
            Vec3::new(side, 0.55, 0.0)
                + Quat::from_rotation_x(sign * swing) * Vec3::new(0.0, -0.45, 0.0)
        };
        let spheres = [
            Sphere::new(Vec3::new(-0.1, 0.95, 0.0), 0.12),
            Sphere::new(knee(-0.1, 1.0), 0.07),
            Sphere::new(Vec3::new(0.1, 0.95, 0.0), 0.12),
            Sphere::new(knee(0.1, -1.0), 0.07),
            Sphere::new(Vec3::new(0.0, 1.0, 0.0), 0.15),
        ];
        cloth.set_colliders(&spheres, &[[0, 1], [2, 3]]).unwrap();
        cloth.step(DT).unwrap();
    }
    cloth
        .positions()
        .iter()
        .map(|p| [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()])
        .collect()
}

#[test]
fn one_two_and_four_threads_give_identical_bits() {
    // 1,152 particles make two blocks; 5,120 make four (a block per 1,024 or more).
    for mesh in [(48, 24), (80, 64)] {
        let one = run(1, mesh);
        assert_eq!(one, run(1, mesh), "not repeatable on one thread");
        let two = run(2, mesh);
        let four = run(4, mesh);
        let differing = one.iter().zip(&two).filter(|(a, b)| a != b).count();
        assert_eq!(
            differing, 0,
            "{mesh:?}: 2 threads differ from 1 in {differing} particles"
        );
        let differing = one.iter().zip(&four).filter(|(a, b)| a != b).count();
        assert_eq!(
            differing, 0,
            "{mesh:?}: 4 threads differ from 1 in {differing} particles"
        );
    }
}
