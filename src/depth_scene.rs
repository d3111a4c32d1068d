//! What the synthetic depth camera sees of the app's world, in sensor space: the room, the
//! posed and shaped avatar's skin, and the garment it wears; and the frame's ground truth
//! (the avatar's 20 Kinect joints and which pixels see body and garment).

use bevy::prelude::*;
use fitroom_body::plugin::{AvatarBody, AvatarJoint, SensorPlacement, world_skin};
use fitroom_depth::synthetic::{Label, Scene, SceneMesh, SyntheticFrame};
use fitroom_depth::truth::{FrameTruth, runs_of};
use fitroom_garment::plugin::WornGarment;
use fitroom_sensor::KinectJoint;
use fitroom_tracker::kinect::{JOINT_BONES, head_joint};
use glam::Affine3A;

/// The back wall's distance from the sensor, metres (inside the 4 m range, so the camera
/// sees it).
pub const WALL_Z_M: f32 = 3.6;

/// The room the avatar stands in: floor and back wall, sensor space.
pub fn room(placement: &SensorPlacement) -> Scene {
    Scene::room(-placement.sensor_height_m, WALL_Z_M)
}

/// What else the synthetic camera sees in the room, standing still: a box, a second person
/// (the avatar's body in its rest pose), each at a sensor-space `(x, z)` on the floor.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Extras {
    pub box_at: Option<[f32; 2]>,
    pub person_at: Option<[f32; 2]>,
}

/// The room with `extras` in it.
pub fn room_with(placement: &SensorPlacement, body: &AvatarBody, extras: Extras) -> Scene {
    let mut scene = room(placement);
    let floor = -placement.sensor_height_m;
    if let Some([x, z]) = extras.box_at {
        // A box of 0.5 x 1.0 x 0.5 m (a chair, a stand).
        scene.add_box(
            Vec3::new(x, floor + 0.5, z),
            Vec3::new(0.25, 0.5, 0.25),
            Label::Other,
        );
    }
    if let Some([x, z]) = extras.person_at {
        let n = (body.model.body_vertex_count as usize).min(body.positions.len());
        let standing = body.model.standing_in_sensor_space(&body.positions);
        scene.meshes.push(SceneMesh {
            positions: body.positions[..n]
                .iter()
                .map(|&p| standing.transform_point3(p) + Vec3::new(x, floor, z))
                .collect(),
            triangles: body.model.triangles.clone(),
            label: Label::Other,
            closed: true,
        });
    }
    // The extras stand still too: the camera keeps them rendered with the room.
    scene.still = scene.meshes.len();
    scene
}

/// World to sensor space.
fn world_to_sensor(placement: &SensorPlacement) -> Affine3A {
    placement.sensor_to_world().compute_affine().inverse()
}

/// The avatar's skin and its garment, sensor space (`None` before the body is loaded).
pub fn avatar_meshes(world: &mut World) -> Option<Vec<SceneMesh>> {
    let to_sensor = world_to_sensor(world.get_resource::<SensorPlacement>()?);
    // The query's state first (it needs the world mutably), then shared borrows only: the
    // body is read in place, not copied every frame.
    let mut joints = world.query::<(&AvatarJoint, &GlobalTransform)>();
    let body = world.get_resource::<AvatarBody>()?;
    let skin = world_skin(body, joints.iter(world));
    let mut meshes = vec![SceneMesh {
        positions: skin
            .iter()
            .map(|&p| to_sensor.transform_point3(p))
            .collect(),
        triangles: body.model.triangles.clone(),
        label: Label::Body,
        closed: true,
    }];
    let mut garments = world.query::<&WornGarment>();
    // The twin's garment is not in front of the camera: the person is.
    for garment in garments.iter(world).filter(|g| !g.is_twin()) {
        let (positions, _) = garment.surface();
        if positions.is_empty() {
            continue;
        }
        meshes.push(SceneMesh {
            positions: positions
                .iter()
                .map(|&p| to_sensor.transform_point3(p))
                .collect(),
            triangles: garment.triangles().to_vec(),
            label: Label::Garment,
            closed: false,
        });
    }
    Some(meshes)
}

/// The avatar's 20 Kinect joints, sensor space, in [`KinectJoint::ALL`] order (`None`
/// before its joints exist or when the rig lacks one).
pub fn avatar_kinect_joints(world: &mut World) -> Option<Vec<Vec3>> {
    let to_sensor = world_to_sensor(world.get_resource::<SensorPlacement>()?);
    let mut query = world.query::<(&AvatarJoint, &Name, &GlobalTransform)>();
    let by_name: std::collections::HashMap<&str, Vec3> = query
        .iter(world)
        .map(|(_, name, t)| (name.as_str(), t.translation()))
        .collect();
    let mut out = Vec::with_capacity(20);
    for (joint, bone) in JOINT_BONES {
        let mut p = *by_name.get(bone)?;
        if joint == KinectJoint::Head {
            p = head_joint(p, *by_name.get("neck_01")?);
        }
        out.push(to_sensor.transform_point3(p));
    }
    Some(out)
}

/// The ground truth of `frame`, the `index`-th of its stream, with the avatar's joints.
pub fn frame_truth(index: usize, frame: &SyntheticFrame, joints: &[Vec3]) -> FrameTruth {
    FrameTruth {
        frame: index,
        time_s: frame.frame.time_s,
        timestamp: frame.frame.timestamp,
        joints: joints.iter().map(|p| p.to_array()).collect(),
        body_runs: runs_of(&frame.labels, Label::Body as u8),
        garment_runs: runs_of(&frame.labels, Label::Garment as u8),
    }
}
