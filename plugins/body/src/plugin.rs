//! Bevy adapter: spawns the skinned avatar from a [`BodyModel`].
//!
//! Entity layout: an [`Avatar`] entity whose `Transform` maps sensor space to the world, with
//! one child entity per bone ([`AvatarJoint`], hierarchy as in the rig, transforms in sensor
//! space) and the skinned mesh. At rest every joint sits where the model's rest pose puts it,
//! turned to face the sensor; the motion plugin writes joint rotations each frame.
//!
//! The avatar's body shape is the [`AvatarShape`] resource: changing it reshapes the avatar
//! live (morph targets, normals, the skeleton's rest pose and the skin's bind poses, ~1.3 ms)
//! and re-measures it into [`AvatarMeasurements`].
//!
//! [`HiddenSkin`] marks the body vertices a garment covers (the garment plugin sets it): the
//! skin's triangles whose three vertices are all covered are left out of the mesh drawn.

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
use fitroom_schedule::FitroomSystems;
use glam::Affine3A;

use crate::{BodyModel, MODEL_TO_SENSOR, Measurements, RestPose, Shape, ShapedBody};

/// The loaded body: the model, the shaped vertex positions (all of the model's vertices) and
/// normals (body vertices), and the rest pose derived from them.
#[derive(Resource, Clone)]
pub struct AvatarBody {
    pub model: Arc<BodyModel>,
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    pub rest: RestPose,
}

impl AvatarBody {
    /// The model with its base mesh (MakeHuman's default body).
    pub fn unshaped(model: Arc<BodyModel>) -> Self {
        let rest = model.rest_pose(&model.positions);
        let n = model.body_vertex_count as usize;
        let normals = crate::rig::compute_normals(&model.positions[..n], &model.triangles);
        Self {
            positions: model.positions.clone(),
            normals,
            rest,
            model,
        }
    }

    /// The model morphed to a shape.
    pub fn shaped(model: Arc<BodyModel>, shaped: ShapedBody) -> Self {
        Self {
            positions: shaped.positions,
            normals: shaped.normals,
            rest: shaped.rest_pose,
            model,
        }
    }
}

/// Systems of the body plugin.
#[derive(SystemSet, Debug, Clone, PartialEq, Eq, Hash)]
pub enum BodySystems {
    /// Follows an edited body file ([`crate::reload`]; before the reshape it triggers).
    Load,
    /// Applies a changed [`AvatarShape`] (then [`AvatarBody`] has changed too).
    Reshape,
    /// Leaves the skin a garment covers out of the drawn mesh ([`HiddenSkin`]).
    HideCoveredSkin,
}

/// The avatar's body shape; change it to reshape the avatar.
#[derive(Resource, Debug, Clone, Default, PartialEq)]
pub struct AvatarShape(pub Shape);

/// The measurements of the avatar's current shape (`None` until measured, or if the body
/// cannot be measured: then `error` says why).
#[derive(Resource, Debug, Clone, Default)]
pub struct AvatarMeasurements {
    pub measurements: Option<Measurements>,
    pub error: Option<String>,
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

/// Per body vertex, whether a garment covers it (`None`: nothing is covered). The skin's
/// triangles whose three vertices are covered are not drawn, so that the body cannot show
/// through the garment where the cloth, resting on colliders inside the skin, lies under it.
#[derive(Resource, Debug, Clone, Default, PartialEq)]
pub struct HiddenSkin(pub Option<Vec<bool>>);

/// Where the avatar stands: the sensor-to-world transform (live-editable).
#[derive(Resource, Debug, Clone, Copy, Reflect)]
#[reflect(Resource)]
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
        fitroom_schedule::ensure(app);
        app.insert_resource(BodyRenderSettings {
            render_mesh: self.render_mesh,
        })
        .init_resource::<SensorPlacement>()
        .register_type::<SensorPlacement>()
        .init_resource::<AvatarShape>()
        .init_resource::<AvatarMeasurements>()
        .init_resource::<HiddenSkin>()
        .add_systems(Startup, (spawn_avatar, measure_avatar))
        .configure_sets(
            PostUpdate,
            (
                BodySystems::Load,
                BodySystems::Reshape,
                BodySystems::HideCoveredSkin,
            )
                .chain()
                .in_set(FitroomSystems::Pose),
        )
        .add_systems(
            PostUpdate,
            (
                reshape_avatar
                    .run_if(resource_exists_and_changed::<AvatarShape>)
                    .in_set(BodySystems::Reshape),
                hide_covered_skin.in_set(BodySystems::HideCoveredSkin),
            ),
        );
        crate::twin::add(app);
    }
}

/// The avatar's skinning transforms, rest model space to world, from the world transforms of its
/// joint entities (bones without an entity keep the identity).
pub fn world_skinning<'a>(
    body: &AvatarBody,
    joints: impl IntoIterator<Item = (&'a AvatarJoint, &'a GlobalTransform)>,
) -> Vec<Affine3A> {
    let mut out = vec![Affine3A::IDENTITY; body.model.bones.len()];
    for (joint, global) in joints {
        let i = joint.0;
        if let (Some(slot), Some(&r), Some(&h)) = (
            out.get_mut(i),
            body.rest.rotations.get(i),
            body.rest.heads.get(i),
        ) {
            *slot = global.affine() * Affine3A::from_rotation_translation(r, h).inverse();
        }
    }
    out
}

/// The avatar's skin (its body vertices, not the helpers) in world space, posed as its joint
/// entities are: what a depth camera sees of it.
pub fn world_skin<'a>(
    body: &AvatarBody,
    joints: impl IntoIterator<Item = (&'a AvatarJoint, &'a GlobalTransform)>,
) -> Vec<Vec3> {
    let n = (body.model.body_vertex_count as usize).min(body.positions.len());
    crate::skin_with_matrices(
        &body.positions[..n],
        &body.model.skin_joints,
        &body.model.skin_weights,
        &world_skinning(body, joints),
    )
}

