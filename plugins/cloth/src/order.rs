//! The solver's particle order: a recursive coordinate bisection of the rest shape.
//!
//! The solver does not keep particles in the mesh's vertex order. At build time the rest
//! positions are split in two at the median along the longest axis of their bounding box,
//! and each half again, recursively (recursive coordinate bisection, Berger and Bokhari
//! 1987); the particles are then numbered leaf by leaf. Every node of that tree is a
//! spatially compact, contiguous range of particles:
//!
//! - the nodes at depth `D` are the **blocks** that the solver's threads work on: `2^D`
//!   blocks of 1,024 to 2,048 particles (at least two blocks from 512 particles on), whose
//!   constraints are solved in parallel ([`crate::constraints`]); `D` depends only on the
//!   particle count, never on the number of threads. Fewer, larger blocks mean fewer
//!   constraints between blocks; on two cores four blocks per 4,096 particles measured
//!   best;
//! - deeper nodes of at most `CHUNK` (32) particles are the **chunks** whose bounding boxes
//!   select the colliders their particles are tested against ([`crate::collision`]).
//!
//! The public API keeps the mesh's vertex order; the solver maps between the two orders
//! once per step.

use glam::Vec3;

/// About how many particles one block holds (between this and twice this; a mesh of at least
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
    /// Bisects `rest` (the rest positions in mesh order).
    pub fn new(rest: &[Vec3]) -> Self {
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
            rest,
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
    rest: &[Vec3],
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
        // Within a chunk, mesh order (neighbours in the mesh are often neighbours in memory).
        ids.sort_unstable();
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
    let mid = ids.len() / 2;
    if mid > 0 {
        ids.select_nth_unstable_by(mid, |&a, &b| {
            rest[a as usize][axis]
                .total_cmp(&rest[b as usize][axis])
                .then(a.cmp(&b))
        });
    }
    let (left, right) = ids.split_at_mut(mid);
    let args = (level + 1, depth);
    bisect(
        rest,
        left,
        offset,
        args.0,
        args.1,
        block_start,
        chunk_start,
        block_chunks,
    );
    bisect(
        rest,
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
            let order = ParticleOrder::new(&rest);
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
        }
    }
}
