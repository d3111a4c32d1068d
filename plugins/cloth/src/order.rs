//! The solver's particle order: a recursive coordinate bisection of the rest shape.
//!
//! The solver does not keep particles in the mesh's vertex order. At build time the rest
//! positions are split in two along the longest axis of their bounding box (at the median,
//! with the exceptions below),
//! and each half again, recursively (recursive coordinate bisection, Berger and Bokhari
//! 1987); the particles are then numbered leaf by leaf. Every node of that tree is a
//! spatially compact, contiguous range of particles:
//!
//! - the nodes at depth `D` are the **blocks** that the solver's threads work on: `2^D`
//!   blocks of 1,024 to 2,048 particles on average (at least two blocks from 512 particles
//!   on), whose constraints are solved in parallel ([`crate::constraints`]); `D` depends only
//!   on the particle count, never on the number of threads. Fewer, larger blocks mean fewer
//!   constraints between blocks; on two cores four blocks per 4,096 particles measured
//!   best. Above the blocks, where the median leaves one side more than 1/32 over half of
//!   the **work**, a node is split where the work halves instead (but not nearer an end than an
//!   eighth of its particles). The work of a particle is 1 if it is free and 0 if it is
//!   attached (constraints between attached particles are dropped and attached particles
//!   are not integrated), unless the caller gives a better hint
//!   ([`crate::ClothSolver::new_balanced`]: a garment counts its particles that lie against
//!   the body 1.8 times, for their contacts, and its attached ones a tenth). (A dress's
//!   bodice is attached: split by count, the skirt's half of the dress had 1,116 free
//!   particles and the bodice's 662, and one thread waited for the other in every substep.
//!   Split by free particles, the 4,000-particle dress's upper block, with the hips'
//!   contacts, took 554 µs a step against the lower one's 392: session 12. With a tolerance
//!   of 1/8 that dress kept its median split, and the skirt's thread worked 35-50 µs a step
//!   more than the other, which waited 40-60 µs: session 13, the threads' busy time
//!   measured per phase);
//! - deeper nodes of at most `CHUNK` (32) particles are the **chunks** whose bounding boxes
//!   select the colliders their particles are tested against ([`crate::collision`]). The
//!   per-particle kernels take eight consecutive free particles at once, one by one
//!   otherwise, so below the blocks a node is split after a multiple of eight particles
//!   (only the last chunk of a block has a remainder), and within a chunk the attached
//!   particles come first, then the free ones, each in mesh order. (Split at the median
//!   with the mesh order kept, 20 % of a dress's free particles, 354 of 1,778, were left to
//!   the one-by-one path.)
//!
//! The public API keeps the mesh's vertex order; the solver maps between the two orders
//! once per step.

use glam::Vec3;

use crate::simd::LANES;

/// About how many particles one block holds on average (between this and twice this; a mesh of at least
/// [`BLOCK_MIN`] particles has at least two blocks).
pub(crate) const BLOCK_TARGET: usize = 1024;
/// The fewest particles that are split into two blocks.
pub(crate) const BLOCK_MIN: usize = 512;
/// The most particles in a collision chunk.
pub(crate) const CHUNK: usize = 32;

/// The solver's particle order and its block tree.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct ParticleOrder {
    /// Mesh vertex of each solver particle.
    pub to_mesh: Vec<u32>,
    /// Solver particle of each mesh vertex.
    pub to_solver: Vec<u32>,
    /// Depth of the blocks in the bisection tree (`2^depth` blocks).
    pub depth: u32,
    /// First particle of each block, and the particle count last (`2^depth + 1` entries).
    pub block_start: Vec<u32>,
    /// First particle of each chunk, and the particle count last.
    pub chunk_start: Vec<u32>,
    /// First chunk of each block, and the chunk count last.
    pub block_chunks: Vec<u32>,
}

impl ParticleOrder {
    /// Bisects `rest` (the rest positions in mesh order); `free[v]` tells whether vertex `v`
    /// is free (not attached), for balancing the blocks by free particles.
    #[cfg(test)]
    pub fn new(rest: &[Vec3], free: &[bool]) -> Self {
        Self::weighted(rest, free, None)
    }

