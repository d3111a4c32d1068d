//! One step ([`ClothSolver::step`]): its constants, the context its work items share, how
//! the items run on the worker threads (or on the caller's alone after a stall), and the
//! items' dispatch, including the XPBD constraint projection (Macklin, Müller and Chentanez
//! 2016, "XPBD: position-based simulation of compliant constrained dynamics").

use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};

use glam::Vec3A;

use super::model::Model;
use super::program::Phase;
use super::report::ItemHealth;
use super::sweep::{Bodies, ColliderBounds};
use super::{ClothSolver, StepReport};
use crate::collision::{Plane, SweptCollider};
use crate::constraints::{BendFrame, BendTarget, RunKind, solve_bend, solve_distance};
use crate::error::{ClothError, positive};
use crate::frame::FrameMotion;
use crate::pool::{SharedSlice, WorkerPool};
use crate::simd::{Isa, LANES};
use crate::wind::Wind;

/// A parallel step in which a thread waited longer than this at once for another's work item
/// (they take microseconds) was slowed down by the operating system descheduling a thread.
pub(super) const STALL_MIN_NS: u64 = 1_000_000;
/// Steps then run on the caller's thread alone before threads are tried again (half a second
/// at 120 Hz).
pub(super) const SOLO_STEPS: u32 = 60;

/// Constants of one step.
#[derive(Debug, Clone, Copy)]
pub(super) struct StepConstants {
    pub(super) substeps: u32,
    pub(super) h: f32,
    pub(super) inv_h: f32,
    pub(super) inv_h2: f32,
    /// Bending compliance over h².
    pub(super) bend_alpha: f32,
    pub(super) damping: f32,
    pub(super) gravity: Vec3A,
    pub(super) keep_lambda: bool,
    pub(super) aero: bool,
    /// The constraint kernels' instruction set.
    pub(super) isa: Isa,
    pub(super) thickness: f32,
    pub(super) friction: f32,
    pub(super) max_velocity: f32,
    pub(super) frame: Option<FrameTerms>,
    pub(super) colliders: usize,
    /// Whether eight particles at a time are collided together (always, except in the test
    /// that compares the two paths).
    #[cfg(test)]
    pub(super) group_collisions: bool,
    /// Whether the second collision pass tests only the shapes before the last mover (always,
    /// except in the test that compares it with testing every shape).
    #[cfg(test)]
    pub(super) prune_passes: bool,
    // Aerodynamics.
    pub(super) air_density: f32,
    pub(super) drag: f32,
    pub(super) lift: f32,
    pub(super) time: f32,
}

#[derive(Debug, Clone, Copy)]
pub(super) struct FrameTerms {
    pub(super) linear: Vec3A,
    pub(super) euler: Vec3A,
    pub(super) coriolis: Vec3A,
    pub(super) omega: Vec3A,
    pub(super) centrifugal: f32,
    // For the air: frame velocity and angular velocity (scaled), world pose.
    pub(super) air_velocity: Vec3A,
    pub(super) air_omega: Vec3A,
    pub(super) motion: FrameMotion,
}

impl ClothSolver {
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
}

/// [`ClothSolver::share_out`] on `pool` (the workers only if `workers_allowed`; `dispatching`
/// marks a job on the workers).
pub(super) fn share_out(
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
pub(super) struct StepContext<'a> {
    pub(super) model: &'a Model,
    pub(super) k: StepConstants,
    pub(super) phases: &'a [Phase],
    /// The colliders swept over each substep (`substep · colliders + collider`), written by
    /// the substep's `Phase::Sweep` item, which everything that reads them waits for.
    pub(super) swept: SharedSlice<'a, SweptCollider>,
    /// Their bounds, eight at a time (`substep · ⌈colliders / 8⌉ + k`), written with them.
    pub(super) swept_bounds: SharedSlice<'a, ColliderBounds>,
    /// What the sweep items make them from.
    pub(super) bodies: Bodies<'a>,
    pub(super) planes: &'a [Plane],
    pub(super) target_start: &'a [Vec3A],
    /// Attachment targets at the end of each substep (`substep · attachments + slot`),
    /// written with the swept colliders.
    pub(super) anchors: SharedSlice<'a, Vec3A>,
    pub(super) wind: Option<&'a Wind>,
    /// Mesh order.
    pub(super) x: SharedSlice<'a, Vec3A>,
    /// Mesh order.
    pub(super) v: SharedSlice<'a, Vec3A>,
    pub(super) xs: SharedSlice<'a, Vec3A>,
    pub(super) xs_prev: SharedSlice<'a, Vec3A>,
    pub(super) vs: SharedSlice<'a, Vec3A>,
    pub(super) external: SharedSlice<'a, Vec3A>,
    pub(super) triangle_force: SharedSlice<'a, Vec3A>,
    pub(super) distance_lambda: SharedSlice<'a, [f32; LANES]>,
    pub(super) bend_lambda: SharedSlice<'a, [[f32; LANES]; 5]>,
    pub(super) distance_inverse: &'a [[f32; LANES]],
    pub(super) bend_inverse: &'a [[[f32; LANES]; 3]],
    pub(super) bend_targets: SharedSlice<'a, BendTarget>,
    pub(super) group_health: SharedSlice<'a, ItemHealth>,
    pub(super) stretch_health: SharedSlice<'a, (f32, u32)>,
}

impl StepContext<'_> {
    /// Runs item `item` of phase `phase`. With [`Isa::Avx`] the whole item is compiled for
    /// that instruction set, not only its SIMD kernels: the work around them (the chunks'
    /// bounds and colliders, the one-particle paths, the kernels' calls, which can then be
    /// inlined) runs with it too. That took 6.6 % off the 4,000-particle dress's step on one
    /// thread and on two (session 16, alternating runs); building the whole program for
    /// x86-64-v3 gained no more. The functions an item runs are `#[inline(always)]` so that
    /// they are compiled into each version; every result is the same to the bit.
    pub(super) fn exec(&self, phase: usize, item: u32) {
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
    pub(super) fn exec_with(&self, phase: usize, item: u32) {
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
    pub(super) fn solve(&self, item: usize, first: bool, new_frame: bool) {
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
}
