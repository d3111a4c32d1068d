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
//! 4. **constraints**: stretch, shear and isometric bending, colour by colour, each colour's
//!    items in parallel ([`crate::constraints`]);
//! 5. **tethers** (Kim et al. 2012): a particle farther from an attachment than its rest
//!    geodesic distance × `tether_scale` is put back on that sphere;
//! 6. **collision** against the swept colliders and planes, with friction;
//! 7. if a collision pushed a particle beyond its tether, the particle **slides** along the
//!    collider's tangent plane to a point its tethers allow; if there is none, the **tether
//!    wins** and the particle goes to the nearest collider surface (an inextensible garment
//!    slips around a limb instead of being dragged and stretched). This repair is kept out of
//!    the velocity;
//! 8. **velocity** `v = (x − x_prev)/h`.
//!
//! Steps 5–8 and the next substep's step 3 touch one particle at a time and run as one
//! parallel pass. After the last substep a **blow-up guard** looks for non-finite positions or
//! velocities, speeds above [`BlowUpGuard::max_speed_m_s`] and constraints stretched beyond
//! [`BlowUpGuard::max_stretch_ratio`], and reports it in the [`StepReport`]; the caller should
//! then [`ClothSolver::reset_to`] the skinned pose.
//!
//! # Determinism and threads
//!
//! All work is split into items that do not depend on the thread count ([`crate::pool`]), so
//! a step gives bit-for-bit the same result on 1, 2 or 4 threads. No memory is allocated
//! during a step (the buffers grow only when the collider count or the substep count grows).

use glam::{Vec3, Vec3A};

use crate::collision::{MAX_COLLIDERS, Plane, Shape, Sphere, SweptCollider, collide_plane};
use crate::constraints::{ConstraintSet, solve_bend, solve_distance};
use crate::error::{ClothError, non_negative, positive};
use crate::fabric::Fabric;
use crate::frame::{FrameInertia, FrameMotion, FrameState, RigidPose};
use crate::mesh::{ClothMesh, MeshTopology};
use crate::pool::{PhaseCounters, SharedSlice, WorkerPool};
use crate::wind::{Wind, triangle_force};

/// Particles per work item (also the chunk whose bounds select collider candidates).
const PARTICLE_ITEM: usize = 64;
/// Triangles per aerodynamics work item.
const TRIANGLE_ITEM: usize = 512;
/// Alternations between the tethers of one particle.
const TETHER_ROUNDS: usize = 6;
/// Alternations between tethers and collider push-out when they conflict.
const RECONCILE_ROUNDS: usize = 8;
/// Distance constraints per stretch-check work item.
const STRETCH_ITEM: usize = 2048;

/// Thresholds of the blow-up guard.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BlowUpGuard {
    /// A particle faster than this (m/s) counts as a blow-up.
    pub max_speed_m_s: f32,
    /// A stretch or shear constraint longer than this multiple of its rest length counts as a
    /// blow-up.
    pub max_stretch_ratio: f32,
}