    /// As [`Self::new`]; with `work`, the blocks are balanced by `work[v]` (each vertex's
    /// share of a step's work, finite and not negative) instead of by free particles.
    pub fn weighted(rest: &[Vec3], free: &[bool], work: Option<&[f32]>) -> Self {
        debug_assert_eq!(rest.len(), free.len());
        debug_assert!(work.is_none_or(|w| w.len() == rest.len()));
        let n = rest.len();
        let mut depth = u32::from(n >= BLOCK_MIN);
        while (n >> (depth + 1)) >= BLOCK_TARGET && depth < 12 {
            depth += 1;
        }
        let mut to_mesh: Vec<u32> = (0..n as u32).collect();
        let mut block_start = Vec::with_capacity((1 << depth) + 1);
        let mut chunk_start = Vec::new();
        let mut block_chunks = Vec::with_capacity((1 << depth) + 1);
        bisect(
            (rest, free, work),
            &mut to_mesh,
            0,
            0,
            depth,
            &mut block_start,
            &mut chunk_start,
            &mut block_chunks,
        );
        block_start.push(n as u32);
        chunk_start.push(n as u32);
        block_chunks.push(chunk_start.len() as u32 - 1);
        let mut to_solver = vec![0u32; n];
        for (i, &m) in to_mesh.iter().enumerate() {
            to_solver[m as usize] = i as u32;
        }
        Self {
            to_mesh,
            to_solver,
            depth,
            block_start,
            chunk_start,
            block_chunks,
        }
    }

    /// Number of blocks.
    pub fn blocks(&self) -> usize {
        1 << self.depth
    }

    /// The block that particle `i` (solver order) belongs to.
    pub fn block_of(&self, i: u32) -> u32 {
        (self.block_start.partition_point(|&s| s <= i) - 1) as u32
    }
}

