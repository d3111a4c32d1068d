//! `fitroom cloth sim|fit|bench`: a garment simulated on the avatar without a window.
//!
//! * `sim`: the garment on the avatar walking a BVH clip (the motion pipeline's poses, 30 Hz,
//!   interpolated to the 120 Hz cloth steps): per-step cost, penetration, strain, resets.
//! * `fit`: the garment draped on the body standing in its rest pose: the fit map's figures
//!   (strain, gap) and the ease at the bust, waist and hip.
//! * `bench`: the cloth step's cost for the dress on the walking avatar (as shipped, and meshed
//!   again to about 4,000 particles, the size of the speed goal's dress), and its growth with
//!   the particle count.

use std::path::Path;

use anyhow::{Context, Result, bail};
use fitroom_body::{
    BodyModel, Shape, ShapedBody,
    measure::{Plane, cross_section, hull_perimeter},
    skinning::{RigidTransform, skinning_matrices},
};
use fitroom_cloth::SolverSettings;
use fitroom_garment::sim::{GarmentSim, SimGarment};
use fitroom_garment::{BodySurface, GarmentMesh, GarmentSource, Pattern};
use fitroom_motion::{AvatarPipeline, eval::clean_stream};
use fitroom_sensor::bvh_source::BvhSource;
use glam::{Affine3A, Quat, Vec2, Vec3};
use serde::Serialize;

/// The cloth rate.
pub const STEP_HZ: f32 = 120.0;

/// Loads a garment (pattern `.ron`, or a mesh garment `.obj` / `.glb` / `.gltf` with its
/// fabric) in `size` on the body shaped by `shape`.
pub fn load_garment(
    model: &BodyModel,
    shape: &Shape,
    garment: &Path,
    size: Option<&str>,
) -> Result<(ShapedBody, GarmentMesh)> {
    let shaped = model.shaped(shape)?;
    let body = BodySurface::new(model, &shaped)?;
    let mesh = mesh_garment(&body, garment, size, None)?;
    Ok((shaped, mesh))
}

/// The garment of [`load_garment`] on `body`; a pattern is meshed at `edge_cm` instead of its
/// file's `target_edge_cm` if given (a mesh garment ignores it).
fn mesh_garment(
    body: &BodySurface,
    garment: &Path,
    size: Option<&str>,
    edge_cm: Option<f32>,
) -> Result<GarmentMesh> {
    let mut source = GarmentSource::load(garment)?;
    if let (Some(edge), Some(pattern)) = (edge_cm, source.pattern_mut()) {
        pattern.target_edge_cm = edge;
    }
    Ok(source.build(body, size)?)
}

fn sim_garment(mesh: &GarmentMesh) -> SimGarment {
    SimGarment::from_mesh(mesh)
}

/// Skinning transforms (rest model space -> sensor space) of an avatar pose.
fn skinning_of(rest: &fitroom_body::RestPose, rotations: &[Quat], heads: &[Vec3]) -> Vec<Affine3A> {
    let posed: Vec<RigidTransform> = rotations
        .iter()
        .zip(heads)
        .map(|(&r, &h)| RigidTransform::new(r, h))
        .collect();
    skinning_matrices(rest, &posed)
}

/// Summary statistics of a series.
#[derive(Debug, Serialize, Clone, Copy, Default)]
pub struct Stats {
    pub mean: f64,
    pub p50: f64,
    pub p95: f64,
    pub max: f64,
}

fn stats(mut v: Vec<f64>) -> Stats {
    if v.is_empty() {
        return Stats::default();
    }
    v.sort_by(|a, b| a.total_cmp(b));
    let at = |q: f64| v[((v.len() - 1) as f64 * q).round() as usize];
    Stats {
        mean: v.iter().sum::<f64>() / v.len() as f64,
        p50: at(0.5),
        p95: at(0.95),
        max: at(1.0),
    }
}

