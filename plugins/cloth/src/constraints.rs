//! Packed XPBD constraints, their projections, and how they are split into parallel work.
//!
//! **Distance** (stretch and shear): `C = |xᵢ − xⱼ| − L`, projected as in XPBD (Macklin et
//! al. 2016): `Δλ = −(C + α̃λ) / (wᵢ + wⱼ + α̃)`, `Δxᵢ = wᵢ n Δλ`, `Δxⱼ = −wⱼ n Δλ`.
//!
//! **Isometric bending** (Bergou et al. 2006; as a PBD constraint in Bender, Müller and
//! Macklin's 2015 PBD survey). For an interior edge `x₀x₁` with opposite vertices `x₂`, `x₃`
//! and the rest-shape cotangent weights `K = (c₀₃+c₀₄, c₀₁+c₀₂, −c₀₁−c₀₃, −c₀₂−c₀₄)`, the
//! energy `E = k_b/2 · 3/(A₀+A₁) |Σ Kᵢxᵢ|²` is the 3-vector constraint
//! `C = √(3/(A₀+A₁)) Σ Kᵢxᵢ` with compliance `1/k_b`. `C` is linear in the positions, so its
//! three components share one denominator `Σ wᵢkᵢ² + α̃` (precomputed but for `α̃`) and the
//! projection is exact in one step. A flat rest stencil has `C = 0` at rest. For a curved
//! rest shape (a garment modelled in 3-D) the rest value of `C` is stored in the stencil's own
//! frame (edge direction, mean normal of the two triangles, their cross product) and the
//! constraint asks `C` to equal that vector re-expressed in the current frame; this keeps the
//! rest shape the minimum and is invariant to rigid motion. (Bergou's model assumes a flat
//! rest shape; this rest-frame target is our extension.) Flat stencils skip the frame. The
//! frame is taken at the first constraint pass of a step and held over its substeps: it turns by at most a few degrees in one step (6° at 720°/s), and
//! computing it once instead of ten times made the curved stencils cost about what flat
//! ones do (the whole step 8% less on one thread).
//!
//! **Pairs.** Most of a step's time goes into loading particles into SIMD lanes and storing
//! them back, so each bending stencil also carries the distance constraints between its
//! vertices: the one along its edge `x₀x₁` (pair 0) and, where the edge is a quad's diagonal,
//! the one along the other diagonal `x₂x₃` (pair 1). A stencil loads its four particles once,
//! projects its bending constraint and then its pairs, and stores them once. Only distance
//! constraints without a stencil (along the garment's borders, or where bending is off) are
//! solved on their own. This took the constraint work of the 4,096-particle bench from
//! 1,082 to 966 µs per step on one thread.
//!
//! **Blocks, seams and corners.** Constraints are solved Gauss–Seidel style, so two
//! constraints that share a particle may not be projected at the same time. The particles are
//! ordered by a recursive bisection of the rest shape ([`crate::order`]), whose blocks are
//! compact patches of the garment. A constraint whose particles all lie in one block belongs
//! to that block; the blocks' constraints are solved in parallel, one work item per block,
//! with no synchronisation inside a block. A constraint that spans blocks belongs to the
//! *seam* between its two blocks, or, near a point where seams meet (it touches three blocks,
//! or a particle that constraints of two different seams touch), to a *corner* (seams and
//! corners together: the *separators*). The seams of
//! different pairs of blocks share no particle, nor do the corners (a corner is a connected
//! cluster of such constraints), so a substep solves the blocks, then all seams in parallel,
//! then all corners in parallel: three levels per constraint iteration, whatever the mesh,
//! instead of one per graph colour. (A seam waits only for its two blocks, and a block's
//! particles only for their block and the separators that touch them: see `crate::pool`.)
//! Attached particles count like the others here:
//! they are not written by constraints, but they are moved by the block that holds them.
//!
//! **Batches.** Within a work item, constraints are coloured greedily (each takes the smallest
//! colour none of its free particles has yet, distance constraints first, in the mesh's
//! order), and each colour is packed into batches of eight whose lanes share no particle
//! ([`crate::simd`]); batches run one after the other, the eight lanes of a batch at once. Per
//! colour the order is: lone distance constraints, flat bending stencils, curved ones, each
//! with fewer pairs first (a batch is solved as its most demanding lane needs: a batch with a
//! curved stencil is solved as curved, its flat lanes skipping the frame; a lane without a
//! pair has a zero inverse denominator there). Empty lanes point at a padding particle of
//! their own item and change nothing. Everything here depends only on the mesh, never on the
//! number of threads.
//!
//! **Fused multiply-adds.** The bending and distance kernels round `a·b + c` once
//! ([`crate::simd::Lanes::mul_add`]): the AVX kernels with the processor's FMA instructions,
//! the baseline ones lane by lane with `f32::mul_add`, so both still give the same bits. On
//! the 4,000-particle dress this took about 4 % off a step on one thread (session 13).

use std::collections::VecDeque;

use glam::Vec3A;

use crate::fabric::{Fabric, bend_compliance, distance_compliance};
use crate::mesh::MeshTopology;
use crate::order::ParticleOrder;
use crate::pool::SharedSlice;
#[cfg(target_arch = "x86_64")]
use crate::simd::Avx8;
use crate::simd::{Baseline8, Isa, LANES, Lanes, V3, dispatch_lanes, offset};

/// Open batches the packer may still add to (a window over the constraint order).
const PACK_WINDOW: usize = 32;
/// An empty lane.
const NONE: u32 = u32::MAX;
/// Items' padding particles lie this many `Vec3A` (64 bytes) apart: the items of a phase run
/// on different threads, and every batch with an empty lane writes its item's padding
/// particle; on one cache line those writes would make the line bounce between cores.
const PADDING_STRIDE: usize = 4;

/// Eight distance constraints, one per lane.
#[derive(Debug, Clone, Copy, PartialEq)]
#[repr(C, align(32))]
pub(crate) struct DistanceBatch {
    /// The two particles, as byte offsets ([`offset`]).
    pub i: [u32; LANES],
    pub j: [u32; LANES],
    pub rest: [f32; LANES],
    pub compliance: [f32; LANES],
    pub wi: [f32; LANES],
    pub wj: [f32; LANES],
}

/// The rest length of a bending batch's pair in a lane without that pair.
pub(crate) const NO_PAIR_REST: f32 = -1.0;

/// Eight isometric bending constraints, one per lane.
#[derive(Debug, Clone, Copy, PartialEq)]
#[repr(C, align(32))]
pub(crate) struct BendBatch {
    /// `v[q][lane]`: vertex `q` of the stencil, as a byte offset ([`offset`]).
    pub v: [[u32; LANES]; 4],
    /// `√(3/(A₀+A₁)) Kᵢ` for `i = 0..4`.
    pub k: [[f32; LANES]; 4],
    /// The inverse masses of the four vertices: the step of vertex `i` per unit `Δλ` is
    /// `wᵢ Kᵢ`, and the pairs' particles move by the same `wᵢ`.
    pub w: [[f32; LANES]; 4],
    /// The distance constraints solved with the stencil (see "Pairs" in the module
    /// documentation): pair 0 is `x₀x₁`, pair 1 `x₂x₃`. Rest length ([`NO_PAIR_REST`] in a
    /// lane without that pair, whose inverse denominator is then zero, so it changes
    /// nothing).
    pub drest: [[f32; LANES]; 2],
}

