//! Bevy adapter: the garment the avatar wears, simulated on worker threads at a fixed rate
//! (120 Hz by default) within a time budget per frame, drawn with an optional fit map.
//!
//! * [`GarmentRequest`] names the garment file and size. The file is loaded through the asset
//!   server ([`crate::asset`]: patterns, OBJ + MTL and glTF alike); changing the request,
//!   reshaping the avatar, or saving the garment or its fabric (hot reload through Bevy's
//!   `file_watcher`) dresses the avatar again. A file that does not load keeps the garment the
//!   avatar had and puts the error (file, line, field) in [`GarmentStatus`].
//! * Each frame, after transform propagation, the avatar's skinning transforms (joint global
//!   transforms times the inverse bind poses) drive the cloth: as many 120 Hz steps as the
//!   frame's time asks for, interpolating the body between the last frame and this one, but
//!   no more than fit in [`ClothSettings::budget_ms`] (the rest is dropped and counted, so a
//!   slow renderer slows the cloth down instead of stalling the app).
//! * A blow-up resets the garment to its skinned pose and is logged; a panic in the cloth
//!   step (a worker thread's included) takes the garment off with the error in
//!   [`GarmentStatus`], and the app goes on. In debug builds a check asserts that every
//!   position stays finite.
//! * With [`ClothSettings::fit_map`] the garment is coloured by strain (blue: slack, white:
//!   rest length, red: stretched 10% or more), like a CLO3D strain map.
//! * With [`ClothSettings::hide_covered_skin`] (the default) the body's skin that the garment
//!   surely covers is not drawn ([`crate::cover`], [`HiddenSkin`]).
//! * [`GarmentRequest::compare`] dresses the avatar's twin ([`fitroom_body::twin`]) in a second
//!   size: a second simulation on the avatar's own pose, drawn at the twin's offset.

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::PathBuf;
use std::time::Instant;

use bevy::{
    asset::RenderAssetUsages,
    mesh::{Indices, PrimitiveTopology, VertexAttributeValues},
    prelude::*,
};
use fitroom_body::{
    ShapedBody,
    plugin::{AvatarBody, AvatarJoint, HiddenSkin, world_skinning},
    twin::TwinAvatar,
};
use fitroom_cloth::SolverSettings;
use fitroom_schedule::FitroomSystems;
use glam::Affine3A;

use bevy::asset::AssetLoadFailedEvent;

use crate::BodySurface;
use crate::asset::{
    FabricAsset, FabricLoader, GarmentAsset, GarmentLoader, SizeChartAsset, SizeChartLoader,
    garment_asset_path,
};
use crate::sim::{GarmentSim, SimGarment, lerp_affine};

/// Cloth settings (live-editable).
#[derive(Resource, Debug, Clone, Reflect)]
#[reflect(Resource)]
pub struct ClothSettings {
    /// Cloth steps per second.
    pub rate_hz: f32,
    /// Substeps per step.
    pub substeps: u32,
    /// Most CPU time per frame for the cloth, ms.
    pub budget_ms: f32,
    /// Colour the garment by strain.
    pub fit_map: bool,
    /// Leave out the body's skin that the garment covers ([`crate::cover`]).
    pub hide_covered_skin: bool,
}

impl Default for ClothSettings {
    fn default() -> Self {
        Self {
            rate_hz: 120.0,
            substeps: 10,
            budget_ms: 8.0,
            fit_map: false,
            hide_covered_skin: true,
        }
    }
}

/// What the avatar wears: a garment file and a size (`None`: nothing / the middle size).
#[derive(Resource, Debug, Clone, Default, PartialEq)]
pub struct GarmentRequest {
    pub path: Option<PathBuf>,
    pub size: Option<String>,
    /// A second size of the same garment for the avatar's twin (`None`: the twin, if any,
    /// wears nothing).
    pub compare: Option<String>,
}