#[allow(clippy::too_many_arguments)]
fn bisect(
    (rest, free, work): (&[Vec3], &[bool], Option<&[f32]>),
    ids: &mut [u32],
    offset: u32,
    level: u32,
    depth: u32,
    block_start: &mut Vec<u32>,
    chunk_start: &mut Vec<u32>,
    block_chunks: &mut Vec<u32>,
) {
    if level == depth {
        block_start.push(offset);
        block_chunks.push(chunk_start.len() as u32);
    }
    if level >= depth && ids.len() <= CHUNK {
        chunk_start.push(offset);
        // Attached, then free; each in mesh order (neighbours in the mesh are often
        // neighbours in memory).
        ids.sort_unstable_by_key(|&v| (free[v as usize], v));
        return;
    }
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for &v in ids.iter() {
        lo = lo.min(rest[v as usize]);
        hi = hi.max(rest[v as usize]);
    }
    let extent = hi - lo;
    let axis = if extent.x >= extent.y && extent.x >= extent.z {
        0
    } else if extent.y >= extent.z {
        1
    } else {
        2
    };
    let along = |a: &u32, b: &u32| {
        rest[*a as usize][axis]
            .total_cmp(&rest[*b as usize][axis])
            .then(a.cmp(b))
    };
    let half = ids.len() / 2;
    let mid = if level >= depth {
        // Below the blocks: after a multiple of eight (a node here has more than `CHUNK`
        // particles, so both sides are non-empty).
        let mid = (half + LANES / 2) / LANES * LANES;
        ids.select_nth_unstable_by(mid, along);
        mid
    } else {
        // Above the blocks: at the median, unless that leaves one side with more than 1/32
        // more of the work than half: then where the work splits evenly. (A small imbalance
        // costs less than a ragged cut across a regular mesh's rows, which makes longer
        // seams: on the 4,096-particle tube, 1,008 against 1,040 free particles is left as it
        // is.)
        if half > 0 {
            ids.select_nth_unstable_by(half, along);
        }
        // In f64: sums of many f32 weights, compared for balance.
        let weight = |v: &u32| match work {
            Some(work) => f64::from(work[*v as usize]),
            None => f64::from(u8::from(free[*v as usize])),
        };
        let total: f64 = ids.iter().map(weight).sum();
        let left: f64 = ids[..half].iter().map(weight).sum();
        if (2.0 * left - total).abs() <= total / 32.0 {
            half
        } else {
            ids.sort_unstable_by(along);
            let mut seen = 0.0;
            let at = ids
                .iter()
                .position(|v| {
                    seen += weight(v);
                    2.0 * seen > total
                })
                .unwrap_or(half);
            // A few clustered free particles must not leave a block empty or nearly so.
            let len = ids.len();
            at.clamp(len / 8, len - len / 8)
        }
    };
    let (left, right) = ids.split_at_mut(mid);
    let args = (level + 1, depth);
    bisect(
        (rest, free, work),
        left,
        offset,
        args.0,
        args.1,
        block_start,
        chunk_start,
        block_chunks,
    );
    bisect(
        (rest, free, work),
        right,
        offset + mid as u32,
        args.0,
        args.1,
        block_start,
        chunk_start,
        block_chunks,
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blocks_and_chunks_partition_the_particles() {
        for n in [1usize, 3, 31, 33, 700, 1500, 4096, 5000] {
            let rest: Vec<Vec3> = (0..n)
                .map(|k| {
                    let a = k as f32 * 0.37;
                    Vec3::new(a.cos(), (k / 17) as f32 * 0.01, a.sin())
                })
                .collect();
            // Every third particle attached.
            let free: Vec<bool> = (0..n).map(|k| k % 3 != 0).collect();
            let order = ParticleOrder::new(&rest, &free);
            let mut seen = vec![false; n];
            for &m in &order.to_mesh {
                assert!(!seen[m as usize]);
                seen[m as usize] = true;
            }
            for (i, &m) in order.to_mesh.iter().enumerate() {
                assert_eq!(order.to_solver[m as usize] as usize, i);
            }
            assert_eq!(order.block_start.len(), order.blocks() + 1);
            assert_eq!(*order.block_start.last().unwrap() as usize, n);
            assert!(order.block_start.windows(2).all(|w| w[0] <= w[1]));
            assert!(order.chunk_start.windows(2).all(|w| w[0] < w[1]));
            assert!(
                order
                    .chunk_start
                    .windows(2)
                    .all(|w| (w[1] - w[0]) as usize <= CHUNK)
            );
            // Every block is a whole number of chunks.
            for b in 0..order.blocks() {
                let (c0, c1) = (order.block_chunks[b], order.block_chunks[b + 1]);
                assert_eq!(
                    order.chunk_start[c0 as usize], order.block_start[b],
                    "n {n}"
                );
                assert_eq!(order.chunk_start[c1 as usize], order.block_start[b + 1]);
            }
            if n >= BLOCK_MIN {
                assert!(order.blocks() >= 2);
            }
            for b in 0..order.blocks() {
                let (c0, c1) = (
                    order.block_chunks[b] as usize,
                    order.block_chunks[b + 1] as usize,
                );
                for c in c0..c1 {
                    let chunk = order.chunk_start[c] as usize..order.chunk_start[c + 1] as usize;
                    // Whole groups of eight but in a block's last chunk.
                    if c + 1 < c1 {
                        assert_eq!(chunk.len() % LANES, 0, "n {n} chunk {chunk:?}");
                    }
                    // Attached first, then free, each in mesh order.
                    let key = |i: usize| {
                        let m = order.to_mesh[i];
                        (free[m as usize], m)
                    };
                    assert!(
                        chunk
                            .clone()
                            .zip(chunk.clone().skip(1))
                            .all(|(i, j)| key(i) < key(j))
                    );
                }
            }
        }
    }

    #[test]
    fn blocks_hold_equally_many_free_particles() {
        // A 64 × 64 sheet whose top 40 rows are attached (a bodice above a skirt): split by
        // count, the lower blocks would hold all the free particles.
        let n = 64;
        let rest: Vec<Vec3> = (0..n * n)
            .map(|k| Vec3::new((k % n) as f32 * 0.01, (k / n) as f32 * 0.011, 0.0))
            .collect();
        let free: Vec<bool> = (0..n * n).map(|k| k / n < n - 40).collect();
        let order = ParticleOrder::new(&rest, &free);
        let total = free.iter().filter(|&&f| f).count();
        assert!(order.blocks() >= 2);
        let per_block: Vec<usize> = (0..order.blocks())
            .map(|b| {
                (order.block_start[b]..order.block_start[b + 1])
                    .filter(|&i| free[order.to_mesh[i as usize] as usize])
                    .count()
            })
            .collect();
        let sizes: Vec<u32> = order.block_start.windows(2).map(|w| w[1] - w[0]).collect();
        for &f in &per_block {
            // Each halving may leave one particle more on one side.
            assert!(
                f.abs_diff(total / order.blocks()) <= order.depth as usize,
                "free particles per block {per_block:?}, particles {sizes:?}"
            );
        }
        // The blocks are still compact: no block spans the whole sheet's height.
        for b in 0..order.blocks() {
            let ys = (order.block_start[b]..order.block_start[b + 1])
                .map(|i| rest[order.to_mesh[i as usize] as usize].y);
            let (lo, hi) = ys.fold((f32::INFINITY, f32::NEG_INFINITY), |(l, h), y| {
                (l.min(y), h.max(y))
            });
            assert!(hi - lo < 0.011 * (n - 1) as f32, "block {b}: {lo}..{hi}");
        }
    }

    /// A `64 × 64` sheet (rows along y, the longer side) whose particles `free` says are free.
    fn sheet(free: impl Fn(usize, usize) -> bool) -> (Vec<Vec3>, Vec<bool>) {
        let n = 64;
        let rest = (0..n * n)
            .map(|k| Vec3::new((k % n) as f32 * 0.01, (k / n) as f32 * 0.011, 0.0))
            .collect();
        let free = (0..n * n).map(|k| free(k % n, k / n)).collect();
        (rest, free)
    }

    fn block_sizes(order: &ParticleOrder) -> Vec<u32> {
        order.block_start.windows(2).map(|w| w[1] - w[0]).collect()
    }

    #[test]
    fn a_small_free_imbalance_keeps_the_median_split() {
        // The top row attached: the first split (across y, at row 32) leaves 2,048 free
        // particles below and 1,984 above; the difference, 64, is within 1/32 of the 4,032
        // free particles (126), so the median stays and the blocks keep equal counts. With
        // two rows attached, 128 against 124: the split moves.
        let (rest, free) = sheet(|_, row| row < 63);
        let order = ParticleOrder::new(&rest, &free);
        assert_eq!(order.blocks(), 4);
        assert_eq!(block_sizes(&order), [1024; 4]);
        let (rest, free) = sheet(|_, row| row < 62);
        let order = ParticleOrder::new(&rest, &free);
        assert!(block_sizes(&order).iter().any(|&s| s != 1024));
    }

    #[test]
    fn few_or_no_free_particles_leave_no_block_nearly_empty() {
        for free_corner in [0usize, 1, 5, 40] {
            // `free_corner` free particles in one corner of the sheet, the rest attached.
            let (rest, free) = sheet(|col, row| row * 64 + col < free_corner);
            let order = ParticleOrder::new(&rest, &free);
            let sizes = block_sizes(&order);
            // Each split keeps at least an eighth of its node on each side.
            let least = (64 * 64) >> (3 * order.depth);
            assert!(
                sizes.iter().all(|&s| s as usize >= least),
                "{free_corner} free: {sizes:?}"
            );
            let mut seen = vec![false; 64 * 64];
            for &m in &order.to_mesh {
                assert!(!std::mem::replace(&mut seen[m as usize], true));
            }
        }
    }

    #[test]
    fn blocks_balance_the_work_hint() {
        // All free; the rows below 16 three times the work of the others (6,144 in all):
        // the median split (across y, at row 32) would leave 4,096 below against 2,048 above,
        // far over 1/32 off, so the split moves to where the work halves, row 16; each half
        // is then split at its median (across x, even work): four blocks of work 1,536 each.
        let (rest, free) = sheet(|_, _| true);
        let work: Vec<f32> = (0..64 * 64)
            .map(|k| if k / 64 < 16 { 3.0 } else { 1.0 })
            .collect();
        let order = ParticleOrder::weighted(&rest, &free, Some(&work));
        let sizes = block_sizes(&order);
        assert_eq!(sizes.iter().sum::<u32>(), 64 * 64);
        assert_eq!(sizes, [512, 512, 1536, 1536]);
        let block_work: Vec<f32> = order
            .block_start
            .windows(2)
            .map(|w| {
                order.to_mesh[w[0] as usize..w[1] as usize]
                    .iter()
                    .map(|&v| work[v as usize])
                    .sum()
            })
            .collect();
        assert!(block_work.iter().all(|&w| w == 1536.0), "{block_work:?}");
    }
}
