//! What the tracker's tests and benchmark share: the shipped MakeHuman body posed by the
//! body crate's own forward kinematics and skinning (independent of the tracker's model), its
//! rig's 20 Kinect joints, and synthetic Kinect frames of it in a room.

#![allow(dead_code)]

use std::path::Path;

use fitroom_body::{BodyModel, RestPose, RigidTransform, forward_kinematics};
use fitroom_depth::synthetic::{Label, NoiseSettings, Scene, SceneMesh, SyntheticCamera};
use fitroom_depth::{DepthCamera, DepthFrame};
use fitroom_tracker::bodyparts::synth::turned_locals;
use fitroom_tracker::kinect::rig_joints;
use glam::{Affine3A, Quat, Vec3};

pub struct Body {
    pub model: BodyModel,
    /// The body's vertices (the model's own, or shaped).
    pub positions: Vec<Vec3>,
    pub rest: RestPose,
    pub standing: Affine3A,
}

pub fn model() -> BodyModel {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/bodies/makehuman.fitbody");
    BodyModel::read(&path).expect("the shipped body")
}

/// The shipped body, MakeHuman's default build.
pub fn body() -> Body {
    let model = model();
    let positions = model.positions.clone();
    Body::of(model, positions)
}

/// The shipped body shaped to `shape`.
pub fn shaped_body(shape: &fitroom_body::Shape) -> Body {
    let model = model();
    let positions = model.shaped(shape).expect("a valid shape").positions;
    Body::of(model, positions)
}

/// The shipped body scaled by `factor` (the same proportions, another size).
pub fn scaled_body(factor: f32) -> Body {
    let model = model();
    let positions = model.positions.iter().map(|p| *p * factor).collect();
    Body::of(model, positions)
}

/// Model-space turns (axis, degrees) of named bones about their heads, applied parents first.
pub type Turns<'a> = &'a [(&'a str, Vec3, f32)];

impl Body {
    fn of(model: BodyModel, positions: Vec<Vec3>) -> Self {
        let rest = model.rest_pose(&positions);
        let standing = model.standing_in_sensor_space(&positions);
        Self {
            model,
            positions,
            rest,
            standing,
        }
    }

    pub fn bone(&self, name: &str) -> usize {
        self.model
            .bone_index(name)
            .unwrap_or_else(|| panic!("the rig has {name}"))
    }

    /// Local rotations for `turns` scaled by `share` (0: rest, 1: the whole pose).
    pub fn locals(&self, turns: Turns, share: f32) -> Vec<Quat> {
        let scaled: Vec<(&str, Vec3, f32)> =
            turns.iter().map(|&(n, a, d)| (n, a, d * share)).collect();
        turned_locals(&self.model, &self.rest, &scaled)
    }

    /// The skin and the 20 Kinect joints, sensor space, for the body standing at `spot`.
    pub fn posed(&self, local: &[Quat], spot: Vec3) -> (Vec<Vec3>, Vec<Vec3>) {
        let globals: Vec<RigidTransform> =
            forward_kinematics(&self.model.bones, &self.rest, local, Vec3::ZERO);
        let place = |p: Vec3| self.standing.transform_point3(p) + spot;
        let skin = self
            .model
            .skin_positions(&self.positions, &self.rest, &globals);
        let n = self.model.body_vertex_count as usize;
        let joints = rig_joints(&self.model, &globals).map(place).to_vec();
        (skin[..n].iter().map(|&p| place(p)).collect(), joints)
    }
}

pub fn scene(meshes: Vec<(Vec<Vec3>, Label)>, triangles: &[[u32; 3]]) -> Scene {
    scene_at(-0.8, meshes, triangles)
}

/// The room with the sensor `-floor_y` metres above the floor.
pub fn scene_at(floor_y: f32, meshes: Vec<(Vec<Vec3>, Label)>, triangles: &[[u32; 3]]) -> Scene {
    let mut scene = Scene::room(floor_y, 3.9);
    for (positions, label) in meshes {
        scene.meshes.push(SceneMesh {
            positions,
            triangles: triangles.to_vec(),
            label,
            closed: true,
        });
    }
    scene
}

pub fn render(scene: &Scene, seed: u64, time_s: f64) -> DepthFrame {
    SyntheticCamera::new(DepthCamera::default(), NoiseSettings::default(), seed)
        .render(scene, time_s)
        .frame
}

pub const ARMS_OUT: Turns = &[
    ("upperarm_l", Vec3::Z, 55.0),
    ("upperarm_r", Vec3::Z, -55.0),
    ("lowerarm_l", Vec3::Z, 20.0),
];
pub const REACH_AND_STEP: Turns = &[
    ("upperarm_l", Vec3::X, -75.0),
    ("lowerarm_l", Vec3::X, -50.0),
    ("thigh_r", Vec3::X, -35.0),
    ("calf_r", Vec3::X, 45.0),
];
pub const TURN_AND_CROSS: Turns = &[
    ("spine_01", Vec3::Y, 20.0),
    ("spine_01", Vec3::X, 10.0),
    ("upperarm_l", Vec3::X, -70.0),
    ("upperarm_l", Vec3::Y, -45.0),
    ("lowerarm_r", Vec3::X, -90.0),
];

/// A second (30 frames) of the default body moving its arms out and back, 2.6 m away, with
/// its trunk's, clavicles' and upper arms' skin `layer_m` out along the skin's normals (a
/// shirt's surface, made from the body crate's own skinning, not the tracker's capsules);
/// noise from `seed`.
pub fn arms_moving_in_a_layer(layer_m: f32, seed: u64) -> Vec<DepthFrame> {
    let person = shaped_body(&fitroom_body::Shape::default());
    let covered = fitroom_tracker::model::clothed_vertices(&person.model);
    (0..30)
        .map(|k| {
            let share = 0.3 + 0.3 * (k as f32 / 10.0).sin();
            let (mut skin, _) =
                person.posed(&person.locals(ARMS_OUT, share), Vec3::new(0.0, -0.8, 2.6));
            let normals = fitroom_body::compute_normals(&skin, &person.model.triangles);
            for ((v, n), &on) in skin.iter_mut().zip(&normals).zip(&covered) {
                if on {
                    *v += *n * layer_m;
                }
            }
            render(
                &scene(vec![(skin, Label::Body)], &person.model.triangles),
                k as u64 + seed,
                k as f64 / 30.0,
            )
        })
        .collect()
}