/// Builds the render mesh of the body (body vertices only) with skin attributes.
pub fn body_mesh(body: &AvatarBody) -> Result<Mesh, String> {
    let model = &body.model;
    let n = model.body_vertex_count as usize;
    let positions: Vec<[f32; 3]> = body.positions[..n].iter().map(|p| p.to_array()).collect();
    let normals: Vec<[f32; 3]> = body.normals.iter().map(|v| v.to_array()).collect();
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
        let transform = joint_rest_transform(model, rest, i);
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
    let mesh = match body_mesh(&body) {
        Ok(mesh) => mesh,
        Err(message) => {
            error!("{message}");
            return;
        }
    };
    let inverse_bindposes = inverse_bindposes(rest);
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

/// The body's triangles (vertex indices) less those whose three vertices `hidden` marks.
pub fn visible_skin_indices(model: &BodyModel, hidden: Option<&[bool]>) -> Vec<u32> {
    let covered = |v: u32| {
        hidden
            .and_then(|h| h.get(v as usize))
            .copied()
            .unwrap_or(false)
    };
    model
        .triangles
        .iter()
        .filter(|t| !t.iter().all(|&v| covered(v)))
        .flatten()
        .copied()
        .collect()
}

/// Applies [`HiddenSkin`] to the skin's mesh when it changes or the mesh is replaced (a
/// reshaped avatar).
fn hide_covered_skin(
    hidden: Res<HiddenSkin>,
    body: Option<Res<AvatarBody>>,
    skins: Query<Ref<Mesh3d>, With<AvatarSkin>>,
    mut meshes: Option<ResMut<Assets<Mesh>>>,
) {
    let (Some(body), Some(meshes)) = (body, meshes.as_mut()) else {
        return;
    };
    for mesh3d in &skins {
        if !(hidden.is_changed() || mesh3d.is_changed()) {
            continue;
        }
        if let Some(mut mesh) = meshes.get_mut(&mesh3d.0) {
            let indices = visible_skin_indices(&body.model, hidden.0.as_deref());
            mesh.insert_indices(Indices::U32(indices));
        }
    }
}

/// The skin's inverse bind poses for a rest pose (model space).
fn inverse_bindposes(rest: &RestPose) -> Vec<Mat4> {
    rest.rotations
        .iter()
        .zip(&rest.heads)
        .map(|(&r, &h)| Mat4::from_rotation_translation(r, h).inverse())
        .collect()
}

/// The joints' rest transforms (sensor space, relative to the parent) of a rest pose.
fn joint_rest_transform(model: &BodyModel, rest: &RestPose, i: usize) -> Transform {
    let sensor_head = MODEL_TO_SENSOR * rest.heads[i];
    let sensor_rot = MODEL_TO_SENSOR * rest.rotations[i];
    match model.bones[i].parent {
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
    }
}

fn measure_avatar(body: Option<Res<AvatarBody>>, mut out: ResMut<AvatarMeasurements>) {
    let Some(body) = body else {
        return;
    };
    *out = match body.model.measure(&body.positions) {
        Ok(m) => AvatarMeasurements {
            measurements: Some(m),
            error: None,
        },
        Err(e) => AvatarMeasurements {
            measurements: None,
            error: Some(e.to_string()),
        },
    };
}

/// Applies a changed [`AvatarShape`]: the body is morphed and re-measured, the skeleton's rest
/// pose re-derived, and the skin's mesh and bind poses replaced. An invalid shape (out of
/// range, unknown slider) keeps the current body and says why in [`AvatarMeasurements`].
#[allow(clippy::too_many_arguments)]
fn reshape_avatar(
    shape: Res<AvatarShape>,
    body: Option<ResMut<AvatarBody>>,
    mut measured: ResMut<AvatarMeasurements>,
    mut joints: Query<(&AvatarJoint, &mut Transform)>,
    mut skins: Query<(&mut Mesh3d, &mut SkinnedMesh), With<AvatarSkin>>,
    mut meshes: Option<ResMut<Assets<Mesh>>>,
    mut bindposes: Option<ResMut<Assets<SkinnedMeshInverseBindposes>>>,
) {
    let Some(mut body) = body else {
        return;
    };
    let shaped = match body.model.shaped(&shape.0) {
        Ok(s) => s,
        Err(e) => {
            warn!("the avatar keeps its shape: {e}");
            measured.error = Some(format!("shape not applied: {e}"));
            return;
        }
    };
    let model = body.model.clone();
    *body = AvatarBody::shaped(model.clone(), shaped);
    for (joint, mut transform) in &mut joints {
        if joint.0 < model.bones.len() {
            *transform = joint_rest_transform(&model, &body.rest, joint.0);
        }
    }
    if let (Some(meshes), Some(bindposes)) = (meshes.as_mut(), bindposes.as_mut()) {
        for (mut mesh3d, mut skin) in &mut skins {
            match body_mesh(&body) {
                Ok(mesh) => mesh3d.0 = meshes.add(mesh),
                Err(message) => error!("{message}"),
            }
            skin.inverse_bindposes = bindposes.add(inverse_bindposes(&body.rest));
        }
    }
    *measured = match model.measure(&body.positions) {
        Ok(m) => AvatarMeasurements {
            measurements: Some(m),
            error: None,
        },
        Err(e) => AvatarMeasurements {
            measurements: None,
            error: Some(e.to_string()),
        },
    };
}