/// What a bending batch needs only now and then, kept apart from [`BendBatch`], which every
/// substep streams through the cache (a tenth smaller without the pairs' compliance alone:
/// the bending kernel took 3-4 % less time; session 15).
#[derive(Debug, Clone, Copy, PartialEq)]
#[repr(C, align(32))]
pub(crate) struct BendSide {
    /// Rest value of `C` in the stencil frame (edge, normal, binormal); zero when flat. Read
    /// when the frame is taken, at a step's first constraint pass.
    pub rest: [[f32; LANES]; 3],
    /// The pairs' compliance, 1/(N·m): read for their inverse denominators, and by further
    /// constraint iterations.
    pub pair_compliance: [[f32; LANES]; 2],
}

/// Eight distance constraints for the stretch check: the two particles (byte offsets) and
/// the rest length (infinite in an empty lane).
#[derive(Debug, Clone, Copy, PartialEq)]
#[repr(C, align(32))]
pub(crate) struct CheckBatch {
    pub i: [u32; LANES],
    pub j: [u32; LANES],
    pub rest: [f32; LANES],
}

/// The target value of eight curved bending stencils in world axes, and which lanes are
/// solved (all bits set) or skipped (a degenerate frame), held over the substeps of a step.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
#[repr(C, align(32))]
pub(crate) struct BendTarget {
    pub value: [[f32; LANES]; 3],
    pub valid: [f32; LANES],
}

/// How [`solve_bend`] treats the rest value of its batches.
#[derive(Clone, Copy)]
pub(crate) enum BendFrame<'a, 's> {
    /// All stencils are flat (zero rest value): no frame.
    Flat,
    /// Curved: compute each stencil's frame from the current positions and store the target
    /// in `targets[base + k]` for batch `k`.
    New(&'a SharedSlice<'s, BendTarget>, usize),
    /// Curved: use the targets stored by the last `New` pass.
    Held(&'a SharedSlice<'s, BendTarget>, usize),
}

/// An isometric bending stencil before packing.
#[derive(Debug, Clone, Copy, PartialEq)]
struct BendConstraint {
    v: [u32; 4],
    k: [f32; 4],
    w: [f32; 4],
    rest: [f32; 3],
    /// The distance constraints of pairs 0 (`v₀v₁`) and 1 (`v₂v₃`) solved with it (indices,
    /// or `NONE`).
    pairs: [u32; 2],
}

/// A distance constraint before packing.
#[derive(Debug, Clone, Copy, PartialEq)]
struct DistanceConstraint {
    i: u32,
    j: u32,
    rest: f32,
    compliance: f32,
    wi: f32,
    wj: f32,
}

/// What a run of batches holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub(crate) enum RunKind {
    Distance,
    /// Bending stencils, with their first `pairs` distance constraints (see "Pairs" in the
    /// module documentation).
    Bend {
        curved: bool,
        pairs: u8,
    },
}

/// Consecutive batches of one kind, solved by one kernel call.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Run {
    pub kind: RunKind,
    /// Range in `distance` or `bend`.
    pub batches: (u32, u32),
}

/// One work item: a block, a seam or a corner, as runs of batches solved in order.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct ConstraintItem {
    /// The item's stretch-check batches (all its distance constraints, standalone or paired).
    pub check: (u32, u32),
    /// Range in `runs`.
    pub runs: (u32, u32),
    /// The padding particle of this item's empty lanes.
    pub padding: u32,
}

/// All constraints, packed into batches and grouped into work items.
#[derive(Debug, Clone, Default)]
pub(crate) struct ConstraintSet {
    /// Distance constraints solved on their own (those no bending stencil carries).
    pub distance: Vec<DistanceBatch>,
    pub bend: Vec<BendBatch>,
    /// Per bending batch: what it needs now and then.
    pub bend_side: Vec<BendSide>,
    /// Every distance constraint, for the stretch check.
    pub check: Vec<CheckBatch>,
    pub runs: Vec<Run>,
    /// The blocks' items first (one per block, in block order), then the seams', then the
    /// corners'.
    pub items: Vec<ConstraintItem>,
    /// Item ranges of the seams and of the corners (each run in parallel after the blocks;
    /// empty ones left out).
    pub separator_levels: Vec<(u32, u32)>,
    /// Compliance of every bending constraint, 1/(N·m).
    pub bend_compliance: f32,
    /// Number of distance (standalone and paired) and bending constraints (without empty
    /// lanes).
    pub distance_count: usize,
    pub bend_count: usize,
    /// Stretch constraints (not shear) in mesh numbering: vertices and rest length.
    pub stretch: Vec<(u32, u32, f32)>,
}

