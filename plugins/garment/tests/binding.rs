//! Attached garment vertices bound to the body surface follow it exactly: in the rest pose,
//! under rigid motions, and plausibly in a skinned pose; skin weights for the static part.

mod common;

use common::{build, default_body, female_body};
use fitroom_body::{forward_kinematics, skin_positions};
use fitroom_garment::{BodySurface, skin_weights_for};
use glam::{Quat, Vec3};

fn max_error(a: &[Vec3], b: &[Vec3]) -> f32 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .map(|(p, q)| p.distance(*q))
        .fold(0.0, f32::max)
}

#[test]
fn binding_reproduces_the_rest_pose_exactly() {
    for body in [default_body(), female_body()] {
        for (garment, size) in [("sundress", "38"), ("tshirt", "M"), ("skirt", "S")] {
            let g = build(garment, size, body);
            let expected: Vec<Vec3> = g
                .attached
                .iter()
                .map(|&v| g.positions[v as usize])
                .collect();
            // Body-only slices and the full shaped mesh (helpers after the body) both work.
            let n = body.surface.vertex_count();
            let got = g
                .binding
                .positions(&body.shaped.positions[..n], &body.shaped.normals[..n]);
            let err = max_error(&got, &expected);
            assert!(
                err < 2e-6,
                "{garment} on {}: rest pose error {err} m",
                body.name
            );
            let got = g
                .binding
                .try_positions(&body.shaped.positions, &body.shaped.normals)
                .expect("long enough");
            assert!(max_error(&got, &expected) < 2e-6);
            // The offsets are the ease: small, and outside the body.
            for e in &g.binding.entries {
                assert!(e.offset.z > 0.0 && e.offset.length() < 0.1, "{e:?}");
            }
        }
    }
}

#[test]
fn binding_follows_a_rigidly_moved_body_exactly() {
    let body = default_body();
    let g = build("sundress", "40", body);
    let rest: Vec<Vec3> = g
        .attached
        .iter()
        .map(|&v| g.positions[v as usize])
        .collect();
    for (rotation, translation) in [
        (Quat::from_rotation_y(1.1), Vec3::new(0.3, 0.0, -1.5)),
        (
            Quat::from_euler(glam::EulerRot::XYZ, 0.4, -2.0, 0.7),
            Vec3::new(-2.0, 1.0, 0.5),
        ),
    ] {
        let positions: Vec<Vec3> = body
            .surface
            .positions
            .iter()
            .map(|&p| rotation * p + translation)
            .collect();
        let normals: Vec<Vec3> = body.surface.normals.iter().map(|&n| rotation * n).collect();
        let got = g.binding.positions(&positions, &normals);
        let expected: Vec<Vec3> = rest.iter().map(|&p| rotation * p + translation).collect();
        let err = max_error(&got, &expected);
        assert!(err < 1e-5, "rigid motion error {err} m");
    }
    // Too short slices are refused, not a panic.
    assert!(
        g.binding
            .try_positions(&body.surface.positions[..100], &body.surface.normals)
            .is_err()
    );
}

#[test]
fn binding_follows_a_skinned_pose() {
    let model = common::model();
    let body = default_body();
    let g = build("tshirt", "M", body);
    let rest = &body.shaped.rest_pose;
    // Bend the spine forward and turn the pelvis: the neckline band moves with the chest.
    let mut local = vec![Quat::IDENTITY; model.bones.len()];
    let spine = model.bone_index("spine_03").expect("bone");
    let pelvis = model.bone_index("pelvis").expect("bone");
    local[spine] = Quat::from_rotation_x(0.5);
    local[pelvis] = Quat::from_rotation_y(0.6);
    let posed = forward_kinematics(&model.bones, rest, &local, Vec3::new(0.1, 0.0, 0.2));
    let n = body.surface.vertex_count();
    let positions = skin_positions(
        &body.shaped.positions[..n],
        &model.skin_joints,
        &model.skin_weights,
        rest,
        &posed,
    );
    let normals = fitroom_body::compute_normals(&positions, &model.triangles);
    let got = g.binding.positions(&positions, &normals);
    let moved = max_error(
        &got,
        &g.attached
            .iter()
            .map(|&v| g.positions[v as usize])
            .collect::<Vec<_>>(),
    );
    assert!(moved > 0.05, "the pose moves the neckline ({moved} m)");
    // Each bound vertex keeps its distance to the skinned surface (the bound triangle's
    // frame turns with it; skinning stretches the skin a little).
    for (e, p) in g.binding.entries.iter().zip(&got) {
        assert!(p.is_finite());
        let [a, b, c] = e.corners.map(|v| positions[v as usize]);
        let q = a * e.barycentric[0] + b * e.barycentric[1] + c * e.barycentric[2];
        assert!((p.distance(q) - e.offset.length()).abs() < 1e-4);
    }
}

#[test]
fn skin_weights_come_from_the_nearest_body_part() {
    let body = default_body();
    let surface: &BodySurface = &body.surface;
    let g = build("tshirt", "L", body);
    let (joints, weights) = g.skin_weights(surface);
    assert_eq!(joints.len(), g.positions.len());
    for w in &weights {
        let sum: f32 = w.iter().sum();
        assert!((sum - 1.0).abs() < 1e-4, "{w:?}");
        assert!(w.windows(2).all(|p| p[0] >= p[1]), "largest first: {w:?}");
    }
    let model = common::model();
    let arm_bone = |j: u16| {
        let name = &model.bones[j as usize].name;
        name.starts_with("upperarm_l") || name.starts_with("lowerarm_l")
    };
    let sleeve = g
        .panels
        .iter()
        .position(|p| p == "sleeve_left")
        .expect("panel") as u16;
    let (on_arm, total) = (0..g.positions.len())
        .filter(|&v| g.panel_of_vertex[v] == sleeve)
        .fold((0, 0), |(a, t), v| {
            (a + usize::from(arm_bone(joints[v][0])), t + 1)
        });
    assert!(
        on_arm * 10 >= total * 7,
        "{on_arm} of {total} left-sleeve vertices follow the left arm"
    );
    // A point on the body gets that vertex's weights.
    let v = 4000;
    let (j, w) = skin_weights_for(surface, &[surface.positions[v]]);
    assert_eq!(j[0][0], model.skin_joints[v][0]);
    assert!(
        (w[0][0] - model.skin_weights[v][0] / model.skin_weights[v].iter().take(4).sum::<f32>())
            .abs()
            < 0.05
    );
}