/// How the garment is doing (for the overlay and tests).
#[derive(Resource, Debug, Clone, Default)]
pub struct GarmentStatus {
    /// `name size` of the garment worn.
    pub worn: Option<String>,
    /// `name size` of the garment the twin wears.
    pub compare_worn: Option<String>,
    /// The garment file worn (or being loaded), and its asset (its size chart, say).
    pub file: Option<PathBuf>,
    pub asset: Option<Handle<GarmentAsset>>,
    pub particles: usize,
    /// The last load error (the garment worn stays).
    pub error: Option<String>,
    pub steps: u64,
    /// Steps the budget dropped.
    pub dropped_steps: u64,
    pub resets: u32,
    /// CPU time of the cloth in the last frame, ms.
    pub frame_ms: f32,
    /// Largest strain now, %.
    pub max_strain_pct: f32,
}

impl GarmentStatus {
    /// The size the avatar wears (the last word of [`Self::worn`]: sizes have no spaces,
    /// names may).
    pub fn worn_size(&self) -> Option<&str> {
        self.worn.as_deref().and_then(size_in)
    }

    /// The size the twin wears.
    pub fn compare_size(&self) -> Option<&str> {
        self.compare_worn.as_deref().and_then(size_in)
    }
}

/// The size in a `name size` status text.
fn size_in(worn: &str) -> Option<&str> {
    worn.rsplit(' ').next()
}

/// The simulated garment entity.
#[derive(Component)]
pub struct WornGarment {
    sim: Box<GarmentSim>,
    mesh: Handle<Mesh>,
    accumulated_s: f32,
    previous: Option<Vec<Affine3A>>,
    /// The drawn surface (positions, normals), kept between frames.
    surface: (Vec<Vec3>, Vec<Vec3>),
    /// Worn by the twin (drawn at its offset; its surface is still on the avatar).
    twin: bool,
}

impl WornGarment {
    /// Whether the twin wears it (the depth camera sees only the avatar's garment).
    pub fn is_twin(&self) -> bool {
        self.twin
    }

    /// The drawn surface in world space (positions, normals; empty before the first step).
    pub fn surface(&self) -> (&[Vec3], &[Vec3]) {
        (&self.surface.0, &self.surface.1)
    }

    /// The surface's triangles.
    pub fn triangles(&self) -> &[[u32; 3]] {
        self.sim.triangles()
    }
}

/// The garment asset requested, and whether the avatar must be dressed again.
#[derive(Resource, Default)]
struct Wearing {
    handle: Option<Handle<GarmentAsset>>,
    dress: bool,
}

/// Systems of the garment plugin.
#[derive(SystemSet, Debug, Clone, PartialEq, Eq, Hash)]
pub enum GarmentSystems {
    Load,
    Step,
}

/// The garment plugin; `root` is the garment folder (see [`crate::asset`]), which the app
/// registers with [`crate::asset::register_garment_source`] before the `AssetPlugin`.
pub struct GarmentPlugin {
    pub root: PathBuf,
}

impl Plugin for GarmentPlugin {
    fn build(&self, app: &mut App) {
        fitroom_schedule::ensure(app);
        app.init_asset::<GarmentAsset>()
            .init_asset::<FabricAsset>()
            .init_asset::<SizeChartAsset>()
            .register_asset_loader(GarmentLoader {
                root: self.root.clone(),
            })
            .register_asset_loader(FabricLoader {
                root: self.root.clone(),
            })
            .register_asset_loader(SizeChartLoader {
                root: self.root.clone(),
            })
            .init_resource::<ClothSettings>()
            .register_type::<ClothSettings>()
            .init_resource::<GarmentRequest>()
            .init_resource::<GarmentStatus>()
            .init_resource::<Wearing>()
            .insert_resource(GarmentRoot(self.root.clone()))
            .configure_sets(
                PostUpdate,
                (GarmentSystems::Load, GarmentSystems::Step)
                    .chain()
                    .in_set(FitroomSystems::Cloth),
            )
            .add_systems(
                PostUpdate,
                (
                    (request_garment, follow_garment_asset, dress_avatar)
                        .chain()
                        .in_set(GarmentSystems::Load),
                    step_garment.in_set(GarmentSystems::Step),
                ),
            );
    }
}

