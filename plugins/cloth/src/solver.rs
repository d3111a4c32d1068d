//! The substepped XPBD cloth solver.
//!
//! # One step
//!
//! A step of length `dt` (1/120 s in the kiosk, seed 000 ch. 7) runs `n` substeps of
//! `h = dt/n` with one constraint iteration each by default: many small steps converge better
//! than many iterations of one big step (Macklin et al. 2019, "Small steps in physics
//! simulation"). Per step, once:
//!
//! 1. the body frame's motion is estimated ([`crate::frame`]), collider poses are interpolated
//!    to every substep boundary ([`crate::collision`]);
//! 2. aerodynamic drag and lift are computed per triangle from the current velocities and the
//!    seeded wind ([`crate::wind`]) and held over the step.
//!
//! Per substep (seed 000 Algorithm 5, the PBD loop of Müller et al. 2007, with XPBD
//! compliance):
//!
//! 3. **predict**: `v += h·(g + f_ext/m + fictitious)`, `v *= exp(−damping·h)`,
//!    `x* = x + h·v`; attached particles move to their targets interpolated linearly across the
//!    substeps between last frame's and this frame's targets;
//! 4. **constraints**: stretch, shear and isometric bending, block by block in parallel, then
//!    the constraints between blocks ([`crate::constraints`]);
//! 5. **tethers** (Kim et al. 2012): a particle farther from an attachment than its rest
//!    geodesic distance × `tether_scale` is put back on that sphere; with two tethers (the
//!    default) it goes to the nearest point of the intersection of the two balls, computed in
//!    closed form; with more, projections onto the balls alternate;
//! 6. **collision** against the swept colliders and planes, with friction; each chunk of at
//!    most 32 neighbouring particles ([`crate::order`]) is tested only against the
//!    colliders whose swept bounds meet the chunk's bounds;
//! 7. if a collision pushed a particle beyond its tether, the particle **slides** along the
//!    collider's tangent plane to a point its tethers allow; if there is none, the **tether
//!    wins** and the particle goes to the nearest collider surface (an inextensible garment
//!    slips around a limb instead of being dragged and stretched). This repair is kept out of
//!    the velocity;
//! 8. **velocity** `v = (x − x_prev)/h`.
//!
//! Steps 5–8 and the next substep's step 3 touch one particle each and run as one parallel
//! pass over groups of collision chunks (a quarter of a block each, so that the threads can
//! share out the uneven collision work); then the blocks' constraints run as one parallel
//! pass, one item per block (their work is nearly equal). After the last
//! substep a **blow-up guard** looks for non-finite positions or velocities, speeds above
//! [`BlowUpGuard::max_speed_m_s`] and constraints stretched beyond
//! [`BlowUpGuard::max_stretch_ratio`], and reports it in the [`StepReport`]; the caller should
//! then [`ClothSolver::reset_to`] the skinned pose.
//!
//! # Determinism and threads
//!
//! All work is split into items that do not depend on the thread count ([`crate::pool`]):
//! the blocks of [`crate::order`], the seams and corners of [`crate::constraints`], and fixed
//! ranges of triangles. So a step gives bit-for-bit the same result on 1, 2 or 4 threads, and
//! with or without AVX ([`crate::simd`]). The solver keeps its particles in the bisection
//! order of [`crate::order`]; positions and velocities are written in the mesh's vertex order
//! at the end of each step, inside the parallel pass (and read back only after
//! [`ClothSolver::positions_mut`]). No memory is allocated during a step (the buffers grow
//! only when the collider count or the substep count grows).
//!
//! A thread that the operating system deschedules while it holds an item stalls the others
//! at the next synchronisation for the rest of its time slice (milliseconds). Items take
//! microseconds, so when a thread waited over a millisecond at once for another's item (a
//! wait that began before every thread had joined the step does not count: a worker still
//! waking up holds no item), and that happened before within the last `SOLO_STEPS` steps,
//! the next `SOLO_STEPS` steps (half a second) run on the caller's thread alone, which gives
//! the same result; then the workers are tried again. On a machine shared with other busy
//! processes this costs at most two slow steps in 120; a lone stall (a virtual machine's
//! processor taken away for a moment) costs only itself.

use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};

use glam::{Vec3, Vec3A};

use crate::collision::{MAX_COLLIDERS, Plane, Shape, Sphere, SweptCollider, collide_plane};
use crate::constraints::{
    BendFrame, BendTarget, ConstraintSet, RunKind, max_stretch_squared, solve_bend, solve_distance,
};
use crate::error::{ClothError, non_negative, positive};
use crate::fabric::Fabric;
use crate::frame::{FrameInertia, FrameMotion, FrameState, RigidPose};
use crate::mesh::{ClothMesh, MeshTopology};
use crate::order::ParticleOrder;
use crate::pool::{Dep, PhaseCounters, SharedSlice, WorkerPool};
use crate::simd::{Isa, LANES, Lanes, V3, dispatch_lanes, offset};
use crate::wind::{Wind, triangle_force_lanes};

/// Work items per block for the particles' part of a substep (prediction, tethers,
/// collisions): collisions make some blocks' particles several times as costly as others'
/// (those by the legs), and smaller items let the threads share that out. Blocks' constraint
/// work is the same for every block.
const PARTICLE_GROUPS: usize = 4;
/// Triangles per aerodynamics work item.
const TRIANGLE_ITEM: usize = 1024;
/// Alternations between the tethers of one particle.
const TETHER_ROUNDS: usize = 6;
/// Alternations between tethers and collider push-out when they conflict.
const RECONCILE_ROUNDS: usize = 8;
/// Rounds of the joint push-out of a particle inside overlapping colliders.
const OVERLAP_ROUNDS: usize = 6;
/// Longest joint push-out out of two shapes, in multiples of the deeper one's depth (the
/// crease of two surfaces meeting at 60° or more).
const CREASE_REACH: f32 = 2.0;
/// A parallel step in which a thread waited longer than this at once for another's work item
/// (they take microseconds) was slowed down by the operating system descheduling a thread.
const STALL_MIN_NS: u64 = 1_000_000;
/// Steps then run on the caller's thread alone before threads are tried again (half a second
/// at 120 Hz).
const SOLO_STEPS: u32 = 60;

/// Thresholds of the blow-up guard.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BlowUpGuard {
    /// A particle faster than this (m/s) counts as a blow-up.
    pub max_speed_m_s: f32,
    /// A stretch or shear constraint longer than this multiple of its rest length counts as a
    /// blow-up. The default, 6, lies above what a pinch reaches and recovers from: a T-shirt
    /// caught between an upper arm swept into the chest and the trunk stretches 4.0-4.1 times
    /// for a few steps and is back under 1.4 once the arm withdraws, while a reset there put
    /// the shirt's skinned pose 41 mm inside the arm (`tests/garment_robust.rs`; with 4 it
    /// fired or not depending on the order the solver visits particles in).
    pub max_stretch_ratio: f32,
}

impl Default for BlowUpGuard {
    fn default() -> Self {
        Self {
            max_speed_m_s: 100.0,
            max_stretch_ratio: 6.0,
        }
    }
}

/// Solver settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SolverSettings {
    /// Substeps per step (10 at 120 Hz gives 1,200 substeps per second).
    pub substeps: u32,
    /// Constraint iterations per substep (1 is the small-steps choice).
    pub iterations: u32,
    /// Threads that solve a step, the caller's included. Results do not depend on it.
    pub threads: usize,
    /// Gravity in world coordinates, m/s².
    pub gravity: Vec3,
    /// Skin distance kept between particles and colliders, metres.
    pub collision_thickness: f32,
    /// Tether length as a multiple of the rest geodesic distance, in `[1.0, 1.1]`.
    pub tether_scale: f32,
    /// Attachments each free particle is tethered to (0 disables tethers).
    pub tethers_per_particle: usize,
    /// Air density for drag and lift, kg/m³ (0 disables aerodynamics).
    pub air_density_kg_m3: f32,
    /// Optional cap on particle speed, m/s, applied after each substep.
    pub max_velocity_m_s: Option<f32>,
    /// How much of the body frame's inertia the cloth feels ([`crate::frame`]).
    pub frame_inertia: FrameInertia,
    /// Blow-up thresholds.
    pub guard: BlowUpGuard,
}

impl Default for SolverSettings {
    fn default() -> Self {
        Self {
            substeps: 10,
            iterations: 1,
            threads: std::thread::available_parallelism()
                .map(|n| n.get().min(4))
                .unwrap_or(1),
            gravity: Vec3::new(0.0, -9.81, 0.0),
            collision_thickness: 0.003,
            tether_scale: 1.0,
            tethers_per_particle: 2,
            air_density_kg_m3: 1.2,
            max_velocity_m_s: None,
            frame_inertia: FrameInertia::FULL,
            guard: BlowUpGuard::default(),
        }
    }
}

impl SolverSettings {
    /// Checks every setting's range.
    pub fn validate(&self) -> Result<(), ClothError> {
        let range = |what, value: u64, lo: u64, hi: u64, requirement| {
            if value < lo || value > hi {
                Err(ClothError::InvalidParameter {
                    what,
                    requirement,
                    value: value as f64,
                })
            } else {
                Ok(())
            }
        };
        range(
            "substeps",
            self.substeps as u64,
            1,
            1000,
            "between 1 and 1000",
        )?;
        range(
            "iterations",
            self.iterations as u64,
            1,
            100,
            "between 1 and 100",
        )?;
        range("threads", self.threads as u64, 1, 64, "between 1 and 64")?;
        range(
            "tethers per particle",
            self.tethers_per_particle as u64,
            0,
            8,
            "between 0 and 8",
        )?;
        if !self.gravity.is_finite() {
            return Err(ClothError::NonFiniteInput {
                what: "gravity",
                index: 0,
            });
        }
        non_negative("collision thickness (m)", self.collision_thickness)?;
        if !self.collision_thickness.is_finite() {
            return Err(ClothError::InvalidParameter {
                what: "collision thickness (m)",
                requirement: "finite",
                value: self.collision_thickness as f64,
            });
        }
        if !(1.0..=1.1).contains(&self.tether_scale) {
            return Err(ClothError::InvalidParameter {
                what: "tether scale",
                requirement: "between 1.0 and 1.1",
                value: self.tether_scale as f64,
            });
        }
        non_negative("air density (kg/m³)", self.air_density_kg_m3)?;
        if let Some(v) = self.max_velocity_m_s {
            positive("maximum velocity (m/s)", v)?;
        }
        for (what, s) in [
            ("linear frame inertia", self.frame_inertia.linear),
            ("angular frame inertia", self.frame_inertia.angular),
            ("centrifugal frame inertia", self.frame_inertia.centrifugal),
        ] {
            if !(0.0..=1.0).contains(&s) {
                return Err(ClothError::InvalidParameter {
                    what,
                    requirement: "between 0 and 1",
                    value: s as f64,
                });
            }
        }
        positive("guard maximum speed (m/s)", self.guard.max_speed_m_s)?;
        positive("guard maximum stretch ratio", self.guard.max_stretch_ratio)?;
        Ok(())
    }
}

/// What the blow-up guard found.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum BlowUp {
    /// A position or velocity is NaN or infinite.
    NonFinite {
        /// The first such particle.
        particle: usize,
    },
    /// A particle moves faster than the guard allows.
    Speed {
        /// The fastest particle.
        particle: usize,
        /// Its speed, m/s.
        speed_m_s: f32,
    },
    /// A constraint is stretched beyond the guard's ratio.
    Stretch {
        /// Its two particles.
        vertices: [u32; 2],
        /// Current length over rest length.
        ratio: f32,
    },
}

/// The state of the simulation after a step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Health {
    /// Finite and within the guard's bounds.
    Ok,
    /// The simulation has blown up: reset it (e.g. to the skinned pose) with
    /// [`ClothSolver::reset_to`].
    BlownUp(BlowUp),
}

/// What a step reports.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepReport {
    /// Blow-up guard verdict.
    pub health: Health,
    /// Fastest particle speed, m/s (NaN if a velocity is not finite).
    pub max_speed_m_s: f32,
    /// Largest length / rest length over stretch and shear constraints.
    pub max_stretch_ratio: f32,
}

impl StepReport {
    /// Whether the guard found nothing wrong.
    pub fn is_healthy(&self) -> bool {
        self.health == Health::Ok
    }
}

/// Static data of a cloth: masses, constraints, tethers, attachments.
///
/// Per-particle arrays are in the solver's order ([`ParticleOrder`]) unless they say mesh.
struct Model {
    order: ParticleOrder,
    /// Mesh order (for the API).
    inverse_mass_mesh: Vec<f32>,
    /// Mesh order (for the API).
    mass_mesh: Vec<f32>,
    inverse_mass: Vec<f32>,
    /// Triangles (solver numbering).
    triangles: Vec<[u32; 3]>,
    /// Triangles around each particle.
    vertex_triangles_start: Vec<u32>,
    vertex_triangles: Vec<u32>,
    /// Per particle: its first eight triangles, padded with `triangles.len()` (a slot of the
    /// triangle forces that stays zero), so that [`StepContext::load`] adds a fixed eight
    /// without a data-dependent loop; more than eight (rare) are added one by one.
    vertex_triangles8: Vec<[u32; LANES]>,
    constraints: ConstraintSet,
    tether_start: Vec<u32>,
    tether_slot: Vec<u32>,
    tether_rest: Vec<f32>,
    tether_limit: Vec<f32>,
    /// Attached mesh vertices, in the order of the targets.
    attached: Vec<u32>,
    attach_slot: Vec<u32>,
    /// Per particle `i`: which eight-particle paths the particles `i..i + 8` may take
    /// ([`EIGHT_FREE`], [`EIGHT_ATTACHED`], [`EIGHT_TWO_TETHERS`]); none where fewer than
    /// eight particles are left. Checked once here, not every substep.
    eight: Vec<u8>,
    fabric: Fabric,
    settings: SolverSettings,
    reach: SeparatorReach,
}

/// [`Model::eight`]: all eight particles are free.
const EIGHT_FREE: u8 = 1;
/// [`Model::eight`]: all eight particles are attached.
const EIGHT_ATTACHED: u8 = 2;
/// [`Model::eight`]: all eight particles have exactly two tethers.
const EIGHT_TWO_TETHERS: u8 = 4;

/// [`Model::eight`] from the solver-ordered inverse masses and tether lists.
fn eight_flags(inverse_mass: &[f32], tether_start: &[u32]) -> Vec<u8> {
    let n = inverse_mass.len();
    (0..n)
        .map(|i| {
            if i + LANES > n {
                return 0;
            }
            let w = &inverse_mass[i..i + LANES];
            let mut flags = 0;
            if w.iter().all(|&w| w > 0.0) {
                flags |= EIGHT_FREE;
            }
            if w.iter().all(|&w| w == 0.0) {
                flags |= EIGHT_ATTACHED;
            }
            if (i..i + LANES).all(|i| tether_start[i + 1] - tether_start[i] == 2) {
                flags |= EIGHT_TWO_TETHERS;
            }
            flags
        })
        .collect()
}

impl Model {
    /// [`Model::eight`] at particle `i` of a range that ends at `end`: none if fewer than
    /// eight particles are left in the range.
    #[inline]
    fn eight_at(&self, i: usize, end: usize) -> u8 {
        if i + LANES <= end { self.eight[i] } else { 0 }
    }
}

/// Lists of `u32` in one array (`start` has one entry per list, and the total last).
#[derive(Debug, Clone, Default)]
struct Lists {
    start: Vec<u32>,
    values: Vec<u32>,
}

impl Lists {
    fn push(&mut self, list: impl IntoIterator<Item = u32>) {
        if self.start.is_empty() {
            self.start.push(0);
        }
        self.values.extend(list);
        self.start.push(self.values.len() as u32);
    }

    fn get(&self, i: usize) -> &[u32] {
        &self.values[self.start[i] as usize..self.start[i + 1] as usize]
    }
}

/// Which blocks each separator (seam or corner) moves particles of, and
/// the separators that move particles of each group: what a step's items wait for (see
/// `ClothSolver::set_dependencies`).
#[derive(Debug, Clone, Default)]
struct SeparatorReach {
    /// Per separator (constraint item `blocks + j`): the blocks it touches.
    blocks: Lists,
    /// Per separator: its level and its index in that level's phase.
    place: Vec<(u32, u32)>,
    /// Per particle group: the separators that touch it.
    of_group: Lists,
}

impl SeparatorReach {
    fn new(order: &ParticleOrder, constraints: &ConstraintSet) -> Self {
        let n = order.to_mesh.len() as u32;
        let blocks = order.blocks();
        let mut reach = Self::default();
        let mut of_group = vec![Vec::new(); blocks * PARTICLE_GROUPS];
        for (level, &(a, b)) in constraints.separator_levels.iter().enumerate() {
            for item in a..b {
                let mut particles: Vec<u32> = constraints
                    .item_particles(item as usize)
                    .filter(|&i| i < n)
                    .collect();
                particles.sort_unstable();
                particles.dedup();
                let mut groups: Vec<u32> = particles.iter().map(|&i| group_of(order, i)).collect();
                groups.dedup();
                let mut touched: Vec<u32> =
                    groups.iter().map(|&g| g / PARTICLE_GROUPS as u32).collect();
                touched.dedup();
                let j = item as usize - blocks;
                debug_assert_eq!(j, reach.place.len());
                for &g in &groups {
                    of_group[g as usize].push(j as u32);
                }
                reach.blocks.push(touched);
                reach.place.push((level as u32, item - a));
            }
        }
        for list in of_group {
            reach.of_group.push(list);
        }
        reach
    }
}

/// The chunks of particle group `group`: `PARTICLE_GROUPS` per block, each a run of the
/// block's chunks (what [`StepContext::group_particles`] steps).
fn group_chunks(order: &ParticleOrder, group: usize) -> std::ops::Range<usize> {
    let (block, part) = (group / PARTICLE_GROUPS, group % PARTICLE_GROUPS);
    let (first, end) = (
        order.block_chunks[block] as usize,
        order.block_chunks[block + 1] as usize,
    );
    let count = end - first;
    first + part * count / PARTICLE_GROUPS..first + (part + 1) * count / PARTICLE_GROUPS
}

/// The particle group (see [`group_chunks`]) that holds particle `i`.
fn group_of(order: &ParticleOrder, i: u32) -> u32 {
    let block = order.block_of(i) as usize;
    let chunk = order.chunk_start.partition_point(|&s| s <= i) - 1;
    let part = (0..PARTICLE_GROUPS)
        .find(|&p| group_chunks(order, block * PARTICLE_GROUPS + p).contains(&chunk))
        .unwrap_or(PARTICLE_GROUPS - 1);
    (block * PARTICLE_GROUPS + part) as u32
}

#[derive(Debug, Clone, Copy, Default)]
struct ItemHealth {
    max_speed2: f32,
    /// Mesh index.
    fastest: u32,
    /// Smallest mesh index.
    first_non_finite: u32,
}

#[derive(Debug, Clone, Copy)]
enum Phase {
    /// The colliders swept over substep `sub` and the attachment targets at its end (one
    /// item). Substep 0's opens the step; a later substep's follows the previous substep's
    /// block phase, so that a thread that would wait for a seam does it.
    Sweep {
        sub: u32,
    },
    AeroTriangles,
    /// Per group of collision chunks (a part of a block, see `PARTICLE_GROUPS`): finish
    /// substep `sub - 1` (if `sub > 0`) and predict substep `sub`. At `sub == 0` the group also
    /// gathers its particles' aerodynamic forces.
    Particles {
        sub: u32,
    },
    /// Per block: solve the block's constraints (first iteration of substep `sub`).
    Block {
        sub: u32,
    },
    /// Per block: a further iteration of the block's constraints.
    BlockIteration,
    /// The seams or the corners (an index into `separator_levels`).
    Separators {
        level: u32,
        first: bool,
        /// The first constraint pass of the step: curved bending stencils take a new frame.
        new_frame: bool,
    },
    /// Per particle group: finish the last substep, check health, write the mesh-ordered
    /// copies (in groups, not blocks, so that the thread done with its block first can help
    /// with the other's).
    Finish,
    /// Per constraint item (the blocks, then the seams and corners): the stretch check of its
    /// distance constraints.
    Stretch,
}