impl ConstraintSet {
    /// Builds the constraints of `topology` (mesh numbering) in the particle numbering of
    /// `order`; `inverse_mass` is in mesh order. Padding particles are numbered from the
    /// particle count on, one per item.
    pub fn build(
        rest: &[glam::Vec3],
        topology: &MeshTopology,
        fabric: &Fabric,
        inverse_mass: &[f32],
        order: &ParticleOrder,
    ) -> Self {
        let to = |v: u32| order.to_solver[v as usize];
        let mut distance = Vec::new();
        let mut stretch = Vec::new();
        // Per distance constraint: whether it is a quad's shear diagonal.
        let mut shear = Vec::new();
        for (stencils, stiffness, is_shear) in [
            (&topology.stretch, fabric.stretch_stiffness_n_m, false),
            (&topology.shear, fabric.shear_stiffness_n_m, true),
        ] {
            for s in stencils {
                let [i, j] = s.vertices;
                let (wi, wj) = (inverse_mass[i as usize], inverse_mass[j as usize]);
                if wi + wj == 0.0 {
                    continue;
                }
                if let Some(compliance) = distance_compliance(stiffness, s.rest_length, s.area) {
                    shear.push(is_shear);
                    distance.push(DistanceConstraint {
                        i: to(i),
                        j: to(j),
                        rest: s.rest_length,
                        compliance,
                        wi,
                        wj,
                    });
                    if !is_shear {
                        stretch.push((i, j, s.rest_length));
                    }
                }
            }
        }
        let mut bend = Vec::new();
        let compliance = bend_compliance(fabric.bend_stiffness_n_m);
        if compliance.is_some() {
            for stencil in &topology.bending {
                let w = stencil.map(|v| inverse_mass[v as usize]);
                if w.iter().sum::<f32>() == 0.0 {
                    continue;
                }
                if let Some(mut c) = bend_stencil(rest, *stencil, w) {
                    c.v = c.v.map(to);
                    bend.push(c);
                }
            }
        }
        // Pairs: each stencil carries the distance constraint of its edge and, across a quad
        // diagonal, the shear constraint of the other diagonal. (Not another edge between its
        // opposite vertices, as where a sliver triangle sits on the edge: that one rides with
        // its own edge's stencil.)
        let pair_index: std::collections::HashMap<(u32, u32), u32> = distance
            .iter()
            .enumerate()
            .map(|(k, c)| ((c.i.min(c.j), c.i.max(c.j)), k as u32))
            .collect();
        let mut claimed = vec![false; distance.len()];
        for c in &mut bend {
            for (pair, (a, b)) in [(c.v[0], c.v[1]), (c.v[2], c.v[3])].into_iter().enumerate() {
                c.pairs[pair] = match pair_index.get(&(a.min(b), a.max(b))) {
                    Some(&k) if !claimed[k as usize] && (pair == 0 || shear[k as usize]) => {
                        claimed[k as usize] = true;
                        k
                    }
                    _ => NONE,
                };
            }
        }
        let paired = claimed;
        // Each constraint's blocks: one block (a block item), two (the seam between a pair of
        // blocks) or more (a corner where blocks meet).
        let blocks = order.blocks();
        let n = order.to_mesh.len();
        let block_of: Vec<u32> = (0..n as u32).map(|i| order.block_of(i)).collect();
        let bend_base = distance.len() as u32;
        let total = distance.len() + bend.len();
        let particles_of = |k: u32| -> ([u32; 4], usize) {
            if k < bend_base {
                let c = &distance[k as usize];
                ([c.i, c.j, 0, 0], 2)
            } else {
                (bend[(k - bend_base) as usize].v, 4)
            }
        };
        let blocks_of = |k: u32| -> (u32, u32, bool) {
            let (ps, count) = particles_of(k);
            let (mut lo, mut hi) = (u32::MAX, 0);
            for &p in &ps[..count] {
                lo = lo.min(block_of[p as usize]);
                hi = hi.max(block_of[p as usize]);
            }
            let more = ps[..count]
                .iter()
                .any(|&p| ![lo, hi].contains(&block_of[p as usize]));
            (lo, hi, more)
        };
        // A particle touched by seam constraints of two different pairs of blocks is a corner
        // particle; constraints at corners (touching a corner particle or three blocks) go to
        // corner items, so that the seams of different pairs share no particle.
        const NO_PAIR: (u32, u32) = (u32::MAX, u32::MAX);
        let mut pair_of_particle = vec![NO_PAIR; n];
        let mut corner = vec![false; n];
        let solved = |k: u32| k >= bend_base || !paired[k as usize];
        for k in (0..total as u32).filter(|&k| solved(k)) {
            let (lo, hi, more) = blocks_of(k);
            if lo == hi {
                continue;
            }
            let (ps, count) = particles_of(k);
            for &p in &ps[..count] {
                let seen = &mut pair_of_particle[p as usize];
                if more || (*seen != NO_PAIR && *seen != (lo, hi)) {
                    corner[p as usize] = true;
                }
                *seen = (lo, hi);
            }
        }
        // Members of each block, of each seam (by pair) and of the corners, in the mesh's order
        // (distance constraints, then bending stencils, offset by the distance count).
        let mut block_members = vec![Vec::new(); blocks];
        let mut seam_members: std::collections::BTreeMap<(u32, u32), Vec<u32>> =
            std::collections::BTreeMap::new();
        let mut corner_members = Vec::new();
        for k in (0..total as u32).filter(|&k| solved(k)) {
            let (lo, hi, more) = blocks_of(k);
            let (ps, count) = particles_of(k);
            if lo == hi {
                block_members[lo as usize].push(k);
            } else if more || ps[..count].iter().any(|&p| corner[p as usize]) {
                corner_members.push(k);
            } else {
                seam_members.entry((lo, hi)).or_default().push(k);
            }
        }
        // Corner constraints fall into small independent clusters (union–find over shared
        // particles); each cluster is an item.
        let mut parent: Vec<u32> = (0..n as u32).collect();
        fn root(parent: &mut [u32], mut p: u32) -> u32 {
            while parent[p as usize] != p {
                let up = parent[parent[p as usize] as usize];
                parent[p as usize] = up;
                p = up;
            }
            p
        }
        for &k in &corner_members {
            let (ps, count) = particles_of(k);
            for &p in &ps[1..count] {
                let (a, b) = (root(&mut parent, ps[0]), root(&mut parent, p));
                if a != b {
                    parent[a.max(b) as usize] = a.min(b);
                }
            }
        }
        let mut clusters: std::collections::BTreeMap<u32, Vec<u32>> =
            std::collections::BTreeMap::new();
        for &k in &corner_members {
            let r = root(&mut parent, particles_of(k).0[0]);
            clusters.entry(r).or_default().push(k);
        }

        // Items: every block, then the seams, then the corner clusters.
        let mut item_members: Vec<Vec<u32>> = block_members;
        let mut separator_levels = Vec::new();
        for group in [
            seam_members.into_values().collect::<Vec<_>>(),
            clusters.into_values().collect(),
        ] {
            let first = item_members.len() as u32;
            item_members.extend(group.into_iter().filter(|m| !m.is_empty()));
            if item_members.len() as u32 > first {
                separator_levels.push((first, item_members.len() as u32));
            }
        }

        let free: Vec<bool> = order
            .to_mesh
            .iter()
            .map(|&m| inverse_mass[m as usize] > 0.0)
            .collect();
        let mut used = vec![0u128; n];
        let mut packer = Packer {
            mask: vec![0; n + PADDING_STRIDE * item_members.len()],
        };
        let mut set = Self {
            bend_compliance: compliance.unwrap_or(0.0),
            distance_count: distance.len(),
            bend_count: bend.len(),
            stretch,
            separator_levels,
            ..Self::default()
        };
        let kind_of = |k: u32| -> RunKind {
            if k < bend_base {
                RunKind::Distance
            } else {
                bend_kind(&bend[(k - bend_base) as usize])
            }
        };
        for (item, members) in item_members.iter().enumerate() {
            let padding = (n + PADDING_STRIDE * item) as u32;
            // Greedy colouring over the item's free particles, distance constraints first
            // (a colour's constraints share no free particle, so the order inside a colour
            // does not change the result); colours past 127 share one last colour.
            let mut colour_of = Vec::with_capacity(members.len());
            for &k in members {
                let (ps, count) = particles_of(k);
                let mut mask = 0u128;
                for &p in &ps[..count] {
                    if free[p as usize] {
                        mask |= used[p as usize];
                    }
                }
                let colour = (!mask).trailing_zeros().min(127);
                for &p in &ps[..count] {
                    if free[p as usize] {
                        used[p as usize] |= 1u128 << colour;
                    }
                }
                colour_of.push(colour);
            }
            for &k in members {
                let (ps, count) = particles_of(k);
                for &p in &ps[..count] {
                    used[p as usize] = 0;
                }
            }
            // Runs: per colour, its distance constraints, then its bending stencils, flat ones
            // first and fewer pairs first; a batch is solved as its most demanding lane needs
            // (curved, pairs): the others give the same result there.
            let class = |k: u32| u8::from(k >= bend_base);
            let mut sorted: Vec<(u32, u8, RunKind, u32)> = members
                .iter()
                .zip(&colour_of)
                .map(|(&k, &colour)| (colour, class(k), kind_of(k), k))
                .collect();
            sorted.sort_by_key(|&(colour, class, kind, _)| (colour, class, kind));
            let r0 = set.runs.len() as u32;
            let mut at = 0;
            while at < sorted.len() {
                let (colour, class, _, _) = sorted[at];
                let mut end = at;
                while end < sorted.len() && (sorted[end].0, sorted[end].1) == (colour, class) {
                    end += 1;
                }
                let ids: Vec<u32> = sorted[at..end].iter().map(|e| e.3).collect();
                at = end;
                // A run is one colour: its batches share no free particle.
                if class == 0 {
                    let start = set.distance.len() as u32;
                    for lanes in packer.pack(&ids, |k| {
                        let c = &distance[k as usize];
                        [c.i, c.j]
                    }) {
                        set.distance.push(distance_batch(&distance, lanes, padding));
                    }
                    set.runs.push(Run {
                        kind: RunKind::Distance,
                        batches: (start, set.distance.len() as u32),
                    });
                } else {
                    let first_run = set.runs.len();
                    for lanes in packer.pack(&ids, |k| bend[(k - bend_base) as usize].v) {
                        let lanes = lanes.map(|k| if k == NONE { NONE } else { k - bend_base });
                        let (batch, side) = bend_batch(&bend, &distance, lanes, padding);
                        // Curved if any lane is, with as many pairs as the lane with most.
                        let (mut curved, mut pairs) = (false, 0);
                        for &k in lanes.iter().filter(|&&k| k != NONE) {
                            if let RunKind::Bend {
                                curved: c,
                                pairs: p,
                            } = bend_kind(&bend[k as usize])
                            {
                                (curved, pairs) = (curved || c, pairs.max(p));
                            }
                        }
                        let kind = RunKind::Bend { curved, pairs };
                        let b = set.bend.len() as u32;
                        set.bend.push(batch);
                        set.bend_side.push(side);
                        let in_colour = set.runs.len() > first_run;
                        match set.runs.last_mut() {
                            Some(run) if in_colour && run.kind == kind && run.batches.1 == b => {
                                run.batches.1 = b + 1;
                            }
                            _ => set.runs.push(Run {
                                kind,
                                batches: (b, b + 1),
                            }),
                        }
                    }
                }
            }
            // The stretch check: the item's distance constraints, standalone or paired.
            let checked: Vec<u32> = members
                .iter()
                .flat_map(|&k| {
                    if k < bend_base {
                        [k, NONE, NONE]
                    } else {
                        let [a, b] = bend[(k - bend_base) as usize].pairs;
                        [a, b, NONE]
                    }
                })
                .filter(|&k| k != NONE)
                .collect();
            let c0 = set.check.len() as u32;
            for chunk in checked.chunks(LANES) {
                let mut b = CheckBatch {
                    i: [offset(padding); LANES],
                    j: [offset(padding); LANES],
                    rest: [f32::INFINITY; LANES],
                };
                for (l, &k) in chunk.iter().enumerate() {
                    let c = &distance[k as usize];
                    (b.i[l], b.j[l], b.rest[l]) = (offset(c.i), offset(c.j), c.rest);
                }
                set.check.push(b);
            }
            set.items.push(ConstraintItem {
                check: (c0, set.check.len() as u32),
                runs: (r0, set.runs.len() as u32),
                padding,
            });
        }
        set
    }