/// The garment folder.
#[derive(Resource, Debug, Clone)]
pub struct GarmentRoot(pub PathBuf);

/// A changed request loads its file (or takes the garment off).
#[allow(clippy::too_many_arguments)]
fn request_garment(
    mut commands: Commands,
    request: Res<GarmentRequest>,
    root: Res<GarmentRoot>,
    server: Res<AssetServer>,
    mut wearing: ResMut<Wearing>,
    mut status: ResMut<GarmentStatus>,
    worn: Query<Entity, With<WornGarment>>,
    mut hidden: Option<ResMut<HiddenSkin>>,
) {
    if !request.is_changed() {
        return;
    }
    status.file = request.path.clone();
    let Some(path) = &request.path else {
        for e in &worn {
            commands.entity(e).despawn();
        }
        *wearing = Wearing::default();
        status.worn = None;
        status.compare_worn = None;
        status.asset = None;
        status.error = None;
        if let Some(hidden) = hidden.as_mut() {
            hidden.0 = None;
        }
        return;
    };
    match garment_asset_path(&root.0, path) {
        Ok(asset) => {
            let handle = server.load(asset);
            status.asset = Some(handle.clone());
            wearing.handle = Some(handle);
            wearing.dress = true;
        }
        Err(e) => {
            warn!("{e}");
            status.error = Some(e);
        }
    }
}

/// Notices the garment asset loading, reloading, or failing to.
fn follow_garment_asset(
    mut events: MessageReader<AssetEvent<GarmentAsset>>,
    mut failures: MessageReader<AssetLoadFailedEvent<GarmentAsset>>,
    mut wearing: ResMut<Wearing>,
    mut status: ResMut<GarmentStatus>,
) {
    let Some(id) = wearing.handle.as_ref().map(Handle::id) else {
        events.clear();
        failures.clear();
        return;
    };
    for event in events.read() {
        if let AssetEvent::Added { id: e }
        | AssetEvent::Modified { id: e }
        | AssetEvent::LoadedWithDependencies { id: e } = event
            && *e == id
        {
            wearing.dress = true;
        }
    }
    for failure in failures.read() {
        if failure.id == id {
            let message = first_line(&failure.error.to_string());
            warn!("garment not (re)loaded, the avatar keeps what it wears: {message}");
            status.error = Some(message);
        }
    }
}

fn garment_mesh(
    (positions, normals): (&[Vec3], &[Vec3]),
    triangles: &[[u32; 3]],
    colours: Option<&[f32]>,
) -> Mesh {
    let mut mesh = Mesh::new(
        PrimitiveTopology::TriangleList,
        RenderAssetUsages::default(),
    )
    .with_inserted_attribute(
        Mesh::ATTRIBUTE_POSITION,
        positions.iter().map(|p| p.to_array()).collect::<Vec<_>>(),
    )
    .with_inserted_attribute(
        Mesh::ATTRIBUTE_NORMAL,
        normals.iter().map(|n| n.to_array()).collect::<Vec<_>>(),
    )
    .with_inserted_indices(Indices::U32(triangles.iter().flatten().copied().collect()));
    let colours: Vec<[f32; 4]> = match colours {
        Some(strain) => strain.iter().map(|&s| strain_colour(s)).collect(),
        None => vec![[1.0; 4]; positions.len()],
    };
    mesh.insert_attribute(Mesh::ATTRIBUTE_COLOR, colours);
    mesh
}