/// Constants of one step.
#[derive(Debug, Clone, Copy)]
struct StepConstants {
    substeps: u32,
    h: f32,
    inv_h: f32,
    inv_h2: f32,
    /// Bending compliance over h².
    bend_alpha: f32,
    damping: f32,
    gravity: Vec3A,
    keep_lambda: bool,
    aero: bool,
    /// The constraint kernels' instruction set.
    isa: Isa,
    thickness: f32,
    friction: f32,
    max_velocity: f32,
    frame: Option<FrameTerms>,
    colliders: usize,
    /// Whether eight particles at a time are collided together (always, except in the test
    /// that compares the two paths).
    #[cfg(test)]
    group_collisions: bool,
    /// Whether the second collision pass tests only the shapes before the last mover (always,
    /// except in the test that compares it with testing every shape).
    #[cfg(test)]
    prune_passes: bool,
    // Aerodynamics.
    air_density: f32,
    drag: f32,
    lift: f32,
    time: f32,
}

#[derive(Debug, Clone, Copy)]
struct FrameTerms {
    linear: Vec3A,
    euler: Vec3A,
    coriolis: Vec3A,
    omega: Vec3A,
    centrifugal: f32,
    // For the air: frame velocity and angular velocity (scaled), world pose.
    air_velocity: Vec3A,
    air_omega: Vec3A,
    motion: FrameMotion,
}

/// A cloth and its XPBD solver. See the module documentation for the algorithm.
pub struct ClothSolver {
    model: Model,
    /// Positions in mesh order (the API's view; read at the start of a step, written at its
    /// end).
    x: Vec<Vec3A>,
    /// Velocities in mesh order (written at the end of a step).
    v: Vec<Vec3A>,
    /// Whether `x` may have been edited since the last step (then `xs` is read from it).
    positions_edited: bool,
    /// Positions in solver order, then one padding particle per constraint item.
    xs: Vec<Vec3A>,
    xs_prev: Vec<Vec3A>,
    /// Velocities in solver order, as the step's last substep leaves them (within a step the
    /// eight-particle kernel does not store them: the next substep derives them from the
    /// positions).
    vs: Vec<Vec3A>,
    external: Vec<Vec3A>,
    external_dirty: bool,
    triangle_force: Vec<Vec3A>,
    distance_lambda: Vec<[f32; LANES]>,
    bend_lambda: Vec<[[f32; LANES]; 5]>,
    /// Inverse XPBD denominators per batch, for substeps with `1/h² = inverse_for_inv_h2`.
    distance_inverse: Vec<[f32; LANES]>,
    bend_inverse: Vec<[[f32; LANES]; 3]>,
    /// Per bending batch: the curved stencils' targets, taken at the step's first constraint
    /// pass and held over its substeps.
    bend_targets: Vec<BendTarget>,
    inverse_for_inv_h2: f32,
    target_start: Vec<Vec3A>,
    target_end: Vec<Vec3A>,
    /// Attachment targets at the end of each substep of the current step.
    anchors: Vec<Vec3A>,
    spheres_start: Vec<Sphere>,
    spheres_end: Vec<Sphere>,
    capsules: Vec<[u32; 2]>,
    solo_spheres: Vec<u32>,
    planes: Vec<Plane>,
    swept: Vec<SweptCollider>,
    /// The swept colliders' bounds, eight colliders at a time (see [`ColliderBounds`]).
    swept_bounds: Vec<ColliderBounds>,
    frame: FrameState,
    wind: Option<Wind>,
    time: f64,
    pool: WorkerPool,
    /// Steps left to run on the caller's thread alone (see `SOLO_STEPS`).
    solo_steps: u32,
    /// [`Self::prewake`] was called since the last step (the step need not wake them again).
    prewoken: AtomicBool,
    /// [`Self::share_out`] is running a job on the workers.
    dispatching: AtomicBool,
    /// Steps since the last stalled one (see `SOLO_STEPS`).
    since_stall: u32,
    isa: Isa,
    /// See `StepConstants::group_collisions`.
    #[cfg(test)]
    group_collisions: bool,
    /// See `StepConstants::prune_passes`.
    #[cfg(test)]
    prune_passes: bool,
    counters: PhaseCounters,
    phases: Vec<Phase>,
    phase_items: Vec<u32>,
    /// What `phases` was built for: substeps, iterations, aerodynamics.
    program: Option<(u32, u32, bool)>,
    /// Per particle group: what its finish found (see [`ItemHealth`]).
    group_health: Vec<ItemHealth>,
    /// Per constraint item: largest squared stretch ratio and its distance lane.
    stretch_health: Vec<(f32, u32)>,
}

impl ClothSolver {
    /// Builds a cloth from `mesh` (its positions are the rest shape and the initial state),
    /// `fabric`, the vertices `attached` to the body (inverse mass 0, moved by
    /// [`Self::set_attachment_targets`]) and `settings`.
    pub fn new(
        mesh: &ClothMesh,
        fabric: Fabric,
        attached: &[u32],
        settings: SolverSettings,
    ) -> Result<Self, ClothError> {
        Self::build(mesh, fabric, attached, settings, None)
    }

    /// As [`Self::new`], with a hint of how a step's work is shared among the vertices:
    /// `work[v]` (mesh order, finite, not negative) for vertex `v`, in any unit. The solver
    /// splits the cloth into blocks of equal work for its threads, each thread keeping its
    /// blocks step after step; without a hint, every free vertex counts 1 and every attached
    /// one 0. A caller that knows better, such as which vertices lie against a collider and
    /// will pay for contacts in every substep, passes more for those. The hint changes the
    /// order in which constraints are solved (the results stay within the solver's accuracy;
    /// they still do not depend on the number of threads), never what is solved.
    pub fn new_balanced(
        mesh: &ClothMesh,
        fabric: Fabric,
        attached: &[u32],
        settings: SolverSettings,
        work: &[f32],
    ) -> Result<Self, ClothError> {
        Self::build(mesh, fabric, attached, settings, Some(work))
    }

    fn build(
        mesh: &ClothMesh,
        fabric: Fabric,
        attached: &[u32],
        settings: SolverSettings,
        work: Option<&[f32]>,
    ) -> Result<Self, ClothError> {
        fabric.validate()?;
        settings.validate()?;
        let n = mesh.vertex_count();
        if let Some(work) = work {
            if work.len() != n {
                return Err(ClothError::LengthMismatch {
                    what: "work hints (one per vertex)",
                    expected: n,
                    got: work.len(),
                });
            }
            if let Some(index) = work.iter().position(|w| !w.is_finite()) {
                return Err(ClothError::NonFiniteInput {
                    what: "work hint of vertex",
                    index,
                });
            }
            if let Some(&w) = work.iter().find(|&&w| w < 0.0) {
                return Err(ClothError::InvalidParameter {
                    what: "a vertex's work hint",
                    requirement: "0 or more",
                    value: f64::from(w),
                });
            }
        }
        let mut attach_slot_mesh = vec![u32::MAX; n];
        for (index, &vertex) in attached.iter().enumerate() {
            let slot = attach_slot_mesh.get_mut(vertex as usize).ok_or(
                ClothError::AttachmentOutOfRange {
                    index,
                    vertex,
                    vertex_count: n,
                },
            )?;
            if *slot != u32::MAX {
                return Err(ClothError::DuplicateAttachment {
                    vertex,
                    first: *slot as usize,
                    second: index,
                });
            }
            *slot = index as u32;
        }
        let mass = mesh.vertex_masses(fabric.areal_density_kg_m2);
        let inverse_mass_mesh: Vec<f32> = mass
            .iter()
            .zip(&attach_slot_mesh)
            .map(|(&m, &slot)| {
                if slot != u32::MAX || m <= 0.0 {
                    0.0
                } else {
                    1.0 / m
                }
            })
            .collect();
        let free: Vec<bool> = inverse_mass_mesh.iter().map(|&w| w > 0.0).collect();
        let order = ParticleOrder::weighted(mesh.positions(), &free, work);
        let to_mesh = &order.to_mesh;
        let topology = MeshTopology::new(mesh);
        let constraints = ConstraintSet::build(
            mesh.positions(),
            &topology,
            &fabric,
            &inverse_mass_mesh,
            &order,
        );
        // Tethers, sorted by mesh vertex, regrouped per solver particle.
        let tethers = topology.tethers(n, attached, settings.tethers_per_particle);
        let mut tethers_of = vec![0u32..0u32; n];
        let mut k = 0;
        while k < tethers.len() {
            let v = tethers[k].vertex;
            let first = k;
            while k < tethers.len() && tethers[k].vertex == v {
                k += 1;
            }
            tethers_of[v as usize] = first as u32..k as u32;
        }
        let mut tether_start = Vec::with_capacity(n + 1);
        let mut tether_slot = Vec::with_capacity(tethers.len());
        let mut tether_rest = Vec::with_capacity(tethers.len());
        tether_start.push(0u32);
        for &m in to_mesh {
            for t in
                &tethers[tethers_of[m as usize].start as usize..tethers_of[m as usize].end as usize]
            {
                tether_slot.push(attach_slot_mesh[t.anchor as usize]);
                tether_rest.push(t.rest_length);
            }
            tether_start.push(tether_slot.len() as u32);
        }
        let tether_limit = tether_rest
            .iter()
            .map(|r| r * settings.tether_scale)
            .collect();
        let inverse_mass: Vec<f32> = to_mesh
            .iter()
            .map(|&m| inverse_mass_mesh[m as usize])
            .collect();
        let attach_slot: Vec<u32> = to_mesh
            .iter()
            .map(|&m| attach_slot_mesh[m as usize])
            .collect();

        // Triangles in the solver's numbering, ordered by their first particle, so that the
        // triangles around a particle are near it in memory.
        let mut triangles: Vec<[u32; 3]> = mesh
            .triangles()
            .iter()
            .map(|t| t.map(|v| order.to_solver[v as usize]))
            .collect();
        triangles.sort_by_key(|t| (t.iter().min().copied(), *t));
        let mut vertex_triangles_start = vec![0u32; n + 1];
        for tri in &triangles {
            for &v in tri {
                vertex_triangles_start[v as usize + 1] += 1;
            }
        }
        for i in 0..n {
            vertex_triangles_start[i + 1] += vertex_triangles_start[i];
        }
        let mut fill = vertex_triangles_start.clone();
        let mut vertex_triangles = vec![0u32; 3 * triangles.len()];
        for (t, tri) in triangles.iter().enumerate() {
            for &v in tri {
                vertex_triangles[fill[v as usize] as usize] = t as u32;
                fill[v as usize] += 1;
            }
        }

        let vertex_triangles8 = (0..n)
            .map(|i| {
                let around = &vertex_triangles
                    [vertex_triangles_start[i] as usize..vertex_triangles_start[i + 1] as usize];
                std::array::from_fn(|k| around.get(k).copied().unwrap_or(triangles.len() as u32))
            })
            .collect();
        let eight = eight_flags(&inverse_mass, &tether_start);
        let x: Vec<Vec3A> = mesh.positions().iter().map(|&p| p.into()).collect();
        let mut xs: Vec<Vec3A> = to_mesh.iter().map(|&m| x[m as usize]).collect();
        xs.resize(n + constraints.padding_particles(), Vec3A::ZERO);
        let targets: Vec<Vec3A> = attached.iter().map(|&v| x[v as usize]).collect();
        let keep_lambda = settings.iterations > 1;
        let reach = SeparatorReach::new(&order, &constraints);
        let blocks = order.blocks();
        let items = constraints.items.len();
        let distance_batches = constraints.distance.len();
        let bend_batches = constraints.bend.len();
        Ok(Self {
            model: Model {
                order,
                inverse_mass_mesh,
                mass_mesh: mass,
                inverse_mass,
                triangles,
                vertex_triangles_start,
                vertex_triangles,
                vertex_triangles8,
                constraints,
                tether_start,
                tether_slot,
                tether_rest,
                tether_limit,
                attached: attached.to_vec(),
                attach_slot,
                eight,
                fabric,
                settings,
                reach,
            },
            xs_prev: xs[..n].to_vec(),
            xs,
            vs: vec![Vec3A::ZERO; n],
            v: vec![Vec3A::ZERO; n],
            positions_edited: false,
            x,
            external: vec![Vec3A::ZERO; n],
            external_dirty: false,
            // One more than the triangles: the zero that pads `vertex_triangles8`.
            triangle_force: vec![Vec3A::ZERO; mesh.triangles().len() + 1],
            distance_lambda: vec![[0.0; LANES]; if keep_lambda { distance_batches } else { 0 }],
            bend_lambda: vec![[[0.0; LANES]; 5]; if keep_lambda { bend_batches } else { 0 }],
            distance_inverse: Vec::new(),
            bend_inverse: Vec::new(),
            bend_targets: vec![BendTarget::default(); bend_batches],
            inverse_for_inv_h2: f32::NAN,
            target_start: targets.clone(),
            target_end: targets,
            anchors: Vec::new(),
            spheres_start: Vec::new(),
            spheres_end: Vec::new(),
            capsules: Vec::new(),
            solo_spheres: Vec::new(),
            planes: Vec::new(),
            swept: Vec::new(),
            swept_bounds: Vec::new(),
            frame: FrameState::default(),
            wind: None,
            time: 0.0,
            pool: WorkerPool::new(settings.threads),
            solo_steps: 0,
            prewoken: AtomicBool::new(false),
            dispatching: AtomicBool::new(false),
            since_stall: u32::MAX,
            isa: Isa::detect(),
            #[cfg(test)]
            group_collisions: true,
            #[cfg(test)]
            prune_passes: true,
            counters: PhaseCounters::new(),
            phases: Vec::new(),
            phase_items: Vec::new(),
            program: None,
            group_health: vec![ItemHealth::default(); blocks * PARTICLE_GROUPS],
            stretch_health: vec![(0.0, u32::MAX); items],
        })
    }

    /// The fabric.
    pub fn fabric(&self) -> &Fabric {
        &self.model.fabric
    }

    /// The settings.
    pub fn settings(&self) -> &SolverSettings {
        &self.model.settings
    }

    /// Changes the settings. The number of tethers per particle and the iteration count's
    /// need for stored multipliers are fixed when the cloth is built; changing
    /// `tethers_per_particle` is refused.
    pub fn set_settings(&mut self, settings: SolverSettings) -> Result<(), ClothError> {
        settings.validate()?;
        if settings.tethers_per_particle != self.model.settings.tethers_per_particle {
            return Err(ClothError::InvalidParameter {
                what: "tethers per particle (fixed when the cloth is built)",
                requirement: "unchanged",
                value: settings.tethers_per_particle as f64,
            });
        }
        if settings.threads != self.pool.threads() {
            self.pool = WorkerPool::new(settings.threads);
        }
        if settings.iterations > 1 {
            self.distance_lambda
                .resize(self.model.constraints.distance.len(), [0.0; LANES]);
            self.bend_lambda
                .resize(self.model.constraints.bend.len(), [[0.0; LANES]; 5]);
        }
        for (limit, rest) in self
            .model
            .tether_limit
            .iter_mut()
            .zip(&self.model.tether_rest)
        {
            *limit = rest * settings.tether_scale;
        }
        self.model.settings = settings;
        Ok(())
    }

    /// Number of particles.
    pub fn particle_count(&self) -> usize {
        self.x.len()
    }

    /// Particle positions (simulation frame, metres), in the mesh's vertex order.
    pub fn positions(&self) -> &[Vec3A] {
        &self.x
    }

    /// Writable particle positions, e.g. for a designer dragging a vertex. Velocities are
    /// unchanged; the edit takes effect at the next step.
    pub fn positions_mut(&mut self) -> &mut [Vec3A] {
        self.positions_edited = true;
        &mut self.x
    }

    /// Particle velocities, m/s.
    pub fn velocities(&self) -> &[Vec3A] {
        &self.v
    }

    /// Particle masses, kg (attached particles keep their mass here; their inverse mass is 0).
    pub fn masses(&self) -> &[f32] {
        &self.model.mass_mesh
    }

    /// Inverse masses, 1/kg (0 for attached particles).
    pub fn inverse_masses(&self) -> &[f32] {
        &self.model.inverse_mass_mesh
    }

    /// The attached vertices, in the order of [`Self::set_attachment_targets`].
    pub fn attached(&self) -> &[u32] {
        &self.model.attached
    }

    /// Number of tethers.
    pub fn tether_count(&self) -> usize {
        self.model.tether_rest.len()
    }

    /// Number of distance (stretch + shear) and bending constraints.
    pub fn constraint_counts(&self) -> (usize, usize) {
        (
            self.model.constraints.distance_count,
            self.model.constraints.bend_count,
        )
    }

    /// Number of blocks whose constraints are solved in parallel, and whether there are
    /// constraints between blocks (seams and corners, solved after the blocks); see
    /// [`crate::constraints`].
    pub fn colour_count(&self) -> (usize, bool) {
        (
            self.model.order.blocks(),
            !self.model.constraints.separator_levels.is_empty(),
        )
    }

    /// Simulated time, seconds.
    pub fn time(&self) -> f64 {
        self.time
    }

    /// Sets where the attached vertices must be at the end of the next step (one target per
    /// [`Self::attached`] vertex). They move there linearly over the step's substeps.
    pub fn set_attachment_targets(&mut self, targets: &[Vec3]) -> Result<(), ClothError> {
        if targets.len() != self.model.attached.len() {
            return Err(ClothError::LengthMismatch {
                what: "attachment targets",
                expected: self.model.attached.len(),
                got: targets.len(),
            });
        }
        if let Some(index) = targets.iter().position(|t| !t.is_finite()) {
            return Err(ClothError::NonFiniteInput {
                what: "attachment target",
                index,
            });
        }
        for (end, &t) in self.target_end.iter_mut().zip(targets) {
            *end = t.into();
        }
        Ok(())
    }

    /// Sets the collision spheres and the capsules joining them (index pairs into `spheres`)
    /// as they are at the end of the next step. Within the step each sphere moves linearly from
    /// its previous pose; when the number of spheres or the capsules change, there is no
    /// previous pose and the colliders appear where they are.
    pub fn set_colliders(
        &mut self,
        spheres: &[Sphere],
        capsules: &[[u32; 2]],
    ) -> Result<(), ClothError> {
        for (index, s) in spheres.iter().enumerate() {
            if !s.center.is_finite()
                || !s.radius.is_finite()
                || s.radius < 0.0
                || !s.friction.is_finite()
                || s.friction < 0.0
            {
                return Err(ClothError::NonFiniteInput {
                    what: "collision sphere (finite centre, finite radius >= 0, finite friction >= 0)",
                    index,
                });
            }
        }
        let mut in_capsule = vec![false; spheres.len()];
        for (capsule, pair) in capsules.iter().enumerate() {
            for &sphere in pair {
                let used =
                    in_capsule
                        .get_mut(sphere as usize)
                        .ok_or(ClothError::CapsuleOutOfRange {
                            capsule,
                            sphere,
                            sphere_count: spheres.len(),
                        })?;
                *used = true;
            }
        }
        let solo: Vec<u32> = (0..spheres.len() as u32)
            .filter(|&s| !in_capsule[s as usize])
            .collect();
        let count = capsules.len() + solo.len();
        if count > MAX_COLLIDERS {
            return Err(ClothError::TooManyColliders {
                count,
                max: MAX_COLLIDERS,
            });
        }
        let same_topology = spheres.len() == self.spheres_end.len() && capsules == self.capsules;
        self.spheres_end.clear();
        self.spheres_end.extend_from_slice(spheres);
        if !same_topology {
            self.spheres_start.clear();
            self.spheres_start.extend_from_slice(spheres);
            self.capsules = capsules.to_vec();
        }
        self.solo_spheres = solo;
        Ok(())
    }