/// The JSON of `fitroom cloth sim`.
#[derive(Debug, Serialize)]
pub struct SimReport {
    pub garment: String,
    pub size: String,
    pub fabric: String,
    /// The garment's vertices.
    pub particles: usize,
    /// Vertices attached to the body by the garment's bands (its skinned panels not counted).
    pub attached: usize,
    /// The particles the solver steps: the free vertices and the attached or skinned ones that
    /// share a constraint with them (the rest of a skinned part is skinned where it is drawn).
    pub simulated_particles: usize,
    pub colliders: usize,
    pub motion: String,
    /// Video frames simulated (each 1/30 s of the clip: four 120 Hz cloth steps).
    pub frames: usize,
    pub steps: usize,
    pub substeps: u32,
    /// CPU time of one 120 Hz cloth step (attachments, colliders, solve), ms.
    pub step_ms: Stats,
    /// CPU time of the cloth per video frame, ms.
    pub frame_ms: Stats,
    /// Deepest particle inside a body collider after a step, mm.
    pub max_penetration_mm: f32,
    /// Largest radius a collider gave up to the skinned (attached) garment in a step, mm
    /// (`fitroom_garment::sim::fit_to_anchors`).
    pub max_collider_shrink_mm: f32,
    /// Largest edge stretch over the run, % (includes the start, where the garment is put in
    /// the skinned pose of the first frame).
    pub max_strain_pct: f32,
    /// Per-vertex strain (largest stretch of its edges, %) at the end of the run.
    pub final_strain_pct: Stats,
    /// Longest tether over the run against its rest geodesic length (the limit is 1.1).
    pub max_tether_ratio: f32,
    /// Blow-ups reset to the skinned pose.
    pub resets: u32,
    /// The first blow-up's cause, if any.
    pub first_blow_up: Option<String>,
    /// Body teleports (the clip looping) the garment was carried across.
    pub teleports: u32,
    pub all_finite: bool,
}

/// `fitroom cloth sim`: the garment put on the body at the clip's first frame, then stepped
/// through the next `frames - 1` frames (with `frames` 0 or 1 only put on).
pub fn sim(
    model: &BodyModel,
    shape: &Shape,
    garment: &Path,
    size: Option<&str>,
    motion: &Path,
    frames: usize,
    threads: Option<usize>,
) -> Result<(SimReport, GarmentSim, Vec<Affine3A>)> {
    let (shaped, mesh) = load_garment(model, shape, garment, size)?;
    sim_mesh(model, &shaped, &mesh, motion, frames, threads, false)
}

/// The body walking a motion as the cloth sees it: the motion pipeline's 30 Hz poses,
/// interpolated to the 120 Hz cloth steps, as skinning transforms. Frames past the clip's end
/// wrap to its start.
pub struct Walk<'a> {
    /// The floor's height in the motion's space.
    pub floor_y: f32,
    /// The skinning at the first frame.
    pub first: Vec<Affine3A>,
    rest: &'a fitroom_body::RestPose,
    pipeline: AvatarPipeline,
    stream: Vec<fitroom_sensor::SensorFrame>,
    next: usize,
    last: (Vec<Quat>, Vec<Vec3>),
    /// Play the clip back and forth instead of jumping from its end to its start.
    ping_pong: bool,
}

impl<'a> Walk<'a> {
    /// The body `shaped` walking the BVH clip `motion`.
    pub fn new(model: &BodyModel, shaped: &'a ShapedBody, motion: &Path) -> Result<Self> {
        let source = BvhSource::load(motion, Default::default())
            .with_context(|| format!("cannot load the motion '{}'", motion.display()))?;
        let floor_y = -source.options().sensor_height_m;
        let skeleton = fitroom_motion::avatar_skeleton(model, &shaped.rest_pose)?;
        let mut pipeline = AvatarPipeline::new(&skeleton, floor_y)?;
        let stream = clean_stream(&source);
        let Some(frame) = stream.first() else {
            bail!("'{}' has no frames", motion.display());
        };
        let pose = pipeline.pose(frame, WALK_FRAME_S);
        let last = (pose.rotations.clone(), pose.heads.clone());
        Ok(Self {
            floor_y,
            first: skinning_of(&shaped.rest_pose, &last.0, &last.1),
            rest: &shaped.rest_pose,
            pipeline,
            stream,
            next: 1,
            last,
            ping_pong: false,
        })
    }

    /// The same walk played forwards, then backwards, and so on: no jump back to the start
    /// (which the garment crosses as a teleport).
    pub fn ping_pong(mut self) -> Self {
        self.ping_pong = true;
        self
    }

    /// The clip's frames (30 Hz); past the last, [`Self::next_frame`] wraps to the first, or
    /// turns back ([`Self::ping_pong`]).
    pub fn frames(&self) -> usize {
        self.stream.len()
    }

