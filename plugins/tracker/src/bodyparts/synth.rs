//! Training and test images for the body-part forest: random bodies (MakeHuman's macro
//! sliders) in random poses (every limb turned within a person's range, independently: no
//! motion capture, so the 15 evaluation clips are never seen), turned any way about the
//! vertical, filmed by the synthetic Kinect (its full noise model) at 2-3.6 m; each pixel's
//! part from a noiseless z-buffer of the same skin drawn part by part.

use fitroom_body::{BodyModel, RestPose, Shape, forward_kinematics};
use fitroom_depth::synthetic::{
    DepthBuffer, Label, NoiseSettings, Scene, SceneMesh, SyntheticCamera, next_unit,
};
use fitroom_depth::{DepthCamera, WIDTH};
use glam::{Affine3A, Quat, Vec3};

use super::forest::BACKGROUND_M;
use super::labels::{PARTS, part_triangles, vertex_parts};
use crate::kinect::rig_joints;

/// One body build, ready to pose.
pub struct SynthBody {
    positions: Vec<Vec3>,
    rest: RestPose,
    standing: Affine3A,
    parts: Vec<Vec<[u32; 3]>>,
}

/// A labelled image: the person's depth in its pixel box (metres, [`BACKGROUND_M`] off the
/// person) and its labelled pixels.
pub struct LabelledImage {
    /// Pixel box: first column and row, width, height.
    pub x0: usize,
    pub y0: usize,
    pub width: usize,
    pub height: usize,
    pub metres: Vec<f32>,
    /// (column, row) in the box and part, every person pixel with a reading and a part.
    pub pixels: Vec<(u16, u16, u8)>,
    /// The 20 Kinect joints, sensor space.
    pub joints: [Vec3; PARTS],
}

/// One side's limb bones and the sign that mirrors a turn about Y or Z onto it.
struct Side {
    sign: f32,
    lowerarm: &'static str,
    hand: &'static str,
    upperarm: &'static str,
    calf: &'static str,
    foot: &'static str,
    thigh: &'static str,
    clavicle: &'static str,
}

const SIDES: [Side; 2] = [
    Side {
        sign: 1.0,
        lowerarm: "lowerarm_l",
        hand: "hand_l",
        upperarm: "upperarm_l",
        calf: "calf_l",
        foot: "foot_l",
        thigh: "thigh_l",
        clavicle: "clavicle_l",
    },
    Side {
        sign: -1.0,
        lowerarm: "lowerarm_r",
        hand: "hand_r",
        upperarm: "upperarm_r",
        calf: "calf_r",
        foot: "foot_r",
        thigh: "thigh_r",
        clavicle: "clavicle_r",
    },
];

/// Local rotations from model-space turns (bone name, axis, degrees) of bones about their
/// heads, applied in order (a turn listed after a child's carries the child with it). A name
/// the rig lacks is skipped.
pub fn turned_locals(model: &BodyModel, rest: &RestPose, turns: &[(&str, Vec3, f32)]) -> Vec<Quat> {
    let bones = &model.bones;
    let mut local = vec![Quat::IDENTITY; bones.len()];
    for &(name, axis, degrees) in turns {
        let Some(b) = model.bone_index(name) else {
            continue;
        };
        let globals = forward_kinematics(bones, rest, &local, Vec3::ZERO);
        let q = Quat::from_axis_angle(axis.normalize(), degrees.to_radians());
        let g = globals[b].rotation;
        local[b] = (local[b] * (g.inverse() * q * g)).normalize();
    }
    local
}

/// Makes the images.
pub struct Synth<'a> {
    model: &'a BodyModel,
    bodies: Vec<SynthBody>,
    camera: SyntheticCamera,
    parts_buffer: DepthBuffer,
    state: u64,
}

fn uniform(state: &mut u64, lo: f32, hi: f32) -> f32 {
    lo + (hi - lo) * next_unit(state)
}

