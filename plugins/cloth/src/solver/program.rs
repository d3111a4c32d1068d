//! The phase program of a step ([`Phase`]): its work items (sweeps, triangle ranges,
//! particle groups, blocks, seams and corners) and what each item waits for
//! ([`crate::pool`]), built once for a substep count, an iteration count and whether there
//! is air, and reused by the steps that share them.

use super::ClothSolver;
use super::aero::TRIANGLE_ITEM;
use crate::constraints::ConstraintSet;
use crate::order::ParticleOrder;
use crate::pool::Dep;

/// Work items per block for the particles' part of a substep (prediction, tethers,
/// collisions): collisions make some blocks' particles several times as costly as others'
/// (those by the legs), and smaller items let the threads share that out. Blocks' constraint
/// work is the same for every block.
pub(super) const PARTICLE_GROUPS: usize = 4;

/// Lists of `u32` in one array (`start` has one entry per list, and the total last).
#[derive(Debug, Clone, Default)]
pub(super) struct Lists {
    pub(super) start: Vec<u32>,
    pub(super) values: Vec<u32>,
}

impl Lists {
    pub(super) fn push(&mut self, list: impl IntoIterator<Item = u32>) {
        if self.start.is_empty() {
            self.start.push(0);
        }
        self.values.extend(list);
        self.start.push(self.values.len() as u32);
    }

    pub(super) fn get(&self, i: usize) -> &[u32] {
        &self.values[self.start[i] as usize..self.start[i + 1] as usize]
    }
}

/// Which blocks each separator (seam or corner) moves particles of, and
/// the separators that move particles of each group: what a step's items wait for (see
/// `ClothSolver::set_dependencies`).
#[derive(Debug, Clone, Default)]
pub(super) struct SeparatorReach {
    /// Per separator (constraint item `blocks + j`): the blocks it touches.
    pub(super) blocks: Lists,
    /// Per separator: its level and its index in that level's phase.
    pub(super) place: Vec<(u32, u32)>,
    /// Per particle group: the separators that touch it.
    pub(super) of_group: Lists,
}

impl SeparatorReach {
    pub(super) fn new(order: &ParticleOrder, constraints: &ConstraintSet) -> Self {
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
pub(super) fn group_chunks(order: &ParticleOrder, group: usize) -> std::ops::Range<usize> {
    let (block, part) = (group / PARTICLE_GROUPS, group % PARTICLE_GROUPS);
    let (first, end) = (
        order.block_chunks[block] as usize,
        order.block_chunks[block + 1] as usize,
    );
    let count = end - first;
    first + part * count / PARTICLE_GROUPS..first + (part + 1) * count / PARTICLE_GROUPS
}

/// The particle group (see [`group_chunks`]) that holds particle `i`.
pub(super) fn group_of(order: &ParticleOrder, i: u32) -> u32 {
    let block = order.block_of(i) as usize;
    let chunk = order.chunk_start.partition_point(|&s| s <= i) - 1;
    let part = (0..PARTICLE_GROUPS)
        .find(|&p| group_chunks(order, block * PARTICLE_GROUPS + p).contains(&chunk))
        .unwrap_or(PARTICLE_GROUPS - 1);
    (block * PARTICLE_GROUPS + part) as u32
}

#[derive(Debug, Clone, Copy)]
pub(super) enum Phase {
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

impl ClothSolver {
    /// The phase program of a step of `substeps` substeps and `iterations` constraint
    /// iterations (with the aerodynamics phase if `aero`), its item counts and dependencies.
    pub(super) fn build_program(&mut self, substeps: u32, iterations: u32, aero: bool) {
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
    pub(super) fn set_dependencies(&mut self) {
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
}