    /// Fills `distance[k]` and `bend[k]` with the inverse XPBD denominators of batch `k` for
    /// substeps with `1/h² = inv_h2` (they change only with the substep length): for a bending
    /// batch, the stencils' and then the two pairs'.
    pub fn inverse_denominators(
        &self,
        inv_h2: f32,
        distance: &mut Vec<[f32; LANES]>,
        bend: &mut Vec<[[f32; LANES]; 3]>,
    ) {
        distance.clear();
        distance.extend(self.distance.iter().map(|c| {
            std::array::from_fn(|l| 1.0 / (c.wi[l] + c.wj[l] + c.compliance[l] * inv_h2))
        }));
        let alpha = self.bend_compliance * inv_h2;
        bend.clear();
        bend.extend(self.bend.iter().zip(&self.bend_side).map(|(c, side)| {
            let pair = |p: usize| -> [f32; LANES] {
                std::array::from_fn(|l| {
                    if c.drest[p][l] == NO_PAIR_REST {
                        0.0
                    } else {
                        1.0 / (c.w[2 * p][l]
                            + c.w[2 * p + 1][l]
                            + side.pair_compliance[p][l] * inv_h2)
                    }
                })
            };
            let stencil = std::array::from_fn(|l| {
                let wkk: f32 = (0..4).map(|q| c.w[q][l] * c.k[q][l] * c.k[q][l]).sum();
                // An empty lane: a harmless non-zero denominator.
                let wkk = if wkk == 0.0 { 1.0 } else { wkk };
                1.0 / (wkk + alpha)
            });
            [stencil, pair(0), pair(1)]
        }));
    }

    /// Number of slots after the particles for the padding particles (one per item, each on
    /// its own cache line).
    pub fn padding_particles(&self) -> usize {
        PADDING_STRIDE * self.items.len()
    }

    /// The particles (solver numbering, padding included, with repeats) that item `item`'s
    /// constraints move.
    pub fn item_particles(&self, item: usize) -> impl Iterator<Item = u32> + '_ {
        let (r0, r1) = self.items[item].runs;
        self.runs[r0 as usize..r1 as usize]
            .iter()
            .flat_map(move |run| {
                let (a, b) = (run.batches.0 as usize, run.batches.1 as usize);
                let (distance, bend) = match run.kind {
                    RunKind::Distance => (&self.distance[a..b], &[][..]),
                    RunKind::Bend { .. } => (&[][..], &self.bend[a..b]),
                };
                let distance = distance
                    .iter()
                    .flat_map(|batch| batch.i.into_iter().chain(batch.j));
                distance.chain(bend.iter().flat_map(|batch| batch.v.into_iter().flatten()))
            })
            .map(|o| o / offset(1))
    }

    /// The vertices (solver numbering) of lane `lane_id % 8` of check batch `lane_id / 8`.
    pub fn distance_vertices(&self, lane_id: u32) -> [u32; 2] {
        let b = &self.check[lane_id as usize / LANES];
        let l = lane_id as usize % LANES;
        [b.i[l] / 16, b.j[l] / 16]
    }
}

fn distance_batch(
    constraints: &[DistanceConstraint],
    lanes: [u32; LANES],
    padding: u32,
) -> DistanceBatch {
    let mut b = DistanceBatch {
        i: [offset(padding); LANES],
        j: [offset(padding); LANES],
        rest: [1.0; LANES],
        // Empty lanes: a harmless non-zero denominator.
        compliance: [1.0; LANES],
        wi: [0.0; LANES],
        wj: [0.0; LANES],
    };
    for (l, &k) in lanes.iter().enumerate() {
        if k == NONE {
            continue;
        }
        let c = &constraints[k as usize];
        b.i[l] = offset(c.i);
        b.j[l] = offset(c.j);
        b.rest[l] = c.rest;
        b.compliance[l] = c.compliance;
        b.wi[l] = c.wi;
        b.wj[l] = c.wj;
    }
    b
}

/// How a stencil is solved: curved or flat, and how many pairs (pair 1 needs pair 0's slot).
fn bend_kind(c: &BendConstraint) -> RunKind {
    RunKind::Bend {
        curved: c.rest != [0.0; 3],
        pairs: if c.pairs[1] != NONE {
            2
        } else {
            u8::from(c.pairs[0] != NONE)
        },
    }
}