    /// Makes the colliders jump to their latest poses without sweeping through the cloth in
    /// the next step (after a tracking loss, say).
    pub fn teleport_colliders(&mut self) {
        self.spheres_start.clone_from(&self.spheres_end);
    }

    /// Sets the collision planes (e.g. [`Plane::floor`]); normals are normalised.
    pub fn set_planes(&mut self, planes: &[Plane]) -> Result<(), ClothError> {
        let mut normalised = Vec::with_capacity(planes.len());
        for (index, p) in planes.iter().enumerate() {
            let n = p.normal.normalize_or_zero();
            if n == Vec3::ZERO || !p.offset.is_finite() {
                return Err(ClothError::NonFiniteInput {
                    what: "plane (finite, non-zero normal and finite offset)",
                    index,
                });
            }
            normalised.push(Plane {
                normal: n,
                offset: p.offset / p.normal.length(),
            });
        }
        self.planes = normalised;
        Ok(())
    }

    /// Sets (or removes) the wind.
    pub fn set_wind(&mut self, wind: Option<Wind>) {
        self.wind = wind;
    }

    /// Gives the body frame's pose at the end of the next step: from now on the simulation
    /// runs in this frame (see [`crate::frame`]). The first pose given starts at rest.
    pub fn set_body_frame(&mut self, pose: RigidPose) -> Result<(), ClothError> {
        if !pose.is_finite() {
            return Err(ClothError::NonFiniteInput {
                what: "body frame pose",
                index: 0,
            });
        }
        self.frame.set_next(pose);
        Ok(())
    }

    /// Puts the body frame at `pose` with zero velocity (after a tracking jump), so that the
    /// jump is not felt as inertia.
    pub fn reset_body_frame(&mut self, pose: RigidPose) -> Result<(), ClothError> {
        if !pose.is_finite() {
            return Err(ClothError::NonFiniteInput {
                what: "body frame pose",
                index: 0,
            });
        }
        self.frame.reset(pose);
        Ok(())
    }

    /// Puts every particle at `positions` (e.g. the skinned garment) at rest: velocities and
    /// multipliers are cleared, attachment targets become the given positions of the attached
    /// vertices, colliders stop sweeping. Use it after a [`Health::BlownUp`] report.
    pub fn reset_to(&mut self, positions: &[Vec3]) -> Result<(), ClothError> {
        if positions.len() != self.x.len() {
            return Err(ClothError::LengthMismatch {
                what: "reset positions",
                expected: self.x.len(),
                got: positions.len(),
            });
        }
        if let Some(index) = positions.iter().position(|p| !p.is_finite()) {
            return Err(ClothError::NonFiniteInput {
                what: "reset position",
                index,
            });
        }
        for (x, &p) in self.x.iter_mut().zip(positions) {
            *x = p.into();
        }
        for (i, &m) in self.model.order.to_mesh.iter().enumerate() {
            self.xs[i] = self.x[m as usize];
            self.xs_prev[i] = self.x[m as usize];
        }
        self.v.fill(Vec3A::ZERO);
        self.vs.fill(Vec3A::ZERO);
        self.external.fill(Vec3A::ZERO);
        self.distance_lambda.fill([0.0; LANES]);
        self.bend_lambda.fill([[0.0; LANES]; 5]);
        for (slot, &vertex) in self.model.attached.iter().enumerate() {
            self.target_start[slot] = self.x[vertex as usize];
            self.target_end[slot] = self.x[vertex as usize];
        }
        self.teleport_colliders();
        Ok(())
    }

    /// Largest current length / rest length over the stretch constraints (not shear).
    pub fn max_stretch_ratio(&self) -> f32 {
        self.model
            .constraints
            .stretch
            .iter()
            .map(|&(i, j, rest)| (self.x[i as usize] - self.x[j as usize]).length() / rest)
            .fold(0.0, f32::max)
    }

    /// Largest current distance / rest geodesic distance over the tethers (1.0 means a tether
    /// is exactly taut at its rest length).
    pub fn max_tether_ratio(&self) -> f32 {
        let m = &self.model;
        let mut worst = 0.0f32;
        for (i, &vertex) in m.order.to_mesh.iter().enumerate() {
            for k in m.tether_start[i] as usize..m.tether_start[i + 1] as usize {
                let anchor = m.attached[m.tether_slot[k] as usize] as usize;
                let ratio = (self.x[vertex as usize] - self.x[anchor]).length() / m.tether_rest[k];
                worst = worst.max(ratio);
            }
        }
        worst
    }

    /// Kinetic energy of the free particles, J.
    pub fn kinetic_energy(&self) -> f64 {
        self.v
            .iter()
            .zip(&self.model.mass_mesh)
            .zip(&self.model.inverse_mass_mesh)
            .filter(|(_, w)| **w > 0.0)
            .map(|((v, m), _)| 0.5 * *m as f64 * v.length_squared() as f64)
            .sum()
    }

    /// Wakes the worker threads for a step that follows soon. [`Self::step`] wakes them
    /// itself, but a sleeping worker takes tens of microseconds to start (measured on the
    /// sun dress walking, `fitroom cloth sim`: 6-31 µs after the parallel pass began, the
    /// caller's thread working alone until then); a caller with work to do before the step
    /// (posing colliders, skinning attachment targets) can call this first, so that the
    /// wake-up overlaps that work. It changes no result.
    pub fn prewake(&self) {
        if self.solo_steps == 0 && !self.prewoken.swap(true, Ordering::Relaxed) {
            self.pool.prewake();
        }
    }

    /// Runs `job(k)` once for every `k` in `0..items`, the items claimed one after another by
    /// the threads the next step will use, and returns when all have run: for the work a
    /// caller does before or after each step, such as posing the attachment targets and
    /// colliders. Only workers that are awake are used: while one is still waking (it takes
    /// tens of microseconds, up to a millisecond here; [`Self::prewake`] starts it), or while
    /// steps run on the caller's thread alone (after a stall), the caller runs every item,
    /// which the waking overlaps; so it does, too, when a `job` the workers run calls this,
    /// or another thread already does (the workers run one job at a time). Returns the
    /// number of threads that took part. A panic in `job` panics here (on a worker, as "a cloth worker thread
    /// panicked", its own message printed by that thread).
    pub fn share_out(&self, items: usize, job: &(dyn Fn(usize) + Sync)) -> usize {
        share_out(
            &self.pool,
            self.solo_steps == 0,
            &self.dispatching,
            items,
            job,
        )
    }

    /// Advances the simulation by `dt` seconds and reports the blow-up guard's verdict.
    pub fn step(&mut self, dt: f32) -> Result<StepReport, ClothError> {
        positive("time step (s)", dt)?;
        self.prewake();
        self.prewoken.store(false, Ordering::Relaxed);
        let settings = self.model.settings;
        let substeps = settings.substeps;
        let h = dt / substeps as f32;
        let motion = self.frame.enabled.then(|| self.frame.advance(dt));
        let to_local = motion.map(|m| m.to_local).unwrap_or_default();
        let fabric = self.model.fabric;
        let aero = settings.air_density_kg_m3 > 0.0
            && (fabric.drag_coefficient > 0.0 || fabric.lift_coefficient > 0.0);
        let inertia = settings.frame_inertia;
        let frame = motion.map(|m| FrameTerms {
            linear: Vec3A::from(m.acceleration * inertia.linear),
            euler: Vec3A::from(m.angular_acceleration * inertia.angular),
            coriolis: Vec3A::from(2.0 * m.angular_velocity * inertia.angular),
            omega: Vec3A::from(m.angular_velocity),
            centrifugal: inertia.centrifugal,
            air_velocity: Vec3A::from(m.velocity * inertia.linear),
            air_omega: Vec3A::from(m.angular_velocity * inertia.angular),
            motion: m,
        });
        let inv_h2 = 1.0 / (h * h);
        let constants = StepConstants {
            substeps,
            h,
            inv_h: 1.0 / h,
            inv_h2,
            bend_alpha: self.model.constraints.bend_compliance * inv_h2,
            damping: (-fabric.damping_per_s * h).exp(),
            gravity: Vec3A::from(to_local * settings.gravity),
            keep_lambda: settings.iterations > 1,
            aero,
            isa: self.isa,
            thickness: settings.collision_thickness,
            friction: fabric.friction,
            max_velocity: settings.max_velocity_m_s.unwrap_or(f32::INFINITY),
            frame,
            colliders: self.capsules.len() + self.solo_spheres.len(),
            #[cfg(test)]
            group_collisions: self.group_collisions,
            #[cfg(test)]
            prune_passes: self.prune_passes,
            air_density: settings.air_density_kg_m3,
            drag: fabric.drag_coefficient,
            lift: fabric.lift_coefficient,
            time: self.time as f32,
        };
        self.prepare_substeps(substeps);
        if inv_h2.to_bits() != self.inverse_for_inv_h2.to_bits() {
            self.model.constraints.inverse_denominators(
                inv_h2,
                &mut self.distance_inverse,
                &mut self.bend_inverse,
            );
            self.inverse_for_inv_h2 = inv_h2;
        }
        if self.positions_edited {
            for (xs, &m) in self.xs.iter_mut().zip(&self.model.order.to_mesh) {
                *xs = self.x[m as usize];
            }
            self.positions_edited = false;
        }
        if !aero && self.external_dirty {
            self.external.fill(Vec3A::ZERO);
            self.external_dirty = false;
        }

        if aero {
            self.external_dirty = true;
        }
        // The phase program and its dependencies depend only on these; steps with the same
        // ones reuse them and only clear the counters.
        let program = (substeps, settings.iterations, aero);
        if self.program != Some(program) {
            self.build_program(substeps, settings.iterations, aero);
            self.program = Some(program);
        } else {
            self.counters.clear();
        }
        {
            let context = StepContext {
                model: &self.model,
                k: constants,
                phases: &self.phases,
                swept: SharedSlice::new(&mut self.swept),
                swept_bounds: SharedSlice::new(&mut self.swept_bounds),
                bodies: Bodies {
                    start: &self.spheres_start,
                    end: &self.spheres_end,
                    capsules: &self.capsules,
                    solo: &self.solo_spheres,
                    target_end: &self.target_end,
                },
                planes: &self.planes,
                target_start: &self.target_start,
                anchors: SharedSlice::new(&mut self.anchors),
                wind: self.wind.as_ref(),
                x: SharedSlice::new(&mut self.x),
                v: SharedSlice::new(&mut self.v),
                xs: SharedSlice::new(&mut self.xs),
                xs_prev: SharedSlice::new(&mut self.xs_prev),
                vs: SharedSlice::new(&mut self.vs),
                external: SharedSlice::new(&mut self.external),
                triangle_force: SharedSlice::new(&mut self.triangle_force),
                distance_lambda: SharedSlice::new(&mut self.distance_lambda),
                bend_lambda: SharedSlice::new(&mut self.bend_lambda),
                distance_inverse: &self.distance_inverse,
                bend_inverse: &self.bend_inverse,
                bend_targets: SharedSlice::new(&mut self.bend_targets),
                group_health: SharedSlice::new(&mut self.group_health),
                stretch_health: SharedSlice::new(&mut self.stretch_health),
            };
            let counters = &self.counters;
            let items = &self.phase_items;
            let exec = |p: usize, k: u32| context.exec(p, k);
            let threads = self.pool.threads();
            let job = |thread, threads| counters.run_phases(thread, threads, items, &exec);
            if threads > 1 && self.solo_steps == 0 {
                let longest_wait = AtomicU64::new(0);
                self.pool.run(&|thread| {
                    let times = job(thread, threads);
                    longest_wait.fetch_max(times.longest_wait.as_nanos() as u64, Ordering::Relaxed);
                });
                self.since_stall = self.since_stall.saturating_add(1);
                if longest_wait.into_inner() > STALL_MIN_NS {
                    // A thread was descheduled while holding an item. Again (the machine is
                    // busy): run the next steps on the caller's thread alone. The results are
                    // the same.
                    if self.since_stall <= SOLO_STEPS {
                        self.solo_steps = SOLO_STEPS;
                    }
                    self.since_stall = 0;
                }
            } else {
                job(0, 1);
                self.solo_steps = self.solo_steps.saturating_sub(1);
                self.since_stall = self.since_stall.saturating_add(1);
            }
        }

        self.target_start.clone_from(&self.target_end);
        self.spheres_start.clone_from(&self.spheres_end);
        self.time += dt as f64;
        Ok(self.report())
    }

    /// The phase program of a step of `substeps` substeps and `iterations` constraint
    /// iterations (with the aerodynamics phase if `aero`), its item counts and dependencies.
    fn build_program(&mut self, substeps: u32, iterations: u32, aero: bool) {
        let blocks = self.model.order.blocks() as u32;
        let groups = blocks * PARTICLE_GROUPS as u32;
        let levels = &self.model.constraints.separator_levels;
        self.phases.clear();
        self.phase_items.clear();
        let mut push = |phase: Phase, items: u32| {
            self.phases.push(phase);
            self.phase_items.push(items);
        };
        push(Phase::Sweep { sub: 0 }, 1);
        if aero {
            let tris = self.model.triangles.len().div_ceil(TRIANGLE_ITEM) as u32;
            push(Phase::AeroTriangles, tris);
        }
        for sub in 0..substeps {
            for iteration in 0..iterations {
                if iteration == 0 {
                    push(Phase::Particles { sub }, groups);
                    push(Phase::Block { sub }, blocks);
                    if sub + 1 < substeps {
                        push(Phase::Sweep { sub: sub + 1 }, 1);
                    }
                } else {
                    push(Phase::BlockIteration, blocks);
                }
                for (level, &(a, b)) in levels.iter().enumerate() {
                    push(
                        Phase::Separators {
                            level: level as u32,
                            first: iteration == 0,
                            new_frame: sub == 0 && iteration == 0,
                        },
                        b - a,
                    );
                }
            }
        }
        push(Phase::Finish, groups);
        push(Phase::Stretch, self.model.constraints.items.len() as u32);

        self.counters.reset(&self.phase_items);
        self.set_dependencies();
    }

    /// What each item of the step's phases waits for, instead of the whole phase before it:
    ///
    /// - a particle group's substep waits for its block's constraints and the separators
    ///   that touch its particles (the first one for the aerodynamic forces);
    /// - a block's constraints wait for its particle groups (a further iteration: for its
    ///   last constraint pass and the separators that touch it);
    /// - a seam waits for the blocks it joins; a corner also for every seam;
    /// - a particle group's finish waits as its next substep would.
    ///
    /// So a thread that is done with its block goes on with the next substep of the groups
    /// that no separator touches while the other thread is still in its block, and the
    /// separators run beside other work. Each item reads and writes what it did before, in an
    /// order these dependencies keep: the results do not change.
    fn set_dependencies(&mut self) {
        let blocks = self.model.order.blocks();
        // With a block per thread, each thread keeps its own block and its particle groups,
        // substep after substep, and their particles stay in its core's cache (taken by
        // whichever thread was free, a block's particles moved between the cores in half of
        // the substeps: the 4,000-particle dress stepped 5-9 % slower). With more blocks, the
        // threads share them out as they come free, which balances blocks of uneven work
        // (pinned two to a thread, the 4,096-particle tube among 28 colliders stepped 6-20 %
        // slower).
        let pin = blocks <= self.pool.threads();
        let reach = &self.model.reach;
        let counters = &mut self.counters;
        let mut aero = None;
        // Per substep: its sweep's phase.
        let mut sweeps: Vec<u32> = Vec::new();
        let mut last_block: Option<u32> = None;
        // The phases of the separator levels since the last block phase.
        let mut separators: Vec<u32> = Vec::new();
        let mut deps: Vec<Dep> = Vec::new();
        let group_deps = |deps: &mut Vec<Dep>, g: usize, separators: &[u32]| {
            for &j in reach.of_group.get(g) {
                let (level, k) = reach.place[j as usize];
                if let Some(&p) = separators.get(level as usize) {
                    deps.push(Dep::Item(p, k));
                }
            }
        };
        for (p, phase) in self.phases.iter().enumerate() {
            let pu = p as u32;
            match *phase {
                // Waits for nothing: it reads only what the step was given.
                Phase::Sweep { sub } => {
                    debug_assert_eq!(sweeps.len(), sub as usize);
                    sweeps.push(pu);
                    counters.set_deps(p, 0, []);
                }
                Phase::AeroTriangles => aero = Some(pu),
                Phase::Particles { sub } => {
                    let sweep = sweeps[sub as usize];
                    for g in 0..blocks * PARTICLE_GROUPS {
                        deps.clear();
                        deps.push(Dep::Item(sweep, 0));
                        match last_block {
                            Some(b) => {
                                deps.push(Dep::Item(b, (g / PARTICLE_GROUPS) as u32));
                                group_deps(&mut deps, g, &separators);
                            }
                            None => deps.extend(aero.map(Dep::Phase)),
                        }
                        counters.set_deps(p, g as u32, deps.iter().copied());
                    }
                }
                Phase::Block { .. } => {
                    for x in 0..blocks {
                        let groups = x * PARTICLE_GROUPS..(x + 1) * PARTICLE_GROUPS;
                        counters.set_deps(p, x as u32, groups.map(|g| Dep::Item(pu - 1, g as u32)));
                    }
                    last_block = Some(pu);
                    separators.clear();
                }
                // As a particle group's next substep would (a step has a block phase; without
                // one, the whole phase before).
                Phase::Finish => {
                    if let Some(b) = last_block {
                        for g in 0..blocks * PARTICLE_GROUPS {
                            deps.clear();
                            deps.push(Dep::Item(b, (g / PARTICLE_GROUPS) as u32));
                            group_deps(&mut deps, g, &separators);
                            counters.set_deps(p, g as u32, deps.iter().copied());
                        }
                    }
                }
                Phase::BlockIteration => {
                    for x in 0..blocks {
                        deps.clear();
                        deps.extend(last_block.map(|b| Dep::Item(b, x as u32)));
                        for g in x * PARTICLE_GROUPS..(x + 1) * PARTICLE_GROUPS {
                            group_deps(&mut deps, g, &separators);
                        }
                        counters.set_deps(p, x as u32, deps.iter().copied());
                    }
                    last_block = Some(pu);
                    separators.clear();
                }
                Phase::Separators { level, .. } => {
                    let (a, b) = self.model.constraints.separator_levels[level as usize];
                    for k in 0..b - a {
                        deps.clear();
                        let j = (a + k) as usize - blocks;
                        deps.extend(
                            reach
                                .blocks
                                .get(j)
                                .iter()
                                .filter_map(|&x| last_block.map(|b| Dep::Item(b, x))),
                        );
                        if level > 0 {
                            deps.push(Dep::Phase(pu - 1));
                        }
                        counters.set_deps(p, k, deps.iter().copied());
                    }
                    separators.push(pu);
                }
                // A block's check after its groups' finish (the phase before), a separator's
                // after the finish of the blocks it touches: one thread checks its block
                // while the other finishes.
                Phase::Stretch => {
                    let groups = |x: u32| {
                        let x = x as usize;
                        (x * PARTICLE_GROUPS..(x + 1) * PARTICLE_GROUPS)
                            .map(|g| Dep::Item(pu - 1, g as u32))
                    };
                    for item in 0..self.model.constraints.items.len() {
                        deps.clear();
                        if item < blocks {
                            deps.extend(groups(item as u32));
                        } else {
                            for &x in reach.blocks.get(item - blocks) {
                                deps.extend(groups(x));
                            }
                        }
                        counters.set_deps(p, item as u32, deps.iter().copied());
                    }
                }
            }
            // Per block or per particle group: pinned to the block's thread. The step's last
            // finish is not: each thread finishes what it can, as the threads' blocks take
            // unequal times, and the particles leave the cores at the step's end anyway.
            let per_block = matches!(
                phase,
                Phase::Particles { .. } | Phase::Block { .. } | Phase::BlockIteration
            );
            if pin && per_block {
                counters.pin(p);
            }
        }
    }

