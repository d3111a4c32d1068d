//! Garments for fitroom: fabrics as data, sewing patterns turned into cloth meshes placed on
//! the body, and mesh garments (OBJ + MTL, glTF), all producing one [`GarmentMesh`] that the
//! cloth core ([`fitroom_cloth`]) simulates.
//!
//! The thesis this product starts from (seed 000 §3.2) dressed its avatar in a mesh garment
//! split in two: a **static part** skinned with the body (the bodice of a dress) and a
//! **simulated part** attached to it just above the waist (the skirt), marked in the mesh by
//! its material. This crate keeps that split for mesh garments ([`mesh_garment`]: the `Free`
//! material suffix, or a per-vertex attachment weight in glTF) and adds garments made the way
//! clothes are made: flat panels cut from a fabric and sewn together ([`pattern`]), sized
//! from a size chart as in seed 002 (EN 13402).
//!
//! - [`fabric`]: fabric files in SI units with their sources -> [`fitroom_cloth::Fabric`].
//! - [`pattern`]: the garment file: panels, seams, wraps, attachments, sizes and grading.
//! - [`mesher`]: constrained Delaunay triangulation with refinement (`spade`).
//! - [`placement`]: panels wound around the body on tubes that follow its cross-sections.
//! - [`garment`]: building a size on a body, sewing (vertex pairs, pre-simulation, welding),
//!   and the [`GarmentMesh`].
//! - [`binding`]: attached vertices bound to body triangles; skin weights for the static part.
//! - [`body`]: the shaped body surface, its landmarks and regions, nearest-triangle queries.
//! - [`files`], [`source`]: one way to read any garment file with the files it names (from
//!   disk, or fetched by the asset loader), and to build it on a body.
//! - [`sim`]: a garment simulated on the posed body (cloth solver, body colliders, blow-up
//!   reset, strain and gap).
//! - `plugin` (feature `plugin`): the Bevy adapter: the garment the avatar wears.
//!
//! # Example
//!
//! ```no_run
//! use fitroom_body::{BodyModel, Shape};
//! use fitroom_garment::{BodySurface, BuildOptions, Pattern};
//!
//! let model = BodyModel::read("assets/bodies/makehuman.fitbody".as_ref())?;
//! let shaped = model.shaped(&Shape::default())?;
//! let body = BodySurface::new(&model, &shaped)?;
//! let pattern = Pattern::load("assets/garments/skirt.ron")?;
//! let skirt = pattern.build(&body, "M", &BuildOptions::default())?.welded(&body)?;
//! let cloth = skirt.cloth_mesh()?;                       // for fitroom_cloth::ClothSolver
//! let targets = skirt.binding.positions(&shaped.positions, &shaped.normals); // pins
//! assert_eq!(targets.len(), skirt.attached.len());
//! # let _ = cloth;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! # Units and frames
//!
//! Patterns are drawn in centimetres (x across, y up, counter-clockwise seen from outside);
//! everything placed is in the body's model space: metres, +Y up, the body faces +Z, +X is
//! the wearer's left.

#![forbid(unsafe_code)]

#[cfg(feature = "plugin")]
pub mod asset;
pub mod binding;
pub mod body;
pub mod cover;
pub mod ease;
pub mod error;
pub mod fabric;
pub mod files;
pub mod garment;
pub mod mesh_garment;
pub mod mesher;
pub mod pattern;
pub mod placement;
#[cfg(feature = "plugin")]
pub mod plugin;
pub mod sim;
pub mod source;

pub use binding::{Binding, BoundVertex, skin_weights_for};
pub use body::{BodyPart, BodySurface, Landmark, Region, SurfacePoint};
pub use error::GarmentError;
pub use fabric::{FabricSpec, load_fabric};
pub use files::{DiskFiles, FetchedFiles, GarmentFiles};
pub use garment::{BuildOptions, GarmentMesh, SeamLine, SewReport};
pub use mesh_garment::{AttachChannel, load_gltf, load_obj, write_glb, write_obj};
pub use pattern::{Axis, Pattern};
pub use placement::RowReport;
pub use source::{GarmentFormat, GarmentSource};