    /// The skinning of each 120 Hz step of the next frame.
    pub fn next_frame(&mut self) -> Vec<Vec<Affine3A>> {
        let len = self.stream.len();
        let index = if self.ping_pong && len > 1 {
            let period = 2 * (len - 1);
            let k = self.next % period;
            if k < len { k } else { period - k }
        } else {
            self.next % len
        };
        let frame = &self.stream[index];
        self.next += 1;
        let pose = self.pipeline.pose(frame, WALK_FRAME_S);
        let now = (pose.rotations.clone(), pose.heads.clone());
        let (r0, h0) = std::mem::replace(&mut self.last, now);
        let now = &self.last;
        let per_frame = (STEP_HZ * WALK_FRAME_S).round() as usize;
        (1..=per_frame)
            .map(|k| {
                let t = k as f32 / per_frame as f32;
                let rot: Vec<Quat> = r0.iter().zip(&now.0).map(|(a, b)| a.slerp(*b, t)).collect();
                let head: Vec<Vec3> = h0.iter().zip(&now.1).map(|(a, b)| a.lerp(*b, t)).collect();
                skinning_of(self.rest, &rot, &head)
            })
            .collect()
    }
}

/// The motion's frame interval as the walk plays it, s.
const WALK_FRAME_S: f32 = 1.0 / 30.0;

/// The simulation of `mesh` on the body `shaped`, on the floor of `walk`, put on in its
/// first pose.
pub fn garment_on_walk(
    model: &BodyModel,
    shaped: &ShapedBody,
    mesh: &GarmentMesh,
    walk: &Walk<'_>,
    settings: SolverSettings,
) -> Result<GarmentSim> {
    let mut sim = GarmentSim::new(
        model,
        &shaped.positions,
        &shaped.rest_pose,
        &sim_garment(mesh),
        settings,
    )?;
    sim.set_floor(Some(walk.floor_y))?;
    sim.reset(&walk.first)?;
    Ok(sim)
}

/// [`sim`] of a garment already meshed on the body `shaped`.
fn sim_mesh(
    model: &BodyModel,
    shaped: &ShapedBody,
    mesh: &GarmentMesh,
    motion: &Path,
    frames: usize,
    threads: Option<usize>,
    ping_pong: bool,
) -> Result<(SimReport, GarmentSim, Vec<Affine3A>)> {
    let mut walk = Walk::new(model, shaped, motion)?;
    if ping_pong {
        walk = walk.ping_pong();
    }
    let mut settings = SolverSettings::default();
    if let Some(t) = threads {
        settings.threads = t.max(1);
    }
    let substeps = settings.substeps;
    let mut sim = garment_on_walk(model, shaped, mesh, &walk, settings)?;
    let (mut step_ms, mut frame_ms) = (Vec::new(), Vec::new());
    let (mut max_pen, mut max_strain, mut max_shrink) = (0.0f32, 0.0f32, 0.0f32);
    let mut all_finite = true;
    let mut first_blow_up: Option<String> = None;
    let mut max_tether = 0.0f32;
    let mut last_skin = walk.first.clone();
    for _ in 1..frames {
        let mut skins = walk.next_frame();
        let mut this_frame = 0.0;
        for skin in &skins {
            let step = sim.step(skin, 1.0 / STEP_HZ)?;
            step_ms.push(step.solve_ms);
            this_frame += step.solve_ms;
            if first_blow_up.is_none() {
                first_blow_up = step.blow_up.clone();
            }
            max_tether = max_tether.max(sim.max_tether_ratio());
            max_pen = max_pen.max(step.max_penetration_m);
            max_shrink = max_shrink.max(step.collider_shrink_m);
            max_strain = max_strain.max(step.max_strain_pct);
        }
        if let Some(skin) = skins.pop() {
            last_skin = skin;
        }
        frame_ms.push(this_frame);
        all_finite &= sim.positions().iter().all(|p| p.is_finite());
    }
    let report = SimReport {
        garment: mesh.name.clone(),
        size: mesh.size.clone(),
        fabric: mesh.fabric_name.clone(),
        particles: mesh.positions.len(),
        attached: mesh.attached.len(),
        simulated_particles: sim.simulated_particles(),
        colliders: sim.collider_count(),
        motion: motion.display().to_string(),
        frames,
        steps: step_ms.len(),
        substeps,
        step_ms: stats(step_ms),
        frame_ms: stats(frame_ms),
        max_penetration_mm: max_pen * 1e3,
        max_collider_shrink_mm: max_shrink * 1e3,
        max_strain_pct: max_strain,
        final_strain_pct: stats(sim.strain_pct().into_iter().map(f64::from).collect()),
        max_tether_ratio: max_tether,
        resets: sim.resets(),
        first_blow_up,
        teleports: sim.teleports(),
        all_finite,
    };
    Ok((report, sim, last_skin))
}