    fn report(&self) -> StepReport {
        let mut max_speed2 = 0.0f32;
        let mut fastest = 0u32;
        let mut non_finite = u32::MAX;
        for h in &self.group_health {
            non_finite = non_finite.min(h.first_non_finite);
            if h.max_speed2 > max_speed2 {
                max_speed2 = h.max_speed2;
                fastest = h.fastest;
            }
        }
        let mut max_ratio2 = 0.0f32;
        let mut worst = u32::MAX;
        for &(ratio2, lane) in &self.stretch_health {
            if ratio2.is_nan() || ratio2 > max_ratio2 {
                max_ratio2 = ratio2;
                worst = lane;
                if ratio2.is_nan() {
                    break;
                }
            }
        }
        let max_ratio = max_ratio2.sqrt();
        let guard = self.model.settings.guard;
        let max_speed = max_speed2.sqrt();
        let health = if non_finite != u32::MAX {
            Health::BlownUp(BlowUp::NonFinite {
                particle: non_finite as usize,
            })
        } else if max_speed > guard.max_speed_m_s {
            Health::BlownUp(BlowUp::Speed {
                particle: fastest as usize,
                speed_m_s: max_speed,
            })
        } else if (max_ratio.is_nan() || max_ratio > guard.max_stretch_ratio) && worst != u32::MAX {
            let to_mesh = &self.model.order.to_mesh;
            let vertices = self
                .model
                .constraints
                .distance_vertices(worst)
                .map(|v| to_mesh[v as usize]);
            Health::BlownUp(BlowUp::Stretch {
                vertices,
                ratio: max_ratio,
            })
        } else {
            Health::Ok
        };
        StepReport {
            health,
            max_speed_m_s: if non_finite != u32::MAX {
                f32::NAN
            } else {
                max_speed
            },
            max_stretch_ratio: max_ratio,
        }
    }

    /// Sizes the per-substep colliders and attachment targets for `substeps` substeps. The
    /// step's `Phase::Sweep` items fill them, one substep each, inside the parallel step
    /// (made here before it, shared out, they kept the second thread idle for ~10 µs of the
    /// 4,000-particle dress's step; session 15). A substep computes the shapes at both its
    /// ends, so the results do not depend on which thread sweeps which substep.
    fn prepare_substeps(&mut self, substeps: u32) {
        let count = self.capsules.len() + self.solo_spheres.len();
        let substeps = substeps as usize;
        let none = Shape::sphere(Vec3A::ZERO, 0.0);
        self.swept
            .resize(substeps * count, SweptCollider::new(none, none, 0.0));
        self.swept_bounds
            .resize(substeps * count.div_ceil(LANES), ColliderBounds::EMPTY);
        self.anchors
            .resize(substeps * self.target_start.len(), Vec3A::ZERO);
    }
}

/// The body's spheres at the start and end of a step, how they make colliders, and where
/// the attachment targets end: what the step's `Phase::Sweep` items read.
#[derive(Clone, Copy)]
struct Bodies<'a> {
    start: &'a [Sphere],
    end: &'a [Sphere],
    capsules: &'a [[u32; 2]],
    solo: &'a [u32],
    target_end: &'a [Vec3A],
}

impl Bodies<'_> {
    /// Sphere `s` at `t` of the step (0 at its start, 1 at its end).
    fn sphere_at(&self, s: u32, t: f32) -> (Vec3A, f32) {
        let (a, b) = (self.start[s as usize], self.end[s as usize]);
        (
            Vec3A::from(a.center.lerp(b.center, t)),
            a.radius + (b.radius - a.radius) * t,
        )
    }

    /// Collider `collider` (the capsules, then the spheres alone) at `t` of the step.
    fn shape_at(&self, collider: usize, t: f32) -> Shape {
        if let Some(&[i, j]) = self.capsules.get(collider) {
            let (a, ra) = self.sphere_at(i, t);
            let (b, rb) = self.sphere_at(j, t);
            Shape::round_cone(a, b, ra, rb)
        } else {
            let (c, r) = self.sphere_at(self.solo[collider - self.capsules.len()], t);
            Shape::sphere(c, r)
        }
    }

    /// A collider's share of the fabric's friction.
    fn friction_of(&self, collider: usize) -> f32 {
        match self.capsules.get(collider) {
            Some(&[i, j]) => self.end[i as usize]
                .friction
                .min(self.end[j as usize].friction),
            None => self.end[self.solo[collider - self.capsules.len()] as usize].friction,
        }
    }
}

/// [`ClothSolver::share_out`] on `pool` (the workers only if `workers_allowed`; `dispatching`
/// marks a job on the workers).
fn share_out(
    pool: &WorkerPool,
    workers_allowed: bool,
    dispatching: &AtomicBool,
    items: usize,
    job: &(dyn Fn(usize) + Sync),
) -> usize {
    let next = AtomicUsize::new(0);
    let claim = || {
        loop {
            let k = next.fetch_add(1, Ordering::Relaxed);
            if k >= items {
                break;
            }
            job(k);
        }
    };
    let threads = pool.threads();
    if threads > 1 && workers_allowed && pool.awake() && !dispatching.swap(true, Ordering::Acquire)
    {
        /// Lowers the flag however `run` returns.
        struct Done<'a>(&'a AtomicBool);
        impl Drop for Done<'_> {
            fn drop(&mut self) {
                self.0.store(false, Ordering::Release);
            }
        }
        let _done = Done(dispatching);
        pool.run(&|_| claim());
        threads
    } else {
        claim();
        1
    }
}

/// Everything one step's items read and write.
struct StepContext<'a> {
    model: &'a Model,
    k: StepConstants,
    phases: &'a [Phase],
    /// The colliders swept over each substep (`substep · colliders + collider`), written by
    /// the substep's `Phase::Sweep` item, which everything that reads them waits for.
    swept: SharedSlice<'a, SweptCollider>,
    /// Their bounds, eight at a time (`substep · ⌈colliders / 8⌉ + k`), written with them.
    swept_bounds: SharedSlice<'a, ColliderBounds>,
    /// What the sweep items make them from.
    bodies: Bodies<'a>,
    planes: &'a [Plane],
    target_start: &'a [Vec3A],
    /// Attachment targets at the end of each substep (`substep · attachments + slot`),
    /// written with the swept colliders.
    anchors: SharedSlice<'a, Vec3A>,
    wind: Option<&'a Wind>,
    /// Mesh order.
    x: SharedSlice<'a, Vec3A>,
    /// Mesh order.
    v: SharedSlice<'a, Vec3A>,
    xs: SharedSlice<'a, Vec3A>,
    xs_prev: SharedSlice<'a, Vec3A>,
    vs: SharedSlice<'a, Vec3A>,
    external: SharedSlice<'a, Vec3A>,
    triangle_force: SharedSlice<'a, Vec3A>,
    distance_lambda: SharedSlice<'a, [f32; LANES]>,
    bend_lambda: SharedSlice<'a, [[f32; LANES]; 5]>,
    distance_inverse: &'a [[f32; LANES]],
    bend_inverse: &'a [[[f32; LANES]; 3]],
    bend_targets: SharedSlice<'a, BendTarget>,
    group_health: SharedSlice<'a, ItemHealth>,
    stretch_health: SharedSlice<'a, (f32, u32)>,
}