impl<'a> Synth<'a> {
    /// `builds` random bodies (at least one: the default build); everything from `seed`.
    pub fn new(model: &'a BodyModel, builds: usize, seed: u64) -> Self {
        let mut state = seed ^ 0x5eed_b0d1_e5a7_7e11;
        let mut bodies = Vec::with_capacity(builds);
        for b in 0..builds.max(1) {
            let shape = if b == 0 {
                Shape::default()
            } else {
                Shape {
                    gender: uniform(&mut state, 0.0, 1.0),
                    age: uniform(&mut state, 0.35, 0.7),
                    muscle: uniform(&mut state, 0.2, 0.8),
                    weight: uniform(&mut state, 0.15, 0.95),
                    height: uniform(&mut state, 0.05, 0.95),
                    proportions: uniform(&mut state, 0.3, 0.8),
                    ..Shape::default()
                }
            };
            let positions = match model.shaped(&shape) {
                Ok(s) => s.positions,
                Err(_) => model.positions.clone(),
            };
            let rest = model.rest_pose(&positions);
            let parts = vertex_parts(model, &positions, &rest);
            bodies.push(SynthBody {
                standing: model.standing_in_sensor_space(&positions),
                parts: part_triangles(&model.triangles, &parts),
                positions,
                rest,
            });
        }
        Self {
            model,
            bodies,
            camera: SyntheticCamera::new(DepthCamera::default(), NoiseSettings::default(), seed),
            parts_buffer: DepthBuffer::default(),
            state,
        }
    }

    /// Local rotations of a random pose: model-space turns (axis, degrees) of named bones
    /// about their heads, children first so that a parent's turn carries them.
    fn random_locals(&mut self, rest: &RestPose) -> Vec<Quat> {
        let s = &mut self.state;
        let mut turns: Vec<(&str, Vec3, f32)> = Vec::new();
        for side in &SIDES {
            let sign = side.sign;
            // Elbow and knee first (hinges about the body's left-right axis at rest).
            let elbow = if next_unit(s) < 0.3 {
                uniform(s, -20.0, 0.0)
            } else {
                uniform(s, -150.0, 0.0)
            };
            turns.push((side.lowerarm, Vec3::X, elbow));
            turns.push((side.hand, Vec3::X, uniform(s, -40.0, 40.0)));
            turns.push((side.upperarm, Vec3::Y, uniform(s, -60.0, 60.0)));
            turns.push((side.upperarm, Vec3::Z, sign * uniform(s, -25.0, 110.0)));
            turns.push((side.upperarm, Vec3::X, uniform(s, -170.0, 50.0)));
            let knee = if next_unit(s) < 0.5 {
                uniform(s, 0.0, 20.0)
            } else {
                uniform(s, 0.0, 130.0)
            };
            turns.push((side.calf, Vec3::X, knee));
            turns.push((side.foot, Vec3::X, uniform(s, -25.0, 30.0)));
            let lift = if next_unit(s) < 0.5 {
                uniform(s, -20.0, 15.0)
            } else {
                uniform(s, -100.0, 35.0)
            };
            turns.push((side.thigh, Vec3::Y, sign * uniform(s, -30.0, 30.0)));
            turns.push((side.thigh, Vec3::Z, sign * uniform(s, -15.0, 45.0)));
            turns.push((side.thigh, Vec3::X, lift));
            turns.push((side.clavicle, Vec3::Z, sign * uniform(s, -10.0, 15.0)));
        }
        turns.push(("neck_01", Vec3::X, uniform(s, -20.0, 30.0)));
        turns.push(("neck_01", Vec3::Y, uniform(s, -40.0, 40.0)));
        turns.push(("spine_02", Vec3::Y, uniform(s, -20.0, 20.0)));
        turns.push(("spine_01", Vec3::X, uniform(s, -15.0, 45.0)));
        turns.push(("spine_01", Vec3::Y, uniform(s, -25.0, 25.0)));
        turns.push(("spine_01", Vec3::Z, uniform(s, -20.0, 20.0)));
        turned_locals(self.model, rest, &turns)
    }