fn bend_batch(
    constraints: &[BendConstraint],
    distance: &[DistanceConstraint],
    lanes: [u32; LANES],
    padding: u32,
) -> (BendBatch, BendSide) {
    let mut side = BendSide {
        rest: [[0.0; LANES]; 3],
        pair_compliance: [[0.0; LANES]; 2],
    };
    let mut b = BendBatch {
        v: [[offset(padding); LANES]; 4],
        // Empty lanes: zero weights (a harmless non-zero denominator, see
        // `inverse_denominators`) and no pairs.
        k: [[0.0; LANES]; 4],
        w: [[0.0; LANES]; 4],
        drest: [[NO_PAIR_REST; LANES]; 2],
    };
    for (l, &k) in lanes.iter().enumerate() {
        if k == NONE {
            continue;
        }
        let c = &constraints[k as usize];
        for (p, &d) in c.pairs.iter().enumerate() {
            if d == NONE {
                continue;
            }
            let d = &distance[d as usize];
            b.drest[p][l] = d.rest;
            side.pair_compliance[p][l] = d.compliance;
        }
        for q in 0..4 {
            b.v[q][l] = offset(c.v[q]);
            b.k[q][l] = c.k[q];
            b.w[q][l] = c.w[q];
        }
        for q in 0..3 {
            side.rest[q][l] = c.rest[q];
        }
    }
    (b, side)
}

/// Greedy packing of constraints into batches whose lanes share no particle.
struct Packer {
    /// Per particle: the open batches (bits of window slots) that already hold it. All zero
    /// between calls.
    mask: Vec<u32>,
}

impl Packer {
    /// Packs `ids` (in this order of preference) into batches; `particles(id)` lists a
    /// constraint's particles. Each constraint goes into the oldest open batch that holds
    /// none of its particles, or a new one; a full batch, or the oldest one when the window
    /// is full, is emitted.
    fn pack<const K: usize>(
        &mut self,
        ids: &[u32],
        particles: impl Fn(u32) -> [u32; K],
    ) -> Vec<[u32; LANES]> {
        let mut out = Vec::with_capacity(ids.len().div_ceil(LANES));
        let mut slots = [[NONE; LANES]; PACK_WINDOW];
        let mut fill = [0usize; PACK_WINDOW];
        let mut open: VecDeque<usize> = VecDeque::with_capacity(PACK_WINDOW);
        let mut free: Vec<usize> = (0..PACK_WINDOW).rev().collect();
        for &c in ids {
            let ps = particles(c);
            let taken = ps.iter().fold(0u32, |m, &p| m | self.mask[p as usize]);
            let s = match open.iter().position(|&s| taken & (1 << s) == 0) {
                Some(at) => open[at],
                None => {
                    if free.is_empty() {
                        let oldest = open.pop_front().expect("a full window has open slots");
                        close(
                            oldest,
                            &mut slots,
                            &mut fill,
                            &mut self.mask,
                            &mut out,
                            &particles,
                        );
                        free.push(oldest);
                    }
                    let s = free.pop().expect("a slot was just freed");
                    open.push_back(s);
                    s
                }
            };
            slots[s][fill[s]] = c;
            fill[s] += 1;
            for p in ps {
                self.mask[p as usize] |= 1 << s;
            }
            if fill[s] == LANES {
                // Full: emit it now (`close` reads the slot before clearing it).
                let at = open.iter().position(|&o| o == s).expect("s is open");
                open.remove(at);
                close(
                    s,
                    &mut slots,
                    &mut fill,
                    &mut self.mask,
                    &mut out,
                    &particles,
                );
                free.push(s);
            }
        }
        while let Some(s) = open.pop_front() {
            close(
                s,
                &mut slots,
                &mut fill,
                &mut self.mask,
                &mut out,
                &particles,
            );
        }
        out
    }
}

/// Emits the batch in window slot `s` and frees the slot.
fn close<const K: usize>(
    s: usize,
    slots: &mut [[u32; LANES]; PACK_WINDOW],
    fill: &mut [usize; PACK_WINDOW],
    mask: &mut [u32],
    out: &mut Vec<[u32; LANES]>,
    particles: &impl Fn(u32) -> [u32; K],
) {
    for &c in &slots[s][..fill[s]] {
        for p in particles(c) {
            mask[p as usize] &= !(1u32 << s);
        }
    }
    out.push(slots[s]);
    slots[s] = [NONE; LANES];
    fill[s] = 0;
}

fn cot(a: glam::Vec3, b: glam::Vec3) -> f32 {
    let cross = a.cross(b).length();
    if cross < 1e-20 { 0.0 } else { a.dot(b) / cross }
}

fn bend_stencil(rest: &[glam::Vec3], v: [u32; 4], w: [f32; 4]) -> Option<BendConstraint> {
    let [x0, x1, x2, x3] = v.map(|i| rest[i as usize]);
    let e0 = x1 - x0;
    let e1 = x2 - x0;
    let e2 = x3 - x0;
    let e3 = x2 - x1;
    let e4 = x3 - x1;
    let c01 = cot(e0, e1);
    let c02 = cot(e0, e2);
    let c03 = cot(-e0, e3);
    let c04 = cot(-e0, e4);
    let a0 = 0.5 * e0.cross(e1).length();
    let a1 = 0.5 * e0.cross(e2).length();
    if a0 + a1 <= 0.0 || (a0 + a1).is_nan() {
        return None;
    }
    let scale = (3.0 / (a0 + a1)).sqrt();
    let k = [
        scale * (c03 + c04),
        scale * (c01 + c02),
        scale * (-c01 - c03),
        scale * (-c02 - c04),
    ];
    if !k.iter().all(|k| k.is_finite()) {
        return None;
    }
    // Relative to x₀ (the weights sum to zero) to keep rounding small.
    let y = k[1] * e0 + k[2] * e1 + k[3] * e2;
    let frame = stencil_frame(
        Vec3A::from(x0),
        Vec3A::from(x1),
        Vec3A::from(x2),
        Vec3A::from(x3),
    )?;
    let y = Vec3A::from(y);
    // Flat at rest: the weighted sum vanishes up to rounding (it is dimensionless, about
    // the dihedral angle in radians).
    let rest_value = if y.length() < 1e-4 {
        [0.0; 3]
    } else {
        [y.dot(frame.0), y.dot(frame.1), y.dot(frame.2)]
    };
    Some(BendConstraint {
        v,
        k,
        w,
        rest: rest_value,
        pairs: [NONE; 2],
    })
}

/// Edge direction, mean normal and binormal of a bending stencil, if not degenerate.
#[inline]
fn stencil_frame(p0: Vec3A, p1: Vec3A, p2: Vec3A, p3: Vec3A) -> Option<(Vec3A, Vec3A, Vec3A)> {
    let e0 = p1 - p0;
    let normal = e0.cross(p2 - p0) + (p3 - p0).cross(e0);
    let el = e0.length();
    let nl = normal.length();
    if !(el > 1e-12 && nl > 1e-9 * el * el) {
        return None;
    }
    let t = e0 / el;
    let n = normal / nl;
    Some((t, n, t.cross(n)))
}

