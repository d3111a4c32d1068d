//! `fitroom cloth sim|fit|bench`: a garment simulated on the avatar without a window.
//!
//! * `sim`: the garment on the avatar walking a BVH clip ([`fitroom_motion::walk::Walk`]: the
//!   motion pipeline's poses, 30 Hz, interpolated to the 120 Hz cloth steps): per-step cost,
//!   penetration, strain, resets.
//! * `fit`: the garment draped on the body standing in its rest pose: the fit map's figures
//!   (strain, gap) and the ease at the bust, waist and hip.
//! * `bench`: the cloth step's cost for the dress on the walking avatar (as shipped, and meshed
//!   again to about 4,000 particles, the size of the speed goal's dress), and its growth with
//!   the particle count.

use std::path::{Path, PathBuf};

use anyhow::Result;
use clap::Subcommand;
use fitroom_body::{BodyModel, Shape, ShapedBody};
use fitroom_cloth::SolverSettings;
use fitroom_garment::sim::{GarmentSim, SimGarment};
use fitroom_garment::{BodySurface, GarmentMesh, GarmentSource};
use fitroom_math::stats::Summary;
use fitroom_motion::walk::Walk;
use glam::Affine3A;
use serde::Serialize;

use super::{BodyArg, OutputArgs, body::load_shape};

pub mod bench;
pub mod fit;

pub use bench::{BenchReport, DRESS_PARTICLES, bench, dress_4k};
pub use fit::{FitMapReport, fit_map};
pub use fitroom_garment::ease::Ease;
/// The cloth rate.
pub use fitroom_motion::walk::STEP_HZ;

#[derive(Subcommand)]
pub enum ClothCommand {
    /// The garment on the avatar walking a clip: per-step cost, penetration, strain, resets.
    Sim {
        /// A garment file (pattern .ron, or .obj/.glb), e.g. assets/garments/sundress.ron.
        #[arg(long)]
        garment: PathBuf,
        /// A size label of the garment (default: its middle size).
        #[arg(long)]
        size: Option<String>,
        /// BVH clip (default: the embedded walk).
        #[arg(long)]
        motion: Option<PathBuf>,
        /// Video frames (1/30 s of the clip each).
        #[arg(long, default_value_t = 120)]
        frames: usize,
        #[arg(long)]
        shape: Option<PathBuf>,
        #[arg(long)]
        threads: Option<usize>,
        #[command(flatten)]
        body: BodyArg,
        #[command(flatten)]
        output: OutputArgs,
    },
    /// The garment settled on the body at rest: strain, gap and the ease at bust, waist, hip.
    Fit {
        #[arg(long)]
        garment: PathBuf,
        #[arg(long)]
        size: Option<String>,
        #[arg(long)]
        shape: Option<PathBuf>,
        /// Simulated settling time, s.
        #[arg(long, default_value_t = 1.5)]
        settle: f32,
        #[command(flatten)]
        body: BodyArg,
        #[command(flatten)]
        output: OutputArgs,
    },
    /// The cloth step's cost: the dress on the walking avatar (as shipped and meshed to about
    /// 4,000 particles), and 1k-64k particles.
    Bench {
        #[arg(long)]
        garment: Option<PathBuf>,
        /// Motion frames (30 Hz, four steps each) the dresses walk, the clip played back and
        /// forth: 240 is about half a second of stepping for the 4,000-particle dress, so
        /// that a hiccup of the machine shorter than that does not decide the median (with
        /// 60 frames one did: 0.771 ms once).
        #[arg(long, default_value_t = 240)]
        frames: usize,
        #[command(flatten)]
        body: BodyArg,
        #[command(flatten)]
        output: OutputArgs,
    },
}

