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

mod aero;
mod contact;
mod integrate;
mod model;
mod program;
mod report;
mod settings;
mod step;
mod sweep;
mod tethers;

use std::sync::atomic::{AtomicBool, Ordering};

use glam::{Vec3, Vec3A};

use crate::collision::{MAX_COLLIDERS, Plane, Sphere, SweptCollider};
use crate::constraints::BendTarget;
use crate::error::ClothError;
use crate::fabric::Fabric;
use crate::frame::{FrameState, RigidTransform};
use crate::mesh::ClothMesh;
use crate::pool::{PhaseCounters, WorkerPool};
use crate::simd::{Isa, LANES};
use crate::wind::Wind;

use model::Model;
use program::Phase;
use report::ItemHealth;
use step::share_out;
use sweep::ColliderBounds;

pub use report::{BlowUp, Health, StepReport};
pub use settings::{BlowUpGuard, SolverSettings};

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
    pub fn set_body_frame(&mut self, pose: RigidTransform) -> Result<(), ClothError> {
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
    pub fn reset_body_frame(&mut self, pose: RigidTransform) -> Result<(), ClothError> {
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
}

#[cfg(test)]
mod tests;
