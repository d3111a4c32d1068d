//! A cloth's static data ([`Model`]): masses, constraints, tethers, attachments and
//! triangles in the solver's particle order ([`crate::order`]), and how [`ClothSolver`] is
//! built from a mesh, a fabric and its attachments.

use std::sync::atomic::AtomicBool;

use glam::Vec3A;

use super::program::{PARTICLE_GROUPS, SeparatorReach};
use super::report::ItemHealth;
use super::{ClothSolver, SolverSettings};
use crate::constraints::{BendTarget, ConstraintSet};
use crate::error::ClothError;
use crate::fabric::Fabric;
use crate::frame::FrameState;
use crate::mesh::{ClothMesh, MeshTopology};
use crate::order::ParticleOrder;
use crate::pool::{PhaseCounters, WorkerPool};
use crate::simd::{Isa, LANES};

/// Static data of a cloth: masses, constraints, tethers, attachments.
///
/// Per-particle arrays are in the solver's order ([`ParticleOrder`]) unless they say mesh.
pub(super) struct Model {
    pub(super) order: ParticleOrder,
    /// Mesh order (for the API).
    pub(super) inverse_mass_mesh: Vec<f32>,
    /// Mesh order (for the API).
    pub(super) mass_mesh: Vec<f32>,
    pub(super) inverse_mass: Vec<f32>,
    /// Triangles (solver numbering).
    pub(super) triangles: Vec<[u32; 3]>,
    /// Triangles around each particle.
    pub(super) vertex_triangles_start: Vec<u32>,
    pub(super) vertex_triangles: Vec<u32>,
    /// Per particle: its first eight triangles, padded with `triangles.len()` (a slot of the
    /// triangle forces that stays zero), so that [`StepContext::load`] adds a fixed eight
    /// without a data-dependent loop; more than eight (rare) are added one by one.
    pub(super) vertex_triangles8: Vec<[u32; LANES]>,
    pub(super) constraints: ConstraintSet,
    pub(super) tether_start: Vec<u32>,
    pub(super) tether_slot: Vec<u32>,
    pub(super) tether_rest: Vec<f32>,
    pub(super) tether_limit: Vec<f32>,
    /// Attached mesh vertices, in the order of the targets.
    pub(super) attached: Vec<u32>,
    pub(super) attach_slot: Vec<u32>,
    /// Per particle `i`: which eight-particle paths the particles `i..i + 8` may take
    /// ([`EIGHT_FREE`], [`EIGHT_ATTACHED`], [`EIGHT_TWO_TETHERS`]); none where fewer than
    /// eight particles are left. Checked once here, not every substep.
    pub(super) eight: Vec<u8>,
    pub(super) fabric: Fabric,
    pub(super) settings: SolverSettings,
    pub(super) reach: SeparatorReach,
}

/// [`Model::eight`]: all eight particles are free.
pub(super) const EIGHT_FREE: u8 = 1;
/// [`Model::eight`]: all eight particles are attached.
pub(super) const EIGHT_ATTACHED: u8 = 2;
/// [`Model::eight`]: all eight particles have exactly two tethers.
pub(super) const EIGHT_TWO_TETHERS: u8 = 4;

/// [`Model::eight`] from the solver-ordered inverse masses and tether lists.
pub(super) fn eight_flags(inverse_mass: &[f32], tether_start: &[u32]) -> Vec<u8> {
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
    pub(super) fn eight_at(&self, i: usize, end: usize) -> u8 {
        if i + LANES <= end { self.eight[i] } else { 0 }
    }
}

impl ClothSolver {
    pub(super) fn build(
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
}
