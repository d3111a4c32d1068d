//! A filmed body dressed: a garment (a pattern garment such as `assets/garments/tshirt.ron`)
//! built on the body's shape, put on it in its pose and settled by the cloth simulation, so
//! that the synthetic camera films the person wearing it.
//!
//! The calls are the ones the app makes when it dresses the avatar (`fitroom_garment`'s
//! plugin): the garment is built on the shaped body at rest (graded, placed, sewn, welded),
//! simulated by [`GarmentSim`] against the body's colliders, put on with [`GarmentSim::reset`]
//! (the rest pose carried by the pelvis, then swept into the pose) and stepped at 120 Hz; what
//! the camera sees is the simulated cloth (not the app's drawn surface,
//! [`GarmentSim::render_surface`], offset 2.5 cm out to hide skin between the colliders).
//! Three things differ:
//!
//! - The skinning transforms: the app takes them from the avatar's joint entities; here they
//!   come from the pose by the rig's forward kinematics. The cloth is simulated in the body's
//!   posed model space (the pelvis where the rig puts it) with gravity turned so that it points
//!   down in sensor space, and the result is carried into sensor space by the [`Placement`]
//!   the way [`Posing`](crate::posed::Posing) places the body's vertices.
//! - The sewing pre-simulation runs [`DressOptions::sew_iterations`] iterations instead of the
//!   app's 200: it is most of the time a dressing takes (about 15 ms an iteration for the
//!   T-shirt), and the cloth simulation settles what it leaves.
//! - The body colliders (capsules) lie inside the skin and do not hold out the breasts, the
//!   chest or a belly, which poke through the settled cloth: the app hides the skin a garment
//!   covers instead ([`fitroom_garment::cover`]). A depth camera must see cloth over them, so
//!   the settled surface is held out of the posed body ([`hold_out`]): pushed out to
//!   [`DressOptions::clearance_m`] ([`push_outside`], the placement's own push), the cloth
//!   around the pushed vertices drawn after them by its edge lengths, pushed again, a few
//!   rounds (pushed alone, the vertices over a breast stretch their triangles 2-3 fold, and
//!   those cut through the skin between them).

use std::path::Path;

use fitroom_body::skinning::skinning_matrices;
use fitroom_body::{
    BodyModel, MeshGraph, RigidTransform, SegmentError, Shape, ShapeError, ShapedBody,
    forward_kinematics,
};
use fitroom_cloth::SolverSettings;
use fitroom_depth::synthetic::{Label, SceneMesh};
use fitroom_garment::placement::push_outside;
use fitroom_garment::sim::{GarmentSim, SimError, SimGarment};
use fitroom_garment::{BodySurface, BuildOptions, GarmentError, GarmentMesh, GarmentSource};
use glam::{Affine3A, Quat, Vec3};

use crate::posed::Placement;

/// Cloth steps per second: the app's rate ([`fitroom_garment`]'s `ClothSettings`).
pub const DRESS_RATE_HZ: f32 = 120.0;

/// How a garment is dressed and settled.
#[derive(Clone, Debug, PartialEq)]
pub struct DressOptions {
    /// Simulated time the garment settles on the still body, seconds (after the put-on
    /// sweep of [`GarmentSim::reset`]).
    pub settle_s: f32,
    /// Solver substeps per 120 Hz step (the app's 10 by default).
    pub substeps: u32,
    /// Solver threads, the caller's included. The evaluation dresses its subjects on several
    /// threads already, so one is the default.
    pub threads: usize,
    /// The pattern meshed at this target edge length (cm) instead of its file's
    /// `target_edge_cm` (coarser: faster); a mesh garment ignores it.
    pub edge_cm: Option<f32>,
    /// Iterations of a pattern's sewing pre-simulation ([`GarmentMesh::sew`]; the app runs
    /// 200). 40 leave the T-shirt's panels 5-6% off their flat edge lengths on average
    /// against 4% after 200, in a quarter of the time.
    pub sew_iterations: usize,
    /// Least distance of the settled surface from the posed body's skin, metres.
    pub clearance_m: f32,
}

impl Default for DressOptions {
    fn default() -> Self {
        Self {
            settle_s: 0.5,
            substeps: 10,
            threads: 1,
            edge_cm: None,
            sew_iterations: 40,
            clearance_m: 0.005,
        }
    }
}