/// Ease of the garment at one landmark.
#[derive(Debug, Serialize)]
pub struct Ease {
    pub landmark: &'static str,
    /// Height above the sole, cm.
    pub height_cm: f32,
    pub body_girth_cm: f32,
    /// `None` where the garment does not go round the body at that height.
    pub garment_girth_cm: Option<f32>,
    /// Garment minus body girth, cm.
    pub ease_cm: Option<f32>,
}

/// The JSON of `fitroom cloth fit`.
#[derive(Debug, Serialize)]
pub struct FitMapReport {
    pub garment: String,
    pub size: String,
    pub fabric: String,
    pub particles: usize,
    pub settle_s: f32,
    pub max_strain_pct: f32,
    pub mean_strain_pct: f32,
    /// Mean distance of the garment from the body colliders, mm (positive outside).
    pub mean_gap_mm: f32,
    pub max_penetration_mm: f32,
    pub ease: Vec<Ease>,
}

/// `fitroom cloth fit`: the garment settles on the body in its rest pose.
pub fn fit_map(
    model: &BodyModel,
    shape: &Shape,
    garment: &Path,
    size: Option<&str>,
    settle_s: f32,
) -> Result<(FitMapReport, GarmentSim)> {
    let (shaped, mesh) = load_garment(model, shape, garment, size)?;
    let mut sim = GarmentSim::new(
        model,
        &shaped.positions,
        &shaped.rest_pose,
        &sim_garment(&mesh),
        SolverSettings::default(),
    )?;
    let body = &shaped.positions[..model.body_vertex_count as usize];
    let floor = body.iter().map(|p| p.y).fold(f32::INFINITY, f32::min);
    sim.set_floor(Some(floor))?;
    let identity = vec![Affine3A::IDENTITY; model.bones.len()];
    sim.reset(&identity)?;
    let steps = (settle_s * STEP_HZ).round().max(1.0) as usize;
    let mut max_pen = 0.0f32;
    for _ in 0..steps {
        let s = sim.step(&identity, 1.0 / STEP_HZ)?;
        max_pen = max_pen.max(s.max_penetration_m);
    }
    let strain = sim.strain_pct();
    let gap = sim.gap_m(&identity);
    let measured = model.measure(&shaped.positions)?;
    let l = &measured.landmarks;
    let girth_at = |points: &[Vec3], tris: &[[u32; 3]], h: f32, keep: &dyn Fn(Vec2) -> bool| {
        let loops = cross_section(points, tris, &Plane::horizontal(h));
        let pts: Vec<Vec2> = loops
            .iter()
            .filter(|l| keep(l.centroid()))
            .flat_map(|l| l.points.iter().copied())
            .collect();
        (pts.len() >= 3).then(|| hull_perimeter(&pts) * 100.0)
    };
    let mut ease = Vec::new();
    for (name, h_cm, body_cm) in [
        ("bust", l.bust_cm, measured.bust_cm),
        ("waist", l.waist_cm, measured.waist_cm),
        ("hip", l.hip_cm, measured.hip_cm),
    ] {
        let h = floor + h_cm / 100.0;
        // The garment's loops around the trunk (not a sleeve).
        let g = girth_at(&sim.positions(), sim.triangles(), h, &|c: Vec2| {
            c.x.abs() < 0.12
        });
        ease.push(Ease {
            landmark: name,
            height_cm: h_cm,
            body_girth_cm: body_cm,
            garment_girth_cm: g,
            ease_cm: g.map(|g| g - body_cm),
        });
    }
    let n = strain.len().max(1) as f32;
    let report = FitMapReport {
        garment: mesh.name.clone(),
        size: mesh.size.clone(),
        fabric: mesh.fabric_name.clone(),
        particles: mesh.positions.len(),
        settle_s,
        max_strain_pct: strain.iter().copied().fold(0.0, f32::max),
        mean_strain_pct: strain.iter().sum::<f32>() / n,
        mean_gap_mm: gap.iter().sum::<f32>() / gap.len().max(1) as f32 * 1e3,
        max_penetration_mm: max_pen * 1e3,
        ease,
    };
    Ok((report, sim))
}

/// The JSON of `fitroom cloth bench`.
#[derive(Debug, Serialize)]
pub struct BenchReport {
    /// The dress on the walking avatar.
    pub dress: SimReport,
    /// The same dress meshed again, to about [`DRESS_PARTICLES`] particles (the size of the
    /// goal's dress, seed 000's 4,088-vertex dress), on the same walk; `None` for a mesh
    /// garment (it cannot be meshed again).
    pub dress_4k: Option<SimReport>,
    /// The edge length `dress_4k` was meshed at, cm.
    pub dress_4k_edge_cm: Option<f32>,
    /// Per particle count (cylinders around the body's colliders, 10 substeps, 120 Hz): one
    /// step's cost, ms.
    pub scaling: Vec<(usize, Stats)>,
    pub threads: usize,
    pub goal_ms: f64,
}

