//! The avatar's twin: a second avatar beside the first, posed as it is every frame, so two
//! sizes of a garment can be seen side by side (the garment plugin dresses it).
//!
//! Present while the [`TwinAvatar`] resource is: inserting it spawns a copy of the avatar's
//! joint hierarchy under a [`TwinRoot`] placed `offset` (world space) from the avatar, and a
//! skin drawn from the same mesh, material and bind poses through those joints; removing it
//! despawns them. Each frame, after the pose is written and before transforms propagate, the
//! twin's joints take the avatar's local transforms, so the twin moves in the same frame and
//! the renderer skins it like any skinned mesh. The twin has no [`AvatarJoint`]s: everything
//! that reads the avatar's pose (cloth, measurement, depth camera) sees the avatar only.

use bevy::{
    camera::visibility::DynamicSkinnedMeshBounds, mesh::skinning::SkinnedMesh, prelude::*,
    transform::TransformSystems,
};
use fitroom_schedule::FitroomSystems;

use crate::plugin::{Avatar, AvatarJoint, AvatarSkin};

/// Show a twin of the avatar, `offset` (metres, world space) from it.
#[derive(Resource, Debug, Clone, Copy, PartialEq)]
pub struct TwinAvatar {
    pub offset: Vec3,
}

/// The twin's root: where the avatar's root is, moved by the offset.
#[derive(Component)]
pub struct TwinRoot;

/// A joint of the twin: bone index, as [`AvatarJoint`].
#[derive(Component, Debug, Clone, Copy)]
pub struct TwinJoint(pub usize);

/// The twin's skin.
#[derive(Component)]
pub struct TwinSkin;

pub(crate) fn add(app: &mut App) {
    app.add_systems(
        PostUpdate,
        (spawn_or_despawn_twin, follow_avatar)
            .chain()
            .after(FitroomSystems::Pose)
            .before(TransformSystems::Propagate),
    );
}

/// Spawns the twin when [`TwinAvatar`] appears (and the avatar exists), despawns it when
/// the resource goes.
fn spawn_or_despawn_twin(
    mut commands: Commands,
    twin: Option<Res<TwinAvatar>>,
    roots: Query<Entity, With<TwinRoot>>,
    avatar: Query<&Transform, (With<Avatar>, Without<TwinRoot>)>,
    joints: Query<(Entity, &AvatarJoint, &Transform, &ChildOf)>,
    skin: Query<(&Mesh3d, &MeshMaterial3d<StandardMaterial>, &SkinnedMesh), With<AvatarSkin>>,
) {
    let exists = !roots.is_empty();
    match (twin, exists) {
        (None, true) => {
            for root in &roots {
                commands.entity(root).despawn();
            }
        }
        (Some(twin), false) => {
            let Ok(avatar) = avatar.single() else {
                return;
            };
            let root = commands
                .spawn((
                    TwinRoot,
                    Name::new("twin avatar"),
                    avatar.with_translation(avatar.translation + twin.offset),
                    Visibility::default(),
                ))
                .id();
            // The avatar's joints by bone index, with their parent's entity.
            let mut bones: Vec<(usize, Entity, Transform, Entity)> = joints
                .iter()
                .map(|(e, j, t, parent)| (j.0, e, *t, parent.parent()))
                .collect();
            bones.sort_by_key(|b| b.0);
            let mut twin_of = std::collections::HashMap::with_capacity(bones.len());
            let mut twin_joints = Vec::with_capacity(bones.len());
            for &(bone, original, transform, _) in &bones {
                let joint = commands
                    .spawn((TwinJoint(bone), transform, Visibility::default()))
                    .id();
                twin_of.insert(original, joint);
                twin_joints.push(joint);
            }
            // The same hierarchy: a joint whose parent is a joint hangs from that joint's
            // twin, the others from the root.
            for &(_, original, _, parent) in &bones {
                if let Some(&joint) = twin_of.get(&original) {
                    let parent = twin_of.get(&parent).copied().unwrap_or(root);
                    commands.entity(parent).add_child(joint);
                }
            }
            let parts = skin.single().ok().map(|(mesh, material, skinned)| {
                (
                    mesh.clone(),
                    material.clone(),
                    SkinnedMesh {
                        inverse_bindposes: skinned.inverse_bindposes.clone(),
                        // The skin's joints in the skin's order, as their twins.
                        joints: skinned
                            .joints
                            .iter()
                            .filter_map(|j| twin_of.get(j).copied())
                            .collect(),
                    },
                )
            });
            if let Some((mesh, material, skinned)) = parts
                && skinned.joints.len() == twin_joints.len()
            {
                let skin = commands
                    .spawn((TwinSkin, mesh, material, skinned, DynamicSkinnedMeshBounds))
                    .id();
                commands.entity(root).add_child(skin);
            }
        }
        _ => {}
    }
}

/// The twin takes the avatar's pose (its joints' local transforms, its root's placement) and
/// the avatar's mesh and bind poses when they were replaced (a reshaped body).
#[allow(clippy::type_complexity, clippy::too_many_arguments)]
fn follow_avatar(
    twin: Option<Res<TwinAvatar>>,
    avatar: Query<&Transform, (With<Avatar>, Without<TwinRoot>, Without<TwinJoint>)>,
    mut root: Query<&mut Transform, (With<TwinRoot>, Without<Avatar>, Without<TwinJoint>)>,
    joints: Query<(&AvatarJoint, &Transform), (Without<TwinJoint>, Without<TwinRoot>)>,
    mut twin_joints: Query<(&TwinJoint, &mut Transform), (Without<AvatarJoint>, Without<TwinRoot>)>,
    skin: Query<(&Mesh3d, &SkinnedMesh), (With<AvatarSkin>, Without<TwinSkin>)>,
    mut twin_skin: Query<(&mut Mesh3d, &mut SkinnedMesh), (With<TwinSkin>, Without<AvatarSkin>)>,
    mut local: Local<Vec<Option<Transform>>>,
) {
    let Some(twin) = twin else {
        return;
    };
    if let (Ok(avatar), Ok(mut root)) = (avatar.single(), root.single_mut()) {
        *root = avatar.with_translation(avatar.translation + twin.offset);
    }
    // The avatar's local transforms by bone (the buffer kept from frame to frame).
    local.clear();
    for (joint, transform) in &joints {
        if local.len() <= joint.0 {
            local.resize(joint.0 + 1, None);
        }
        local[joint.0] = Some(*transform);
    }
    for (joint, mut transform) in &mut twin_joints {
        if let Some(Some(t)) = local.get(joint.0) {
            // Written only when it moved, so change detection stays meaningful.
            if *transform != *t {
                *transform = *t;
            }
        }
    }
    if let (Ok((mesh, skinned)), Ok((mut twin_mesh, mut twin_skinned))) =
        (skin.single(), twin_skin.single_mut())
    {
        if twin_mesh.0 != mesh.0 {
            twin_mesh.0 = mesh.0.clone();
        }
        if twin_skinned.inverse_bindposes != skinned.inverse_bindposes {
            twin_skinned.inverse_bindposes = skinned.inverse_bindposes.clone();
        }
    }
}
