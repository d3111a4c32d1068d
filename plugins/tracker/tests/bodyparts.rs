//! The body-part forest (`fitroom_tracker::bodyparts`): the parts it is taught, its file, and
//! that a forest grown on some random bodies and poses labels other bodies and poses.

mod common;

use fitroom_body::BodyModel;
use fitroom_body::{RigidTransform, forward_kinematics};
use fitroom_sensor::KinectJoint;
use fitroom_tracker::bodyparts::forest::{DepthImage, ForestError};
use fitroom_tracker::bodyparts::labels::vertex_parts;
use fitroom_tracker::bodyparts::synth::{LabelledImage, Synth};
use fitroom_tracker::bodyparts::train::{TrainSettings, train};
use fitroom_tracker::bodyparts::{Forest, PARTS};
use fitroom_tracker::kinect::rig_joints;
use glam::{Quat, Vec3};

#[test]
fn each_part_gathers_around_its_joint_on_its_side() {
    let model = common::model();
    let rest = model.rest_pose(&model.positions);
    let parts = vertex_parts(&model, &model.positions, &rest);
    let locals = vec![Quat::IDENTITY; model.bones.len()];
    let globals: Vec<RigidTransform> = forward_kinematics(&model.bones, &rest, &locals, Vec3::ZERO);
    let joints = rig_joints(&model, &globals);
    for joint in KinectJoint::ALL {
        let j = joint.index();
        let of: Vec<Vec3> = parts
            .iter()
            .zip(&model.positions)
            .filter(|(p, _)| usize::from(**p) == j)
            .map(|(_, v)| *v)
            .collect();
        assert!(of.len() >= 50, "{joint:?}: {} vertices", of.len());
        let centre = of.iter().sum::<Vec3>() / of.len() as f32;
        let off = centre.distance(joints[j]);
        println!(
            "{joint:?}: {} vertices, centre {:.0} mm from the joint",
            of.len(),
            off * 1000.0
        );
        // Within a part's reach of its joint (the trunk's parts are the broadest).
        assert!(off < 0.16, "{joint:?}: centre {off} m from its joint");
        // Model space: +X is the body's left.
        let name = format!("{joint:?}");
        if name.ends_with("Left") {
            assert!(
                of.iter().all(|v| v.x > 0.0),
                "{joint:?} has vertices on the right"
            );
        } else if name.ends_with("Right") {
            assert!(
                of.iter().all(|v| v.x < 0.0),
                "{joint:?} has vertices on the left"
            );
        }
    }
}

/// `n` labelled images of `builds` random builds, all from `seed`.
fn images(model: &BodyModel, builds: usize, seed: u64, n: usize) -> Vec<LabelledImage> {
    let mut synth = Synth::new(model, builds, seed);
    std::iter::from_fn(|| Some(synth.next_image()))
        .flatten()
        .take(n)
        .collect()
}

fn settings() -> TrainSettings {
    TrainSettings {
        trees: 2,
        max_depth: 14,
        min_pixels: 20,
        features: 80,
        thresholds: 10,
        split_sample: 1000,
        pixels_per_image: 200,
        max_offset: 200.0,
        seed: 3,
    }
}

#[test]
fn a_forest_grown_on_some_bodies_and_poses_labels_others() {
    let model = common::model();
    let training = images(&model, 6, 1, 80);
    let forest = train(&training, PARTS, settings());
    // Other bodies, poses, places and noise.
    let tests = images(&model, 6, 2, 12);
    let (mut right, mut all) = (0usize, 0usize);
    let mut counts = [0usize; PARTS];
    let mut probs = vec![0f32; PARTS];
    for image in &tests {
        let view = DepthImage {
            metres: &image.metres,
            width: image.width,
            height: image.height,
        };
        for &(x, y, part) in &image.pixels {
            let (x, y) = (i32::from(x), i32::from(y));
            probs.fill(0.0);
            forest.classify_into(&view, x, y, view.at(x, y), &mut probs);
            let best = (0..PARTS)
                .max_by(|&a, &b| probs[a].total_cmp(&probs[b]))
                .unwrap_or(0);
            right += usize::from(best == usize::from(part));
            counts[usize::from(part)] += 1;
            all += 1;
        }
    }
    let accuracy = right as f32 / all as f32;
    // What always answering the commonest part would score.
    let commonest = counts.iter().copied().max().unwrap_or(0) as f32 / all as f32;
    println!(
        "per-pixel accuracy {accuracy:.3} on {all} pixels (the commonest part: {commonest:.3})"
    );
    assert!(accuracy > 0.3, "accuracy {accuracy}");
    assert!(
        accuracy > 2.5 * commonest,
        "accuracy {accuracy} vs {commonest}"
    );

    // The file keeps the forest exactly.
    let mut bytes = Vec::new();
    forest.write(&mut bytes).expect("written to memory");
    let back = Forest::read(&mut bytes.as_slice()).expect("read back");
    assert_eq!(back, forest);
}

#[test]
fn a_damaged_forest_file_is_an_error_not_a_panic() {
    let model = common::model();
    let few = images(&model, 1, 5, 4);
    let small = TrainSettings {
        max_depth: 4,
        ..settings()
    };
    let forest = train(&few, PARTS, small);
    let mut bytes = Vec::new();
    forest.write(&mut bytes).expect("written to memory");
    assert!(matches!(
        Forest::read(&mut b"not a forest at all".as_slice()),
        Err(ForestError::Magic)
    ));
    for cut in [9, 20, bytes.len() / 2, bytes.len() - 1] {
        assert!(Forest::read(&mut &bytes[..cut]).is_err(), "cut at {cut}");
    }
    // A split whose children lie past the tree's end: the first node's child index
    // (after magic 8, parts 4, trees 4, nodes 4, tag 1, offsets 8, threshold 4).
    let mut bad = bytes.clone();
    bad[33..37].copy_from_slice(&u32::MAX.to_le_bytes());
    let err = Forest::read(&mut bad.as_slice()).expect_err("a child past the end");
    assert!(err.to_string().contains("node 0"), "{err}");
}