/// Writes the garment's new surface and colours into `mesh` in place (its triangles do not
/// change); rebuilds it if the mesh's data is not there to write.
fn update_garment_mesh(
    mesh: &mut Mesh,
    (positions, normals): (&[Vec3], &[Vec3]),
    triangles: &[[u32; 3]],
    colours: Option<&[f32]>,
) {
    let mut write =
        |id, values: &mut dyn Iterator<Item = [f32; 3]>| match mesh.try_attribute_mut(id) {
            Ok(VertexAttributeValues::Float32x3(old)) if old.len() == positions.len() => {
                old.iter_mut().zip(values).for_each(|(o, v)| *o = v);
                true
            }
            _ => false,
        };
    let written = write(
        Mesh::ATTRIBUTE_POSITION.id,
        &mut positions.iter().map(|p| p.to_array()),
    ) && write(
        Mesh::ATTRIBUTE_NORMAL.id,
        &mut normals.iter().map(|n| n.to_array()),
    );
    let coloured = match mesh.try_attribute_mut(Mesh::ATTRIBUTE_COLOR) {
        Ok(VertexAttributeValues::Float32x4(old)) if old.len() == positions.len() => {
            match colours {
                Some(strain) => old
                    .iter_mut()
                    .zip(strain)
                    .for_each(|(o, &s)| *o = strain_colour(s)),
                None => old.fill([1.0; 4]),
            }
            true
        }
        _ => false,
    };
    if !(written && coloured) {
        *mesh = garment_mesh((positions, normals), triangles, colours);
    }
}

/// The fit map's colour of a strain (%): blue (-5% and less) - white (0) - red (+10% and more).
pub fn strain_colour(strain_pct: f32) -> [f32; 4] {
    if strain_pct >= 0.0 {
        let t = (strain_pct / 10.0).clamp(0.0, 1.0);
        [1.0, 1.0 - t, 1.0 - t, 1.0]
    } else {
        let t = (-strain_pct / 5.0).clamp(0.0, 1.0);
        [1.0 - t, 1.0 - 0.6 * t, 1.0, 1.0]
    }
}

/// A garment built and ready to simulate: its mesh, its simulation, and the skin it covers.
pub type Built = (crate::GarmentMesh, GarmentSim, Option<Vec<bool>>);

/// Builds `source` in `size` on the body, its simulation ready to step.
pub fn build_garment(
    source: &crate::source::GarmentSource,
    body: &AvatarBody,
    size: Option<&str>,
    settings: &ClothSettings,
) -> Result<Built, String> {
    let shaped = ShapedBody {
        weights: Vec::new(),
        positions: body.positions.clone(),
        normals: body.normals.clone(),
        rest_pose: body.rest.clone(),
    };
    let surface = BodySurface::new(&body.model, &shaped).map_err(|e| e.to_string())?;
    let mesh = source.build(&surface, size).map_err(|e| e.to_string())?;
    let solver = SolverSettings {
        substeps: settings.substeps.max(1),
        ..SolverSettings::default()
    };
    let garment = SimGarment::from_mesh(&mesh);
    let sim = GarmentSim::new(&body.model, &body.positions, &body.rest, &garment, solver)
        .map_err(|e| e.to_string())?;
    let n = (body.model.body_vertex_count as usize)
        .min(body.positions.len())
        .min(body.normals.len());
    let covered = if settings.hide_covered_skin {
        let skin = (&body.positions[..n], &body.normals[..n]);
        let covered = crate::cover::covered_skin(
            &body.model,
            skin,
            &mesh.positions,
            &mesh.triangles,
            &garment.attached,
        )
        .map_err(|e| format!("{}: {e}", source.path().display()))?;
        Some(covered)
    } else {
        None
    };
    Ok((mesh, sim, covered))
}