impl StepContext<'_> {
    /// Runs item `item` of phase `phase`. With [`Isa::Avx`] the whole item is compiled for
    /// that instruction set, not only its SIMD kernels: the work around them (the chunks'
    /// bounds and colliders, the one-particle paths, the kernels' calls, which can then be
    /// inlined) runs with it too. That took 6.6 % off the 4,000-particle dress's step on one
    /// thread and on two (session 16, alternating runs); building the whole program for
    /// x86-64-v3 gained no more. The functions an item runs are `#[inline(always)]` so that
    /// they are compiled into each version; every result is the same to the bit.
    fn exec(&self, phase: usize, item: u32) {
        #[cfg(target_arch = "x86_64")]
        crate::simd::avx_features! {
            unsafe fn avx(context: &StepContext<'_>, phase: usize, item: u32) {
                context.exec_with(phase, item)
            }
        }
        #[cfg(target_arch = "x86_64")]
        if self.k.isa == Isa::Avx {
            // SAFETY: `Isa::Avx` is only detected where the processor has these features.
            unsafe { avx(self, phase, item) };
            return;
        }
        self.exec_with(phase, item)
    }

    /// [`Self::exec`] for the instruction set of the function it is inlined into.
    #[inline(always)]
    fn exec_with(&self, phase: usize, item: u32) {
        let item = item as usize;
        match self.phases[phase] {
            Phase::Sweep { sub } => self.sweep(sub),
            Phase::AeroTriangles => self.aero_triangles(item),
            Phase::Particles { sub } => self.group_particles(sub, item),
            Phase::Block { sub } => self.solve(item, true, sub == 0),
            Phase::BlockIteration => self.solve(item, false, false),
            Phase::Separators {
                level,
                first,
                new_frame,
            } => {
                let (a, _) = self.model.constraints.separator_levels[level as usize];
                self.solve(a as usize + item, first, new_frame);
            }
            Phase::Finish => self.finish_group(item),
            Phase::Stretch => self.stretch(item),
        }
    }

    /// Projects the constraints of item `item` once; `new_frame`: the curved bending
    /// stencils take their frame from the current positions (else they keep the last one).
    #[inline(always)]
    fn solve(&self, item: usize, first: bool, new_frame: bool) {
        let c = &self.model.constraints;
        let (r0, r1) = c.items[item].runs;
        let keep = self.k.keep_lambda;
        let x = self.xs.as_ptr();
        for run in &c.runs[r0 as usize..r1 as usize] {
            let (a, b) = (run.batches.0 as usize, run.batches.1 as usize);
            // SAFETY: the constraint set was built for this particle count (padding
            // included); items of one phase touch disjoint particles (see
            // `crate::constraints`), and the lambdas of this item's batches belong to it.
            unsafe {
                match run.kind {
                    RunKind::Distance => solve_distance(
                        self.k.isa,
                        &c.distance[a..b],
                        &self.distance_inverse[a..b],
                        keep.then_some((&self.distance_lambda, a)),
                        x,
                        self.k.inv_h2,
                        first,
                    ),
                    RunKind::Bend { curved, pairs } => solve_bend(
                        self.k.isa,
                        match (curved, new_frame) {
                            (false, _) => BendFrame::Flat,
                            (true, true) => BendFrame::New(&self.bend_targets, a),
                            (true, false) => BendFrame::Held(&self.bend_targets, a),
                        },
                        pairs,
                        (&c.bend[a..b], &c.bend_side[a..b]),
                        &self.bend_inverse[a..b],
                        keep.then_some((&self.bend_lambda, a)),
                        x,
                        (self.k.bend_alpha, self.k.inv_h2),
                        first,
                    ),
                }
            }
        }
    }

    /// The stretch check of item `item`'s distance constraints.
    #[inline(always)]
    fn stretch(&self, item: usize) {
        let c = &self.model.constraints;
        let (d0, d1) = c.items[item].check;
        // SAFETY: positions are only read in this phase; slot `item` belongs to this item.
        unsafe {
            let worst = max_stretch_squared(
                self.k.isa,
                &c.check[d0 as usize..d1 as usize],
                d0 as usize,
                self.xs.as_ptr(),
            );
            self.stretch_health.set(item, worst);
        }
    }

    /// Finishes substep `sub - 1` (if `sub > 0`) and predicts substep `sub` for every chunk of
    /// particle group `group`; the first substep first gathers the aerodynamic forces (the
    /// positions are read back from the mesh-ordered copy in `step`, and only when edited).
    #[inline(always)]
    fn group_particles(&self, sub: u32, group: usize) {
        let o = &self.model.order;
        for c in group_chunks(o, group) {
            let range = o.chunk_start[c] as usize..o.chunk_start[c + 1] as usize;
            if sub == 0 {
                self.load(range.clone());
            }
            self.particles(sub.checked_sub(1), Some(sub), range);
        }
    }

    /// Finishes the last substep of particle group `group`, checks its health, and writes its
    /// positions and velocities in mesh order.
    #[inline(always)]
    fn finish_group(&self, group: usize) {
        let o = &self.model.order;
        let chunks = group_chunks(o, group);
        for c in chunks.clone() {
            let range = o.chunk_start[c] as usize..o.chunk_start[c + 1] as usize;
            self.particles(Some(self.k.substeps - 1), None, range);
        }
        let range = o.chunk_start[chunks.start] as usize..o.chunk_start[chunks.end] as usize;
        let mut h = ItemHealth {
            max_speed2: 0.0,
            fastest: 0,
            first_non_finite: u32::MAX,
        };
        for i in range {
            let m = o.to_mesh[i];
            // SAFETY: particle `i` (mesh vertex `m`) belongs to this group.
            let (p, vel) = unsafe {
                let (p, vel) = (self.xs.get(i), self.vs.get(i));
                self.x.set(m as usize, p);
                self.v.set(m as usize, vel);
                (p, vel)
            };
            if !p.is_finite() || !vel.is_finite() {
                h.first_non_finite = h.first_non_finite.min(m);
                continue;
            }
            let s2 = vel.length_squared();
            if s2 > h.max_speed2 {
                h.max_speed2 = s2;
                h.fastest = m;
            }
        }
        // SAFETY: slot `group` belongs to this item.
        unsafe { self.group_health.set(group, h) };
    }

    /// Gathers the aerodynamic forces of the particles of `range` from their triangles'.
    #[inline(always)]
    fn load(&self, range: std::ops::Range<usize>) {
        if !self.k.aero {
            return;
        }
        let m = self.model;
        for i in range {
            let w = m.inverse_mass[i];
            let mut sum = Vec3A::ZERO;
            if w > 0.0 {
                // SAFETY (both blocks): the triangle forces are only read in this phase.
                let f = |t: u32| unsafe { self.triangle_force.get(t as usize) };
                // A tree of eight (short dependency chains, no branch on the count).
                let t = &m.vertex_triangles8[i];
                sum = ((f(t[0]) + f(t[1])) + (f(t[2]) + f(t[3])))
                    + ((f(t[4]) + f(t[5])) + (f(t[6]) + f(t[7])));
                let (start, end) = (m.vertex_triangles_start[i], m.vertex_triangles_start[i + 1]);
                for &t in
                    &m.vertex_triangles[(start as usize + LANES).min(end as usize)..end as usize]
                {
                    sum += f(t);
                }
            }
            // SAFETY: particle `i` belongs to this item.
            unsafe { self.external.set(i, sum * (w / 3.0)) };
        }
    }

    #[inline(always)]
    fn aero_triangles(&self, item: usize) {
        let tris = &self.model.triangles;
        let lo = item * TRIANGLE_ITEM;
        let hi = (lo + TRIANGLE_ITEM).min(tris.len());
        // Eight triangles at a time; a last, shorter group repeats its last triangle in the
        // spare lanes.
        for t in (lo..hi).step_by(LANES) {
            // SAFETY: positions and velocities are only read in this phase; the force slots
            // of triangles `t..hi` belong to this item.
            unsafe { aero8(self.k.isa, self, t, (hi - t).min(LANES)) };
        }
    }

    /// Where attachment `slot` is at the end of substep `sub`.
    #[inline]
    fn anchor(&self, slot: u32, sub: u32) -> Vec3A {
        self.anchors_of(sub)[slot as usize]
    }

    /// The attachment targets at the end of substep `sub`.
    #[inline]
    fn anchors_of(&self, sub: u32) -> &[Vec3A] {
        let n = self.target_start.len();
        debug_assert!((sub as usize + 1) * n <= self.anchors.len());
        // SAFETY: in bounds (the sweep's slots); written by substep `sub`'s sweep item, which
        // every item that reads them waits for, and not written again in the step.
        unsafe { std::slice::from_raw_parts(self.anchors.as_ptr().add(sub as usize * n), n) }
    }

    /// The bounds of the colliders swept over substep `sub`, eight at a time.
    #[inline]
    fn swept_bounds_of(&self, sub: u32) -> &[ColliderBounds] {
        let n = self.k.colliders.div_ceil(LANES);
        debug_assert!((sub as usize + 1) * n <= self.swept_bounds.len());
        // SAFETY: as for `anchors_of`.
        unsafe { std::slice::from_raw_parts(self.swept_bounds.as_ptr().add(sub as usize * n), n) }
    }

    /// The colliders swept over substep `sub`.
    #[inline]
    fn swept_of(&self, sub: u32) -> &[SweptCollider] {
        let n = self.k.colliders;
        debug_assert!((sub as usize + 1) * n <= self.swept.len());
        // SAFETY: as for `anchors_of`.
        unsafe { std::slice::from_raw_parts(self.swept.as_ptr().add(sub as usize * n), n) }
    }

    /// Sweeps the colliders over substep `sub` and moves the attachment targets to its end
    /// (the `Phase::Sweep` item).
    #[inline(always)]
    fn sweep(&self, sub: u32) {
        let b = &self.bodies;
        let (count, attachments) = (self.k.colliders, self.target_start.len());
        let substeps = self.k.substeps;
        let (t0, t1) = (
            sub as f32 / substeps as f32,
            (sub + 1) as f32 / substeps as f32,
        );
        let sub = sub as usize;
        let eights = count.div_ceil(LANES);
        for eight in 0..eights {
            let mut bounds = ColliderBounds::EMPTY;
            for (l, collider) in (eight * LANES..count.min((eight + 1) * LANES)).enumerate() {
                let c = SweptCollider::new(
                    b.shape_at(collider, t0),
                    b.shape_at(collider, t1),
                    self.k.thickness,
                )
                .with_friction(b.friction_of(collider));
                bounds.set(l, &c);
                // SAFETY: substep `sub`'s slots are written by this item alone, and read only
                // by items that wait for it.
                unsafe { self.swept.set(sub * count + collider, c) };
            }
            // SAFETY: as above.
            unsafe { self.swept_bounds.set(sub * eights + eight, bounds) };
        }
        for (slot, (a, e)) in self.target_start.iter().zip(b.target_end).enumerate() {
            // SAFETY: as above.
            unsafe { self.anchors.set(sub * attachments + slot, a.lerp(*e, t1)) };
        }
    }

    /// Puts particle `i` at `p` back within its tethers (see the module documentation).
    #[inline]
    fn apply_tethers(&self, i: usize, p: Vec3A, sub: u32) -> Vec3A {
        let m = self.model;
        let first = m.tether_start[i] as usize;
        if m.tether_start[i + 1] as usize - first == 2 {
            let a0 = self.anchor(m.tether_slot[first], sub);
            let a1 = self.anchor(m.tether_slot[first + 1], sub);
            let (r0, r1) = (m.tether_limit[first], m.tether_limit[first + 1]);
            if let Some(q) = project_on_two_balls(p, a0, r0, a1, r1) {
                return q;
            }
        }
        self.alternate_tethers(i, p, sub)
    }

    /// [`Self::apply_tethers`] for particles `i..i + 8`, which have two tethers each.
    ///
    /// # Safety
    /// Particles `i..i + 8` belong to the calling item.
    #[inline]
    unsafe fn tethers8(&self, i: usize, sub: u32) {
        let m = self.model;
        let s = m.tether_start[i] as usize;
        let anchors = self.anchors_of(sub).as_ptr();
        let p = &mut [Vec3A::ZERO; LANES];
        // SAFETY: slots index the attachments; `i..i + 8` belong to the calling item.
        let mut fallback = unsafe {
            two_tethers(
                self.k.isa,
                self.xs.as_ptr().add(i),
                anchors,
                &m.tether_slot[s..s + 2 * LANES],
                &m.tether_limit[s..s + 2 * LANES],
                p,
            )
        };
        while fallback != 0 {
            let l = fallback.trailing_zeros() as usize;
            fallback &= fallback - 1;
            // SAFETY: as above.
            unsafe { self.xs.set(i + l, self.apply_tethers(i + l, p[l], sub)) };
        }
    }

    /// Alternating projections onto the tether balls of particle `i`.
    #[inline(never)]
    fn alternate_tethers(&self, i: usize, mut p: Vec3A, sub: u32) -> Vec3A {
        let m = self.model;
        let tethers = m.tether_start[i] as usize..m.tether_start[i + 1] as usize;
        // Projecting onto one tether's sphere can violate another: alternate (it converges
        // to the intersection of the balls, which holds the particle's anchors' common
        // region); one round when only one tether is tight.
        for round in 0..TETHER_ROUNDS {
            let mut moved = false;
            // Later rounds only fix violations above 0.1 % (two anchors next to each other
            // make nearly equal balls, whose alternation converges slowly).
            let slack = if round == 0 { 1.0 } else { 1.0 + 2e-3 };
            for k in tethers.clone() {
                let a = self.anchor(m.tether_slot[k], sub);
                let d = p - a;
                let limit = m.tether_limit[k];
                let l2 = d.length_squared();
                if l2 > limit * limit * slack {
                    p = a + d * (limit / l2.sqrt());
                    moved = true;
                }
            }
            if !moved || tethers.len() < 2 {
                break;
            }
        }
        p
    }

    #[inline]
    fn tether_violated(&self, i: usize, p: Vec3A, sub: u32) -> bool {
        let m = self.model;
        (m.tether_start[i] as usize..m.tether_start[i + 1] as usize).any(|k| {
            let limit = m.tether_limit[k] * (1.0 + 1e-3);
            (p - self.anchor(m.tether_slot[k], sub)).length_squared() > limit * limit
        })
    }

    /// Finishes substep `finish` (tethers, collision, velocity) and then predicts substep
    /// `predict` for the particles of `range` (a chunk).
    #[inline(always)]
    fn particles(&self, finish: Option<u32>, predict: Option<u32>, range: std::ops::Range<usize>) {
        let k = &self.k;
        let m = self.model;
        if let Some(sub) = finish {
            self.tethers_and_collisions(sub, range.clone());
        }
        let fast = finish.is_some() && predict.is_some();
        let mut i = range.start;
        while i < range.end {
            let flags = m.eight_at(i, range.end);
            if fast && flags & EIGHT_FREE != 0 {
                // SAFETY: particles `i..i + 8` belong to this item.
                unsafe {
                    integrate_free(
                        k.isa,
                        [self.xs.as_ptr().add(i), self.xs_prev.as_ptr().add(i)],
                        self.external.as_ptr().add(i),
                        k,
                    )
                };
                i += LANES;
                continue;
            }
            if finish.is_some() && predict.is_none() && flags & EIGHT_FREE != 0 {
                // SAFETY: particles `i..i + 8` belong to this item.
                unsafe {
                    finish_free(
                        k.isa,
                        [
                            self.xs.as_ptr().add(i),
                            self.xs_prev.as_ptr().add(i),
                            self.vs.as_ptr().add(i),
                        ],
                        k.inv_h,
                        k.max_velocity,
                    )
                };
                i += LANES;
                continue;
            }
            if let Some(sub) = predict
                && flags & EIGHT_ATTACHED != 0
                && m.attach_slot[i..i + LANES]
                    .iter()
                    .all(|&slot| (slot as usize) < self.target_start.len())
            {
                let slots = &m.attach_slot[i..i + LANES];
                let anchors = self.anchors_of(sub);
                // SAFETY: particles `i..i + 8` belong to this item; their slots index the
                // attachments (checked above).
                unsafe {
                    follow_anchors(
                        k.isa,
                        [
                            self.xs.as_ptr().add(i),
                            self.xs_prev.as_ptr().add(i),
                            self.vs.as_ptr().add(i),
                        ],
                        anchors.as_ptr(),
                        slots,
                        k.inv_h,
                    )
                };
                i += LANES;
                continue;
            }
            let range = i..i + 1;
            i += 1;
            for i in range {
                // SAFETY: particle `i` belongs to this item; nothing else touches it in this phase.
                unsafe {
                    let p = self.xs.get(i);
                    if m.inverse_mass[i] == 0.0 {
                        if let Some(sub) = predict {
                            let target = self.anchor(m.attach_slot[i], sub);
                            self.xs_prev.set(i, p);
                            self.xs.set(i, target);
                            self.vs.set(i, (target - p) * k.inv_h);
                        }
                        continue;
                    }
                    let mut vel = if finish.is_some() {
                        let vel = (p - self.xs_prev.get(i)) * k.inv_h;
                        let speed2 = vel.length_squared();
                        if speed2 > k.max_velocity * k.max_velocity {
                            vel * (k.max_velocity / speed2.sqrt())
                        } else {
                            vel
                        }
                    } else {
                        self.vs.get(i)
                    };
                    if predict.is_some() {
                        vel = predict_velocity(k, p, vel, self.external.get(i));
                        self.xs_prev.set(i, p);
                        self.xs.set(i, p + vel * k.h);
                    }
                    self.vs.set(i, vel);
                }
            }
        }
    }

    /// Tethers, then collision with the colliders and planes near the chunk `range`.
    #[inline(always)]
    fn tethers_and_collisions(&self, sub: u32, range: std::ops::Range<usize>) {
        let k = &self.k;
        let m = self.model;
        let colliders = self.swept_of(sub);
        let mut low = Vec3A::splat(f32::INFINITY);
        let mut high = Vec3A::splat(f32::NEG_INFINITY);
        // SAFETY (whole function): particles of `range` belong to this item; attachment
        // targets and colliders are read-only.
        let mut i = range.start;
        while i < range.end {
            let flags = m.eight_at(i, range.end);
            if flags & EIGHT_TWO_TETHERS != 0 {
                // SAFETY: particles `i..i + 8` belong to this item.
                unsafe { self.tethers8(i, sub) };
                // The group's bounds as a tree (short dependency chains).
                // SAFETY: as above.
                let pairs: [(Vec3A, Vec3A); LANES] = std::array::from_fn(|l| unsafe {
                    (self.xs.get(i + l), self.xs_prev.get(i + l))
                });
                let lo = pairs.map(|(p, q)| p.min(q));
                let hi = pairs.map(|(p, q)| p.max(q));
                let lo = [
                    lo[0].min(lo[1]),
                    lo[2].min(lo[3]),
                    lo[4].min(lo[5]),
                    lo[6].min(lo[7]),
                ];
                let hi = [
                    hi[0].max(hi[1]),
                    hi[2].max(hi[3]),
                    hi[4].max(hi[5]),
                    hi[6].max(hi[7]),
                ];
                low = low.min(lo[0].min(lo[1]).min(lo[2].min(lo[3])));
                high = high.max(hi[0].max(hi[1]).max(hi[2].max(hi[3])));
                i += LANES;
                continue;
            }
            if flags & EIGHT_ATTACHED != 0 {
                // No tethers, no bounds.
                i += LANES;
                continue;
            }
            if m.inverse_mass[i] != 0.0 {
                unsafe {
                    let mut p = self.xs.get(i);
                    if m.tether_start[i] != m.tether_start[i + 1] {
                        p = self.apply_tethers(i, p, sub);
                        self.xs.set(i, p);
                    }
                    let q = self.xs_prev.get(i);
                    low = low.min(p).min(q);
                    high = high.max(p).max(q);
                }
            }
            i += 1;
        }
        // No free particle, or a NaN (the guard will see it): no collider, every plane, as
        // the chunk's bounds say nothing.
        let bounded = low.cmple(high).all();
        // Colliders and planes whose bounds meet the chunk's (at most `NEAR` of each; more
        // than that and every one is tested).
        const NEAR: usize = 64;
        let mut near = [0u16; NEAR];
        let mut count = 0usize;
        if bounded {
            for (eight, bounds) in self.swept_bounds_of(sub).iter().enumerate() {
                // SAFETY: the instruction set detected.
                let mut hits = unsafe { overlaps8(k.isa, bounds, low, high) };
                while hits != 0 {
                    let c = eight * LANES + hits.trailing_zeros() as usize;
                    hits &= hits - 1;
                    if count < NEAR {
                        near[count] = c as u16;
                    }
                    count += 1;
                }
            }
        }
        let all: [u16; 0] = [];
        let (near, test_all) = if count > NEAR {
            (&all[..], true)
        } else {
            (&near[..count], false)
        };
        let mut near_planes = [0u8; 8];
        let mut plane_count = 0usize;
        for (c, plane) in self.planes.iter().enumerate() {
            let n = Vec3A::from(plane.normal);
            // The chunk's lowest point along the normal.
            let corner = Vec3A::select(n.cmpge(Vec3A::ZERO), low, high);
            let clearance = n.dot(corner) - plane.offset - k.thickness;
            if !bounded || clearance.is_nan() || clearance < 0.0 {
                if plane_count < near_planes.len() {
                    near_planes[plane_count] = c as u8;
                }
                plane_count += 1;
            }
        }
        let all_planes = plane_count > near_planes.len();
        let plane_count = plane_count.min(near_planes.len());
        let shapes = if test_all {
            colliders.len()
        } else {
            near.len()
        } + if all_planes {
            self.planes.len()
        } else {
            plane_count
        };
        if shapes == 0 {
            return;
        }
        let near = (!test_all).then_some(near);
        let planes = if all_planes {
            None
        } else {
            Some(&near_planes[..plane_count])
        };
        let scene = Scene {
            colliders,
            near,
            planes,
            any_plane: plane_count > 0,
            shapes,
        };
        #[cfg(test)]
        let together = k.group_collisions;
        #[cfg(not(test))]
        let together = true;
        let group = together && near.is_none_or(|n| !n.is_empty());
        // Without a plane near, the pass after the first is made on the eight particles
        // together too (see `collide8`).
        let second = !scene.any_plane && scene.shapes >= 2;
        let mut pass = GroupPass {
            p: [Vec3A::ZERO; LANES],
            last: [0; LANES],
        };
        let mut i = range.start;
        while i < range.end {
            // Eight free particles: collided together, each collider with the lanes its box
            // meets; only what the eight-particle passes leave open is done one by one.
            let flags = m.eight_at(i, range.end);
            if group && flags & EIGHT_FREE != 0 {
                // SAFETY: particles `i..i + 8` belong to this item.
                match unsafe { self.collide_group(i, &scene, second, &mut pass) } {
                    Some((moved, again)) if scene.any_plane => {
                        // The planes (and every pass after the first) one by one.
                        for l in 0..LANES {
                            let last = (moved & (1 << l) != 0).then_some(pass.last[l]);
                            // SAFETY: as above.
                            unsafe {
                                let start = self.xs_prev.get(i + l);
                                let resume = Resume::AfterColliders(last);
                                self.collide_particle(i + l, sub, start, pass.p[l], resume, &scene);
                            }
                        }
                        debug_assert_eq!(again, 0);
                    }
                    Some((moved, again)) => {
                        // A particle no collider moved is done (its position is unchanged).
                        let mut rest = moved;
                        while rest != 0 {
                            let l = rest.trailing_zeros() as usize;
                            rest &= rest - 1;
                            // SAFETY: as above.
                            unsafe {
                                let start = self.xs_prev.get(i + l);
                                if again & (1 << l) != 0 {
                                    let resume = Resume::ThirdPass;
                                    self.collide_particle(
                                        i + l,
                                        sub,
                                        start,
                                        pass.p[l],
                                        resume,
                                        &scene,
                                    );
                                } else {
                                    self.settle(i + l, sub, start, pass.p[l], colliders);
                                }
                            }
                        }
                    }
                    // A position that is not finite: each particle on its own.
                    None => {
                        for i in i..i + LANES {
                            // SAFETY: as above.
                            unsafe {
                                let (start, p) = (self.xs_prev.get(i), self.xs.get(i));
                                self.collide_particle(i, sub, start, p, Resume::Fresh, &scene);
                            }
                        }
                    }
                }
                i += LANES;
                continue;
            }
            if flags & EIGHT_ATTACHED != 0 {
                // Not collided.
                i += LANES;
                continue;
            }
            if m.inverse_mass[i] != 0.0 {
                // SAFETY: particle `i` belongs to this item.
                unsafe {
                    let (start, p) = (self.xs_prev.get(i), self.xs.get(i));
                    self.collide_particle(i, sub, start, p, Resume::Fresh, &scene);
                }
            }
            i += 1;
        }
    }

    /// The collision passes over the colliders (not the planes) that the eight particles
    /// from `i` make together ([`collide8`]; the second only if `second`), into `pass`: the
    /// lanes moved, and those the second pass moved (they need a third, one by one). `None`
    /// if a position is not finite (the one-particle path handles it).
    ///
    /// # Safety
    /// Particles `i..i + 8` belong to the calling item.
    #[inline(always)]
    unsafe fn collide_group(
        &self,
        i: usize,
        scene: &Scene<'_>,
        second: bool,
        pass: &mut GroupPass,
    ) -> Option<(u32, u32)> {
        let k = &self.k;
        #[cfg(test)]
        let prune = k.prune_passes;
        #[cfg(not(test))]
        let prune = true;
        // SAFETY: the caller's contract.
        unsafe {
            collide8(
                k.isa,
                self.xs_prev.as_ptr().add(i),
                self.xs.as_ptr().add(i),
                scene,
                (k.thickness, k.friction),
                (second, prune),
                pass,
            )
        }
    }

    /// Stores particle `i`'s position `p` after a collider moved it (from `start` in
    /// substep `sub`), reconciled with its tethers if it left them.
    ///
    /// # Safety
    /// Particle `i` belongs to the calling item.
    #[inline]
    unsafe fn settle(
        &self,
        i: usize,
        sub: u32,
        start: Vec3A,
        mut p: Vec3A,
        colliders: &[SweptCollider],
    ) {
        // SAFETY: the caller's contract.
        unsafe {
            if self.tether_violated(i, p, sub) {
                p = self.reconcile(i, start, p, sub, colliders);
            }
            self.xs.set(i, p);
        }
    }

    /// Collides particle `i`, moving from `start` to `p` in substep `sub`, with the scene's
    /// colliders and planes and stores the result; `resume` says which passes were already
    /// made ([`Resume`]).
    ///
    /// A pass tests the colliders, then the planes, in the scene's order, and is repeated
    /// while it moves the particle. The pass after the first tests only the shapes before the
    /// last one that moved it, if the particle ended the first pass within the box of its
    /// path at the start of that pass (the box tested against each collider's bounds): the
    /// shapes after the last mover tested it where it still is, or their bounds missed a box
    /// that holds its new path, and a shape leaves a particle it moved on its skin, where it
    /// does not move it again (`CONTACT_TOLERANCE`). Once a shape moves it in that pass, the
    /// shapes after that one are all tested too: they have not seen it where it now is (a
    /// pass that stopped at the last mover anyway left those moves to the third pass, and
    /// differed from testing every shape: session 13, found when a different block split
    /// moved a skirt's particles between the one-particle and the grouped path). Otherwise,
    /// and in a third pass, every shape is tested.
    ///
    /// # Safety
    /// Particle `i` belongs to the calling item.
    unsafe fn collide_particle(
        &self,
        i: usize,
        sub: u32,
        start: Vec3A,
        mut p: Vec3A,
        resume: Resume,
        scene: &Scene<'_>,
    ) {
        let k = &self.k;
        let colliders = scene.colliders;
        let collider_count = scene.near.map_or(colliders.len(), <[u16]>::len);
        let mut touched = resume == Resume::ThirdPass;
        let mut settled = true;
        // Shapes (colliders, then planes) this pass tests: those before `limit`, and every one
        // after a shape has moved the particle in this pass.
        let mut limit = usize::MAX;
        // SAFETY: the caller's contract (the particle's position before the first pass).
        let before = unsafe { self.xs.get(i) };
        let (box_low, box_high) = (start.min(before), start.max(before));
        let passes = if touched { 2..3 } else { 0..3 };
        for pass in passes {
            // The place of the last shape that moved the particle in this pass.
            let mut last: Option<usize> = None;
            match resume {
                Resume::AfterColliders(first_last) if pass == 0 => {
                    last = first_last.map(usize::from)
                }
                _ => {
                    let (seg_low, seg_high) = (start.min(p), start.max(p));
                    let mut test = |place: usize, collider: &SweptCollider| {
                        if place >= limit && last.is_none() {
                            return;
                        }
                        if collider.overlaps(seg_low, seg_high) {
                            let friction = k.friction * collider.friction;
                            let (q, hit) = collider.collide(start, p, k.thickness, friction);
                            if hit {
                                p = q;
                                last = Some(place);
                            }
                        }
                    };
                    match scene.near {
                        None => colliders[..collider_count]
                            .iter()
                            .enumerate()
                            .for_each(|(c, s)| test(c, s)),
                        Some(near) => near
                            .iter()
                            .enumerate()
                            .for_each(|(c, &s)| test(c, &colliders[s as usize])),
                    }
                }
            }
            let mut test_plane = |place: usize, plane: &Plane| {
                if collider_count + place >= limit && last.is_none() {
                    return;
                }
                let q = collide_plane(plane, start, p, k.thickness, k.friction);
                if q != p {
                    p = q;
                    last = Some(collider_count + place);
                }
            };
            match scene.planes {
                None => self
                    .planes
                    .iter()
                    .enumerate()
                    .for_each(|(c, plane)| test_plane(c, plane)),
                Some(near) => near
                    .iter()
                    .enumerate()
                    .for_each(|(c, &plane)| test_plane(c, &self.planes[plane as usize])),
            }
            let Some(last) = last else {
                break;
            };
            touched = true;
            if scene.shapes < 2 {
                break;
            }
            #[cfg(test)]
            let prune = k.prune_passes;
            #[cfg(not(test))]
            let prune = true;
            let in_box = prune && p.cmpge(box_low).all() && p.cmple(box_high).all();
            limit = if pass == 0 && in_box {
                last
            } else {
                usize::MAX
            };
            settled = pass < 2;
        }
        if !settled {
            // Still pushed back and forth after the last pass: caught where two shapes
            // overlap (the thighs in a stride); settle in the crease between them.
            p = match scene.near {
                None => self.resolve_overlaps(p, colliders.iter()),
                Some(near) => {
                    self.resolve_overlaps(p, near.iter().map(|&c| &colliders[c as usize]))
                }
            };
        }
        // SAFETY: the caller's contract.
        unsafe {
            if touched {
                self.settle(i, sub, start, p, colliders);
            } else {
                self.xs.set(i, p);
            }
        }
    }

    /// Moves `p` out of every collider and plane (with the skin): the smallest move that
    /// clears the two most violated shapes, linearised at `p` (their tangent half-spaces),
    /// repeated. One violated shape is a plain push-out; two are solved together, so a particle
    /// caught where two colliders overlap settles in the crease between them instead of being
    /// pushed back and forth (sequential push-outs leave it inside one of them).
    fn resolve_overlaps<'c>(
        &self,
        mut p: Vec3A,
        colliders: impl Iterator<Item = &'c SweptCollider> + Clone,
    ) -> Vec3A {
        let thickness = self.k.thickness;
        for _round in 0..OVERLAP_ROUNDS {
            // The two deepest violations: (signed skin distance, outward normal).
            let mut worst: [Option<(f32, Vec3A)>; 2] = [None, None];
            let mut note = |s: f32, n: Vec3A| {
                if s >= 0.0 || s.is_nan() {
                    return;
                }
                if worst[0].is_none_or(|w| s < w.0) {
                    worst[1] = worst[0];
                    worst[0] = Some((s, n));
                } else if worst[1].is_none_or(|w| s < w.0) {
                    worst[1] = Some((s, n));
                }
            };
            for collider in colliders.clone() {
                if collider.contains_point(p) {
                    let (s, n) = collider.skin_distance(p, thickness);
                    note(s, n);
                }
            }
            for plane in self.planes {
                let n = Vec3A::from(plane.normal);
                note(n.dot(p) - plane.offset - thickness, n);
            }
            p += match worst {
                [None, _] => break,
                [Some((s, n)), None] => -s * n,
                [Some(a), Some(b)] => clear_two(a, b),
            };
        }
        p
    }

    /// Resolves a particle that a collider pushed beyond its tether (see the module
    /// documentation). First the particle slides: alternating projections onto its tether
    /// balls and onto the tangent half-space of the collider it rests on, which keeps it on
    /// its side of the collider. If no such point exists (a collider dragging the cloth
    /// farther than the garment reaches), the tether wins and the particle goes to the nearest
    /// collider surface, possibly the far side. The repair is kept out of the velocity.
    ///
    /// # Safety
    /// Particle `i` belongs to the calling item.
    unsafe fn reconcile(
        &self,
        i: usize,
        start: Vec3A,
        collided: Vec3A,
        sub: u32,
        colliders: &[SweptCollider],
    ) -> Vec3A {
        let k = &self.k;
        // The surface the particle rests on: the nearest collider (or plane).
        let mut support: Option<(f32, Vec3A)> = None;
        let mut best = f32::INFINITY;
        for collider in colliders {
            if collider.contains_point(collided) {
                let (s, n) = collider.skin_distance(collided, k.thickness);
                if s < best {
                    best = s;
                    support = Some((n.dot(collided) - s, n));
                }
            }
        }
        for plane in self.planes {
            let n = Vec3A::from(plane.normal);
            let s = n.dot(collided) - plane.offset - k.thickness;
            if s < best {
                best = s;
                support = Some((plane.offset + k.thickness, n));
            }
        }
        let mut p = collided;
        let mut slid = false;
        if let Some((offset, n)) = support {
            for _round in 0..RECONCILE_ROUNDS {
                p = self.apply_tethers(i, p, sub);
                let s = n.dot(p) - offset;
                if s >= 0.0 {
                    slid = true;
                    break;
                }
                p -= s * n;
            }
            slid |= !self.tether_violated(i, p, sub);
        }
        if !slid {
            p = self.apply_tethers(i, collided, sub);
        }
        // Out of every collider (a slid particle is at most a rounding error inside).
        p = self.resolve_overlaps(p, colliders.iter());
        // SAFETY: particle `i` belongs to the calling item.
        unsafe { self.xs_prev.set(i, start + (p - collided)) };
        p
    }
}