impl Default for BlowUpGuard {
    fn default() -> Self {
        Self {
            max_speed_m_s: 100.0,
            max_stretch_ratio: 4.0,
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
struct Model {
    inverse_mass: Vec<f32>,
    mass: Vec<f32>,
    triangles: Vec<[u32; 3]>,
    vertex_triangles_start: Vec<u32>,
    vertex_triangles: Vec<u32>,
    constraints: ConstraintSet,
    tether_start: Vec<u32>,
    tether_slot: Vec<u32>,
    tether_rest: Vec<f32>,
    tether_limit: Vec<f32>,
    attached: Vec<u32>,
    attach_slot: Vec<u32>,
    fabric: Fabric,
    settings: SolverSettings,
}

#[derive(Debug, Clone, Copy, Default)]
struct ItemHealth {
    max_speed2: f32,
    fastest: u32,
    first_non_finite: u32,
}

#[derive(Debug, Clone, Copy)]
enum Phase {
    AeroTriangles,
    AeroVertices,
    /// Finish substep `sub - 1` (if `sub > 0`) and predict substep `sub` (if `sub < n`).
    Particles {
        sub: u32,
    },
    Colour {
        colour: u32,
        first: bool,
    },
    Stretch,
}

/// Constants of one step.
#[derive(Debug, Clone, Copy)]
struct StepConstants {
    substeps: u32,
    h: f32,
    inv_h: f32,
    inv_h2: f32,
    damping: f32,
    gravity: Vec3A,
    keep_lambda: bool,
    thickness: f32,
    friction: f32,
    max_velocity: f32,
    frame: Option<FrameTerms>,
    colliders: usize,
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
    x: Vec<Vec3A>,
    x_prev: Vec<Vec3A>,
    v: Vec<Vec3A>,
    external: Vec<Vec3A>,
    external_dirty: bool,
    triangle_force: Vec<Vec3A>,
    distance_lambda: Vec<f32>,
    bend_lambda: Vec<Vec3A>,
    target_start: Vec<Vec3A>,
    target_end: Vec<Vec3A>,
    spheres_start: Vec<Sphere>,
    spheres_end: Vec<Sphere>,
    capsules: Vec<[u32; 2]>,
    solo_spheres: Vec<u32>,
    planes: Vec<Plane>,
    swept: Vec<SweptCollider>,
    frame: FrameState,
    wind: Option<Wind>,
    time: f64,
    pool: WorkerPool,
    counters: PhaseCounters,
    phases: Vec<Phase>,
    phase_items: Vec<u32>,
    particle_health: Vec<ItemHealth>,
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
        fabric.validate()?;
        settings.validate()?;
        let n = mesh.vertex_count();
        let mut attach_slot = vec![u32::MAX; n];
        for (index, &vertex) in attached.iter().enumerate() {
            let slot =
                attach_slot
                    .get_mut(vertex as usize)
                    .ok_or(ClothError::AttachmentOutOfRange {
                        index,
                        vertex,
                        vertex_count: n,
                    })?;
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
        let inverse_mass: Vec<f32> = mass
            .iter()
            .zip(&attach_slot)
            .map(|(&m, &slot)| {
                if slot != u32::MAX || m <= 0.0 {
                    0.0
                } else {
                    1.0 / m
                }
            })
            .collect();
        let topology = MeshTopology::new(mesh);
        let constraints = ConstraintSet::build(mesh.positions(), &topology, &fabric, &inverse_mass);
        let tethers = topology.tethers(n, attached, settings.tethers_per_particle);
        let mut tether_start = vec![0u32; n + 1];
        for t in &tethers {
            tether_start[t.vertex as usize + 1] += 1;
        }
        for i in 0..n {
            tether_start[i + 1] += tether_start[i];
        }
        // `tethers` is sorted by vertex.
        let tether_slot: Vec<u32> = tethers
            .iter()
            .map(|t| attach_slot[t.anchor as usize])
            .collect();
        let tether_rest: Vec<f32> = tethers.iter().map(|t| t.rest_length).collect();
        let tether_limit = tether_rest
            .iter()
            .map(|r| r * settings.tether_scale)
            .collect();

        let triangles = mesh.triangles().to_vec();
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

        let x: Vec<Vec3A> = mesh.positions().iter().map(|&p| p.into()).collect();
        let targets: Vec<Vec3A> = attached.iter().map(|&v| x[v as usize]).collect();
        let particle_items = n.div_ceil(PARTICLE_ITEM);
        let stretch_items = constraints.distance.len().div_ceil(STRETCH_ITEM);
        let distance_count = constraints.distance.len();
        let bend_count = constraints.bend.len();
        let keep_lambda = settings.iterations > 1;
        Ok(Self {
            model: Model {
                inverse_mass,
                mass,
                triangles,
                vertex_triangles_start,
                vertex_triangles,
                constraints,
                tether_start,
                tether_slot,
                tether_rest,
                tether_limit,
                attached: attached.to_vec(),
                attach_slot,
                fabric,
                settings,
            },
            x_prev: x.clone(),
            v: vec![Vec3A::ZERO; n],
            external: vec![Vec3A::ZERO; n],
            external_dirty: false,
            triangle_force: vec![Vec3A::ZERO; mesh.triangles().len()],
            distance_lambda: vec![0.0; if keep_lambda { distance_count } else { 0 }],
            bend_lambda: vec![Vec3A::ZERO; if keep_lambda { bend_count } else { 0 }],
            x,
            target_start: targets.clone(),
            target_end: targets,
            spheres_start: Vec::new(),
            spheres_end: Vec::new(),
            capsules: Vec::new(),
            solo_spheres: Vec::new(),
            planes: Vec::new(),
            swept: Vec::new(),
            frame: FrameState::default(),
            wind: None,
            time: 0.0,
            pool: WorkerPool::new(settings.threads),
            counters: PhaseCounters::new(),
            phases: Vec::new(),
            phase_items: Vec::new(),
            particle_health: vec![ItemHealth::default(); particle_items],
            stretch_health: vec![(0.0, 0); stretch_items],
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
                .resize(self.model.constraints.distance.len(), 0.0);
            self.bend_lambda
                .resize(self.model.constraints.bend.len(), Vec3A::ZERO);
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

    /// Particle positions (simulation frame, metres).
    pub fn positions(&self) -> &[Vec3A] {
        &self.x
    }

    /// Writable particle positions, e.g. for a designer dragging a vertex. Velocities are
    /// unchanged; the edit takes effect at the next step.
    pub fn positions_mut(&mut self) -> &mut [Vec3A] {
        &mut self.x
    }

    /// Particle velocities, m/s.
    pub fn velocities(&self) -> &[Vec3A] {
        &self.v
    }

    /// Particle masses, kg (attached particles keep their mass here; their inverse mass is 0).
    pub fn masses(&self) -> &[f32] {
        &self.model.mass
    }

    /// Inverse masses, 1/kg (0 for attached particles).
    pub fn inverse_masses(&self) -> &[f32] {
        &self.model.inverse_mass
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
            self.model.constraints.distance.len(),
            self.model.constraints.bend.len(),
        )
    }

    /// Number of parallel colours, and whether there is a sequential tail batch.
    pub fn colour_count(&self) -> (usize, bool) {
        (
            self.model.constraints.parallel_colours(),
            self.model.constraints.has_tail,
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
            if !s.center.is_finite() || !s.radius.is_finite() || s.radius < 0.0 {
                return Err(ClothError::NonFiniteInput {
                    what: "collision sphere (finite centre, finite radius >= 0)",
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
        for ((x, xp), &p) in self.x.iter_mut().zip(&mut self.x_prev).zip(positions) {
            *x = p.into();
            *xp = p.into();
        }
        self.v.fill(Vec3A::ZERO);
        self.external.fill(Vec3A::ZERO);
        self.distance_lambda.fill(0.0);
        self.bend_lambda.fill(Vec3A::ZERO);
        for (slot, &vertex) in self.model.attached.iter().enumerate() {
            self.target_start[slot] = self.x[vertex as usize];
            self.target_end[slot] = self.x[vertex as usize];
        }
        self.teleport_colliders();
        Ok(())
    }

    /// Largest current length / rest length over the stretch constraints (not shear).
    pub fn max_stretch_ratio(&self) -> f32 {
        let c = &self.model.constraints;
        c.distance
            .iter()
            .zip(&c.distance_is_shear)
            .filter(|(_, shear)| !**shear)
            .map(|(d, _)| (self.x[d.i as usize] - self.x[d.j as usize]).length() / d.rest)
            .fold(0.0, f32::max)
    }

    /// Largest current distance / rest geodesic distance over the tethers (1.0 means a tether
    /// is exactly taut at its rest length).
    pub fn max_tether_ratio(&self) -> f32 {
        let m = &self.model;
        let mut worst = 0.0f32;
        for i in 0..self.x.len() {
            for k in m.tether_start[i] as usize..m.tether_start[i + 1] as usize {
                let anchor = m.attached[m.tether_slot[k] as usize] as usize;
                let ratio = (self.x[i] - self.x[anchor]).length() / m.tether_rest[k];
                worst = worst.max(ratio);
            }
        }
        worst
    }

    /// Kinetic energy of the free particles, J.
    pub fn kinetic_energy(&self) -> f64 {
        self.v
            .iter()
            .zip(&self.model.mass)
            .zip(&self.model.inverse_mass)
            .filter(|(_, w)| **w > 0.0)
            .map(|((v, m), _)| 0.5 * *m as f64 * v.length_squared() as f64)
            .sum()
    }

    /// Advances the simulation by `dt` seconds and reports the blow-up guard's verdict.
    pub fn step(&mut self, dt: f32) -> Result<StepReport, ClothError> {
        positive("time step (s)", dt)?;
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
        let constants = StepConstants {
            substeps,
            h,
            inv_h: 1.0 / h,
            inv_h2: 1.0 / (h * h),
            damping: (-fabric.damping_per_s * h).exp(),
            gravity: Vec3A::from(to_local * settings.gravity),
            keep_lambda: settings.iterations > 1,
            thickness: settings.collision_thickness,
            friction: fabric.friction,
            max_velocity: settings.max_velocity_m_s.unwrap_or(f32::INFINITY),
            frame,
            colliders: self.capsules.len() + self.solo_spheres.len(),
            air_density: settings.air_density_kg_m3,
            drag: fabric.drag_coefficient,
            lift: fabric.lift_coefficient,
            time: self.time as f32,
        };
        self.prepare_colliders(substeps, settings.collision_thickness);
        if !aero && self.external_dirty {
            self.external.fill(Vec3A::ZERO);
            self.external_dirty = false;
        }

        // The phase program of this step.
        let n = self.x.len();
        let particle_items = n.div_ceil(PARTICLE_ITEM) as u32;
        self.phases.clear();
        self.phase_items.clear();
        let push = |phase: Phase, items: u32, phases: &mut Vec<Phase>, counts: &mut Vec<u32>| {
            phases.push(phase);
            counts.push(items);
        };
        if aero {
            self.external_dirty = true;
            let tris = self.model.triangles.len().div_ceil(TRIANGLE_ITEM) as u32;
            push(
                Phase::AeroTriangles,
                tris,
                &mut self.phases,
                &mut self.phase_items,
            );
            push(
                Phase::AeroVertices,
                particle_items,
                &mut self.phases,
                &mut self.phase_items,
            );
        }
        push(
            Phase::Particles { sub: 0 },
            particle_items,
            &mut self.phases,
            &mut self.phase_items,
        );
        for sub in 0..substeps {
            for iteration in 0..settings.iterations {
                for (colour, &(a, b)) in self.model.constraints.colours.iter().enumerate() {
                    push(
                        Phase::Colour {
                            colour: colour as u32,
                            first: iteration == 0,
                        },
                        b - a,
                        &mut self.phases,
                        &mut self.phase_items,
                    );
                }
            }
            push(
                Phase::Particles { sub: sub + 1 },
                particle_items,
                &mut self.phases,
                &mut self.phase_items,
            );
        }
        push(
            Phase::Stretch,
            self.stretch_health.len() as u32,
            &mut self.phases,
            &mut self.phase_items,
        );

        self.counters.reset(self.phases.len());
        {
            let context = StepContext {
                model: &self.model,
                k: constants,
                phases: &self.phases,
                swept: &self.swept,
                planes: &self.planes,
                target_start: &self.target_start,
                target_end: &self.target_end,
                wind: self.wind.as_ref(),
                x: SharedSlice::new(&mut self.x),
                x_prev: SharedSlice::new(&mut self.x_prev),
                v: SharedSlice::new(&mut self.v),
                external: SharedSlice::new(&mut self.external),
                triangle_force: SharedSlice::new(&mut self.triangle_force),
                distance_lambda: SharedSlice::new(&mut self.distance_lambda),
                bend_lambda: SharedSlice::new(&mut self.bend_lambda),
                particle_health: SharedSlice::new(&mut self.particle_health),
                stretch_health: SharedSlice::new(&mut self.stretch_health),
            };
            let counters = &self.counters;
            let items = &self.phase_items;
            let exec = |p: usize, k: u32| context.exec(p, k);
            self.pool.run(&|| counters.run_phases(items, &exec));
        }

        self.target_start.clone_from(&self.target_end);
        self.spheres_start.clone_from(&self.spheres_end);
        self.time += dt as f64;
        Ok(self.report())
    }

    fn report(&self) -> StepReport {
        let mut max_speed2 = 0.0f32;
        let mut fastest = 0u32;
        let mut non_finite = u32::MAX;
        for h in &self.particle_health {
            non_finite = non_finite.min(h.first_non_finite);
            if h.max_speed2 > max_speed2 {
                max_speed2 = h.max_speed2;
                fastest = h.fastest;
            }
        }
        let mut max_ratio = 0.0f32;
        let mut worst = u32::MAX;
        for &(ratio, index) in &self.stretch_health {
            if ratio.is_nan() || ratio > max_ratio {
                max_ratio = ratio;
                worst = index;
            }
        }
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
            let c = self.model.constraints.distance[worst as usize];
            Health::BlownUp(BlowUp::Stretch {
                vertices: [c.i, c.j],
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

    /// Interpolates every collider to every substep boundary.
    fn prepare_colliders(&mut self, substeps: u32, thickness: f32) {
        let count = self.capsules.len() + self.solo_spheres.len();
        self.swept.clear();
        if count == 0 {
            return;
        }
        let (start, end) = (&self.spheres_start, &self.spheres_end);
        let sphere_at = |s: u32, t: f32| -> (Vec3A, f32) {
            let (a, b) = (start[s as usize], end[s as usize]);
            (
                Vec3A::from(a.center.lerp(b.center, t)),
                a.radius + (b.radius - a.radius) * t,
            )
        };
        let shape_at = |collider: usize, t: f32| -> Shape {
            if let Some(&[i, j]) = self.capsules.get(collider) {
                let (a, ra) = sphere_at(i, t);
                let (b, rb) = sphere_at(j, t);
                Shape::round_cone(a, b, ra, rb)
            } else {
                let (c, r) = sphere_at(self.solo_spheres[collider - self.capsules.len()], t);
                Shape::sphere(c, r)
            }
        };
        for sub in 0..substeps {
            let t0 = sub as f32 / substeps as f32;
            let t1 = (sub + 1) as f32 / substeps as f32;
            for collider in 0..count {
                self.swept.push(SweptCollider::new(
                    shape_at(collider, t0),
                    shape_at(collider, t1),
                    thickness,
                ));
            }
        }
    }
}

/// Everything one step's items read and write.
struct StepContext<'a> {
    model: &'a Model,
    k: StepConstants,
    phases: &'a [Phase],
    swept: &'a [SweptCollider],
    planes: &'a [Plane],
    target_start: &'a [Vec3A],
    target_end: &'a [Vec3A],
    wind: Option<&'a Wind>,
    x: SharedSlice<'a, Vec3A>,
    x_prev: SharedSlice<'a, Vec3A>,
    v: SharedSlice<'a, Vec3A>,
    external: SharedSlice<'a, Vec3A>,
    triangle_force: SharedSlice<'a, Vec3A>,
    distance_lambda: SharedSlice<'a, f32>,
    bend_lambda: SharedSlice<'a, Vec3A>,
    particle_health: SharedSlice<'a, ItemHealth>,
    stretch_health: SharedSlice<'a, (f32, u32)>,
}

impl StepContext<'_> {
    fn exec(&self, phase: usize, item: u32) {
        match self.phases[phase] {
            Phase::AeroTriangles => self.aero_triangles(item as usize),
            Phase::AeroVertices => self.aero_vertices(item as usize),
            Phase::Particles { sub } => self.particles(sub, item as usize),
            Phase::Colour { colour, first } => {
                let c = &self.model.constraints;
                let (a, _) = c.colours[colour as usize];
                let work = c.items[(a + item) as usize];
                solve_distance(
                    &c.distance,
                    &self.distance_lambda,
                    &self.x,
                    work.distance,
                    self.k.inv_h2,
                    self.k.keep_lambda,
                    first,
                );
                solve_bend(
                    &c.bend,
                    &self.bend_lambda,
                    &self.x,
                    work.bend,
                    self.k.inv_h2,
                    self.k.keep_lambda,
                    first,
                );
            }
            Phase::Stretch => self.stretch(item as usize),
        }
    }

    fn particle_range(&self, item: usize) -> std::ops::Range<usize> {
        let lo = item * PARTICLE_ITEM;
        lo..(lo + PARTICLE_ITEM).min(self.x.len())
    }

    fn aero_triangles(&self, item: usize) {
        let tris = &self.model.triangles;
        let lo = item * TRIANGLE_ITEM;
        let hi = (lo + TRIANGLE_ITEM).min(tris.len());
        let k = &self.k;
        for (t, tri) in tris.iter().enumerate().take(hi).skip(lo) {
            // SAFETY: positions and velocities are only read in this phase; triangle `t`'s
            // force slot belongs to this item.
            unsafe {
                let p = tri.map(|v| self.x.get(v as usize));
                let vel = (self.v.get(tri[0] as usize)
                    + self.v.get(tri[1] as usize)
                    + self.v.get(tri[2] as usize))
                    / 3.0;
                let centroid = (p[0] + p[1] + p[2]) / 3.0;
                let mut relative = vel;
                let mut wind_world_point = Vec3::from(centroid);
                let mut to_local = glam::Quat::IDENTITY;
                if let Some(f) = &k.frame {
                    relative += f.air_velocity + f.air_omega.cross(centroid);
                    wind_world_point = f.motion.pose.transform_point(wind_world_point);
                    to_local = f.motion.to_local;
                }
                if let Some(wind) = self.wind {
                    relative -= Vec3A::from(to_local * wind.velocity(wind_world_point, k.time));
                }
                self.triangle_force.set(
                    t,
                    triangle_force(p, relative, k.air_density, k.drag, k.lift),
                );
            }
        }
    }

    fn aero_vertices(&self, item: usize) {
        let m = self.model;
        for i in self.particle_range(item) {
            let w = m.inverse_mass[i];
            let mut sum = Vec3A::ZERO;
            if w > 0.0 {
                for &t in &m.vertex_triangles
                    [m.vertex_triangles_start[i] as usize..m.vertex_triangles_start[i + 1] as usize]
                {
                    // SAFETY: triangle forces are only read in this phase.
                    sum += unsafe { self.triangle_force.get(t as usize) };
                }
            }
            // SAFETY: particle `i` belongs to this item.
            unsafe { self.external.set(i, sum * (w / 3.0)) };
        }
    }

    fn particles(&self, sub: u32, item: usize) {
        let range = self.particle_range(item);
        if sub > 0 {
            self.finish_substep(sub - 1, range.clone());
        }
        if sub < self.k.substeps {
            self.predict(sub, range);
        } else {
            self.health(item, range);
        }
    }

    #[inline]
    fn anchor(&self, slot: u32, t: f32) -> Vec3A {
        self.target_start[slot as usize].lerp(self.target_end[slot as usize], t)
    }

    #[inline]
    fn apply_tethers(&self, i: usize, mut p: Vec3A, t: f32) -> Vec3A {
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
                let a = self.anchor(m.tether_slot[k], t);
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
    fn tether_violated(&self, i: usize, p: Vec3A, t: f32) -> bool {
        let m = self.model;
        (m.tether_start[i] as usize..m.tether_start[i + 1] as usize).any(|k| {
            let limit = m.tether_limit[k] * (1.0 + 1e-3);
            (p - self.anchor(m.tether_slot[k], t)).length_squared() > limit * limit
        })
    }

    fn predict(&self, sub: u32, range: std::ops::Range<usize>) {
        let k = &self.k;
        let m = self.model;
        let t1 = (sub + 1) as f32 / k.substeps as f32;
        for i in range {
            // SAFETY: particle `i` belongs to this item; nothing else touches it in this phase.
            unsafe {
                let p = self.x.get(i);
                if m.inverse_mass[i] == 0.0 {
                    let target = self.anchor(m.attach_slot[i], t1);
                    self.x_prev.set(i, p);
                    self.x.set(i, target);
                    self.v.set(i, (target - p) * k.inv_h);
                    continue;
                }
                let mut vel = self.v.get(i);
                let mut a = k.gravity + self.external.get(i);
                if let Some(f) = &k.frame {
                    a -= f.linear + f.euler.cross(p) + f.coriolis.cross(vel);
                    a -= f.centrifugal * f.omega.cross(f.omega.cross(p));
                }
                vel = (vel + a * k.h) * k.damping;
                self.x_prev.set(i, p);
                self.x.set(i, p + vel * k.h);
            }
        }
    }

    fn finish_substep(&self, sub: u32, range: std::ops::Range<usize>) {
        let k = &self.k;
        let m = self.model;
        let t1 = (sub + 1) as f32 / k.substeps as f32;
        let colliders = &self.swept[sub as usize * k.colliders..(sub as usize + 1) * k.colliders];
        let mut low = Vec3A::splat(f32::INFINITY);
        let mut high = Vec3A::splat(f32::NEG_INFINITY);
        // SAFETY (whole function): particles of `range` belong to this item; attachment
        // targets and colliders are read-only.
        for i in range.clone() {
            if m.inverse_mass[i] == 0.0 {
                continue;
            }
            unsafe {
                let p = self.apply_tethers(i, self.x.get(i), t1);
                self.x.set(i, p);
                let q = self.x_prev.get(i);
                low = low.min(p).min(q);
                high = high.max(p).max(q);
            }
        }
        let mut candidates = [0u16; MAX_COLLIDERS];
        let mut count = 0usize;
        if low.cmple(high).all() {
            for (c, collider) in colliders.iter().enumerate() {
                if collider.overlaps(low, high) {
                    candidates[count] = c as u16;
                    count += 1;
                }
            }
        }
        let candidates = &candidates[..count];
        let shapes = count + self.planes.len();
        if shapes > 0 {
            for i in range.clone() {
                if m.inverse_mass[i] == 0.0 {
                    continue;
                }
                unsafe {
                    let start = self.x_prev.get(i);
                    let mut p = self.x.get(i);
                    let mut touched = false;
                    for _pass in 0..3 {
                        let mut moved = false;
                        let (seg_low, seg_high) = (start.min(p), start.max(p));
                        for &c in candidates {
                            let collider = &colliders[c as usize];
                            if !collider.overlaps(seg_low, seg_high) {
                                continue;
                            }
                            let (q, hit) = collider.collide(start, p, k.thickness, k.friction);
                            if hit {
                                p = q;
                                moved = true;
                            }
                        }
                        for plane in self.planes {
                            let q = collide_plane(plane, start, p, k.thickness, k.friction);
                            if q != p {
                                p = q;
                                moved = true;
                            }
                        }
                        touched |= moved;
                        if !moved || shapes < 2 {
                            break;
                        }
                    }
                    if touched && self.tether_violated(i, p, t1) {
                        p = self.reconcile(i, start, p, t1, colliders);
                    }
                    self.x.set(i, p);
                }
            }
        }
        for i in range {
            if m.inverse_mass[i] == 0.0 {
                continue;
            }
            unsafe {
                let mut vel = (self.x.get(i) - self.x_prev.get(i)) * k.inv_h;
                let speed2 = vel.length_squared();
                if speed2 > k.max_velocity * k.max_velocity {
                    vel *= k.max_velocity / speed2.sqrt();
                }
                self.v.set(i, vel);
            }
        }
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
        t1: f32,
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
                p = self.apply_tethers(i, p, t1);
                let s = n.dot(p) - offset;
                if s >= 0.0 {
                    slid = true;
                    break;
                }
                p -= s * n;
            }
            slid |= !self.tether_violated(i, p, t1);
        }
        if !slid {
            p = self.apply_tethers(i, collided, t1);
        }
        // Out of every collider (a slid particle is at most a rounding error inside).
        for _round in 0..2 {
            let mut pushed = false;
            for collider in colliders {
                if collider.contains_point(p) {
                    let (q, hit) = collider.push_out(p, k.thickness);
                    p = q;
                    pushed |= hit;
                }
            }
            for plane in self.planes {
                let q = collide_plane(plane, p, p, k.thickness, 0.0);
                pushed |= q != p;
                p = q;
            }
            if !pushed {
                break;
            }
        }
        // SAFETY: particle `i` belongs to the calling item.
        unsafe { self.x_prev.set(i, start + (p - collided)) };
        p
    }

    fn health(&self, item: usize, range: std::ops::Range<usize>) {
        let mut h = ItemHealth {
            max_speed2: 0.0,
            fastest: 0,
            first_non_finite: u32::MAX,
        };
        for i in range {
            // SAFETY: particle `i` belongs to this item.
            let (p, vel) = unsafe { (self.x.get(i), self.v.get(i)) };
            if !p.is_finite() || !vel.is_finite() {
                h.first_non_finite = h.first_non_finite.min(i as u32);
                continue;
            }
            let s2 = vel.length_squared();
            if s2 > h.max_speed2 {
                h.max_speed2 = s2;
                h.fastest = i as u32;
            }
        }
        // SAFETY: slot `item` belongs to this item.
        unsafe { self.particle_health.set(item, h) };
    }

    fn stretch(&self, item: usize) {
        let d = &self.model.constraints.distance;
        let lo = item * STRETCH_ITEM;
        let hi = (lo + STRETCH_ITEM).min(d.len());
        let mut worst = (0.0f32, u32::MAX);
        for (k, c) in d.iter().enumerate().take(hi).skip(lo) {
            // SAFETY: positions are only read in this phase.
            let (a, b) = unsafe { (self.x.get(c.i as usize), self.x.get(c.j as usize)) };
            let ratio = (a - b).length() / c.rest;
            if ratio.is_nan() || ratio > worst.0 {
                worst = (ratio, k as u32);
                if ratio.is_nan() {
                    break;
                }
            }
        }
        // SAFETY: slot `item` belongs to this item.
        unsafe { self.stretch_health.set(item, worst) };
    }
}
