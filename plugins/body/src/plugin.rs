//! Bevy adapter: spawns the skinned avatar from a [`BodyModel`].
//!
//! Entity layout: an [`Avatar`] entity whose `Transform` maps sensor space to the world, with
//! one child entity per bone ([`AvatarJoint`], hierarchy as in the rig, transforms in sensor
//! space) and the skinned mesh. At rest every joint sits where the model's rest pose puts it,
//! turned to face the sensor; the motion plugin writes joint rotations each frame.

use std::sync::Arc;

use bevy::{
    asset::RenderAssetUsages,
    camera::visibility::DynamicSkinnedMeshBounds,
    mesh::{
        Indices, PrimitiveTopology, VertexAttributeValues,
        skinning::{SkinnedMesh, SkinnedMeshInverseBindposes},
    },
    prelude::*,
};

use crate::{BodyModel, MODEL_TO_SENSOR, RestPose};

/// The loaded body: the model and its rest pose.
#[derive(Resource, Clone)]
pub struct AvatarBody {
    pub model: Arc<BodyModel>,
    pub rest: RestPose,
}

/// The avatar's root; its `Transform` is the sensor-to-world transform.
#[derive(Component, Debug)]
pub struct Avatar;

/// A bone of the avatar, by index into [`BodyModel::bones`].
#[derive(Component, Debug, Clone, Copy, PartialEq, Eq)]
pub struct AvatarJoint(pub usize);

/// The avatar's skinned mesh.
#[derive(Component, Debug)]
pub struct AvatarSkin;

/// Where the avatar stands: the sensor-to-world transform.
#[derive(Resource, Debug, Clone, Copy)]
pub struct SensorPlacement {
    /// Height of the sensor above the floor, metres.
    pub sensor_height_m: f32,
}

impl Default for SensorPlacement {
    fn default() -> Self {
        Self {
            sensor_height_m: 0.8,
        }
    }
}

impl SensorPlacement {
    /// World space: +Y up, floor at y = 0, the sensor at the origin's vertical looking along
    /// world -Z. Sensor space looks along its +Z, so the two differ by a half turn about +Y.
    pub fn sensor_to_world(&self) -> Transform {
        Transform {
            translation: Vec3::new(0.0, self.sensor_height_m, 0.0),
            rotation: Quat::from_rotation_y(std::f32::consts::PI),
            scale: Vec3::ONE,
        }
    }
}

/// Settings of the body plugin.
#[derive(Resource, Debug, Clone, Copy)]
pub struct BodyRenderSettings {
    /// Spawn the skinned mesh (off in headless runs without a renderer).
    pub render_mesh: bool,
}

pub struct BodyPlugin {
    pub render_mesh: bool,
}

impl Plugin for BodyPlugin {
    fn build(&self, app: &mut App) {
        app.insert_resource(BodyRenderSettings {
            render_mesh: self.render_mesh,
        })
        .init_resource::<SensorPlacement>()
        .add_systems(Startup, spawn_avatar);
    }
}

/// Builds the render mesh of the body (body vertices only) with skin attributes.
pub fn body_mesh(model: &BodyModel) -> Result<Mesh, String> {
    let n = model.body_vertex_count as usize;
    let positions: Vec<[f32; 3]> = model.positions[..n].iter().map(|p| p.to_array()).collect();
    let normals: Vec<[f32; 3]> =
        crate::rig::compute_normals(&model.positions[..n], &model.triangles)
            .iter()
            .map(|v| v.to_array())
            .collect();
    let indices: Vec<u32> = model.triangles.iter().flatten().copied().collect();
    let mut mesh = Mesh::new(
        PrimitiveTopology::TriangleList,
        RenderAssetUsages::default(),
    )
    .with_inserted_attribute(Mesh::ATTRIBUTE_POSITION, positions)
    .with_inserted_attribute(Mesh::ATTRIBUTE_NORMAL, normals)
    .with_inserted_attribute(
        Mesh::ATTRIBUTE_JOINT_INDEX,
        VertexAttributeValues::Uint16x4(model.skin_joints.clone()),
    )
    .with_inserted_attribute(Mesh::ATTRIBUTE_JOINT_WEIGHT, model.skin_weights.clone())
    .with_inserted_indices(Indices::U32(indices));
    if model.uvs.len() == n {
        let uvs: Vec<[f32; 2]> = model.uvs.iter().map(|u| u.to_array()).collect();
        mesh.insert_attribute(Mesh::ATTRIBUTE_UV_0, uvs);
    }
    mesh.with_generated_skinned_mesh_bounds()
        .map_err(|e| format!("cannot compute the skinned bounds of the body mesh: {e}"))
}