/// The particle count of the speed goal's dress.
pub const DRESS_PARTICLES: usize = 4_000;

/// The pattern garment `dress` (in its middle size), meshed as its file says to `meshed`
/// particles, meshed again to about `particles`: the mesh and its edge length, cm.
fn remesh(
    body: &BodySurface,
    dress: &Path,
    meshed: usize,
    particles: usize,
) -> Result<(GarmentMesh, f32)> {
    // The particle count grows as the inverse square of the edge length (kept within what a
    // pattern file may ask for).
    let edge_cm = (Pattern::load(dress)?.target_edge_cm
        * (meshed as f32 / particles as f32).sqrt())
    .clamp(0.5, 20.0);
    let mesh = mesh_garment(body, dress, None, Some(edge_cm)).with_context(|| {
        format!(
            "cannot mesh '{}' again at {edge_cm:.2} cm edges for the {particles}-particle bench",
            dress.display()
        )
    })?;
    Ok((mesh, edge_cm))
}

/// The goal's dress: the pattern garment `dress` meshed to about [`DRESS_PARTICLES`]
/// particles (as `fitroom cloth bench` does) on the default body, which it returns too.
pub fn dress_4k(model: &BodyModel, dress: &Path) -> Result<(ShapedBody, GarmentMesh)> {
    let (shaped, body, base) = dress_on_default_body(model, dress)?;
    let (mesh, _) = remesh(&body, dress, base.positions.len(), DRESS_PARTICLES)?;
    Ok((shaped, mesh))
}

/// The default body, its surface, and `dress` (middle size, as its file meshes it) on it.
fn dress_on_default_body(
    model: &BodyModel,
    dress: &Path,
) -> Result<(ShapedBody, BodySurface, GarmentMesh)> {
    let shaped = model.shaped(&Shape::default())?;
    let body = BodySurface::new(model, &shaped)?;
    let mesh = mesh_garment(&body, dress, None, None)?;
    Ok((shaped, body, mesh))
}

/// `fitroom cloth bench`.
pub fn bench(model: &BodyModel, dress: &Path, motion: &Path, frames: usize) -> Result<BenchReport> {
    let (shaped, body, mesh) = dress_on_default_body(model, dress)?;
    let (report, _, _) = sim_mesh(model, &shaped, &mesh, motion, frames, None, true)?;
    let pattern = dress
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("ron"));
    let (dress_4k, edge_cm) = if pattern {
        let (fine, edge_cm) = remesh(&body, dress, report.particles, DRESS_PARTICLES)?;
        let (fine, _, _) = sim_mesh(model, &shaped, &fine, motion, frames, None, true)?;
        (Some(fine), Some(edge_cm))
    } else {
        (None, None)
    };
    let dress = report;
    let mut scaling = Vec::new();
    for (around, rows) in [(32u32, 32u32), (64, 64), (128, 128), (256, 256)] {
        // A tube around the hips and legs: a skirt-like cloth of around × rows particles.
        // Around the hips (model space: the hips at about y = 0), hanging to the knees.
        let mesh =
            fitroom_cloth::ClothMesh::cylinder(Vec3::new(0.0, -0.45, 0.0), 0.2, 0.5, around, rows)?;
        let positions: Vec<Vec3> = mesh.positions().to_vec();
        let attached: Vec<u32> =
            fitroom_cloth::ClothMesh::cylinder_ring(around, rows - 1).collect();
        let garment = SimGarment {
            positions,
            triangles: mesh.triangles().to_vec(),
            attached,
            fabric: fitroom_cloth::Fabric::cotton(),
            ignore_colliders: Vec::new(),
        };
        let mut s = GarmentSim::new(
            model,
            &shaped.positions,
            &shaped.rest_pose,
            &garment,
            SolverSettings::default(),
        )?;
        let identity = vec![Affine3A::IDENTITY; model.bones.len()];
        s.reset(&identity)?;
        let mut times = Vec::new();
        let n = if around >= 256 { 10 } else { 40 };
        for _ in 0..n {
            times.push(s.step(&identity, 1.0 / STEP_HZ)?.solve_ms);
        }
        scaling.push(((around * rows) as usize, stats(times)));
    }
    Ok(BenchReport {
        dress,
        dress_4k,
        dress_4k_edge_cm: edge_cm,
        scaling,
        threads: SolverSettings::default().threads,
        goal_ms: 0.6,
    })
}
