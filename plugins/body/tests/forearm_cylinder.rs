//! The cross-section measurement against the closed form of linear blend skinning on a
//! synthetic forearm: a tube with two bones in series and weights linear along it.

use std::f32::consts::PI;

use fitroom_body::forearm::{SectionPlane, lbs_area_ratio, limb_section, section_area};
use fitroom_body::{
    Bone, JointPlacement, RestPose, bone_frame, forward_kinematics, skin_positions,
};
use glam::{Quat, Vec3};

struct Tube {
    positions: Vec<Vec3>,
    triangles: Vec<[u32; 3]>,
    joints: Vec<[u16; 4]>,
    weights: Vec<[f32; 4]>,
    bones: Vec<Bone>,
    rest: RestPose,
    start: Vec3,
    axis: Vec3,
    length: f32,
}

const RINGS: usize = 53;
const SEGMENTS: usize = 24;

/// A tilted tube (like a forearm in A-pose): 53 rings 5 mm apart, radius 3.5 cm; bone 0 from
/// the start to the middle, bone 1 (its child) from the middle to the end; the weight of bone 1
/// is the fraction along the tube.
fn tube() -> Tube {
    let start = Vec3::new(0.31, 0.35, 0.01);
    let axis = Vec3::new(0.12, -0.10, 0.16).normalize();
    let length = 0.26;
    let radius = 0.035;
    let e1 = axis.any_orthonormal_vector();
    let e2 = axis.cross(e1);
    let mut positions = Vec::new();
    let mut joints = Vec::new();
    let mut weights = Vec::new();
    for r in 0..RINGS {
        let f = r as f32 / (RINGS - 1) as f32;
        for s in 0..SEGMENTS {
            let a = 2.0 * PI * s as f32 / SEGMENTS as f32;
            positions.push(start + axis * (f * length) + (e1 * a.cos() + e2 * a.sin()) * radius);
            joints.push([1, 0, 0, 0]);
            weights.push([f, 1.0 - f, 0.0, 0.0]);
        }
    }
    let mut triangles = Vec::new();
    for r in 0..RINGS as u32 - 1 {
        for s in 0..SEGMENTS as u32 {
            let a = r * SEGMENTS as u32 + s;
            let b = r * SEGMENTS as u32 + (s + 1) % SEGMENTS as u32;
            triangles.push([a, b, b + SEGMENTS as u32]);
            triangles.push([a, b + SEGMENTS as u32, a + SEGMENTS as u32]);
        }
    }
    let middle = start + axis * (length / 2.0);
    let end = start + axis * length;
    let roll = 0.7;
    let bone = |name: &str, parent| Bone {
        name: name.into(),
        parent,
        head_placement: JointPlacement::Vertex(0),
        tail_placement: JointPlacement::Vertex(0),
        roll,
    };
    let rest = RestPose {
        heads: vec![start, middle],
        tails: vec![middle, end],
        rotations: vec![
            bone_frame(start, middle, roll),
            bone_frame(middle, end, roll),
        ],
    };
    Tube {
        positions,
        triangles,
        joints,
        weights,
        bones: vec![bone("proximal", None), bone("distal", Some(0))],
        rest,
        start,
        axis,
        length,
    }
}

/// Area ratio of the section at fraction `f` when bone 0 twists by `proximal` and bone 1 by a
/// further `distal` (radians, about the bone axis).
fn measured_ratio(t: &Tube, f: f32, proximal: f32, distal: f32) -> f32 {
    let posed = forward_kinematics(
        &t.bones,
        &t.rest,
        &[
            Quat::from_rotation_y(proximal),
            Quat::from_rotation_y(distal),
        ],
        Vec3::ZERO,
    );
    let skinned = skin_positions(&t.positions, &t.joints, &t.weights, &t.rest, &posed);
    let plane = SectionPlane {
        point: t.start + t.axis * (f * t.length),
        normal: t.axis,
    };
    let posed_axis = (posed[0].rotation * t.rest.rotations[0].inverse() * t.axis).normalize();
    section_area(&t.positions, &skinned, &t.triangles, plane, posed_axis)
        .expect("a section around the tube")
        .ratio()
}

#[test]
fn the_tube_section_is_one_closed_loop_around_it() {
    let t = tube();
    let polygon = 0.5 * SEGMENTS as f32 * 0.035f32.powi(2) * (2.0 * PI / SEGMENTS as f32).sin();
    // Between rings the plane cuts each quad's two long edges and its diagonal: 48 points.
    let between = SectionPlane {
        point: t.start + t.axis * (0.51 * t.length),
        normal: t.axis,
    };
    let section = limb_section(&t.positions, &t.triangles, between).expect("section");
    assert_eq!(section.points.len(), 2 * SEGMENTS);
    let area = section.area(&t.positions, t.axis);
    assert!((area / polygon - 1.0).abs() < 1e-3, "{area} vs {polygon}");
    // Through a ring (up to rounding) the loop is that ring's polygon.
    let on_ring = SectionPlane {
        point: t.start + t.axis * (0.5 * t.length),
        normal: t.axis,
    };
    let section = limb_section(&t.positions, &t.triangles, on_ring).expect("section");
    let area = section.area(&t.positions, t.axis);
    assert!((area / polygon - 1.0).abs() < 1e-4, "{area} vs {polygon}");
}

#[test]
fn half_blend_matches_cos_squared_of_half_the_angle() {
    let t = tube();
    for deg in [-90.0f32, -45.0, 60.0, -150.0] {
        let phi = deg.to_radians();
        // Literal split: all twist on the distal bone; 50/50 at the middle.
        let literal = measured_ratio(&t, 0.5, 0.0, phi);
        let expected = (phi / 2.0).cos().powi(2);
        assert!(
            (literal - expected).abs() < 1e-4,
            "{deg}°: {literal} vs {expected}"
        );
        // Shared split: the bones differ by half the twist.
        let shared = measured_ratio(&t, 0.5, phi / 2.0, phi / 2.0);
        let expected = (phi / 4.0).cos().powi(2);
        assert!(
            (shared - expected).abs() < 1e-4,
            "{deg}°: {shared} vs {expected}"
        );
        // A single rigidly twisted bone keeps the section.
        let rigid = measured_ratio(&t, 0.5, phi, 0.0);
        assert!((rigid - 1.0).abs() < 1e-4, "{deg}°: {rigid}");
    }
}

#[test]
fn uneven_blends_match_the_determinant() {
    let t = tube();
    let phi = -90f32.to_radians();
    // Planes through rings (fractions k / 52) and between rings.
    for f in [0.25f32, 13.0 / 52.0, 0.6, 40.0 / 52.0, 0.9] {
        let measured = measured_ratio(&t, f, 0.0, phi);
        let expected = lbs_area_ratio(f, phi);
        println!("f = {f:.3}: measured {measured:.5}, closed form {expected:.5}");
        // Between rings the section points are interpolated from skinned ring vertices, which
        // differs from skinning the interpolated point by O(ring spacing²).
        assert!(
            (measured - expected).abs() < 2e-3,
            "f {f}: {measured} vs {expected}"
        );
    }
}
