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

mod bending;
mod distance;
mod packing;
mod stencil;

use crate::pool::SharedSlice;
use crate::simd::{LANES, offset};

pub(crate) use bending::solve_bend;
pub(crate) use distance::{max_stretch_squared, solve_distance};

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

#[cfg(test)]
mod tests;