/// Why a body cannot be dressed.
#[derive(Debug, thiserror::Error)]
pub enum DressError {
    #[error("the body's shape cannot be made: {0}")]
    Shape(#[from] ShapeError),
    #[error("the garment cannot be read or built on the body: {0}")]
    Garment(#[from] GarmentError),
    #[error("the garment cannot be simulated on the body: {0}")]
    Sim(#[from] SimError),
    #[error("the garment's mesh: {0}")]
    Mesh(#[from] SegmentError),
    #[error("dressing option {what} is {value}; it must be {requirement}")]
    Option {
        what: &'static str,
        value: f32,
        requirement: &'static str,
    },
    #[error("{got} bone rotations for a rig of {bones} bones")]
    Pose { got: usize, bones: usize },
    #[error("the pose or placement is not finite")]
    NotFinitePose,
    #[error("the settled garment has {count} non-finite vertices")]
    NotFinite { count: usize },
}

/// A garment as worn, in sensor space.
#[derive(Clone, Debug)]
pub struct DressedGarment {
    /// The garment's name and size label.
    pub name: String,
    pub size: String,
    /// The cloth's surface, sensor space, metres.
    pub positions: Vec<Vec3>,
    /// Counter-clockwise seen from outside the garment.
    pub triangles: Vec<[u32; 3]>,
    /// Blow-ups the simulation reset to the skinned pose (0 in a good settle).
    pub resets: u32,
    /// Largest edge stretch of the settled cloth, % over rest length.
    pub max_strain_pct: f32,
    /// Vertices of the settled surface the body poked through, pushed out ([`hold_out`]).
    pub pushed_out: usize,
}

impl DressedGarment {
    /// The garment as the synthetic camera takes it: an open mesh, seen from both sides.
    pub fn scene_mesh(&self) -> SceneMesh {
        SceneMesh {
            positions: self.positions.clone(),
            triangles: self.triangles.clone(),
            label: Label::Garment,
            closed: false,
        }
    }
}

/// The garment `path` (a garment file, e.g. `assets/garments/tshirt.ron`) in size `size`
/// (`None`: its middle size) draped on the body of `shape` posed by `locals` (per bone, its
/// rotation from rest, as [`crate::posed::Posing`] takes them) and placed at `placement`,
/// settled by the cloth simulation for `settle_s` seconds. Returns the garment's mesh in
/// sensor space.
///
/// Reads the garment file (and its fabric) each call; [`dress`] takes a garment read once.
pub fn dressed(
    model: &BodyModel,
    shape: &Shape,
    locals: &[Quat],
    placement: &Placement,
    path: &Path,
    size: Option<&str>,
    settle_s: f32,
) -> Result<DressedGarment, DressError> {
    let source = GarmentSource::load(path)?;
    let options = DressOptions {
        settle_s,
        ..DressOptions::default()
    };
    dress(model, shape, locals, placement, &source, size, &options)
}

/// [`dressed`] with a garment already read ([`GarmentSource::load`]) and the options.
pub fn dress(
    model: &BodyModel,
    shape: &Shape,
    locals: &[Quat],
    placement: &Placement,
    source: &GarmentSource,
    size: Option<&str>,
    options: &DressOptions,
) -> Result<DressedGarment, DressError> {
    check_options(options)?;
    if locals.len() > model.bones.len() {
        return Err(DressError::Pose {
            got: locals.len(),
            bones: model.bones.len(),
        });
    }
    let finite_pose = locals.iter().all(|q| q.is_finite())
        && placement.rotation.is_finite()
        && placement.pelvis.is_finite();
    if !finite_pose {
        return Err(DressError::NotFinitePose);
    }

    // The garment is built on the shaped body at rest (model space), as the app builds it.
    let shaped = model.shaped(shape)?;
    let surface = BodySurface::new(model, &shaped)?;
    let mesh = build(source, &surface, size, options)?;

    // Simulated in the posed model space, where the body's skinning transforms take its rest
    // (the pelvis stays where the rig has it); gravity is sensor space's down seen from there.
    let rest = &shaped.rest_pose;
    let globals = forward_kinematics(&model.bones, rest, locals, Vec3::ZERO);
    let skinning = skinning_matrices(rest, &globals);
    let defaults = SolverSettings::default();
    let settings = SolverSettings {
        substeps: options.substeps,
        threads: options.threads,
        gravity: placement.rotation.inverse() * defaults.gravity,
        ..defaults
    };
    let mut sim = GarmentSim::new(
        model,
        &shaped.positions,
        rest,
        &SimGarment::from_mesh(&mesh),
        settings,
    )?;
    // The figures are read once at the end, not after every step.
    sim.set_measuring(false);
    // No floor: a garment worn on a standing body does not reach it.
    sim.set_floor(None)?;
    sim.reset(&skinning)?;
    let steps = (options.settle_s * DRESS_RATE_HZ).ceil() as usize;
    for _ in 0..steps {
        // A blow-up resets the garment to its skinned pose inside the step (counted).
        sim.step(&skinning, 1.0 / DRESS_RATE_HZ)?;
    }
    let max_strain_pct = sim
        .strain_pct()
        .into_iter()
        .fold(f32::NEG_INFINITY, f32::max);

    // The simulated cloth held out of the posed body (see the module's documentation). Not
    // the app's drawn surface: that is offset 2.5 cm out along the normals to hide skin
    // showing through between the colliders, and a camera would see 16 cm of girth that
    // is not there.
    let mut drawn = sim.positions();
    let posed_positions = model.skin_positions(&shaped.positions, rest, &globals);
    let posed = ShapedBody {
        weights: Vec::new(),
        normals: model.body_normals(&posed_positions),
        positions: posed_positions,
        rest_pose: rest.clone(),
    };
    let pushed_out = hold_out(
        &BodySurface::new(model, &posed)?,
        &mut drawn,
        sim.triangles(),
        options.clearance_m,
    )?;

    let count = drawn.iter().filter(|p| !p.is_finite()).count();
    if count > 0 {
        return Err(DressError::NotFinite { count });
    }
    let to_sensor = posed_to_sensor(model, &globals, placement);
    Ok(DressedGarment {
        name: mesh.name,
        size: mesh.size,
        positions: drawn
            .into_iter()
            .map(|p| to_sensor.transform_point3(p))
            .collect(),
        triangles: sim.triangles().to_vec(),
        resets: sim.resets(),
        max_strain_pct,
        pushed_out,
    })
}

/// The garment in `size` on `body`, as [`GarmentSource::build`] makes it, a pattern meshed
/// at [`DressOptions::edge_cm`] and sewn for [`DressOptions::sew_iterations`].
fn build(
    source: &GarmentSource,
    body: &BodySurface,
    size: Option<&str>,
    options: &DressOptions,
) -> Result<GarmentMesh, GarmentError> {
    let Some(pattern) = source.pattern() else {
        // A mesh garment is bound to the body as modelled.
        return source.build(body, size);
    };
    let size = source.resolve_size(size)?;
    let build = BuildOptions {
        sew_iterations: options.sew_iterations,
        ..BuildOptions::default()
    };
    let built = match options.edge_cm {
        Some(edge) if edge != pattern.target_edge_cm => {
            let mut coarser = pattern.clone();
            coarser.target_edge_cm = edge;
            coarser.build(body, &size, &build)?
        }
        _ => pattern.build(body, &size, &build)?,
    };
    built.welded(body)
}

/// Rings of neighbours around the vertices the body pokes through that [`hold_out`] draws
/// after them (about 7 cm of cloth at the T-shirt's 2.5 cm edges).
const HOLD_OUT_RINGS: u32 = 3;
/// Rounds of [`hold_out`], each some edge sweeps and a push.
const HOLD_OUT_ROUNDS: usize = 6;
/// Gauss-Seidel sweeps over the edges per round.
const HOLD_OUT_SWEEPS: usize = 4;

/// Holds the garment surface `positions` (triangles `triangles`) out of `body` by
/// `clearance` metres: the vertices inside or closer are pushed out ([`push_outside`]), then
/// a few rounds draw the cloth within [`HOLD_OUT_RINGS`] of them after them (position-based
/// edge constraints at the surface's edge lengths before the push, the cloth farther out held
/// still) and push again, so that the cloth tents over what poked through instead of
/// stretching single triangles over it. The last round ends with a push: no vertex is left
/// closer to the body than `clearance`. Returns the number of vertices first pushed.
pub fn hold_out(
    body: &BodySurface,
    positions: &mut [Vec3],
    triangles: &[[u32; 3]],
    clearance: f32,
) -> Result<usize, SegmentError> {
    let n = positions.len();
    let before = positions.to_vec();
    if push_outside(body, positions, clearance) == 0 {
        return Ok(0);
    }
    let pushed: Vec<u32> = (0..n as u32)
        .filter(|&v| positions[v as usize] != before[v as usize])
        .collect();
    let graph = MeshGraph::new(n, triangles)?;
    let mut free = vec![false; n];
    let mut active: Vec<u32> = Vec::new();
    for (v, _) in graph.hops_from(&pushed, HOLD_OUT_RINGS)? {
        free[v as usize] = true;
        active.push(v);
    }
    active.sort_unstable();
    // Each edge touching the free cloth once, at its length before the push.
    let edges: Vec<(usize, usize, f32)> = active
        .iter()
        .flat_map(|&a| {
            let free = &free;
            graph
                .neighbours(a as usize)
                .iter()
                .filter(move |&&b| b > a || !free[b as usize])
                .map(move |&b| (a as usize, b as usize))
        })
        .map(|(a, b)| (a, b, before[a].distance(before[b])))
        .collect();
    let mut near: Vec<Vec3> = Vec::with_capacity(active.len());
    for _ in 0..HOLD_OUT_ROUNDS {
        for _ in 0..HOLD_OUT_SWEEPS {
            for &(a, b, rest) in &edges {
                // Inverse masses: the cloth beyond the rings does not move.
                let (wa, wb) = (f32::from(u8::from(free[a])), f32::from(u8::from(free[b])));
                let d = positions[b] - positions[a];
                let length = d.length();
                if length < 1e-9 || wa + wb == 0.0 {
                    continue;
                }
                let correction = d * ((length - rest) / (length * (wa + wb)));
                positions[a] += correction * wa;
                positions[b] -= correction * wb;
            }
        }
        near.clear();
        near.extend(active.iter().map(|&v| positions[v as usize]));
        push_outside(body, &mut near, clearance);
        for (&v, &p) in active.iter().zip(&near) {
            positions[v as usize] = p;
        }
    }
    Ok(pushed.len())
}

/// From the posed model space (bone transforms `globals`, from [`forward_kinematics`] without
/// a root offset) to sensor space: the pelvis (the rig's `pelvis` bone, else its first root,
/// as [`crate::posed::Posing`] anchors it) at `placement.pelvis`, the body turned by
/// `placement.rotation` about it.
fn posed_to_sensor(
    model: &BodyModel,
    globals: &[RigidTransform],
    placement: &Placement,
) -> Affine3A {
    let root = model
        .bone_index("pelvis")
        .or_else(|| model.bones.iter().position(|b| b.parent.is_none()))
        .unwrap_or(0);
    let pelvis = globals.get(root).map_or(Vec3::ZERO, |g| g.translation);
    Affine3A::from_rotation_translation(placement.rotation, placement.pelvis)
        * Affine3A::from_translation(-pelvis)
}

fn check_options(options: &DressOptions) -> Result<(), DressError> {
    let out_of_range = |what, value, requirement| DressError::Option {
        what,
        value,
        requirement,
    };
    if !(options.settle_s.is_finite() && (0.0..=60.0).contains(&options.settle_s)) {
        return Err(out_of_range(
            "settle_s",
            options.settle_s,
            "between 0 and 60 seconds",
        ));
    }
    if let Some(edge) = options.edge_cm
        && !(edge.is_finite() && (0.5..=10.0).contains(&edge))
    {
        return Err(out_of_range("edge_cm", edge, "between 0.5 and 10 cm"));
    }
    if !(options.clearance_m.is_finite() && (0.0..=0.05).contains(&options.clearance_m)) {
        return Err(out_of_range(
            "clearance_m",
            options.clearance_m,
            "between 0 and 0.05 m",
        ));
    }
    if options.sew_iterations > 1000 {
        return Err(out_of_range(
            "sew_iterations",
            options.sew_iterations as f32,
            "at most 1000",
        ));
    }
    // Substeps and threads are checked by the solver (`SolverSettings::validate`).
    Ok(())
}

/// `source` in `size` dressed on the body of `shape` in the calibration pose of `stance`, as
/// [`super::record`] films it (the garment then moves with the body), and the dressing's
/// report.
pub fn worn(
    model: &BodyModel,
    shape: &Shape,
    stance: &super::Stance,
    source: &GarmentSource,
    size: Option<&str>,
    options: &DressOptions,
) -> Result<(super::Worn, DressedGarment), DressError> {
    let rest = model.shaped(shape)?.rest_pose;
    let locals = super::calibration_pose(model, &rest, stance);
    // Facing the sensor, the pelvis at the origin: `record` turns and places it.
    let at = Placement {
        rotation: fitroom_body::MODEL_TO_SENSOR,
        pelvis: Vec3::ZERO,
    };
    let dressed = dress(model, shape, &locals, &at, source, size, options)?;
    let worn = super::Worn {
        positions: dressed.positions.clone(),
        triangles: dressed.triangles.clone(),
    };
    Ok((worn, dressed))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::eval::{Stance, calibration_pose};
    use crate::posed::Posing;
    use fitroom_body::{MODEL_TO_SENSOR, compute_normals};

    fn assets() -> std::path::PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets")
    }

    /// The T-shirt on MakeHuman's default body in the calibration pose, 2.7 m in front of
    /// the sensor: settled without a blow-up, on the torso (between the hips and the neck,
    /// around the body's axis) and outside the skin.
    #[test]
    fn a_tshirt_is_dressed_on_the_torso_outside_the_skin_in_sensor_space() {
        let model = BodyModel::read(&assets().join("bodies/makehuman.fitbody")).expect("body");
        let shape = Shape::default();
        let shaped = model.shaped(&shape).expect("shape");
        let stance = Stance {
            distance_m: 2.7,
            offset_m: 0.1,
            yaw_deg: 10.0,
            arm_left_deg: -15.0,
            arm_right_deg: -15.0,
            sensor_height_m: 0.95,
        };
        let locals = calibration_pose(&model, &shaped.rest_pose, &stance);
        let placement = Placement {
            rotation: Quat::from_rotation_y(stance.yaw_deg.to_radians()) * MODEL_TO_SENSOR,
            pelvis: Vec3::new(stance.offset_m, -0.1, stance.distance_m),
        };
        let shirt = dressed(
            &model,
            &shape,
            &locals,
            &placement,
            &assets().join("garments/tshirt.ron"),
            None,
            0.25,
        )
        .expect("dressed");
        assert_eq!(shirt.resets, 0);
        assert!(shirt.positions.len() > 500, "{}", shirt.positions.len());
        let body = Posing::new(&model, locals)
            .body(&shape, &placement)
            .expect("posed");
        let top = body.vertices.iter().map(|v| v.y).fold(f32::MIN, f32::max);
        let (low, high) = shirt
            .positions
            .iter()
            .fold((f32::MAX, f32::MIN), |(lo, hi), p| {
                (lo.min(p.y), hi.max(p.y))
            });
        // From about the crotch to below the head's top.
        assert!(low > placement.pelvis.y - 0.2, "hem at {low}");
        assert!(
            high < top - 0.15 && high > placement.pelvis.y + 0.3,
            "top at {high}"
        );
        let mean = shirt.positions.iter().sum::<Vec3>() / shirt.positions.len() as f32;
        let aside = Vec3::new(
            mean.x - placement.pelvis.x,
            0.0,
            mean.z - placement.pelvis.z,
        );
        assert!(aside.length() < 0.08, "centred {aside}");
        // Outside the skin: the nearest body vertex's normal points towards the vertex.
        let normals = compute_normals(&body.vertices, &model.triangles);
        let inside = shirt
            .positions
            .iter()
            .filter(|p| {
                let (k, _) = body
                    .vertices
                    .iter()
                    .enumerate()
                    .map(|(k, v)| (k, v.distance_squared(**p)))
                    .fold((0, f32::MAX), |a, b| if b.1 < a.1 { b } else { a });
                (**p - body.vertices[k]).dot(normals[k]) < 0.0
            })
            .count();
        assert!(inside * 100 < shirt.positions.len(), "{inside} inside");
    }

    #[test]
    fn bad_options_are_refused_before_any_work() {
        for options in [
            DressOptions {
                settle_s: f32::NAN,
                ..DressOptions::default()
            },
            DressOptions {
                edge_cm: Some(0.0),
                ..DressOptions::default()
            },
            DressOptions {
                clearance_m: -0.01,
                ..DressOptions::default()
            },
        ] {
            assert!(matches!(
                check_options(&options),
                Err(DressError::Option { .. })
            ));
        }
        assert!(check_options(&DressOptions::default()).is_ok());
    }
}