pub fn run(command: ClothCommand) -> Result<()> {
    let assets = crate::assets::assets_dir()?;
    match command {
        ClothCommand::Sim {
            garment,
            size,
            motion,
            frames,
            shape,
            threads,
            body,
            output,
        } => {
            let model = body.load()?;
            let shape = load_shape(shape.as_deref())?;
            let motion = motion.unwrap_or_else(|| assets.join(crate::assets::DEFAULT_MOTION));
            let (r, _, _) = sim(
                &model,
                &shape,
                &garment,
                size.as_deref(),
                &motion,
                frames,
                threads,
            )?;
            output.print(&r, print_sim)
        }
        ClothCommand::Fit {
            garment,
            size,
            shape,
            settle,
            body,
            output,
        } => {
            let model = body.load()?;
            let shape = load_shape(shape.as_deref())?;
            let (r, _) = fit_map(&model, &shape, &garment, size.as_deref(), settle)?;
            output.print(&r, fit::print_fit)
        }
        ClothCommand::Bench {
            garment,
            frames,
            body,
            output,
        } => {
            let model = body.load()?;
            let dress = garment.unwrap_or_else(|| assets.join("garments/sundress.ron"));
            let motion = assets.join(crate::assets::DEFAULT_MOTION);
            let r = bench(&model, &dress, &motion, frames)?;
            output.print(&r, bench::print_bench)
        }
    }
}

/// Summary statistics of a series, as the reports print them
/// ([`fitroom_math::stats::Summary`] without its sample count).
#[derive(Debug, Serialize, Clone, Copy, Default)]
pub struct Stats {
    pub mean: f64,
    pub p50: f64,
    pub p95: f64,
    pub max: f64,
}

impl Stats {
    /// The statistics of `values`.
    pub fn of(values: &[f64]) -> Self {
        Self::from(Summary::of(values))
    }
}

impl From<Summary> for Stats {
    fn from(s: Summary) -> Self {
        Self {
            mean: s.mean,
            p50: s.p50,
            p95: s.p95,
            max: s.max,
        }
    }
}

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
pub(crate) fn mesh_garment(
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
    /// FNV-1a hash of the bits of every particle position after the last step, in hex: two
    /// builds that simulate the same bit for bit give the same checksum.
    pub checksum: String,
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
        &SimGarment::from_mesh(mesh),
        settings,
    )?;
    sim.set_floor(Some(walk.floor_y))?;
    sim.reset(&walk.first)?;
    Ok(sim)
}

/// [`sim`] of a garment already meshed on the body `shaped`.
pub(crate) fn sim_mesh(
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
        step_ms: Stats::of(&step_ms),
        frame_ms: Stats::of(&frame_ms),
        max_penetration_mm: max_pen * 1e3,
        max_collider_shrink_mm: max_shrink * 1e3,
        max_strain_pct: max_strain,
        final_strain_pct: Stats::of(
            &sim.strain_pct()
                .into_iter()
                .map(f64::from)
                .collect::<Vec<_>>(),
        ),
        max_tether_ratio: max_tether,
        resets: sim.resets(),
        first_blow_up,
        teleports: sim.teleports(),
        all_finite,
        checksum: positions_checksum(&sim.positions()),
    };
    Ok((report, sim, last_skin))
}

/// FNV-1a (64 bit) over the little-endian bits of every coordinate, in hex.
fn positions_checksum(positions: &[glam::Vec3]) -> String {
    let mut hash: u64 = 0xcbf2_9ce4_8422_2325;
    for p in positions {
        for v in [p.x, p.y, p.z] {
            for b in v.to_bits().to_le_bytes() {
                hash = (hash ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3);
            }
        }
    }
    format!("{hash:016x}")
}

fn print_sim(r: &SimReport) {
    println!(
        "{} size {} ({}): {} particles, {} attached, {} colliders; {} steps of 1/120 s, {} substeps\n\
         step {:.2} ms mean, {:.2} p95, {:.2} max; per video frame {:.2} ms mean\n\
         max penetration {:.2} mm, longest tether {:.3} of its rest length, max strain {:.1}%, resets {}, all finite: {}\n\
         colliders gave up at most {:.1} mm of radius to the skinned garment",
        r.garment,
        r.size,
        r.fabric,
        r.particles,
        r.attached,
        r.colliders,
        r.steps,
        r.substeps,
        r.step_ms.mean,
        r.step_ms.p95,
        r.step_ms.max,
        r.frame_ms.mean,
        r.max_penetration_mm,
        r.max_tether_ratio,
        r.max_strain_pct,
        r.resets,
        r.all_finite,
        r.max_collider_shrink_mm
    );
}