/// The collision passes of eight particles made together ([`StepContext::collide_group`]).
struct GroupPass {
    /// The positions after them.
    p: [Vec3A; LANES],
    /// Per lane the first pass moved: the place in the scene's order of the last collider
    /// that moved it.
    last: [u16; LANES],
}

/// Where [`StepContext::collide_particle`] starts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Resume {
    /// At the first pass.
    Fresh,
    /// After the first pass's colliders (not its planes); the place in the scene's order of
    /// the last collider that moved the particle (`None`: none did).
    AfterColliders(Option<u16>),
    /// At the third pass: the first two moved the particle.
    ThirdPass,
}

/// Every lane of a group of eight, as bits.
const ALL_LANES: u32 = (1 << LANES) - 1;

/// What the particles of one chunk collide with in one substep.
struct Scene<'a> {
    /// The substep's colliders.
    colliders: &'a [SweptCollider],
    /// The colliders near the chunk (indices into `colliders`), or `None` for all of them.
    near: Option<&'a [u16]>,
    /// The planes near the chunk (indices), or `None` for all of them.
    planes: Option<&'a [u8]>,
    /// Whether any plane is tested.
    any_plane: bool,
    /// How many colliders and planes are tested.
    shapes: usize,
}

impl Scene<'_> {
    /// The collider at place `c` of the scene's order.
    #[inline]
    fn collider(&self, c: usize) -> &SweptCollider {
        match self.near {
            None => &self.colliders[c],
            Some(near) => &self.colliders[near[c] as usize],
        }
    }
}

/// The collision passes over the scene's colliders of eight particles (`start`: at the
/// substep start, `now`: now, both eight consecutive particles), made together in lanes as
/// [`StepContext::collide_particle`] makes them for each particle: the first pass, and if
/// `second`, the second one for the lanes the first moved (`prune`: testing only the
/// colliders before the last mover of a particle that stayed within its box, and all those
/// after a collider that moves it again; tests turn it off). A collider tests the lanes
/// whose path box meets its own. Returns the lanes moved and those the second pass moved
/// (they need the third pass, made one by one), and writes the positions after the passes,
/// and per lane moved in the first pass the place in the scene's order of the last collider
/// that moved it, to `out`; `None` (and nothing useful in `out`) if a position is not
/// finite, or the first pass made one so.
///
/// # Safety
/// `start` and `now` point at eight particles that the calling item owns.
#[inline]
unsafe fn collide8(
    isa: Isa,
    start: *const Vec3A,
    now: *const Vec3A,
    scene: &Scene<'_>,
    contact: (f32, f32),
    passes: (bool, bool),
    out: &mut GroupPass,
) -> Option<(u32, u32)> {
    dispatch_lanes!(
        isa,
        collide8_with(
            start: *const Vec3A,
            now: *const Vec3A,
            scene: &Scene<'_>,
            contact: (f32, f32),
            passes: (bool, bool),
            out: &mut GroupPass,
        ) -> Option<(u32, u32)>
    )
}

/// One collider's test in a pass of [`collide8`]: the lanes of `active` whose path box (from
/// `path.0` to `path.1`) meets the collider's are collided at `p`, which takes the moved
/// ones' new positions; returns the lanes moved.
#[inline(always)]
fn collide_near<L: Lanes>(
    collider: &SweptCollider,
    (start, box_end): (V3<L>, V3<L>),
    p: &mut V3<L>,
    active: L,
    (thickness, friction): (f32, f32),
) -> L {
    let lanes = collider.overlaps_lanes(start, box_end).and(active);
    if lanes.bits() == 0 {
        return lanes;
    }
    let friction = friction * collider.friction;
    let (q, hit) = collider.collide_lanes(start, *p, lanes, thickness, friction);
    if hit.bits() != 0 {
        *p = V3::select(hit, q, *p);
    }
    hit
}

#[inline(always)]
unsafe fn collide8_with<L: Lanes>(
    start: *const Vec3A,
    now: *const Vec3A,
    scene: &Scene<'_>,
    contact: (f32, f32),
    (second, prune): (bool, bool),
    out: &mut GroupPass,
) -> Option<(u32, u32)> {
    let index: [u32; LANES] = std::array::from_fn(|l| offset(l as u32));
    // SAFETY: the caller's contract.
    let (s, first) = unsafe { (L::gather(start, &index), L::gather(now, &index)) };
    // (No closures: they would not inherit the caller's target features.) `|v|² · 0` is zero
    // for a finite `v` and NaN for an infinite or NaN one (or one too large to square, which
    // the one-particle path then handles too).
    let zero = L::splat(0.0);
    if (s.dot(s) * zero)
        .is_nan()
        .or((first.dot(first) * zero).is_nan())
        .bits()
        != 0
    {
        return None;
    }
    let count = scene.near.map_or(scene.colliders.len(), <[u16]>::len);
    // Masks: no lane.
    let mut moved = zero;
    let mut last = zero;
    let mut p = first;
    let every = zero.le(zero);
    for c in 0..count {
        let hit = collide_near(scene.collider(c), (s, first), &mut p, every, contact);
        if hit.bits() != 0 {
            last = L::select(hit, L::splat(c as f32), last);
            moved = moved.or(hit);
        }
    }
    let mut again = zero;
    if second && moved.bits() != 0 {
        // The second pass, over the lanes the first moved: the colliders before the last
        // mover if the particle stayed within the box of its path at the start of the first
        // pass (and every one after a collider that moves it again), else all of them. (A
        // position the first pass made not finite: the whole group one by one, as for a
        // non-finite input.)
        let p1 = p;
        if (p1.dot(p1) * zero).is_nan().bits() != 0 {
            return None;
        }
        let in_box =
            s.x.le(p1.x)
                .or(first.x.le(p1.x))
                .and(s.y.le(p1.y).or(first.y.le(p1.y)))
                .and(s.z.le(p1.z).or(first.z.le(p1.z)))
                .and(p1.x.le(s.x).or(p1.x.le(first.x)))
                .and(p1.y.le(s.y).or(p1.y.le(first.y)))
                .and(p1.z.le(s.z).or(p1.z.le(first.z)));
        let in_box = if prune { in_box } else { zero };
        let mut limit = L::select(in_box, last, L::splat(f32::INFINITY));
        for c in 0..count {
            let active = moved.and(limit.gt(L::splat(c as f32)));
            if active.bits() != 0 {
                let hit = collide_near(scene.collider(c), (s, p1), &mut p, active, contact);
                again = again.or(hit);
                // Moved again: the shapes after this one may now touch it (as one that
                // tests every shape finds).
                limit = L::select(hit, L::splat(f32::INFINITY), limit);
            }
        }
    }
    // SAFETY: `out.p` holds eight positions.
    unsafe { L::scatter(out.p.as_mut_ptr(), &index, p) };
    let last = last.to_array();
    out.last = std::array::from_fn(|l| last[l] as u16);
    Some((moved.bits(), again.bits()))
}

/// The smallest displacement `d` with `n_a·d ≥ -s_a` and `n_b·d ≥ -s_b` (both `s < 0`: the
/// depths inside two half-spaces with unit normals `n_a`, `n_b`).
#[inline]
fn clear_two((sa, na): (f32, Vec3A), (sb, nb): (f32, Vec3A)) -> Vec3A {
    // One push alone may clear both.
    let da = -sa * na;
    if nb.dot(da) >= -sb {
        return da;
    }
    let db = -sb * nb;
    if na.dot(db) >= -sa {
        return db;
    }
    // Both active: d = α n_a + β n_b with n_a·d = -s_a and n_b·d = -s_b.
    let c = na.dot(nb);
    let det = 1.0 - c * c;
    if det < 1e-4 {
        // (Anti)parallel normals: no finite crease; take the deeper push.
        return if sa < sb { da } else { db };
    }
    let alpha = (-sa + c * sb) / det;
    let beta = (-sb + c * sa) / det;
    let d = alpha * na + beta * nb;
    // Nearly opposite normals (a particle pinched between two shapes) put the linearised crease
    // far away: there the deeper push alone is taken.
    let deeper = if sa < sb { da } else { db };
    if d.length_squared() > CREASE_REACH * CREASE_REACH * deeper.length_squared() {
        deeper
    } else {
        d
    }
}

/// The nearest point to `p` in the intersection of the balls `(a0, r0)` and `(a1, r1)`;
/// `None` if they do not intersect (or nearly coincide with different radii in a way that
/// rounding makes unreliable).
///
/// The nearest point is `p` itself, or its projection onto one ball if that lies in the
/// other, or else on the circle where the two spheres meet, towards `p`.
#[inline]
fn project_on_two_balls(p: Vec3A, a0: Vec3A, r0: f32, a1: Vec3A, r1: f32) -> Option<Vec3A> {
    let d0 = p - a0;
    let d1 = p - a1;
    let (l0, l1) = (d0.length_squared(), d1.length_squared());
    if l0.is_nan() || l1.is_nan() {
        // Let the alternating projections carry the NaN to the blow-up guard.
        return None;
    }
    let (in0, in1) = (l0 <= r0 * r0, l1 <= r1 * r1);
    if in0 && in1 {
        return Some(p);
    }
    if !in0 {
        let q = a0 + d0 * (r0 / l0.sqrt());
        if (q - a1).length_squared() <= r1 * r1 {
            return Some(q);
        }
    }
    if !in1 {
        let q = a1 + d1 * (r1 / l1.sqrt());
        if (q - a0).length_squared() <= r0 * r0 {
            return Some(q);
        }
    }
    // Both constraints are active: the circle where the spheres meet.
    let axis = a1 - a0;
    let length = axis.length();
    if length <= 1e-9 * (r0 + r1) {
        return None;
    }
    let u = axis / length;
    let along = (length * length + r0 * r0 - r1 * r1) / (2.0 * length);
    let radius2 = r0 * r0 - along * along;
    if radius2.is_nan() || radius2 < 0.0 {
        return None;
    }
    let across = d0 - d0.dot(u) * u;
    let across_length = across.length();
    let dir = if across_length > 1e-12 * r0 {
        across / across_length
    } else {
        Vec3A::from(Vec3::from(u).any_orthonormal_vector())
    };
    Some(a0 + along * u + radius2.sqrt() * dir)
}

/// [`ClothSolver`]'s tethers for eight consecutive particles with two tethers each, at `x`
/// (updated in place); `slots` and `limits` are their tethers' attachment slots and lengths
/// (two per particle), `anchors` the attachments' positions. Lanes whose bit is set in the
/// result need the scalar [`StepContext::apply_tethers`], from their positions left in
/// `before` (NaN, degenerate balls, a point on the axis).
///
/// # Safety
/// `x` points at eight particles that the calling item owns; the slots index `anchors`.
#[inline]
unsafe fn two_tethers(
    isa: Isa,
    x: *mut Vec3A,
    anchors: *const Vec3A,
    slots: &[u32],
    limits: &[f32],
    before: &mut [Vec3A; LANES],
) -> u32 {
    dispatch_lanes!(
        isa,
        two_tethers_with(
            x: *mut Vec3A,
            anchors: *const Vec3A,
            slots: &[u32],
            limits: &[f32],
            before: &mut [Vec3A; LANES],
        ) -> u32
    )
}

#[inline(always)]
unsafe fn two_tethers_with<L: Lanes>(
    x: *mut Vec3A,
    anchors: *const Vec3A,
    slots: &[u32],
    limits: &[f32],
    before: &mut [Vec3A; LANES],
) -> u32 {
    let index: [u32; LANES] = std::array::from_fn(|l| offset(l as u32));
    let slot0: [u32; LANES] = std::array::from_fn(|l| offset(slots[2 * l]));
    let slot1: [u32; LANES] = std::array::from_fn(|l| offset(slots[2 * l + 1]));
    let r0 = L::load(&std::array::from_fn(|l| limits[2 * l]));
    let r1 = L::load(&std::array::from_fn(|l| limits[2 * l + 1]));
    // SAFETY: the caller's contract.
    unsafe {
        let a0 = L::gather(anchors, &slot0);
        let a1 = L::gather(anchors, &slot1);
        let p = L::gather(x, &index);
        let (q, fallback, moved) = project_on_two_balls_lanes(p, a0, r0, a1, r1);
        if moved {
            L::scatter(x, &index, q);
        }
        if fallback != 0 {
            let (px, py, pz) = (p.x.to_array(), p.y.to_array(), p.z.to_array());
            *before = std::array::from_fn(|l| Vec3A::new(px[l], py[l], pz[l]));
        }
        fallback
    }
}

/// [`project_on_two_balls`] for eight points at once; lanes whose bit is set in the returned
/// mask need the scalar function (NaN, degenerate balls, a point on the axis). The flag is
/// false when every point was inside both balls (the points are returned unchanged).
#[inline(always)]
fn project_on_two_balls_lanes<L: Lanes>(
    p: V3<L>,
    a0: V3<L>,
    r0: L,
    a1: V3<L>,
    r1: L,
) -> (V3<L>, u32, bool) {
    let d0 = p - a0;
    let d1 = p - a1;
    let (l0, l1) = (d0.dot(d0), d1.dot(d1));
    let (r0r0, r1r1) = (r0 * r0, r1 * r1);
    let in0 = l0.le(r0r0);
    let in1 = l1.le(r1r1);
    let inside = in0.and(in1);
    if inside.bits() == ALL_LANES {
        return (p, 0, false);
    }
    let nan = l0.is_nan().or(l1.is_nan()).bits();
    let q0 = a0 + d0.scale(r0r0.div(l0).sqrt());
    let e0 = q0 - a1;
    let ok0 = e0.dot(e0).le(r1r1).and_not(in0);
    let q1 = a1 + d1.scale(r1r1.div(l1).sqrt());
    let e1 = q1 - a0;
    let ok1 = e1.dot(e1).le(r0r0).and_not(in1);
    let settled = inside.or(ok0).or(ok1);
    let mut q = V3::select(ok0, q0, V3::select(ok1, q1, p));
    let mut fallback = nan;
    if settled.bits() != ALL_LANES {
        // The circle where the spheres meet: centre a0 + along·û, radius √radius2.
        let axis = a1 - a0;
        let length2 = axis.dot(axis);
        let inv_length2 = L::splat(1.0).div(length2);
        let twice_along_length = length2 + r0r0 - r1r1;
        let centre = a0 + axis.scale(L::splat(0.5) * twice_along_length * inv_length2);
        let radius2 = r0r0 - L::splat(0.25) * twice_along_length * twice_along_length * inv_length2;
        let across = d0 - axis.scale(d0.dot(axis) * inv_length2);
        let across2 = across.dot(across);
        let circle = centre + across.scale(radius2.div(across2).sqrt());
        let tiny = L::splat(1e-9) * (r0 + r1);
        let circle_ok = length2
            .gt(tiny * tiny)
            .and(radius2.not_lt(L::splat(0.0)).and_not(radius2.is_nan()))
            .and(across2.gt(L::splat(1e-24) * r0r0));
        q = V3::select(settled, q, circle);
        fallback |= !circle_ok.or(settled).bits() & ALL_LANES;
    }
    (V3::select(inside, p, q), fallback, true)
}

