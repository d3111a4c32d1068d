//! The carousel's thumbnails: each garment of the kiosk configuration drawn draped on the
//! avatar ([`crate::thumbnail`]) on a background task, drawn anew when its file (or fabric)
//! changes or the configuration's list does, and handed to egui as a texture. A garment that
//! cannot be drawn keeps its name in the carousel and says why in the log.

use std::path::PathBuf;

use bevy::asset::{AssetLoadFailedEvent, RenderAssetUsages};
use bevy::prelude::*;
use bevy::render::render_resource::{Extent3d, TextureDimension, TextureFormat};
use bevy::tasks::{AsyncComputeTaskPool, Task, block_on};
use bevy_egui::{EguiContexts, EguiTextureHandle, egui};
use fitroom_body::plugin::AvatarBody;
use fitroom_garment::asset::{GarmentAsset, garment_asset_path};
use fitroom_garment::plugin::GarmentRoot;

use super::config::ActiveKioskConfig;
use crate::thumbnail::{Thumbnail, garment_thumbnail};

/// Thumbnails' side, pixels.
pub const SIDE: usize = 72;

/// One garment's thumbnail, by the configuration's order.
pub struct Entry {
    pub file: PathBuf,
    handle: Option<Handle<GarmentAsset>>,
    state: State,
}

enum State {
    /// The garment is loading (or must be drawn anew).
    Waiting,
    Drawing(Task<Result<Thumbnail, String>>),
    Ready(egui::TextureId, Handle<Image>),
    Failed,
}

/// The thumbnails of the configuration's garments.
#[derive(Resource, Default)]
pub struct Thumbnails {
    pub entries: Vec<Entry>,
}

impl Thumbnails {
    /// The texture of garment `index`, once drawn.
    pub fn texture(&self, index: usize) -> Option<egui::TextureId> {
        match self.entries.get(index).map(|e| &e.state) {
            Some(State::Ready(id, _)) => Some(*id),
            _ => None,
        }
    }
}

/// Loads, draws and follows the configuration's garments' thumbnails.
#[allow(clippy::too_many_arguments)]
pub(super) fn follow_thumbnails(
    mut thumbnails: ResMut<Thumbnails>,
    config: Res<ActiveKioskConfig>,
    root: Option<Res<GarmentRoot>>,
    server: Res<AssetServer>,
    garments: Res<Assets<GarmentAsset>>,
    body: Option<Res<AvatarBody>>,
    mut images: ResMut<Assets<Image>>,
    mut events: MessageReader<AssetEvent<GarmentAsset>>,
    mut failures: MessageReader<AssetLoadFailedEvent<GarmentAsset>>,
    mut contexts: EguiContexts,
) {
    let (Some(root), Some(body)) = (root, body) else {
        return;
    };
    // The list is looked at when the configuration changed (an edit) or none is kept yet.
    if config.is_changed() || thumbnails.entries.is_empty() {
        let files: Vec<PathBuf> = config
            .config
            .garments
            .iter()
            .map(|g| config.folder.join(&g.file))
            .collect();
        if thumbnails.entries.iter().map(|e| &e.file).ne(files.iter()) {
            for entry in &thumbnails.entries {
                if let State::Ready(_, image) = &entry.state {
                    contexts.remove_image(image);
                }
            }
            thumbnails.entries = files
                .into_iter()
                .map(|file| Entry {
                    handle: garment_asset_path(&root.0, &file)
                        .map(|path| server.load(path))
                        .inspect_err(|e| warn!("no thumbnail: {e}"))
                        .ok(),
                    file,
                    state: State::Waiting,
                })
                .collect();
        }
    }
    for event in events.read() {
        if let AssetEvent::Modified { id } = event {
            for entry in &mut thumbnails.entries {
                if entry.handle.as_ref().is_some_and(|h| h.id() == *id) {
                    if let State::Ready(_, image) = &entry.state {
                        contexts.remove_image(image);
                    }
                    entry.state = State::Waiting;
                }
            }
        }
    }
    for failure in failures.read() {
        for entry in &mut thumbnails.entries {
            if entry.handle.as_ref().is_some_and(|h| h.id() == failure.id) {
                entry.state = State::Failed;
            }
        }
    }
    for entry in &mut thumbnails.entries {
        match &mut entry.state {
            State::Waiting => {
                let Some(source) = entry.handle.as_ref().and_then(|h| garments.get(h)) else {
                    continue;
                };
                let (source, body) = (source.0.clone(), body.clone());
                entry.state = State::Drawing(
                    AsyncComputeTaskPool::get()
                        .spawn(async move { garment_thumbnail(&source, &body, None, SIDE) }),
                );
            }
            State::Drawing(task) if task.is_finished() => {
                let State::Drawing(task) = std::mem::replace(&mut entry.state, State::Failed)
                else {
                    continue;
                };
                match block_on(task) {
                    Ok(thumbnail) => {
                        let image = Image::new(
                            Extent3d {
                                width: thumbnail.side as u32,
                                height: thumbnail.side as u32,
                                depth_or_array_layers: 1,
                            },
                            TextureDimension::D2,
                            thumbnail.rgba,
                            TextureFormat::Rgba8UnormSrgb,
                            RenderAssetUsages::default(),
                        );
                        let handle = images.add(image);
                        let id = contexts.add_image(EguiTextureHandle::Strong(handle.clone()));
                        entry.state = State::Ready(id, handle);
                    }
                    Err(e) => warn!("no thumbnail of {}: {e}", entry.file.display()),
                }
            }
            _ => {}
        }
    }
}