/// Dresses the avatar in the requested garment when its asset (re)loaded, the size changed or
/// the body was reshaped, and the twin in the size compared; a garment that cannot be built
/// keeps what the avatar wears.
#[allow(clippy::too_many_arguments)]
fn dress_avatar(
    mut commands: Commands,
    request: Res<GarmentRequest>,
    body: Option<Res<AvatarBody>>,
    settings: Res<ClothSettings>,
    garments: Res<Assets<GarmentAsset>>,
    twin: Option<Res<TwinAvatar>>,
    mut wearing: ResMut<Wearing>,
    mut status: ResMut<GarmentStatus>,
    worn: Query<Entity, With<WornGarment>>,
    joints: Query<(&AvatarJoint, &GlobalTransform)>,
    mut meshes: Option<ResMut<Assets<Mesh>>>,
    mut materials: Option<ResMut<Assets<StandardMaterial>>>,
    mut hidden: Option<ResMut<HiddenSkin>>,
) {
    let Some(body) = body else {
        return;
    };
    if !(wearing.dress || body.is_changed()) {
        return;
    }
    let Some(source) = wearing
        .handle
        .as_ref()
        .and_then(|h| garments.get(h))
        .map(|g| &g.0)
    else {
        // Not loaded yet: dressed when it is.
        return;
    };
    wearing.dress = false;
    let built = build_garment(source, &body, request.size.as_deref(), &settings);
    // The twin's size failing (one this garment does not have) leaves the twin bare, not the
    // avatar.
    // The skin left out is the avatar's garment's: the twin's is not computed.
    let twin_settings = ClothSettings {
        hide_covered_skin: false,
        ..settings.clone()
    };
    let (compared, compare_error) = match request.compare.as_deref() {
        Some(size) => match build_garment(source, &body, Some(size), &twin_settings) {
            Ok(b) => (Some(b), None),
            Err(e) => (None, Some(format!("the twin's size {size}: {e}"))),
        },
        None => (None, None),
    };
    let ((garment, sim, covered), compared) = match built.map(|b| (b, compared)) {
        Ok(b) => b,
        Err(e) => {
            warn!("garment not (re)loaded, the avatar keeps what it wears: {e}");
            status.error = Some(e);
            return;
        }
    };
    let skin = world_skinning(&body, joints);
    let mut ready = Vec::with_capacity(2);
    for (garment, mut sim, twin_worn) in std::iter::once((garment, sim, false))
        .chain(compared.map(|(garment, sim, _)| (garment, sim, true)))
    {
        sim.set_measuring(false);
        let floor = sim.set_floor(Some(0.0)).and_then(|_| sim.reset(&skin));
        if let Err(e) = floor {
            status.error = Some(e.to_string());
            return;
        }
        ready.push((garment, sim, twin_worn));
    }
    for e in &worn {
        commands.entity(e).despawn();
    }
    if let Some(hidden) = hidden.as_mut() {
        hidden.0 = covered;
    }
    status.error = compare_error;
    status.compare_worn = None;
    let offset = twin.map_or(Vec3::ZERO, |t| t.offset);
    for (garment, sim, twin_worn) in ready {
        let name = format!("{} {}", garment.name, garment.size);
        if twin_worn {
            status.compare_worn = Some(name);
        } else {
            status.worn = Some(name);
            status.particles = garment.positions.len();
        }
        let worn = WornGarment {
            sim: Box::new(sim),
            mesh: Handle::default(),
            accumulated_s: 0.0,
            previous: None,
            surface: Default::default(),
            twin: twin_worn,
        };
        let (Some(meshes), Some(materials)) = (meshes.as_mut(), materials.as_mut()) else {
            // Headless without a renderer: simulate without drawing.
            commands.spawn(worn);
            continue;
        };
        let (positions, normals) = worn.sim.render_surface();
        let mesh = meshes.add(garment_mesh(
            (&positions, &normals),
            worn.sim.triangles(),
            None,
        ));
        commands.spawn((
            WornGarment {
                mesh: mesh.clone(),
                ..worn
            },
            Mesh3d(mesh),
            MeshMaterial3d(materials.add(StandardMaterial {
                base_color: Color::srgb(0.35, 0.45, 0.75),
                perceptual_roughness: 0.85,
                cull_mode: None,
                double_sided: true,
                ..default()
            })),
            Transform::from_translation(if twin_worn { offset } else { Vec3::ZERO }),
            Visibility::default(),
        ));
    }
}