/// The aerodynamic forces of the `count` (1 to 8) triangles from `t` on
/// ([`StepContext::aero_triangles`]).
///
/// # Safety
/// Positions and velocities are only read in this phase, and the force slots of these
/// triangles belong to the calling item.
unsafe fn aero8(isa: Isa, context: &StepContext<'_>, t: usize, count: usize) {
    dispatch_lanes!(isa, aero_with(context: &StepContext<'_>, t: usize, count: usize))
}

#[inline(always)]
unsafe fn aero_with<L: Lanes>(context: &StepContext<'_>, t: usize, count: usize) {
    let k = &context.k;
    // Spare lanes repeat the last triangle: the same force is stored to its slot again.
    let mut slots = [0u32; LANES];
    let mut corners = [[0u32; LANES]; 3];
    for l in 0..LANES {
        let triangle = t + l.min(count - 1);
        slots[l] = offset(triangle as u32);
        for (corner, &v) in corners.iter_mut().zip(&context.model.triangles[triangle]) {
            corner[l] = offset(v);
        }
    }
    let (xs, vs) = (context.xs.as_ptr(), context.vs.as_ptr());
    // SAFETY: the caller's contract. (No closures here: they would not inherit the caller's
    // target features.)
    unsafe {
        let p = [
            L::gather(xs, &corners[0]),
            L::gather(xs, &corners[1]),
            L::gather(xs, &corners[2]),
        ];
        let third = L::splat(1.0 / 3.0);
        let mut relative =
            (L::gather(vs, &corners[0]) + L::gather(vs, &corners[1]) + L::gather(vs, &corners[2]))
                .scale(third);
        let centroid = (p[0] + p[1] + p[2]).scale(third);
        if let Some(f) = &k.frame {
            relative =
                relative + V3::splat(f.air_velocity) + V3::splat(f.air_omega).cross(centroid);
        }
        if let Some(wind) = context.wind {
            let (pose, to_local) = match &k.frame {
                Some(f) => (f.motion.pose, f.motion.to_local),
                None => (RigidPose::IDENTITY, glam::Quat::IDENTITY),
            };
            let c = centroid.to_arrays();
            let mut air = [[0.0f32; LANES]; 3];
            for l in 0..LANES {
                let world = pose.transform_point(Vec3::new(c[0][l], c[1][l], c[2][l]));
                let a = to_local * wind.velocity(world, k.time);
                (air[0][l], air[1][l], air[2][l]) = (a.x, a.y, a.z);
            }
            relative = relative - V3::load(&air);
        }
        let force = triangle_force_lanes(p, relative, k.air_density, k.drag, k.lift);
        L::scatter(context.triangle_force.as_ptr(), &slots, force);
    }
}

/// Moves eight consecutive attached particles (positions, positions at the substep start and
/// velocities at `x`) to their attachment targets (`slots` into `anchors`) for the next
/// substep, as the one-particle path of [`StepContext::particles`] does.
///
/// # Safety
/// The eight particles belong to the calling item; the slots index `anchors`.
#[inline]
unsafe fn follow_anchors(
    isa: Isa,
    x: [*mut Vec3A; 3],
    anchors: *const Vec3A,
    slots: &[u32],
    inv_h: f32,
) {
    dispatch_lanes!(
        isa,
        follow_anchors_with(x: [*mut Vec3A; 3], anchors: *const Vec3A, slots: &[u32], inv_h: f32)
    )
}

#[inline(always)]
unsafe fn follow_anchors_with<L: Lanes>(
    [xs, xs_prev, vs]: [*mut Vec3A; 3],
    anchors: *const Vec3A,
    slots: &[u32],
    inv_h: f32,
) {
    let lanes: [u32; LANES] = std::array::from_fn(|l| offset(l as u32));
    let slots: [u32; LANES] = std::array::from_fn(|l| offset(slots[l]));
    // SAFETY: the caller's contract.
    unsafe {
        let p = L::gather(xs, &lanes);
        let target = L::gather(anchors, &slots);
        L::scatter(xs_prev, &lanes, p);
        L::scatter(xs, &lanes, target);
        L::scatter(vs, &lanes, (target - p).scale(L::splat(inv_h)));
    }
}

/// The velocity of a free particle at `p` moving at `vel` after a substep's external, frame
/// and damping terms ([`integrate_free`] does the same for eight particles).
#[inline]
fn predict_velocity(k: &StepConstants, p: Vec3A, vel: Vec3A, external: Vec3A) -> Vec3A {
    let mut a = k.gravity + external;
    if let Some(f) = &k.frame {
        a -= f.linear + f.euler.cross(p) + f.coriolis.cross(vel);
        a -= f.centrifugal * f.omega.cross(f.omega.cross(p));
    }
    (vel + a * k.h) * k.damping
}

/// The velocity of substep `s` and the prediction of substep `s + 1` for eight consecutive
/// free particles, with the moving body frame's terms: the vectorised form of
/// [`StepContext::particles`]. `x` holds the positions and positions at the substep start of
/// the first particle; `external` its external acceleration. The velocity is not stored: the
/// next substep derives it from the positions, and the step's last substep (which predicts
/// nothing) stores it.
///
/// # Safety
/// The eight particles belong to the calling item.
#[inline]
unsafe fn integrate_free(isa: Isa, x: [*mut Vec3A; 2], external: *const Vec3A, k: &StepConstants) {
    dispatch_lanes!(
        isa,
        integrate_free_with(x: [*mut Vec3A; 2], external: *const Vec3A, k: &StepConstants)
    )
}

#[inline(always)]
unsafe fn integrate_free_with<L: Lanes>(
    [xs, xs_prev]: [*mut Vec3A; 2],
    external: *const Vec3A,
    k: &StepConstants,
) {
    let lanes: [u32; LANES] = std::array::from_fn(|l| offset(l as u32));
    // SAFETY: the caller's contract. (No closures here: they would not inherit the caller's
    // target features.)
    unsafe {
        let p = L::gather(xs, &lanes);
        let mut vel = (p - L::gather(xs_prev, &lanes)).scale(L::splat(k.inv_h));
        let speed2 = vel.dot(vel);
        let max = L::splat(k.max_velocity);
        let fast = speed2.gt(max * max);
        if fast.bits() != 0 {
            vel = V3::select(fast, vel.scale(max.div(speed2.sqrt())), vel);
        }
        let mut a = V3::splat(k.gravity) + L::gather(external, &lanes);
        if let Some(f) = &k.frame {
            // The fictitious accelerations of the moving body frame, as in the one-particle
            // path of `StepContext::particles`.
            let omega = V3::splat(f.omega);
            a = a
                - (V3::splat(f.linear)
                    + V3::splat(f.euler).cross(p)
                    + V3::splat(f.coriolis).cross(vel));
            a = a - omega.cross(omega.cross(p)).scale(L::splat(f.centrifugal));
        }
        let vel = (vel + a.scale(L::splat(k.h))).scale(L::splat(k.damping));
        L::scatter(xs_prev, &lanes, p);
        L::scatter(xs, &lanes, p + vel.scale(L::splat(k.h)));
    }
}

/// The bounds of eight swept colliders, by axis (`min[axis][lane]`), so that a chunk of
/// particles picks the colliders near it eight at a time ([`overlaps8`]); a lane without a
/// collider has an empty box (the lowest corner +∞, the highest −∞), which meets nothing.
#[derive(Debug, Clone, Copy, PartialEq)]
#[repr(C, align(32))]
struct ColliderBounds {
    min: [[f32; LANES]; 3],
    max: [[f32; LANES]; 3],
}

impl ColliderBounds {
    const EMPTY: Self = Self {
        min: [[f32::INFINITY; LANES]; 3],
        max: [[f32::NEG_INFINITY; LANES]; 3],
    };

    /// Puts `collider`'s bounds in lane `l`.
    fn set(&mut self, l: usize, collider: &SweptCollider) {
        let (lo, hi) = (collider.bounds_min, collider.bounds_max);
        for axis in 0..3 {
            self.min[axis][l] = lo[axis];
            self.max[axis][l] = hi[axis];
        }
    }
}

/// The lanes of `bounds` whose box meets the box from `low` to `high`, as bits: the same
/// comparisons as [`SweptCollider::overlaps`] makes for each.
///
/// # Safety
/// None beyond the instruction set's (see `dispatch_lanes`).
#[inline]
unsafe fn overlaps8(isa: Isa, bounds: &ColliderBounds, low: Vec3A, high: Vec3A) -> u32 {
    dispatch_lanes!(
        isa,
        overlaps8_with(bounds: &ColliderBounds, low: Vec3A, high: Vec3A) -> u32
    )
}

#[inline(always)]
unsafe fn overlaps8_with<L: Lanes>(bounds: &ColliderBounds, low: Vec3A, high: Vec3A) -> u32 {
    let mut meets = L::splat(0.0).le(L::splat(0.0));
    for axis in 0..3 {
        let (lo, hi) = (L::load(&bounds.min[axis]), L::load(&bounds.max[axis]));
        meets = meets
            .and(lo.le(L::splat(high[axis])))
            .and(L::splat(low[axis]).le(hi));
    }
    meets.bits()
}

/// The velocity of the step's last substep for eight consecutive free particles (`x`: their
/// positions, positions at the substep start and velocities), as the one-particle path of
/// [`StepContext::particles`] finishes it: what [`integrate_free`] computes before its
/// prediction.
///
/// # Safety
/// The eight particles belong to the calling item.
#[inline]
unsafe fn finish_free(isa: Isa, x: [*mut Vec3A; 3], inv_h: f32, max_velocity: f32) {
    dispatch_lanes!(
        isa,
        finish_free_with(x: [*mut Vec3A; 3], inv_h: f32, max_velocity: f32)
    )
}

#[inline(always)]
unsafe fn finish_free_with<L: Lanes>(
    [xs, xs_prev, vs]: [*mut Vec3A; 3],
    inv_h: f32,
    max_velocity: f32,
) {
    let lanes: [u32; LANES] = std::array::from_fn(|l| offset(l as u32));
    // SAFETY: the caller's contract.
    unsafe {
        let p = L::gather(xs, &lanes);
        let mut vel = (p - L::gather(xs_prev, &lanes)).scale(L::splat(inv_h));
        let speed2 = vel.dot(vel);
        let max = L::splat(max_velocity);
        let fast = speed2.gt(max * max);
        if fast.bits() != 0 {
            vel = V3::select(fast, vel.scale(max.div(speed2.sqrt())), vel);
        }
        L::scatter(vs, &lanes, vel);
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn eight_flags_mark_runs_of_free_attached_and_two_tether_particles() {
        // 20 particles: 0..4 attached, 4..20 free; free ones have two tethers but 15 (one).
        let inverse_mass: Vec<f32> = (0..20).map(|i| if i < 4 { 0.0 } else { 2.0 }).collect();
        let mut tether_start = vec![0u32];
        for i in 0..20u32 {
            let count = match i {
                0..4 => 0,
                15 => 1,
                _ => 2,
            };
            tether_start.push(tether_start[i as usize] + count);
        }
        let flags = eight_flags(&inverse_mass, &tether_start);
        assert_eq!(flags.len(), 20);
        // Independently: each window checked particle by particle.
        for (i, &f) in flags.iter().enumerate() {
            let window: Vec<usize> = (i..i + 8).filter(|&j| j < 20).collect();
            let full = window.len() == 8;
            let free = full && window.iter().all(|&j| j >= 4);
            let attached = full && window.iter().all(|&j| j < 4);
            let two = full && window.iter().all(|&j| j >= 4 && j != 15);
            assert_eq!(f & EIGHT_FREE != 0, free, "free at {i}");
            assert_eq!(f & EIGHT_ATTACHED != 0, attached, "attached at {i}");
            assert_eq!(f & EIGHT_TWO_TETHERS != 0, two, "two tethers at {i}");
        }
        assert_eq!(flags[4], EIGHT_FREE | EIGHT_TWO_TETHERS);
        assert_eq!(flags[8], EIGHT_FREE);
        assert_eq!(flags[12], EIGHT_FREE);
        assert_eq!(flags[13], 0);
    }

    #[test]
    fn clear_two_finds_the_smallest_move_out_of_two_half_spaces() {
        // Independent check: the smallest move out of two half-spaces, by brute force over a
        // grid of moves in their plane.
        let cases = [
            (-0.01, Vec3A::X, -0.004, Vec3A::Y),
            (-0.01, Vec3A::X, -0.004, Vec3A::new(0.6, 0.8, 0.0)),
            (
                -0.003,
                Vec3A::new(0.0, 1.0, 0.0),
                -0.01,
                Vec3A::new(-0.5, 0.866, 0.0),
            ),
            (-0.01, Vec3A::X, -0.002, Vec3A::new(0.999, 0.0447, 0.0)),
        ];
        for (sa, na, sb, nb) in cases {
            let na = na.normalize();
            let nb = nb.normalize();
            let d = clear_two((sa, na), (sb, nb));
            assert!(na.dot(d) >= -sa - 1e-6 && nb.dot(d) >= -sb - 1e-6, "{d}");
            let mut best = f32::INFINITY;
            let n = 400;
            for i in -n..=n {
                for j in -n..=n {
                    let m = Vec3A::new(i as f32, j as f32, 0.0) * (0.05 / n as f32);
                    if na.dot(m) >= -sa && nb.dot(m) >= -sb {
                        best = best.min(m.length());
                    }
                }
            }
            assert!(d.length() <= best + 2e-4, "{} vs {best}", d.length());
        }
        // Opposite normals (pinched): only the deeper push, never a far escape.
        let d = clear_two(
            (-0.01, Vec3A::X),
            (-0.005, -Vec3A::X.lerp(Vec3A::Y, 0.05).normalize()),
        );
        assert!(d.length() <= 0.0101, "{d}");
    }

    use super::*;
    use crate::simd::Baseline8;

    fn random(seed: &mut u32) -> f32 {
        *seed = seed.wrapping_mul(1664525).wrapping_add(1013904223);
        (*seed >> 8) as f32 / (1u32 << 24) as f32
    }

    #[test]
    fn eight_colliders_boxes_meet_a_chunk_as_each_one_alone_does() {
        // Random spheres' swept boxes, five in a group of eight (three empty lanes), against
        // random chunk boxes, some of them NaN: the lanes set are those whose collider's own
        // test says it meets the chunk, on both instruction sets.
        let mut seed = 4242u32;
        let mut r = |scale: f32| (random(&mut seed) - 0.5) * scale;
        let (mut met, mut missed) = (0, 0);
        for round in 0..500 {
            let colliders: Vec<SweptCollider> = (0..5)
                .map(|_| {
                    let a = Vec3A::new(r(1.0), r(1.0), r(1.0));
                    let b = a + Vec3A::new(r(0.1), r(0.1), r(0.1));
                    let radius = 0.02 + r(0.1).abs();
                    SweptCollider::new(Shape::sphere(a, radius), Shape::sphere(b, radius), 0.003)
                })
                .collect();
            let mut bounds = ColliderBounds::EMPTY;
            for (l, c) in colliders.iter().enumerate() {
                bounds.set(l, c);
            }
            let low = Vec3A::new(r(1.0), r(1.0), r(1.0)) - Vec3A::splat(0.25);
            let mut high = low + Vec3A::new(r(1.0), r(1.0), r(1.0)) + Vec3A::splat(0.5);
            if round % 50 == 0 {
                high.y = f32::NAN;
            }
            let want = colliders
                .iter()
                .enumerate()
                .filter(|(_, c)| c.overlaps(low, high))
                .fold(0u32, |bits, (l, _)| bits | 1 << l);
            met += want.count_ones();
            missed += 5 - want.count_ones();
            for isa in [Isa::Baseline, Isa::detect()] {
                // SAFETY: the detected instruction set.
                let got = unsafe { overlaps8(isa, &bounds, low, high) };
                assert_eq!(got, want, "round {round} {isa:?}");
            }
        }
        assert!(met > 100 && missed > 100, "{met} met, {missed} missed");
    }

    #[test]
    fn eight_particles_collide_as_each_one_alone_does() {
        // Spheres and round cones, moving and turning over the substep, and particles placed
        // around and inside them: the eight-particle pass (both instruction sets) must give
        // the one-particle pass's result bit for bit, lane by lane.
        let mut seed = 777u32;
        let mut r = |scale: f32| (random(&mut seed) - 0.5) * scale;
        let (mut hit_lanes, mut missed_lanes, mut second_lanes) = (0, 0, 0);
        for round in 0..200 {
            let mut swept = Vec::new();
            for c in 0..4 {
                let a = Vec3A::new(r(0.4), r(0.4), r(0.4));
                let shape = |a: Vec3A, b: Vec3A, ra: f32, rb: f32| {
                    if c % 2 == 0 {
                        Shape::sphere(a, ra)
                    } else {
                        Shape::round_cone(a, b, ra, rb)
                    }
                };
                let (b, ra, rb) = (
                    a + Vec3A::new(r(0.5), r(0.5), r(0.5)),
                    0.05 + r(0.06),
                    0.05 + r(0.06),
                );
                // Half the rounds with still colliders.
                let motion = if round % 2 == 0 { 0.05 } else { 0.0 };
                let shift = Vec3A::new(r(motion), r(motion), r(motion));
                let turn = Vec3A::new(r(motion), r(motion), r(motion));
                swept.push(SweptCollider::new(
                    shape(a, b, ra, rb),
                    shape(a + shift, b + shift + turn, ra, rb),
                    0.003,
                ));
            }
            // Each particle near one collider's first sphere; lanes 4 and 5 within a few
            // millimetres of its skin, lanes 6 and 7 on it (cloth resting on the body) and
            // moving 50 µm inwards: resting contacts, decided by the contact tolerance.
            let mut inwards = [Vec3A::ZERO; LANES];
            let start: [Vec3A; LANES] = std::array::from_fn(|l| {
                let c = &swept[l % swept.len()];
                let p = c.start_origin + Vec3A::new(r(0.25), r(0.25), r(0.25));
                if l < 4 {
                    return p;
                }
                let (d, n) = c.end.distance_normal(p - c.end.origin);
                let off = if l < 6 { r(0.004) } else { 0.0 };
                inwards[l] = -5e-5 * n;
                p - (d - 0.003 + off) * n
            });
            // Lanes 0 to 5: half move a few centimetres, half a fraction of a millimetre.
            let now: [Vec3A; LANES] = std::array::from_fn(|l| {
                if l >= 6 {
                    return start[l] + inwards[l];
                }
                let reach = if l % 2 == 0 { 0.06 } else { 0.0005 };
                start[l] + Vec3A::new(r(reach), r(reach), r(reach))
            });
            let near: Vec<u16> = (0..swept.len() as u16).rev().collect();
            for near in [None, Some(&near[..])] {
                let scene = Scene {
                    colliders: &swept,
                    near,
                    planes: None,
                    any_plane: false,
                    shapes: swept.len(),
                };
                let order: Vec<usize> = match near {
                    None => (0..swept.len()).collect(),
                    Some(n) => n.iter().map(|&c| c as usize).collect(),
                };
                let mut expected = now;
                let mut expected_moved = 0u32;
                let mut expected_last = [0u16; LANES];
                for l in 0..LANES {
                    let (low, high) = (start[l].min(now[l]), start[l].max(now[l]));
                    for (place, &c) in order.iter().enumerate() {
                        if swept[c].overlaps(low, high) {
                            let (q, hit) = swept[c].collide(start[l], expected[l], 0.003, 0.4);
                            if hit {
                                expected[l] = q;
                                expected_moved |= 1 << l;
                                expected_last[l] = place as u16;
                            }
                        }
                    }
                }
                // The second pass as the one-particle path makes it (see `collide_particle`):
                // over the colliders before the last mover if the particle stayed within its
                // first path's box, else over all of them; and once one of them has moved it,
                // over all the rest too.
                let mut expected_second = expected;
                let mut expected_again = 0u32;
                for l in (0..LANES).filter(|&l| expected_moved & (1 << l) != 0) {
                    let (low, high) = (start[l].min(now[l]), start[l].max(now[l]));
                    let in_box = expected[l].cmpge(low).all() && expected[l].cmple(high).all();
                    let limit = if in_box {
                        expected_last[l] as usize
                    } else {
                        usize::MAX
                    };
                    let (low, high) = (start[l].min(expected[l]), start[l].max(expected[l]));
                    for (place, &c) in order.iter().enumerate() {
                        if place >= limit && expected_again & (1 << l) == 0 {
                            break;
                        }
                        if swept[c].overlaps(low, high) {
                            let (q, hit) =
                                swept[c].collide(start[l], expected_second[l], 0.003, 0.4);
                            if hit {
                                expected_second[l] = q;
                                expected_again |= 1 << l;
                            }
                        }
                    }
                }
                for isa in [Isa::Baseline, Isa::detect()] {
                    for second in [false, true] {
                        let mut pass = GroupPass {
                            p: [Vec3A::ZERO; LANES],
                            last: [0; LANES],
                        };
                        // SAFETY: eight positions each.
                        let moved = unsafe {
                            collide8(
                                isa,
                                start.as_ptr(),
                                now.as_ptr(),
                                &scene,
                                (0.003, 0.4),
                                (second, true),
                                &mut pass,
                            )
                        };
                        let (want, again) = if second {
                            (expected_second, expected_again)
                        } else {
                            (expected, 0)
                        };
                        assert_eq!(
                            moved,
                            Some((expected_moved, again)),
                            "round {round} {isa:?}"
                        );
                        for l in (0..LANES).filter(|&l| expected_moved & (1 << l) != 0) {
                            assert_eq!(pass.last[l], expected_last[l], "round {round} lane {l}");
                        }
                        hit_lanes += expected_moved.count_ones();
                        missed_lanes += LANES as u32 - expected_moved.count_ones();
                        second_lanes += again.count_ones();
                        for (l, (got, want)) in pass.p.iter().zip(&want).enumerate() {
                            assert_eq!(
                                got.to_array(),
                                want.to_array(),
                                "round {round} lane {l} second {second}"
                            );
                        }
                    }
                }
            }
        }
        // Both outcomes were exercised.
        assert!(
            hit_lanes > 500 && missed_lanes > 500 && second_lanes > 0,
            "{hit_lanes} hit, {missed_lanes} not, {second_lanes} in the second pass"
        );
    }

    #[test]
    fn eight_particles_with_a_nan_are_left_to_the_one_particle_path() {
        let swept = [SweptCollider::new(
            Shape::sphere(Vec3A::ZERO, 0.1),
            Shape::sphere(Vec3A::ZERO, 0.1),
            0.003,
        )];
        let scene = Scene {
            colliders: &swept,
            near: None,
            planes: None,
            any_plane: false,
            shapes: 1,
        };
        let mut now = [Vec3A::splat(0.05); LANES];
        now[5].y = f32::NAN;
        let mut pass = GroupPass {
            p: [Vec3A::ZERO; LANES],
            last: [0; LANES],
        };
        for isa in [Isa::Baseline, Isa::detect()] {
            // SAFETY: eight positions each.
            let moved = unsafe {
                collide8(
                    isa,
                    now.as_ptr(),
                    now.as_ptr(),
                    &scene,
                    (0.003, 0.0),
                    (true, true),
                    &mut pass,
                )
            };
            assert_eq!(moved, None);
        }
    }

    /// The nearest point of the intersection of two balls to `p`, by brute force: the best of
    /// `p` (if inside), its projections onto each sphere (if inside the other) and points of
    /// the circle where the spheres meet.
    fn brute_force(p: Vec3A, a0: Vec3A, r0: f32, a1: Vec3A, r1: f32) -> Vec3A {
        let inside = |q: Vec3A| (q - a0).length() <= r0 + 1e-5 && (q - a1).length() <= r1 + 1e-5;
        let mut candidates = vec![
            p,
            a0 + (p - a0).normalize() * r0,
            a1 + (p - a1).normalize() * r1,
        ];
        let axis = (a1 - a0).normalize();
        let d = (a1 - a0).length();
        let along = (d * d + r0 * r0 - r1 * r1) / (2.0 * d);
        if r0 * r0 >= along * along {
            let radius = (r0 * r0 - along * along).sqrt();
            let u = Vec3A::from(Vec3::from(axis).any_orthonormal_vector());
            let v = axis.cross(u);
            for k in 0..20_000 {
                let angle = k as f32 / 20_000.0 * std::f32::consts::TAU;
                candidates.push(a0 + along * axis + radius * (angle.cos() * u + angle.sin() * v));
            }
        }
        candidates
            .into_iter()
            .filter(|&q| inside(q))
            .min_by(|a, b| (*a - p).length().total_cmp(&(*b - p).length()))
            .expect("the balls intersect")
    }

    /// A point, two balls, and the projection of the point onto their intersection.
    type Case = (Vec3A, Vec3A, f32, Vec3A, f32, Vec3A);

    #[test]
    fn two_tethers_project_onto_the_nearest_point_of_both_balls() {
        let mut seed = 7u32;
        let mut r = || random(&mut seed);
        let mut points = Vec::new();
        for _ in 0..64 {
            let a0 = Vec3A::new(r(), r(), r()) * 0.2;
            let a1 = a0 + Vec3A::new(r() - 0.5, r() - 0.5, r() - 0.5) * 0.1;
            let (r0, r1) = (0.3 + 0.3 * r(), 0.3 + 0.3 * r());
            let p = a0 + Vec3A::new(r() - 0.5, r() - 0.7, r() - 0.5) * 1.6;
            let q = project_on_two_balls(p, a0, r0, a1, r1).expect("intersecting balls");
            let expected = brute_force(p, a0, r0, a1, r1);
            assert!(
                (q - p).length() <= (expected - p).length() + 2e-4,
                "{p}: {q} vs {expected}"
            );
            assert!(
                (q - a0).length() <= r0 * (1.0 + 1e-5) && (q - a1).length() <= r1 * (1.0 + 1e-5)
            );
            points.push((p, a0, r0, a1, r1, q));
        }
        // Eight at a time, in lanes, give the same points.
        for group in points.chunks(LANES) {
            let lanes = |f: &dyn Fn(&Case) -> Vec3A| V3 {
                x: Baseline8::load(&std::array::from_fn(|l| f(&group[l]).x)),
                y: Baseline8::load(&std::array::from_fn(|l| f(&group[l]).y)),
                z: Baseline8::load(&std::array::from_fn(|l| f(&group[l]).z)),
            };
            let scalars =
                |f: &dyn Fn(&Case) -> f32| Baseline8::load(&std::array::from_fn(|l| f(&group[l])));
            let (q, fallback, _) = project_on_two_balls_lanes(
                lanes(&|g| g.0),
                lanes(&|g| g.1),
                scalars(&|g| g.2),
                lanes(&|g| g.3),
                scalars(&|g| g.4),
            );
            assert_eq!(fallback, 0);
            let [x, y, z] = q.to_arrays();
            for (l, g) in group.iter().enumerate() {
                let q = Vec3A::new(x[l], y[l], z[l]);
                assert!((q - g.5).length() < 1e-5, "lane {l}: {q} vs {}", g.5);
            }
        }
    }

    /// A 40 × 30 cylinder from `base` (radius, height), pinned at its top ring, on 2 threads.
    fn skirt_on_two_threads(base: Vec3, radius: f32, height: f32) -> ClothSolver {
        let mesh = ClothMesh::cylinder(base, radius, height, 40, 30).expect("a valid skirt");
        let top: Vec<u32> = ClothMesh::cylinder_ring(40, 30).collect();
        let settings = SolverSettings {
            threads: 2,
            ..SolverSettings::default()
        };
        ClothSolver::new(&mesh, Fabric::cotton(), &top, settings).expect("a valid cloth")
    }

    /// `share_out` runs every item exactly once, on the workers too when they are awake, and
    /// a call from inside an item (the workers are busy with it) runs its items on that
    /// thread alone instead of waiting for itself.
    #[test]
    fn share_out_runs_each_item_once_and_a_nested_call_alone() {
        let mut cloth = skirt_on_two_threads(Vec3::ZERO, 0.3, 0.5);
        let mut on_two = false;
        // Until the worker takes part: a sleeping one is not used, nor any while the steps
        // run on one thread after a stall (a busy machine); steps end that.
        let deadline = std::time::Instant::now() + std::time::Duration::from_secs(30);
        'tries: while std::time::Instant::now() < deadline {
            cloth.step(1.0 / 120.0).expect("a valid step");
            for _ in 0..20 {
                cloth.prewake();
                let runs: Vec<AtomicUsize> = (0..64).map(|_| AtomicUsize::new(0)).collect();
                let (nested_threads, nested_items) = (AtomicUsize::new(0), AtomicUsize::new(0));
                let used = cloth.share_out(runs.len(), &|k| {
                    runs[k].fetch_add(1, Ordering::Relaxed);
                    let inner = cloth.share_out(3, &|_| {
                        nested_items.fetch_add(1, Ordering::Relaxed);
                    });
                    nested_threads.fetch_max(inner, Ordering::Relaxed);
                });
                assert!(runs.iter().all(|r| r.load(Ordering::Relaxed) == 1));
                assert_eq!(nested_items.load(Ordering::Relaxed), 3 * runs.len());
                if used == 2 {
                    // The workers were busy with the outer call, so no inner one used them.
                    assert_eq!(nested_threads.load(Ordering::Relaxed), 1);
                    on_two = true;
                    break 'tries;
                }
                // The outer call ran alone (the worker was still waking up); an inner call
                // may then have found it awake and used it: the items still ran once each.
                assert_eq!(used, 1);
            }
        }
        assert!(on_two, "the worker never took part");
    }

    #[test]
    fn work_hints_are_checked_and_keep_results_independent_of_threads() {
        let mesh = ClothMesh::cylinder(Vec3::ZERO, 0.3, 0.5, 40, 30).expect("a valid skirt");
        let top: Vec<u32> = ClothMesh::cylinder_ring(40, 30).collect();
        let n = mesh.vertex_count();
        let build = |work: &[f32], threads: usize| {
            let settings = SolverSettings {
                threads,
                ..SolverSettings::default()
            };
            ClothSolver::new_balanced(&mesh, Fabric::cotton(), &top, settings, work)
        };
        let err = |work: &[f32]| build(work, 1).err().map(|e| e.to_string());
        assert_eq!(
            err(&vec![1.0; n - 1]),
            Some(format!(
                "expected {n} work hints (one per vertex), got {}",
                n - 1
            ))
        );
        let mut work = vec![1.0; n];
        work[7] = f32::NAN;
        assert!(err(&work).is_some_and(|e| e.contains("work hint of vertex 7")));
        work[7] = -1.0;
        assert!(err(&work).is_some_and(|e| e.contains("0 or more")));
        // The particles on one side (x < 0) three times the work: a different split of the
        // blocks, the same bits on one thread and two.
        let work: Vec<f32> = mesh
            .positions()
            .iter()
            .map(|p| if p.x < 0.0 { 3.0 } else { 1.0 })
            .collect();
        let run = |threads: usize| {
            let mut cloth = build(&work, threads).expect("a valid cloth");
            let ball = [Sphere::new(Vec3::new(0.05, 0.2, 0.0), 0.31)];
            cloth.set_colliders(&ball, &[]).expect("a valid collider");
            for _ in 0..30 {
                cloth.step(1.0 / 120.0).expect("a valid step");
            }
            position_bits(&cloth)
        };
        assert_eq!(run(1), run(2));
        let plain = ClothSolver::new(&mesh, Fabric::cotton(), &top, SolverSettings::default())
            .expect("a valid cloth");
        let hinted = build(&work, 2).expect("a valid cloth");
        assert_ne!(
            plain.model.order.block_start, hinted.model.order.block_start,
            "the hint did not move the split"
        );
    }

    /// The cloth's positions as bits, for comparisons that must be exact.
    fn position_bits(cloth: &ClothSolver) -> Vec<[u32; 3]> {
        cloth
            .positions()
            .iter()
            .map(|p| p.to_array().map(f32::to_bits))
            .collect()
    }

    #[test]
    fn the_baseline_and_avx_kernels_give_the_same_bits() {
        if Isa::detect() != Isa::Avx {
            return;
        }
        let run = |isa: Isa| {
            let mut cloth = skirt_on_two_threads(Vec3::new(0.0, 0.4, 0.0), 0.25, 0.6);
            cloth.isa = isa;
            cloth.set_wind(Some(Wind::new(Vec3::new(1.0, 0.0, 0.5), 1.0, 0.3, 3)));
            let legs = |t: f32| {
                [
                    Sphere::new(Vec3::new(-0.1, 0.95, 0.0), 0.12),
                    Sphere::new(Vec3::new(-0.1, 0.5, 0.3 * t.sin()), 0.07),
                    Sphere::new(Vec3::new(0.0, 1.0, 0.05), 0.15),
                ]
            };
            for step in 0..40 {
                cloth
                    .set_colliders(&legs(step as f32 * 0.1), &[[0, 1]])
                    .expect("valid colliders");
                cloth.step(1.0 / 120.0).expect("a valid step");
            }
            position_bits(&cloth)
        };
        assert_eq!(run(Isa::Baseline), run(Isa::Avx));
    }

    #[test]
    fn new_settings_between_steps_step_as_a_cloth_built_with_them() {
        // The phase program is kept from step to step while substeps, iterations and the
        // aerodynamics stay; changing them must step as a cloth built with the new ones.
        let spheres = [
            Sphere::new(Vec3::new(-0.1, 0.85, 0.0), 0.12),
            Sphere::new(Vec3::new(0.1, 0.85, 0.0), 0.12),
        ];
        let later = SolverSettings {
            threads: 2,
            substeps: 4,
            iterations: 2,
            ..SolverSettings::default()
        };
        let run = |cloth: &mut ClothSolver, steps: usize| {
            for _ in 0..steps {
                cloth.set_colliders(&spheres, &[]).expect("valid colliders");
                cloth.step(1.0 / 120.0).expect("a valid step");
            }
        };
        let mut changed = skirt_on_two_threads(Vec3::ZERO, 0.22, 0.95);
        let rest: Vec<Vec3> = changed.positions().iter().map(|&p| p.into()).collect();
        run(&mut changed, 5);
        changed.set_settings(later).expect("valid settings");
        changed.reset_to(&rest).expect("valid positions");
        run(&mut changed, 20);
        let mut built = skirt_on_two_threads(Vec3::ZERO, 0.22, 0.95);
        built.set_settings(later).expect("valid settings");
        run(&mut built, 20);
        assert_eq!(position_bits(&changed), position_bits(&built));
        // With the old program it would not: 10 substeps, 1 iteration.
        let mut kept = skirt_on_two_threads(Vec3::ZERO, 0.22, 0.95);
        run(&mut kept, 20);
        assert_ne!(position_bits(&kept), position_bits(&built));
    }

    #[test]
    fn grouped_and_one_by_one_collisions_give_the_same_bits() {
        // A skirt tethered to its waist, around overlapping spheres and capsules (hips, swinging
        // thighs, pelvis) and standing on the floor: colliding eight particles together must
        // give the one-particle pass's positions bit for bit, through the later passes, the
        // floor, the crease between overlapping shapes and the tether repairs; and a second
        // pass over only the shapes before the last mover (and all after one that moves it
        // again) the positions of one over all. (With the blocks split at 1/32 instead of
        // 1/8, a pass that stopped at the last mover regardless differed here at step 29.)
        // One thigh is frictionless: both paths take each collider's share of the friction.
        let run_with = |group: bool, colliders: bool, prune: bool, thigh_friction: f32| {
            let mut cloth = skirt_on_two_threads(Vec3::ZERO, 0.22, 0.95);
            cloth.group_collisions = group;
            cloth.prune_passes = prune;
            cloth
                .set_planes(&[Plane::floor(0.0)])
                .expect("a valid floor");
            for step in 0..60 {
                let swing = 0.35 * (step as f32 * 0.15).sin();
                let spheres = [
                    Sphere::new(Vec3::new(-0.1, 0.85, 0.0), 0.12),
                    Sphere::new(Vec3::new(-0.1, 0.45, swing), 0.07),
                    Sphere::new(Vec3::new(0.1, 0.85, 0.0), 0.12).with_friction(thigh_friction),
                    Sphere::new(Vec3::new(0.1, 0.45, -swing), 0.07).with_friction(thigh_friction),
                    Sphere::new(Vec3::new(0.0, 0.95, 0.03), 0.16),
                    // A foot by the hem, which lies on the floor.
                    Sphere::new(Vec3::new(0.2, 0.04, swing), 0.06),
                ];
                if colliders {
                    cloth
                        .set_colliders(&spheres, &[[0, 1], [2, 3]])
                        .expect("valid colliders");
                }
                cloth.step(1.0 / 120.0).expect("a valid step");
            }
            position_bits(&cloth)
        };
        let run =
            |group: bool, colliders: bool, prune: bool| run_with(group, colliders, prune, 0.0);
        let grouped = run(true, true, true);
        assert_eq!(grouped, run(false, true, true));
        // The second pass gives what testing every shape again gives.
        assert_eq!(grouped, run(true, true, false));
        // The colliders did move the cloth, and the frictionless thigh let it slide.
        assert_ne!(grouped, run(true, false, true));
        assert_ne!(grouped, run_with(true, true, true, 1.0));
    }

    #[test]
    fn eight_particles_integrate_as_one_does_in_a_moving_frame() {
        let motion = FrameMotion {
            velocity: Vec3::new(0.3, 0.0, -0.2),
            acceleration: Vec3::new(1.5, -0.4, 2.0),
            angular_velocity: Vec3::new(0.2, 3.0, -0.5),
            angular_acceleration: Vec3::new(-4.0, 12.0, 1.0),
            to_local: glam::Quat::from_rotation_y(0.4),
            pose: RigidPose::IDENTITY,
        };
        let inertia = FrameInertia::FULL;
        let h = 1.0 / 1200.0;
        let k = StepConstants {
            substeps: 10,
            h,
            inv_h: 1.0 / h,
            inv_h2: 1.0 / (h * h),
            bend_alpha: 0.0,
            damping: 0.999,
            gravity: Vec3A::new(0.0, -9.81, 0.0),
            keep_lambda: false,
            aero: false,
            isa: Isa::detect(),
            thickness: 0.003,
            friction: 0.3,
            max_velocity: 5.0,
            frame: Some(FrameTerms {
                linear: Vec3A::from(motion.acceleration * inertia.linear),
                euler: Vec3A::from(motion.angular_acceleration * inertia.angular),
                coriolis: Vec3A::from(2.0 * motion.angular_velocity * inertia.angular),
                omega: Vec3A::from(motion.angular_velocity),
                centrifugal: inertia.centrifugal,
                air_velocity: Vec3A::ZERO,
                air_omega: Vec3A::ZERO,
                motion,
            }),
            colliders: 0,
            group_collisions: true,
            prune_passes: true,
            air_density: 0.0,
            drag: 0.0,
            lift: 0.0,
            time: 0.0,
        };
        let mut seed = 7u32;
        let mut point = |scale: f32| {
            Vec3A::new(random(&mut seed), random(&mut seed), random(&mut seed)) * scale
        };
        let p: Vec<Vec3A> = (0..LANES).map(|_| point(0.5)).collect();
        // One particle moves faster than the cap.
        let moved: Vec<f32> = (0..LANES)
            .map(|l| if l == 3 { 0.02 } else { 0.002 })
            .collect();
        let prev: Vec<Vec3A> = p
            .iter()
            .zip(&moved)
            .map(|(&p, &m)| p - point(1.0).normalize_or_zero() * m)
            .collect();
        let external: Vec<Vec3A> = (0..LANES).map(|_| point(2.0)).collect();
        for isa in [Isa::Baseline, Isa::detect()] {
            let (mut xs, mut xs_prev) = (p.clone(), prev.clone());
            // SAFETY: eight particles in each buffer.
            unsafe {
                integrate_free(
                    isa,
                    [xs.as_mut_ptr(), xs_prev.as_mut_ptr()],
                    external.as_ptr(),
                    &StepConstants { isa, ..k },
                )
            };
            for l in 0..LANES {
                let mut vel = (p[l] - prev[l]) * k.inv_h;
                if vel.length() > k.max_velocity {
                    vel = vel * (k.max_velocity / vel.length());
                }
                let vel = predict_velocity(&k, p[l], vel, external[l]);
                assert!(
                    (xs[l] - (p[l] + vel * h)).length() <= 1e-6,
                    "{l}: {} vs {}",
                    xs[l],
                    p[l] + vel * h
                );
                assert_eq!(xs_prev[l], p[l]);
            }
        }
    }

    #[test]
    fn a_nan_position_stays_nan_through_the_tethers() {
        let (a0, a1) = (Vec3A::ZERO, Vec3A::X * 0.05);
        assert!(project_on_two_balls(Vec3A::NAN, a0, 0.5, a1, 0.5).is_none());
        let nan = V3 {
            x: Baseline8::splat(f32::NAN),
            y: Baseline8::splat(0.0),
            z: Baseline8::splat(0.0),
        };
        let splat = |v: Vec3A| V3 {
            x: Baseline8::splat(v.x),
            y: Baseline8::splat(v.y),
            z: Baseline8::splat(v.z),
        };
        let r = Baseline8::splat(0.5);
        let (_, fallback, _) = project_on_two_balls_lanes(nan, splat(a0), r, splat(a1), r);
        assert_eq!(fallback, 0xFF);
    }
}