#[allow(clippy::too_many_arguments)]
fn spawn_avatar(
    mut commands: Commands,
    body: Option<Res<AvatarBody>>,
    settings: Res<BodyRenderSettings>,
    placement: Res<SensorPlacement>,
    mut meshes: Option<ResMut<Assets<Mesh>>>,
    mut materials: Option<ResMut<Assets<StandardMaterial>>>,
    mut bindposes: Option<ResMut<Assets<SkinnedMeshInverseBindposes>>>,
) {
    let Some(body) = body else {
        error!("no body loaded: the avatar is not spawned");
        return;
    };
    let model = &body.model;
    let rest = &body.rest;
    let avatar = commands
        .spawn((Avatar, placement.sensor_to_world(), Visibility::default()))
        .id();

    // Joint entities, parents first.
    let mut joints: Vec<Entity> = Vec::with_capacity(model.bones.len());
    for (i, bone) in model.bones.iter().enumerate() {
        let sensor_head = MODEL_TO_SENSOR * rest.heads[i];
        let sensor_rot = MODEL_TO_SENSOR * rest.rotations[i];
        let transform = match bone.parent {
            Some(p) if p < i => {
                let parent_rot = MODEL_TO_SENSOR * rest.rotations[p];
                let parent_head = MODEL_TO_SENSOR * rest.heads[p];
                Transform {
                    translation: parent_rot.inverse() * (sensor_head - parent_head),
                    rotation: (parent_rot.inverse() * sensor_rot).normalize(),
                    scale: Vec3::ONE,
                }
            }
            _ => Transform::from_translation(sensor_head).with_rotation(sensor_rot),
        };
        let parent_entity = match bone.parent {
            Some(p) if p < i => joints[p],
            _ => avatar,
        };
        let joint = commands
            .spawn((AvatarJoint(i), Name::new(bone.name.clone()), transform))
            .id();
        commands.entity(parent_entity).add_child(joint);
        joints.push(joint);
    }

    if !settings.render_mesh {
        return;
    }
    let (Some(meshes), Some(materials), Some(bindposes)) =
        (meshes.as_mut(), materials.as_mut(), bindposes.as_mut())
    else {
        error!("the body plugin was asked to render but the renderer's assets are missing");
        return;
    };
    let mesh = match body_mesh(model) {
        Ok(mesh) => mesh,
        Err(message) => {
            error!("{message}");
            return;
        }
    };
    let inverse_bindposes: Vec<Mat4> = (0..model.bones.len())
        .map(|i| Mat4::from_rotation_translation(rest.rotations[i], rest.heads[i]).inverse())
        .collect();
    let skin = commands
        .spawn((
            AvatarSkin,
            Mesh3d(meshes.add(mesh)),
            MeshMaterial3d(materials.add(StandardMaterial {
                base_color: Color::srgb(0.80, 0.62, 0.52),
                perceptual_roughness: 0.65,
                reflectance: 0.35,
                ..default()
            })),
            SkinnedMesh {
                inverse_bindposes: bindposes.add(inverse_bindposes),
                joints: joints.clone(),
            },
            DynamicSkinnedMeshBounds,
        ))
        .id();
    commands.entity(avatar).add_child(skin);
}
