//! The body file through Bevy's asset server: a `.fitbody` is an asset of the `body` source
//! (the body file's folder), so Bevy's file watcher sees it re-imported. A re-imported body
//! with the same rig replaces the avatar's model live: shaped with the current
//! [`AvatarShape`], then re-measured, re-skinned and re-posed by the reshape system. A file
//! that does not read, a shape the new model refuses, or a body with another rig (its joint
//! entities would no longer match) keeps the current body and says why in
//! [`BodyFile::error`].
//!
//! The first read stays synchronous (the app's builder reads the body before the first frame:
//! the motion pipeline and the garments are built on its skeleton); this plugin watches it.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use bevy::asset::io::{AssetSourceBuilder, Reader};
use bevy::asset::{AssetLoadFailedEvent, AssetLoader, AssetPath, LoadContext};
use bevy::prelude::*;

use crate::plugin::{AvatarBody, AvatarShape, BodySystems};
use crate::{AssetError, BodyModel};

/// The asset source of the body file's folder.
pub const BODY_SOURCE: &str = "body";

/// Registers [`BODY_SOURCE`] on the folder of `body_file`; call before adding the
/// `AssetPlugin` (Bevy reads the sources when the plugin is built).
pub fn register_body_source(app: &mut App, body_file: &Path) {
    let folder = folder_of(body_file);
    app.register_asset_source(
        BODY_SOURCE,
        AssetSourceBuilder::platform_default(&folder.to_string_lossy(), None),
    );
}

fn folder_of(file: &Path) -> PathBuf {
    match file.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_owned(),
        _ => PathBuf::from("."),
    }
}

/// A body model read by the asset server.
#[derive(Asset, TypePath, Debug)]
pub struct BodyAsset(pub Arc<BodyModel>);

/// Reads `.fitbody` files; `folder` is the source's folder, so that errors name the file on
/// disk.
#[derive(TypePath)]
pub struct BodyLoader {
    pub folder: PathBuf,
}

impl AssetLoader for BodyLoader {
    type Asset = BodyAsset;
    type Settings = ();
    type Error = AssetError;

    async fn load(
        &self,
        reader: &mut dyn Reader,
        _settings: &(),
        load_context: &mut LoadContext<'_>,
    ) -> Result<BodyAsset, AssetError> {
        let path = self.folder.join(load_context.path().path());
        let mut bytes = Vec::new();
        reader
            .read_to_end(&mut bytes)
            .await
            .map_err(|source| AssetError::Io {
                path: path.clone(),
                action: "cannot read",
                source,
            })?;
        Ok(BodyAsset(Arc::new(BodyModel::from_bytes_named(
            &bytes, &path,
        )?)))
    }

    fn extensions(&self) -> &[&str] {
        &["fitbody"]
    }
}

/// The body file the avatar was made from, its asset, and the last reload's error.
#[derive(Resource, Debug)]
pub struct BodyFile {
    pub path: PathBuf,
    pub handle: Handle<BodyAsset>,
    pub error: Option<String>,
}

/// Watches the avatar's body file (registered with [`register_body_source`] first).
pub struct BodyFilePlugin {
    pub file: PathBuf,
}

impl Plugin for BodyFilePlugin {
    fn build(&self, app: &mut App) {
        let file = self.file.clone();
        let name = file
            .file_name()
            .map(PathBuf::from)
            .unwrap_or_else(|| file.clone());
        app.init_asset::<BodyAsset>()
            .register_asset_loader(BodyLoader {
                folder: folder_of(&file),
            })
            .add_systems(
                Startup,
                move |mut commands: Commands, server: Res<AssetServer>| {
                    let path = AssetPath::from_path_buf(name.clone()).with_source(BODY_SOURCE);
                    commands.insert_resource(BodyFile {
                        path: file.clone(),
                        handle: server.load(path),
                        error: None,
                    });
                },
            )
            .add_systems(PostUpdate, follow_body_file.in_set(BodySystems::Load));
    }
}

/// A re-imported body file replaces the avatar's model (see the module documentation).
fn follow_body_file(
    mut events: MessageReader<AssetEvent<BodyAsset>>,
    mut failures: MessageReader<AssetLoadFailedEvent<BodyAsset>>,
    bodies: Res<Assets<BodyAsset>>,
    file: Option<ResMut<BodyFile>>,
    avatar: Option<ResMut<AvatarBody>>,
    mut shape: ResMut<AvatarShape>,
) {
    let (Some(mut file), Some(mut avatar)) = (file, avatar) else {
        events.clear();
        failures.clear();
        return;
    };
    let id = file.handle.id();
    for event in events.read() {
        // The first load is the file the app was built from; only edits count.
        let AssetEvent::Modified { id: e } = event else {
            continue;
        };
        let Some(BodyAsset(model)) = bodies.get(id).filter(|_| *e == id) else {
            continue;
        };
        match replacement(&avatar, model, &shape) {
            Ok(body) => {
                info!("the body file changed: the avatar is made again from it");
                *avatar = body;
                // The reshape that follows re-poses the joints and rebuilds the skin.
                shape.set_changed();
                file.error = None;
            }
            Err(message) => {
                warn!("the avatar keeps its body: {message}");
                file.error = Some(message);
            }
        }
    }
    for failure in failures.read() {
        if failure.id == id {
            // The loader's message is one line; a backtrace may follow.
            let message = failure.error.to_string();
            let message = message.lines().next().unwrap_or_default().to_owned();
            warn!("the avatar keeps its body: {message}");
            file.error = Some(message);
        }
    }
}

/// The avatar made from `model` in the current shape, if its rig matches the spawned one.
fn replacement(
    current: &AvatarBody,
    model: &Arc<BodyModel>,
    shape: &AvatarShape,
) -> Result<AvatarBody, String> {
    let names = |m: &BodyModel| m.bones.iter().map(|b| b.name.clone()).collect::<Vec<_>>();
    if names(model) != names(&current.model) {
        return Err(format!(
            "the new body file has another rig ({} bones, was {}); restart to use it",
            model.bones.len(),
            current.model.bones.len()
        ));
    }
    let shaped = model
        .shaped(&shape.0)
        .map_err(|e| format!("the new body file cannot take the avatar's shape: {e}"))?;
    Ok(AvatarBody::shaped(model.clone(), shaped))
}