#[allow(clippy::too_many_arguments)]
fn step_garment(
    mut commands: Commands,
    time: Res<Time>,
    settings: Res<ClothSettings>,
    body: Option<Res<AvatarBody>>,
    joints: Query<(&AvatarJoint, &GlobalTransform)>,
    mut worn: Query<(Entity, &mut WornGarment)>,
    mut status: ResMut<GarmentStatus>,
    mut meshes: Option<ResMut<Assets<Mesh>>>,
    mut hidden: Option<ResMut<HiddenSkin>>,
) {
    let Some(body) = body else {
        return;
    };
    let skin = world_skinning(&body, joints);
    let dt = 1.0 / settings.rate_hz.max(1.0);
    status.frame_ms = 0.0;
    for (entity, mut g) in &mut worn {
        let start = Instant::now();
        g.accumulated_s += time.delta_secs();
        let due = (g.accumulated_s / dt).floor() as u64;
        let previous = g.previous.take().unwrap_or_else(|| skin.clone());
        let mut pose = Vec::with_capacity(skin.len());
        let mut done = 0u64;
        let mut taken_off = false;
        for k in 0..due {
            if start.elapsed().as_secs_f32() * 1e3 > settings.budget_ms {
                break;
            }
            let t = (k + 1) as f32 / due as f32;
            pose.clear();
            pose.extend(
                previous
                    .iter()
                    .zip(&skin)
                    .map(|(a, b)| lerp_affine(a, b, t)),
            );
            // A panic in the step (on this thread or a cloth worker's) must not take the
            // app down: the garment is taken off and the error shown.
            let stepped = catch_unwind(AssertUnwindSafe(|| g.sim.step(&pose, dt)));
            let stepped = match stepped {
                Ok(stepped) => stepped,
                Err(panic) => {
                    let message = format!(
                        "the cloth simulation of {} failed ({}); the garment was taken off",
                        status.worn.as_deref().unwrap_or("the garment"),
                        panic_message(panic.as_ref())
                    );
                    error!("{message}");
                    status.error = Some(message);
                    if g.twin {
                        status.compare_worn = None;
                    } else {
                        status.worn = None;
                        if let Some(hidden) = hidden.as_mut() {
                            hidden.0 = None;
                        }
                    }
                    commands.entity(entity).despawn();
                    taken_off = true;
                    break;
                }
            };
            match stepped {
                Ok(s) => {
                    if s.reset {
                        warn!(
                            "the garment blew up ({}) and was reset to its skinned pose",
                            s.blow_up.as_deref().unwrap_or("?")
                        );
                    }
                    if !g.twin {
                        status.max_strain_pct = s.max_strain_pct;
                    }
                }
                Err(e) => {
                    status.error = Some(e.to_string());
                    break;
                }
            }
            done += 1;
        }
        if taken_off {
            continue;
        }
        if !g.twin {
            status.steps += done;
            status.dropped_steps += due - done;
        }
        g.accumulated_s = 0.0_f32.max(g.accumulated_s - due as f32 * dt);
        // The buffer taken at the top of the loop keeps this frame's pose for the next.
        let mut previous = previous;
        previous.clone_from(&skin);
        g.previous = Some(previous);
        if !g.twin {
            status.resets = g.sim.resets();
        }
        if cfg!(debug_assertions) && !g.sim.positions().iter().all(|p| p.is_finite()) {
            error!("garment positions are not finite after the step");
        }
        // The surface is kept without a renderer too: the synthetic depth camera sees it.
        let g = &mut *g;
        let (positions, normals) = &mut g.surface;
        g.sim.render_surface_into(positions, normals);
        if let Some(meshes) = meshes.as_mut()
            && let Some(mut mesh) = meshes.get_mut(&g.mesh)
        {
            let strain = settings.fit_map.then(|| g.sim.strain_pct());
            let (positions, normals) = &g.surface;
            update_garment_mesh(
                &mut mesh,
                (positions, normals),
                g.sim.triangles(),
                strain.as_deref(),
            );
        }
        // Both garments' time when the twin wears one.
        status.frame_ms += start.elapsed().as_secs_f32() * 1e3;
    }
}

