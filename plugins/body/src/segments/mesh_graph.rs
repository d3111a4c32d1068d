//! The vertex adjacency (edge graph) of a triangle mesh and what is measured on it: graph distances
//! from a vertex set, the propagation of a segment's core, and the roughness of a vertex set. After
//! seed 002 (Uğur 2008, parametric bodies for virtual dressing) §4.3 (propagation, eq. 4.1) and
//! §7.1 (the uniform Laplacian, eq. 7.1, and the roughness, eq. 7.2).

use std::collections::VecDeque;

use glam::Vec3;

use super::{Propagation, SegmentError, SegmentWeights};

/// The vertex adjacency of a triangle mesh (its edge graph), as compressed rows: the seed's
/// winged-edge table answers the same 1-ring queries.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshGraph {
    offsets: Vec<u32>,
    neighbours: Vec<u32>,
}

impl MeshGraph {
    /// The edge graph of `triangles` over `vertex_count` vertices (indices `0..vertex_count`).
    /// Repeated edges count once; a vertex in no triangle has no neighbours.
    pub fn new(vertex_count: usize, triangles: &[[u32; 3]]) -> Result<Self, SegmentError> {
        let mut adjacency: Vec<Vec<u32>> = vec![Vec::new(); vertex_count];
        for (i, t) in triangles.iter().enumerate() {
            if let Some(&v) = t.iter().find(|&&v| v as usize >= vertex_count) {
                return Err(SegmentError::TriangleIndex {
                    triangle: i,
                    vertex: v,
                    vertex_count,
                });
            }
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                if a != b {
                    adjacency[a as usize].push(b);
                    adjacency[b as usize].push(a);
                }
            }
        }
        let mut offsets = Vec::with_capacity(vertex_count + 1);
        let mut neighbours = Vec::new();
        offsets.push(0);
        for mut ring in adjacency {
            ring.sort_unstable();
            ring.dedup();
            neighbours.extend_from_slice(&ring);
            offsets.push(neighbours.len() as u32);
        }
        Ok(Self {
            offsets,
            neighbours,
        })
    }

    /// Number of vertices.
    pub fn vertex_count(&self) -> usize {
        self.offsets.len() - 1
    }

    /// Number of (undirected) edges.
    pub fn edge_count(&self) -> usize {
        self.neighbours.len() / 2
    }

    /// The 1-ring of vertex `v`, sorted.
    ///
    /// # Panics
    /// If `v` is not below [`MeshGraph::vertex_count`].
    pub fn neighbours(&self, v: usize) -> &[u32] {
        &self.neighbours[self.offsets[v] as usize..self.offsets[v + 1] as usize]
    }

    fn check_vertices(&self, field: &'static str, vertices: &[u32]) -> Result<(), SegmentError> {
        match vertices
            .iter()
            .find(|&&v| v as usize >= self.vertex_count())
        {
            Some(&vertex) => Err(SegmentError::VertexIndex {
                field,
                vertex,
                vertex_count: self.vertex_count(),
            }),
            None => Ok(()),
        }
    }

    /// Graph distance (hops) from the set `core` of every vertex at most `max_hops` away, as
    /// `(vertex, hops)` sorted by vertex; the core itself at 0 hops. Breadth-first search.
    pub fn hops_from(&self, core: &[u32], max_hops: u32) -> Result<Vec<(u32, u32)>, SegmentError> {
        self.check_vertices("core", core)?;
        let mut hops = vec![u32::MAX; self.vertex_count()];
        let mut queue: VecDeque<u32> = VecDeque::new();
        for &v in core {
            if hops[v as usize] != 0 {
                hops[v as usize] = 0;
                queue.push_back(v);
            }
        }
        while let Some(v) = queue.pop_front() {
            let h = hops[v as usize];
            if h >= max_hops {
                continue;
            }
            for &n in self.neighbours(v as usize) {
                if hops[n as usize] == u32::MAX {
                    hops[n as usize] = h + 1;
                    queue.push_back(n);
                }
            }
        }
        Ok(hops
            .iter()
            .enumerate()
            .filter(|(_, h)| **h != u32::MAX)
            .map(|(v, &h)| (v as u32, h))
            .collect())
    }

    /// The propagation of `core` (§4.3): every vertex within `propagation.depth` hops, with its
    /// weight `f(k, d)` (1 on the core).
    pub fn propagate(
        &self,
        core: &[u32],
        propagation: Propagation,
    ) -> Result<SegmentWeights, SegmentError> {
        let reached = self.hops_from(core, propagation.depth)?;
        Ok(SegmentWeights {
            vertices: reached.iter().map(|r| r.0).collect(),
            hops: reached.iter().map(|r| r.1).collect(),
            weights: reached
                .iter()
                .map(|r| propagation.decay.weight(r.1, propagation.depth))
                .collect(),
        })
    }

    /// Distance (metres) of vertex `v` from its Laplacian coordinate, the mean of its 1-ring
    /// (seed eq. 7.1); `None` for a vertex without neighbours.
    ///
    /// # Panics
    /// If `v` or one of its neighbours is not an index into `positions`.
    pub fn laplacian_distance_m(&self, positions: &[Vec3], v: usize) -> Option<f32> {
        let ring = self.neighbours(v);
        if ring.is_empty() {
            return None;
        }
        let mean = ring.iter().map(|&n| positions[n as usize]).sum::<Vec3>() / ring.len() as f32;
        Some(mean.distance(positions[v]))
    }

    /// Roughness of the vertex set `region` (seed §7.1, eq. 7.2 as a mean): the mean distance
    /// (metres) of its vertices from their Laplacian coordinates. Vertices without neighbours
    /// are left out; an empty region has roughness 0.
    pub fn roughness_m(&self, positions: &[Vec3], region: &[u32]) -> Result<f32, SegmentError> {
        self.check_positions(positions)?;
        self.check_vertices("region", region)?;
        let (sum, count) = region
            .iter()
            .filter_map(|&v| self.laplacian_distance_m(positions, v as usize))
            .fold((0.0f64, 0usize), |(s, c), d| (s + d as f64, c + 1));
        Ok(if count == 0 {
            0.0
        } else {
            (sum / count as f64) as f32
        })
    }

    /// Roughness (metres) of the whole mesh: [`MeshGraph::roughness_m`] over every vertex.
    pub fn mesh_roughness_m(&self, positions: &[Vec3]) -> Result<f32, SegmentError> {
        let all: Vec<u32> = (0..self.vertex_count() as u32).collect();
        self.roughness_m(positions, &all)
    }

    fn check_positions(&self, positions: &[Vec3]) -> Result<(), SegmentError> {
        if positions.len() < self.vertex_count() {
            return Err(SegmentError::Length {
                field: "positions",
                got: positions.len(),
                expected: self.vertex_count(),
                fix: "pass the positions of the mesh the graph was built from (at least one per \
                      graph vertex)",
            });
        }
        Ok(())
    }
}