    /// The next image: a random body, pose, turn and place. `None` when too little of the
    /// person is seen (a body turned out of the image).
    pub fn next_image(&mut self) -> Option<LabelledImage> {
        let b = (next_unit(&mut self.state) * self.bodies.len() as f32) as usize;
        let b = b.min(self.bodies.len() - 1);
        let rest = self.bodies[b].rest.clone();
        let locals = self.random_locals(&rest);
        let s = &mut self.state;
        let yaw = if next_unit(s) < 0.7 {
            uniform(s, -60.0, 60.0)
        } else {
            uniform(s, -180.0, 180.0)
        };
        let spot = Vec3::new(
            uniform(s, -0.4, 0.4),
            uniform(s, -1.1, -0.6),
            uniform(s, 2.0, 3.6),
        );
        let body = &self.bodies[b];
        let globals = forward_kinematics(&self.model.bones, &body.rest, &locals, Vec3::ZERO);
        let skin = self
            .model
            .skin_positions(&body.positions, &body.rest, &globals);
        let n = self.model.body_vertex_count as usize;
        let pelvis = self
            .model
            .bone_index("pelvis")
            .map_or(Vec3::ZERO, |p| globals[p].translation);
        let turn = Affine3A::from_translation(spot)
            * Affine3A::from_rotation_y(yaw.to_radians())
            * body.standing
            * Affine3A::from_translation(Vec3::new(-pelvis.x, 0.0, -pelvis.z));
        let placed: Vec<Vec3> = skin[..n]
            .iter()
            .map(|&p| turn.transform_point3(p))
            .collect();

        let mut scene = Scene::room(spot.y, 4.2);
        scene.meshes.push(SceneMesh {
            positions: placed.clone(),
            triangles: self.model.triangles.clone(),
            label: Label::Body,
            closed: true,
        });
        let shot = self.camera.render(&scene, 0.0);
        let cam = self.camera.camera;
        self.parts_buffer.clear();
        for (p, tris) in body.parts.iter().enumerate() {
            self.parts_buffer
                .draw(&cam, &placed, tris, p as u8 + 1, true);
        }
        let (mut x0, mut y0, mut x1, mut y1) = (usize::MAX, usize::MAX, 0, 0);
        for (k, (&l, &mm)) in shot
            .labels
            .iter()
            .zip(shot.frame.depth_mm.iter())
            .enumerate()
        {
            if l == Label::Body as u8 && mm > 0 {
                let (x, y) = (k % WIDTH, k / WIDTH);
                x0 = x0.min(x);
                y0 = y0.min(y);
                x1 = x1.max(x);
                y1 = y1.max(y);
            }
        }
        if x0 > x1 || (x1 - x0) * (y1 - y0) < 400 {
            return None;
        }
        let (width, height) = (x1 - x0 + 1, y1 - y0 + 1);
        let mut metres = vec![BACKGROUND_M; width * height];
        let mut pixels = Vec::new();
        for y in y0..=y1 {
            for x in x0..=x1 {
                let k = y * WIDTH + x;
                let mm = shot.frame.depth_mm[k];
                if shot.labels[k] != Label::Body as u8 || mm == 0 {
                    continue;
                }
                let local = (y - y0) * width + (x - x0);
                metres[local] = f32::from(mm) * 0.001;
                let part = self.parts_buffer.label[k];
                if part > 0 && usize::from(part) <= PARTS {
                    pixels.push(((x - x0) as u16, (y - y0) as u16, part - 1));
                }
            }
        }
        let joints = rig_joints(self.model, &globals).map(|j| turn.transform_point3(j));
        Some(LabelledImage {
            joints,
            x0,
            y0,
            width,
            height,
            metres,
            pixels,
        })
    }
}