/// The first line of an asset server error: the loader's message (a backtrace follows it when
/// `RUST_BACKTRACE` is set; it is not for the screen).
fn first_line(message: &str) -> String {
    message.lines().next().unwrap_or_default().to_owned()
}

/// The message a panic carried (a `&str` or a `String`), for the screen.
fn panic_message(panic: &(dyn std::any::Any + Send)) -> String {
    panic
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| panic.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "a panic without a message".into())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_panic_message_is_read_from_either_payload() {
        let from_str = catch_unwind(|| panic!("worker gave up")).expect_err("it panicked");
        assert_eq!(panic_message(from_str.as_ref()), "worker gave up");
        let n = 3;
        let from_string = catch_unwind(|| panic!("item {n} failed")).expect_err("it panicked");
        assert_eq!(panic_message(from_string.as_ref()), "item 3 failed");
    }

    fn float3(mesh: &Mesh, id: bevy::mesh::MeshVertexAttribute) -> Vec<[f32; 3]> {
        match mesh.attribute(id) {
            Some(VertexAttributeValues::Float32x3(v)) => v.clone(),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn a_garment_mesh_is_updated_in_place_with_its_triangles_kept() {
        let triangles = [[0, 1, 2], [0, 2, 3]];
        let square = |z: f32| -> (Vec<Vec3>, Vec<Vec3>) {
            (
                vec![
                    Vec3::new(0.0, 0.0, z),
                    Vec3::new(1.0, 0.0, z),
                    Vec3::new(1.0, 1.0, z),
                    Vec3::new(0.0, 1.0, z),
                ],
                vec![Vec3::Z; 4],
            )
        };
        let (flat, raised) = (square(0.0), square(0.5));
        let mut mesh = garment_mesh((&flat.0, &flat.1), &triangles, None);
        update_garment_mesh(
            &mut mesh,
            (&raised.0, &raised.1),
            &triangles,
            Some(&[10.0, 0.0, -5.0, 3.0]),
        );
        assert_eq!(float3(&mesh, Mesh::ATTRIBUTE_POSITION)[2], [1.0, 1.0, 0.5]);
        assert_eq!(float3(&mesh, Mesh::ATTRIBUTE_NORMAL)[0], [0.0, 0.0, 1.0]);
        let Some(VertexAttributeValues::Float32x4(colours)) = mesh.attribute(Mesh::ATTRIBUTE_COLOR)
        else {
            panic!("no colours");
        };
        assert_eq!(colours[0], strain_colour(10.0));
        assert_eq!(colours[2], strain_colour(-5.0));
        let Some(Indices::U32(indices)) = mesh.indices() else {
            panic!("no indices");
        };
        assert_eq!(indices, &vec![0, 1, 2, 0, 2, 3]);
        // The fit map turned off: white again.
        update_garment_mesh(&mut mesh, (&raised.0, &raised.1), &triangles, None);
        let Some(VertexAttributeValues::Float32x4(colours)) = mesh.attribute(Mesh::ATTRIBUTE_COLOR)
        else {
            panic!("no colours");
        };
        assert!(colours.iter().all(|c| *c == [1.0; 4]));
        // A surface of another size (a reloaded garment) rebuilds the mesh.
        let (mut p, mut n) = square(0.0);
        p.push(Vec3::ONE);
        n.push(Vec3::Z);
        update_garment_mesh(&mut mesh, (&p, &n), &triangles, None);
        assert_eq!(float3(&mesh, Mesh::ATTRIBUTE_POSITION).len(), 5);
    }
}