/// Projects the distance batches `batches` (XPBD); `inverse_denominator[k]` is
/// `1 / (wᵢ + wⱼ + α̃)` of `batches[k]` ([`ConstraintSet::inverse_denominators`]) and
/// `lambda[k]` its multipliers. `first` means λ starts at zero.
///
/// # Safety
/// Every particle index of the batches is in bounds of `x`'s allocation, and the calling
/// item has exclusive access to those particles in this phase.
#[inline]
pub(crate) unsafe fn solve_distance(
    isa: Isa,
    batches: &[DistanceBatch],
    inverse_denominator: &[[f32; LANES]],
    lambda: Option<(&SharedSlice<'_, [f32; LANES]>, usize)>,
    x: *mut Vec3A,
    inv_h2: f32,
    first: bool,
) {
    dispatch_lanes!(
        isa,
        distance_kernel(
            batches: &[DistanceBatch],
            inverse_denominator: &[[f32; LANES]],
            lambda: Option<(&SharedSlice<'_, [f32; LANES]>, usize)>,
            x: *mut Vec3A,
            inv_h2: f32,
            first: bool,
        )
    )
}

#[inline(always)]
unsafe fn distance_kernel<L: Lanes>(
    batches: &[DistanceBatch],
    inverse_denominator: &[[f32; LANES]],
    lambda: Option<(&SharedSlice<'_, [f32; LANES]>, usize)>,
    x: *mut Vec3A,
    inv_h2: f32,
    first: bool,
) {
    let inv_h2 = L::splat(inv_h2);
    for (k, (c, inv)) in batches.iter().zip(inverse_denominator).enumerate() {
        // SAFETY: see `solve_distance`.
        unsafe {
            let pi = L::gather(x, &c.i);
            let pj = L::gather(x, &c.j);
            let mut lam = None;
            if let Some((lambda, base)) = lambda
                && !first
            {
                lam = Some(L::load(&lambda.get(base + k)));
            }
            let (pi, pj, lam) = project_pair(
                (pi, pj),
                (L::load(&c.wi), L::load(&c.wj)),
                L::load(&c.rest),
                L::load(&c.compliance) * inv_h2,
                L::load(inv),
                lam,
            );
            if let Some((lambda, base)) = lambda {
                lambda.set(base + k, lam.to_array());
            }
            L::scatter(x, &c.i, pi);
            L::scatter(x, &c.j, pj);
        }
    }
}

/// One XPBD projection of eight distance constraints between `pi` and `pj` (inverse masses
/// `w`, rest length `rest`, compliance over h² `alpha`, inverse denominator `inv`, multiplier
/// `lambda` if kept): the moved particles and the new multiplier.
#[inline(always)]
fn project_pair<L: Lanes>(
    (pi, pj): (V3<L>, V3<L>),
    (wi, wj): (L, L),
    rest: L,
    alpha: L,
    inv: L,
    lambda: Option<L>,
) -> (V3<L>, V3<L>, L) {
    let d = pi - pj;
    let len = d.dot_fused(d).sqrt();
    // Degenerate (coincident) pairs are skipped; NaN goes through (the guard sees it).
    let valid = len.not_lt(L::splat(1e-9));
    let mut residual = len - rest;
    let lam = lambda.unwrap_or(L::splat(0.0));
    if lambda.is_some() {
        residual = alpha.mul_add(lam, residual);
    }
    let dl = -(residual * inv);
    let s = dl.div(len).and(valid);
    (
        d.mul_add(wi * s, pi),
        d.mul_add(-(wj * s), pj),
        L::select(valid, lam + dl, lam),
    )
}

/// Projects the bending batches `batches` (XPBD) with their first `pairs` distance
/// constraints (solved after the bending, see "Pairs" in the module documentation), all
/// flat (`frame` is `Flat`: zero rest value) or all curved; `inverse_denominator[k]` holds the inverse denominators of `batches[k]`
/// ([`ConstraintSet::inverse_denominators`]) and `lambda[k]` its multipliers (bending x, y, z,
/// then the pairs'). `first` means λ starts at zero.
///
/// # Safety
/// As [`solve_distance`].
#[allow(clippy::too_many_arguments)]
#[inline]
pub(crate) unsafe fn solve_bend(
    isa: Isa,
    frame: BendFrame<'_, '_>,
    pairs: u8,
    (batches, side): (&[BendBatch], &[BendSide]),
    inverse_denominator: &[[[f32; LANES]; 3]],
    lambda: Option<(&SharedSlice<'_, [[f32; LANES]; 5]>, usize)>,
    x: *mut Vec3A,
    (alpha, inv_h2): (f32, f32),
    first: bool,
) {
    let (mode, targets) = match frame {
        BendFrame::Flat => (0, None),
        BendFrame::New(t, base) => (1, Some((t, base))),
        BendFrame::Held(t, base) => (2, Some((t, base))),
    };
    let args = BendArgs {
        batches,
        side,
        inverse_denominator,
        lambda,
        x,
        alpha,
        inv_h2,
        first,
        targets,
    };
    #[cfg(target_arch = "x86_64")]
    crate::simd::avx_features! {
        unsafe fn avx<const MODE: u8, const PAIRS: u8>(args: BendArgs<'_, '_>) {
            // SAFETY: the caller's contract.
            unsafe { bend_kernel::<Avx8, MODE, PAIRS>(args) }
        }
    }
    macro_rules! dispatch {
        ($($mode:literal, $pairs:literal);*) => {
            match (isa, mode, pairs) {
                $(
                    #[cfg(target_arch = "x86_64")]
                    (Isa::Avx, $mode, $pairs) => avx::<$mode, $pairs>(args),
                    (_, $mode, $pairs) => bend_kernel::<Baseline8, $mode, $pairs>(args),
                )*
                _ => unreachable!("bending runs have 0 to 2 pairs"),
            }
        };
    }
    // SAFETY: the caller's contract; AVX only where detected.
    unsafe { dispatch!(0, 0; 0, 1; 0, 2; 1, 0; 1, 1; 1, 2; 2, 0; 2, 1; 2, 2) }
}

/// The arguments of [`bend_kernel`] (see [`solve_bend`]).
#[derive(Clone, Copy)]
struct BendArgs<'a, 's> {
    batches: &'a [BendBatch],
    side: &'a [BendSide],
    inverse_denominator: &'a [[[f32; LANES]; 3]],
    lambda: Option<(&'a SharedSlice<'s, [[f32; LANES]; 5]>, usize)>,
    x: *mut Vec3A,
    alpha: f32,
    inv_h2: f32,
    first: bool,
    targets: Option<(&'a SharedSlice<'s, BendTarget>, usize)>,
}

/// `MODE`: 0 flat, 1 curved with a new frame, 2 curved with the held one; `PAIRS`: distance
/// constraints solved after the bending.
#[inline(always)]
unsafe fn bend_kernel<L: Lanes, const MODE: u8, const PAIRS: u8>(a: BendArgs<'_, '_>) {
    let (lambda, x, first, targets) = (a.lambda, a.x, a.first, a.targets);
    let side = a.side;
    let alpha = L::splat(a.alpha);
    let inv_h2 = L::splat(a.inv_h2);
    for (k, (c, inv)) in a.batches.iter().zip(a.inverse_denominator).enumerate() {
        // SAFETY: see `solve_bend`.
        unsafe {
            // (No closures here: they would not inherit the caller's target features.)
            let p = [
                L::gather(x, &c.v[0]),
                L::gather(x, &c.v[1]),
                L::gather(x, &c.v[2]),
                L::gather(x, &c.v[3]),
            ];
            let kept = match lambda {
                Some((lambda, base)) if !first => Some(lambda.get(base + k)),
                _ => None,
            };
            let [p0, p1, p2, p3] = p;
            let e1 = p1 - p0;
            let mut value = (p3 - p0).mul_add(
                L::load(&c.k[3]),
                (p2 - p0).mul_add(L::load(&c.k[2]), e1.scale(L::load(&c.k[1]))),
            );
            let mut valid = None;
            if MODE == 1 {
                // The stencil frame: edge t, mean normal n (e₁ × (x₂ − x₃) is the sum of the
                // two triangles' area normals), binormal t × n.
                let normal = e1.cross(p2 - p3);
                let el = e1.dot_fused(e1).sqrt();
                let nl = normal.dot_fused(normal).sqrt();
                let framed = el.gt(L::splat(1e-12)).and(nl.gt(L::splat(1e-9) * el * el));
                // One division for both lengths: 1/el = nl/(el·nl), 1/nl = el/(el·nl).
                let inv_both = L::splat(1.0).div(el * nl);
                let t = e1.scale(nl * inv_both);
                let n = normal.scale(el * inv_both);
                let b = t.cross(n);
                let rest = V3::load(&side[k].rest);
                let target = b
                    .mul_add(rest.z, n.mul_add(rest.y, t.scale(rest.x)))
                    .and(framed);
                // A flat lane (zero rest value) needs no frame: it is always solved.
                let flat = rest.dot_fused(rest).not_gt(L::splat(0.0));
                let lanes = framed.or(flat);
                if let Some((targets, base)) = targets {
                    let [tx, ty, tz] = target.to_arrays();
                    targets.set(
                        base + k,
                        BendTarget {
                            value: [tx, ty, tz],
                            valid: lanes.to_array(),
                        },
                    );
                }
                value = value - target;
                valid = Some(lanes);
            } else if MODE == 2
                && let Some((targets, base)) = targets
            {
                let held = targets.get(base + k);
                value = value - V3::load(&held.value);
                valid = Some(L::load(&held.valid));
            }
            let mut lam = V3 {
                x: L::splat(0.0),
                y: L::splat(0.0),
                z: L::splat(0.0),
            };
            if let Some(kept) = kept {
                lam = V3::load(&[kept[0], kept[1], kept[2]]);
                value = lam.mul_add(alpha, value);
            }
            let mut dl = value.scale(-L::load(&inv[0]));
            if let Some(valid) = valid {
                dl = dl.and(valid);
            }
            let mut p = [
                dl.mul_add(L::load(&c.w[0]) * L::load(&c.k[0]), p0),
                dl.mul_add(L::load(&c.w[1]) * L::load(&c.k[1]), p1),
                dl.mul_add(L::load(&c.w[2]) * L::load(&c.k[2]), p2),
                dl.mul_add(L::load(&c.w[3]) * L::load(&c.k[3]), p3),
            ];
            let mut pair_lambda = [L::splat(0.0); 2];
            for pair in 0..PAIRS as usize {
                let (a, b) = (2 * pair, 2 * pair + 1);
                // A closure (`Option::map`) would not inherit the target features.
                #[allow(clippy::manual_map)]
                let lam = match &kept {
                    Some(kept) => Some(L::load(&kept[3 + pair])),
                    None => None,
                };
                // (The compliance only weighs a kept λ.)
                let alpha = match &kept {
                    Some(_) => L::load(&side[k].pair_compliance[pair]) * inv_h2,
                    None => L::splat(0.0),
                };
                let (pa, pb, lam) = project_pair(
                    (p[a], p[b]),
                    (L::load(&c.w[a]), L::load(&c.w[b])),
                    L::load(&c.drest[pair]),
                    alpha,
                    L::load(&inv[1 + pair]),
                    lam,
                );
                (p[a], p[b], pair_lambda[pair]) = (pa, pb, lam);
            }
            if let Some((lambda, base)) = lambda {
                let [lx, ly, lz] = (lam + dl).to_arrays();
                let (l3, l4) = (pair_lambda[0].to_array(), pair_lambda[1].to_array());
                lambda.set(base + k, [lx, ly, lz, l3, l4]);
            }
            L::scatter(x, &c.v[0], p[0]);
            L::scatter(x, &c.v[1], p[1]);
            L::scatter(x, &c.v[2], p[2]);
            L::scatter(x, &c.v[3], p[3]);
        }
    }
}

/// The largest squared length / rest length over `batches`, and its lane
/// (`(first_batch + k) · LANES + lane`); NaN (and the first such lane) if any is NaN;
/// `(0, u32::MAX)` if there is none.
///
/// # Safety
/// Every particle index of the batches is in bounds of `x`'s allocation, and no thread
/// writes those particles in this phase.
#[inline]
pub(crate) unsafe fn max_stretch_squared(
    isa: Isa,
    batches: &[CheckBatch],
    first_batch: usize,
    x: *const Vec3A,
) -> (f32, u32) {
    dispatch_lanes!(
        isa,
        max_stretch_squared_with(
            batches: &[CheckBatch],
            first_batch: usize,
            x: *const Vec3A,
        ) -> (f32, u32)
    )
}

#[inline(always)]
unsafe fn max_stretch_squared_with<L: Lanes>(
    batches: &[CheckBatch],
    first_batch: usize,
    x: *const Vec3A,
) -> (f32, u32) {
    let mut worst = (0.0f32, u32::MAX);
    for (k, c) in batches.iter().enumerate() {
        // SAFETY: see `max_stretch_squared`.
        let (pi, pj) = unsafe { (L::gather(x, &c.i), L::gather(x, &c.j)) };
        let d = pi - pj;
        let rest = L::load(&c.rest);
        let ratio2 = d.dot(d).div(rest * rest);
        // (No closure: it would not inherit the caller's target features.)
        let lane_base = ((first_batch + k) * LANES) as u32;
        let nan = ratio2.is_nan().bits();
        if nan != 0 {
            return (f32::NAN, lane_base + nan.trailing_zeros());
        }
        let mut above = ratio2.gt(L::splat(worst.0)).bits();
        if above != 0 {
            let r = ratio2.to_array();
            while above != 0 {
                let lane = above.trailing_zeros();
                above &= above - 1;
                if r[lane as usize] > worst.0 {
                    worst = (r[lane as usize], lane_base + lane);
                }
            }
        }
    }
    worst
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::ClothMesh;
    use glam::Vec3;

    fn build(mesh: &ClothMesh, w: &[f32]) -> (ConstraintSet, ParticleOrder) {
        let topo = MeshTopology::new(mesh);
        let free: Vec<bool> = w.iter().map(|&w| w > 0.0).collect();
        let order = ParticleOrder::new(mesh.positions(), &free);
        let set = ConstraintSet::build(mesh.positions(), &topo, &Fabric::cotton(), w, &order);
        (set, order)
    }

    /// The particles item `k`'s constraints touch, without its padding particle.
    fn item_particles(set: &ConstraintSet, k: usize) -> Vec<u32> {
        let padding = set.items[k].padding;
        set.item_particles(k).filter(|&v| v != padding).collect()
    }

    #[test]
    fn parallel_items_and_batch_lanes_never_share_a_particle() {
        let mesh = ClothMesh::cylinder(Vec3::ZERO, 0.3, 0.6, 48, 40).unwrap();
        let mut w = vec![1.0f32; mesh.vertex_count()];
        for v in ClothMesh::cylinder_ring(48, 40) {
            w[v as usize] = 0.0;
        }
        let (set, order) = build(&mesh, &w);
        assert!(order.blocks() >= 2);
        let n = mesh.vertex_count();
        // Lanes of a batch.
        for b in &set.distance {
            let mut v: Vec<u32> =
                b.i.into_iter()
                    .chain(b.j)
                    .map(|o| o / 16)
                    .filter(|&v| v < n as u32)
                    .collect();
            let len = v.len();
            v.sort_unstable();
            v.dedup();
            assert_eq!(v.len(), len, "a distance batch repeats a particle");
        }
        for b in &set.bend {
            let mut v: Vec<u32> =
                b.v.into_iter()
                    .flatten()
                    .map(|o| o / 16)
                    .filter(|&v| v < n as u32)
                    .collect();
            let len = v.len();
            v.sort_unstable();
            v.dedup();
            assert_eq!(v.len(), len, "a bending batch repeats a particle");
        }
        // Items of one phase: the blocks, then the seams, then the corners.
        let mut phases = vec![(0u32, order.blocks() as u32)];
        phases.extend(set.separator_levels.iter().copied());
        for (a, b) in phases {
            let mut owner = vec![u32::MAX; n];
            for k in a..b {
                for v in item_particles(&set, k as usize) {
                    assert!(
                        owner[v as usize] == u32::MAX || owner[v as usize] == k,
                        "items {k} and {} share particle {v}",
                        owner[v as usize]
                    );
                    owner[v as usize] = k;
                }
            }
        }
        // Block items touch only their block's particles.
        for k in 0..order.blocks() {
            let range = order.block_start[k]..order.block_start[k + 1];
            for v in item_particles(&set, k) {
                assert!(range.contains(&v), "block {k} touches particle {v}");
            }
        }
        // Every constraint is in exactly one lane: a distance constraint standalone or as a
        // stencil's pair, with the stencil's own edge (pair 0) or its other diagonal (pair 1).
        let lanes = |v: &[u32]| v.iter().filter(|&&o| o / 16 < n as u32).count();
        let mut pairs = Vec::new();
        for b in &set.distance {
            for l in 0..LANES {
                if b.i[l] / 16 < n as u32 {
                    pairs.push((b.i[l].min(b.j[l]), b.i[l].max(b.j[l])));
                }
            }
        }
        let standalone = pairs.len();
        for b in &set.bend {
            for (pair, (qa, qb)) in [(0, 1), (2, 3)].into_iter().enumerate() {
                for l in 0..LANES {
                    if b.drest[pair][l] != NO_PAIR_REST {
                        let (i, j) = (b.v[qa][l], b.v[qb][l]);
                        assert!(b.drest[pair][l] > 0.0);
                        pairs.push((i.min(j), i.max(j)));
                    }
                }
            }
        }
        assert_eq!(pairs.len(), set.distance_count);
        pairs.sort_unstable();
        pairs.dedup();
        assert_eq!(
            pairs.len(),
            set.distance_count,
            "a distance constraint is solved twice"
        );
        // Every lane's pairs are solved by its run's kernel.
        for run in &set.runs {
            let RunKind::Bend { pairs, .. } = run.kind else {
                continue;
            };
            for b in &set.bend[run.batches.0 as usize..run.batches.1 as usize] {
                for pair in 0..2 {
                    if pair as u8 >= pairs {
                        assert!(
                            (0..LANES).all(|l| b.drest[pair][l] == NO_PAIR_REST),
                            "a lane's pair {pair} is in a run solving {pairs} pairs"
                        );
                    }
                }
            }
        }
        // Nearly all of them ride with a stencil.
        assert!(
            standalone * 10 < set.distance_count,
            "{standalone} standalone"
        );
        let bend: usize = set.bend.iter().map(|b| lanes(&b.v[0])).sum();
        assert_eq!(bend, set.bend_count);
        // The stretch check sees every distance constraint once.
        let mut checked: Vec<(u32, u32)> = set
            .check
            .iter()
            .flat_map(|b| (0..LANES).map(move |l| (b.i[l], b.j[l], b.rest[l])))
            .filter(|&(_, _, rest)| rest.is_finite())
            .map(|(i, j, _)| (i.min(j), i.max(j)))
            .collect();
        checked.sort_unstable();
        assert_eq!(checked, pairs);
        // Batches are nearly full.
        assert!(set.bend.len() * LANES < set.bend_count * 11 / 10);
    }

    #[test]
    fn flat_stencils_have_zero_rest_curvature_and_curved_ones_do_not() {
        let flat = ClothMesh::grid(Vec3::ZERO, Vec3::X, Vec3::Z, 4, 4).unwrap();
        let (set, _) = build(&flat, &vec![1.0; flat.vertex_count()]);
        assert!(set.bend_count > 0);
        let is_curved = |kind: RunKind| matches!(kind, RunKind::Bend { curved: true, .. });
        assert!(set.runs.iter().all(|r| !is_curved(r.kind)));
        let tube = ClothMesh::cylinder(Vec3::ZERO, 0.2, 0.3, 16, 4).unwrap();
        let (set, _) = build(&tube, &vec![1.0; tube.vertex_count()]);
        assert!(set.runs.iter().any(|r| is_curved(r.kind)));
        for run in set.runs.iter().filter(|r| r.kind != RunKind::Distance) {
            for side in &set.bend_side[run.batches.0 as usize..run.batches.1 as usize] {
                let curved = side.rest.iter().flatten().any(|&r| r != 0.0);
                assert_eq!(curved, is_curved(run.kind));
            }
        }
    }

    /// The stretch check on both instruction sets against a plain loop over the pairs: the
    /// same largest ratio and lane, and the first NaN.
    #[test]
    fn stretch_check_finds_the_largest_ratio_and_the_first_nan() {
        let n = 200u32;
        let mut seed = 12345u32;
        let mut next = || {
            seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (seed >> 8) as f32 / (1u32 << 24) as f32
        };
        let mut x: Vec<Vec3A> = (0..n).map(|_| Vec3A::new(next(), next(), next())).collect();
        let batches: Vec<CheckBatch> = (0..37)
            .map(|_| {
                let mut pick = || ((next() * n as f32) as u32).min(n - 1);
                let (i, j): (Vec<u32>, Vec<u32>) = (0..LANES).map(|_| (pick(), pick())).unzip();
                CheckBatch {
                    i: std::array::from_fn(|l| offset(i[l])),
                    j: std::array::from_fn(|l| offset(j[l])),
                    rest: std::array::from_fn(|_| 0.05 + next()),
                }
            })
            .collect();
        let plain = |x: &[Vec3A], first: usize| {
            let mut worst = (0.0f32, u32::MAX);
            for (k, c) in batches.iter().enumerate() {
                for l in 0..LANES {
                    let (i, j) = (c.i[l] as usize / 16, c.j[l] as usize / 16);
                    let ratio2 = (x[i] - x[j]).length_squared() / (c.rest[l] * c.rest[l]);
                    let lane = ((first + k) * LANES + l) as u32;
                    if ratio2.is_nan() {
                        return (f32::NAN, lane);
                    }
                    if ratio2 > worst.0 {
                        worst = (ratio2, lane);
                    }
                }
            }
            worst
        };
        let mut isas = vec![Isa::Baseline];
        if Isa::detect() != Isa::Baseline {
            isas.push(Isa::detect());
        }
        for nan in [false, true] {
            if nan {
                let c = &batches[20];
                x[c.j[5] as usize / 16].y = f32::NAN;
            }
            let expected = plain(&x, 3);
            assert_eq!(expected.0.is_nan(), nan);
            for &isa in &isas {
                // SAFETY: every index is a particle of `x`, which nothing writes.
                let got = unsafe { max_stretch_squared(isa, &batches, 3, x.as_ptr()) };
                assert_eq!(got.1, expected.1, "{isa:?}, NaN {nan}");
                assert!(
                    got.0.to_bits() == expected.0.to_bits() || (nan && got.0.is_nan()),
                    "{isa:?}: {} against {}",
                    got.0,
                    expected.0
                );
            }
        }
    }
}
