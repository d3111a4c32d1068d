//! Garments, fabrics and size charts as Bevy assets.
//!
//! [`GarmentLoader`] reads a garment file of any kind ([`GarmentSource`]: pattern `.ron`,
//! `.obj` + MTL, `.glb`/`.gltf`) through the asset server. The files a garment names (its
//! fabric, its size chart, an MTL file, glTF buffers) are read through the same load, so they
//! are the garment's loader dependencies: with Bevy's `file_watcher`, saving the garment *or
//! only its fabric* reloads the garment. A load that fails leaves the last good
//! [`GarmentAsset`] in place; the asset server reports the failure (file, line, field) as an
//! `AssetLoadFailedEvent`, which the plugin shows.
//!
//! Garments are read from the asset source [`GARMENT_SOURCE`], a folder on disk with the
//! product's layout (`garments/`, `fabrics/`, `sizecharts/`); [`register_garment_source`]
//! names that folder, before the `AssetPlugin` is added.

use std::path::{Path, PathBuf};

use bevy::asset::io::{AssetSourceBuilder, Reader};
use bevy::asset::{AssetLoader, AssetPath, LoadContext};
use bevy::prelude::*;
use fitroom_body::sizing::{SizeChart, SizeChartError};

use crate::error::GarmentError;
use crate::fabric::FabricSpec;
use crate::files::{FetchedFiles, normalize};
use crate::source::GarmentSource;

/// The name of the asset source garments are read from.
pub const GARMENT_SOURCE: &str = "garments";

/// Names the folder garments, fabrics and size charts are read from (the product's
/// `assets/`, or a designer's own folder with the same layout). Call before adding the
/// `AssetPlugin` (`DefaultPlugins`).
pub fn register_garment_source(app: &mut App, root: &Path) {
    app.register_asset_source(
        GARMENT_SOURCE,
        AssetSourceBuilder::platform_default(&root.to_string_lossy(), None),
    );
}

/// The asset path of a garment file under `root` (the folder of [`register_garment_source`]),
/// or why it cannot be read from there.
pub fn garment_asset_path(root: &Path, file: &Path) -> Result<AssetPath<'static>, String> {
    let (root_n, file_n) = (normalize(&absolute(root)), normalize(&absolute(file)));
    let relative = file_n.strip_prefix(&root_n).map_err(|_| {
        format!(
            "'{}' is not inside the garment folder '{}' (garments, fabrics and size charts are \
             read from one folder with `garments/`, `fabrics/` and `sizecharts/` in it)",
            file.display(),
            root.display()
        )
    })?;
    Ok(AssetPath::from_path_buf(relative.to_owned()).with_source(GARMENT_SOURCE))
}

fn absolute(path: &Path) -> PathBuf {
    std::path::absolute(path).unwrap_or_else(|_| path.to_owned())
}

/// A garment file read with every file it names.
#[derive(Asset, TypePath, Debug)]
pub struct GarmentAsset(pub GarmentSource);

/// A fabric file.
#[derive(Asset, TypePath, Debug)]
pub struct FabricAsset(pub FabricSpec);

/// A size chart file.
#[derive(Asset, TypePath, Debug)]
pub struct SizeChartAsset(pub SizeChart);

/// Reads garments ([`GarmentSource`]) from the garment folder `root`; errors name the files
/// by their path on disk.
#[derive(TypePath)]
pub struct GarmentLoader {
    pub root: PathBuf,
}

/// Files a garment names are fetched and the garment read again until nothing is missing;
/// a garment names at most a few files (fabric and size chart, or MTL and buffers).
const MAX_FETCH_ROUNDS: usize = 8;

impl AssetLoader for GarmentLoader {
    type Asset = GarmentAsset;
    type Settings = ();
    type Error = GarmentError;

    async fn load(
        &self,
        reader: &mut dyn Reader,
        _settings: &(),
        load_context: &mut LoadContext<'_>,
    ) -> Result<GarmentAsset, GarmentError> {
        let relative = load_context.path().path().to_owned();
        let file = self.root.join(&relative);
        let mut bytes = Vec::new();
        reader
            .read_to_end(&mut bytes)
            .await
            .map_err(|source| GarmentError::Read {
                path: file.clone(),
                source,
            })?;
        let mut files = FetchedFiles::default();
        files.insert(&file, Ok(bytes));
        let source_id = load_context.path().source().clone_owned();
        let root = normalize(&self.root);
        let mut last_error = None;
        for _ in 0..MAX_FETCH_ROUNDS {
            let error = match GarmentSource::read(&file, &files) {
                Ok(source) => return Ok(GarmentAsset(source)),
                Err(e) => e,
            };
            let missing = files.take_missing();
            if missing.is_empty() {
                return Err(error);
            }
            for path in missing {
                let fetched = match path.strip_prefix(&root) {
                    Ok(inside) => {
                        let asset = AssetPath::from_path_buf(inside.to_owned())
                            .with_source(source_id.clone());
                        load_context
                            .read_asset_bytes(asset)
                            .await
                            .map_err(|e| e.to_string())
                    }
                    Err(_) => Err(format!(
                        "outside the garment folder '{}'",
                        self.root.display()
                    )),
                };
                files.insert(&path, fetched);
            }
            last_error = Some(error);
        }
        Err(last_error.unwrap_or(GarmentError::Read {
            path: file,
            source: std::io::Error::other("the garment names too many files"),
        }))
    }

    fn extensions(&self) -> &[&str] {
        &crate::source::GarmentFormat::EXTENSIONS
    }
}

/// Reads fabric files ([`FabricSpec`]).
#[derive(TypePath)]
pub struct FabricLoader {
    pub root: PathBuf,
}

impl AssetLoader for FabricLoader {
    type Asset = FabricAsset;
    type Settings = ();
    type Error = GarmentError;

    async fn load(
        &self,
        reader: &mut dyn Reader,
        _settings: &(),
        load_context: &mut LoadContext<'_>,
    ) -> Result<FabricAsset, GarmentError> {
        let file = self.root.join(load_context.path().path());
        let text = read_text(reader, &file).await?;
        FabricSpec::from_ron_str(&text, &file.display().to_string()).map(FabricAsset)
    }
}

/// Reads size charts ([`SizeChart`]).
#[derive(TypePath)]
pub struct SizeChartLoader {
    pub root: PathBuf,
}

impl AssetLoader for SizeChartLoader {
    type Asset = SizeChartAsset;
    type Settings = ();
    type Error = SizeChartError;

    async fn load(
        &self,
        reader: &mut dyn Reader,
        _settings: &(),
        load_context: &mut LoadContext<'_>,
    ) -> Result<SizeChartAsset, SizeChartError> {
        let file = self.root.join(load_context.path().path());
        let mut bytes = Vec::new();
        reader
            .read_to_end(&mut bytes)
            .await
            .map_err(|source| SizeChartError::Read {
                path: file.clone(),
                source,
            })?;
        let text = String::from_utf8_lossy(&bytes);
        SizeChart::from_ron_str(&text, &file.display().to_string()).map(SizeChartAsset)
    }
}

async fn read_text(reader: &mut dyn Reader, file: &Path) -> Result<String, GarmentError> {
    let mut bytes = Vec::new();
    reader
        .read_to_end(&mut bytes)
        .await
        .map_err(|source| GarmentError::Read {
            path: file.to_owned(),
            source,
        })?;
    String::from_utf8(bytes).map_err(|e| GarmentError::Read {
        path: file.to_owned(),
        source: std::io::Error::new(std::io::ErrorKind::InvalidData, e),
    })
}
