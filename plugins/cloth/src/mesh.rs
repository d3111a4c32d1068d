//! Cloth meshes and the constraint topology derived from them.
//!
//! A [`ClothMesh`] is a validated triangle mesh in metres. [`MeshTopology`] derives the
//! constraint stencils the solver needs, following the mass-spring reading of a garment mesh
//! that PhysX's cloth cooker uses (seed 000 §5.4.1: stretch and shear "fibers"):
//!
//! - **Quads.** Garment meshes are usually quad meshes exported as triangles. Two triangles
//!   that share an edge which is the strictly longest edge of both are read as one quad; that
//!   edge is a quad diagonal (unless the other diagonal is much shorter, see
//!   [`MIN_QUAD_DIAGONAL_RATIO`]).
//! - **Stretch** constraints: every mesh edge that is not a quad diagonal.
//! - **Shear** constraints: both diagonals of every quad (the shared edge and the segment
//!   between the two opposite vertices). Unpaired triangles get no shear constraint; their
//!   three stretch edges already resist shear.
//! - **Bending** stencils: every interior edge shared by exactly two triangles, as
//!   `[edge vertex, edge vertex, opposite in triangle A, opposite in triangle B]` for the
//!   isometric bending model of Bergou et al. 2006. Edges shared by more than two triangles
//!   (non-manifold) get no bending stencil.
//!
//! Each distance constraint also carries the membrane area it stands for, so that stiffness
//! can be given in physical units (N/m) independently of the mesh resolution
//! (see [`crate::fabric`]).
//!
//! Tethers ([`MeshTopology::tethers`]) follow the long-range attachments of Kim et al. 2012:
//! each free vertex is tied to its nearest attached vertices by their rest geodesic distance,
//! measured by a multi-source Dijkstra over the mesh edges and quad cross diagonals.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use glam::Vec3;

use crate::error::ClothError;

/// Two triangles make a quad only if its diagonals differ by at most this ratio (a square's
/// are equal, a 60° rhombus's 0.58; sewn armholes squash a few quads far below that).
pub const MIN_QUAD_DIAGONAL_RATIO: f32 = 0.3;

/// The largest vertex count the solver addresses (indices are `u32`).
pub const MAX_VERTICES: usize = u32::MAX as usize - 1;

/// A validated triangle mesh in metres.
#[derive(Debug, Clone, PartialEq)]
pub struct ClothMesh {
    positions: Vec<Vec3>,
    triangles: Vec<[u32; 3]>,
}

/// Two triangles of the quad `[a, b, c, d]` (counter-clockwise), split along `a-c` or, for
/// alternate quads, along `b-d` (a grid without a preferred diagonal).
fn push_quad(triangles: &mut Vec<[u32; 3]>, [a, b, c, d]: [u32; 4], along_ac: bool) {
    if along_ac {
        triangles.push([a, b, c]);
        triangles.push([a, c, d]);
    } else {
        triangles.push([a, b, d]);
        triangles.push([b, c, d]);
    }
}

impl ClothMesh {
    /// Validates and wraps a mesh: at least one triangle, finite positions, indices in range,
    /// no repeated vertex in a triangle and no zero-area triangle.
    pub fn new(positions: Vec<Vec3>, triangles: Vec<[u32; 3]>) -> Result<Self, ClothError> {
        if positions.is_empty() || triangles.is_empty() {
            return Err(ClothError::EmptyMesh {
                vertices: positions.len(),
                triangles: triangles.len(),
            });
        }
        if positions.len() > MAX_VERTICES {
            return Err(ClothError::TooManyVertices {
                count: positions.len(),
                max: MAX_VERTICES,
            });
        }
        for (index, p) in positions.iter().enumerate() {
            if !p.is_finite() {
                return Err(ClothError::NonFiniteVertex {
                    index,
                    value: p.to_array(),
                });
            }
        }
        for (t, tri) in triangles.iter().enumerate() {
            for (k, &v) in tri.iter().enumerate() {
                if v as usize >= positions.len() {
                    return Err(ClothError::IndexOutOfRange {
                        triangle: t,
                        vertex: v,
                        vertex_count: positions.len(),
                    });
                }
                if tri[(k + 1) % 3] == v {
                    return Err(ClothError::RepeatedVertex {
                        triangle: t,
                        vertex: v,
                    });
                }
            }
            let [a, b, c] = tri.map(|v| positions[v as usize]);
            let doubled = (b - a).cross(c - a).length();
            let scale = (b - a).length_squared().max((c - a).length_squared());
            if doubled.is_nan() || doubled <= 1e-7 * scale || doubled == 0.0 {
                return Err(ClothError::DegenerateTriangle {
                    triangle: t,
                    area_m2: 0.5 * doubled,
                });
            }
        }
        Ok(Self {
            positions,
            triangles,
        })
    }

    /// A rectangular grid spanned by `u` and `v` from `origin`, with `cells_u × cells_v` quads,
    /// each split into two triangles (the diagonal alternates like a checkerboard).
    ///
    /// Vertex `(i, j)` (`i` along `u`, `j` along `v`) has index `j * (cells_u + 1) + i` and
    /// lies at `origin + u * i / cells_u + v * j / cells_v`.
    pub fn grid(
        origin: Vec3,
        u: Vec3,
        v: Vec3,
        cells_u: u32,
        cells_v: u32,
    ) -> Result<Self, ClothError> {
        check_cells("grid cells along u", cells_u)?;
        check_cells("grid cells along v", cells_v)?;
        let nu = cells_u + 1;
        let mut positions = Vec::with_capacity((nu * (cells_v + 1)) as usize);
        for j in 0..=cells_v {
            for i in 0..=cells_u {
                positions.push(
                    origin + u * (i as f32 / cells_u as f32) + v * (j as f32 / cells_v as f32),
                );
            }
        }
        let mut triangles = Vec::with_capacity((2 * cells_u * cells_v) as usize);
        for j in 0..cells_v {
            for i in 0..cells_u {
                let a = j * nu + i;
                push_quad(
                    &mut triangles,
                    [a, a + 1, a + nu + 1, a + nu],
                    (i + j) % 2 == 0,
                );
            }
        }
        Self::new(positions, triangles)
    }

    /// An open cylinder (a straight skirt or a sleeve) around the +Y axis through
    /// `base_center`: `around` vertices per ring, `rows + 1` rings from `base_center.y` to
    /// `base_center.y + height`. Vertex `(i, j)` (`i` around, `j` up) has index
    /// `j * around + i`; the top ring is [`Self::cylinder_ring`]`(around, rows)`.
    pub fn cylinder(
        base_center: Vec3,
        radius: f32,
        height: f32,
        around: u32,
        rows: u32,
    ) -> Result<Self, ClothError> {
        crate::error::positive("cylinder radius", radius)?;
        crate::error::positive("cylinder height", height)?;
        if around < 3 {
            return Err(ClothError::InvalidParameter {
                what: "cylinder vertices around",
                requirement: "at least 3",
                value: around as f64,
            });
        }
        check_cells("cylinder rows", rows)?;
        let mut positions = Vec::with_capacity((around * (rows + 1)) as usize);
        for j in 0..=rows {
            for i in 0..around {
                let angle = std::f32::consts::TAU * i as f32 / around as f32;
                positions.push(
                    base_center
                        + Vec3::new(
                            radius * angle.cos(),
                            height * j as f32 / rows as f32,
                            radius * angle.sin(),
                        ),
                );
            }
        }
        let mut triangles = Vec::with_capacity((2 * around * rows) as usize);
        for j in 0..rows {
            for i in 0..around {
                let i1 = (i + 1) % around;
                let quad = [
                    j * around + i,
                    j * around + i1,
                    (j + 1) * around + i1,
                    (j + 1) * around + i,
                ];
                push_quad(&mut triangles, quad, (i + j) % 2 == 0);
            }
        }
        Self::new(positions, triangles)
    }

    /// The vertex indices of ring `row` of a mesh made by [`Self::cylinder`].
    pub fn cylinder_ring(around: u32, row: u32) -> std::ops::Range<u32> {
        row * around..(row + 1) * around
    }

    /// Vertex positions, metres.
    pub fn positions(&self) -> &[Vec3] {
        &self.positions
    }

    /// Triangles as vertex index triples.
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    /// Number of vertices.
    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }

    /// Area of each triangle, m².
    pub fn triangle_areas(&self) -> Vec<f32> {
        self.triangles
            .iter()
            .map(|t| triangle_area(&self.positions, *t))
            .collect()
    }

    /// Lumped vertex masses, kg: each triangle's area × `areal_density_kg_m2`, a third to each
    /// corner.
    pub fn vertex_masses(&self, areal_density_kg_m2: f32) -> Vec<f32> {
        let mut masses = vec![0.0f32; self.positions.len()];
        for tri in &self.triangles {
            let third = triangle_area(&self.positions, *tri) * areal_density_kg_m2 / 3.0;
            for &v in tri {
                masses[v as usize] += third;
            }
        }
        masses
    }
}

fn check_cells(what: &'static str, cells: u32) -> Result<(), ClothError> {
    if cells == 0 || cells > 1 << 15 {
        return Err(ClothError::InvalidParameter {
            what,
            requirement: "between 1 and 32768",
            value: cells as f64,
        });
    }
    Ok(())
}

fn triangle_area(positions: &[Vec3], [a, b, c]: [u32; 3]) -> f32 {
    let (a, b, c) = (
        positions[a as usize],
        positions[b as usize],
        positions[c as usize],
    );
    0.5 * (b - a).cross(c - a).length()
}

/// A distance constraint stencil: two vertices, their rest distance and the membrane area the
/// segment stands for.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DistanceStencil {
    /// The two vertices.
    pub vertices: [u32; 2],
    /// Rest distance, metres.
    pub rest_length: f32,
    /// Membrane area this segment represents, m² (see [`crate::fabric`]).
    pub area: f32,
}

/// A tether: a free vertex may not be farther from an attached vertex than `rest_length`
/// (times the solver's tether scale).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tether {
    /// The free vertex.
    pub vertex: u32,
    /// The attached vertex it is tied to.
    pub anchor: u32,
    /// Rest geodesic distance between them, metres.
    pub rest_length: f32,
}

/// Constraint stencils derived from a [`ClothMesh`] (see the module documentation).
#[derive(Debug, Clone, PartialEq)]
pub struct MeshTopology {
    /// Stretch constraints: the mesh edges that are not quad diagonals.
    pub stretch: Vec<DistanceStencil>,
    /// Shear constraints: both diagonals of each detected quad.
    pub shear: Vec<DistanceStencil>,
    /// Bending stencils `[e0, e1, opposite A, opposite B]` over interior manifold edges.
    pub bending: Vec<[u32; 4]>,
    /// Number of triangle pairs read as quads.
    pub quad_count: usize,
}

impl MeshTopology {
    /// Derives stretch, shear and bending stencils from `mesh`.
    pub fn new(mesh: &ClothMesh) -> Self {
        let positions = &mesh.positions;
        let triangles = &mesh.triangles;
        // Half-edges sorted by (min vertex, max vertex, triangle): a deterministic edge list
        // (no hash map iteration order).
        let mut half: Vec<(u32, u32, u32, u32)> = Vec::with_capacity(triangles.len() * 3);
        for (t, tri) in triangles.iter().enumerate() {
            for k in 0..3 {
                let a = tri[k];
                let b = tri[(k + 1) % 3];
                let opposite = tri[(k + 2) % 3];
                half.push((a.min(b), a.max(b), t as u32, opposite));
            }
        }
        half.sort_unstable();

        let length = |a: u32, b: u32| (positions[a as usize] - positions[b as usize]).length();
        // The strictly longest edge of each triangle, if any.
        let longest: Vec<Option<(u32, u32)>> = triangles
            .iter()
            .map(|tri| {
                let mut lens = [(0.0f32, 0u32, 0u32); 3];
                for k in 0..3 {
                    let (a, b) = (tri[k], tri[(k + 1) % 3]);
                    lens[k] = (length(a, b), a.min(b), a.max(b));
                }
                lens.sort_by(|x, y| y.0.total_cmp(&x.0));
                (lens[0].0 > lens[1].0 * (1.0 + 1e-3)).then_some((lens[0].1, lens[0].2))
            })
            .collect();
        let areas = mesh.triangle_areas();

        struct Edge {
            a: u32,
            b: u32,
            tris: Vec<(u32, u32)>,
        }
        let mut edges: Vec<Edge> = Vec::with_capacity(half.len() / 2 + 1);
        for &(a, b, t, opposite) in &half {
            match edges.last_mut() {
                Some(e) if e.a == a && e.b == b => e.tris.push((t, opposite)),
                _ => edges.push(Edge {
                    a,
                    b,
                    tris: vec![(t, opposite)],
                }),
            }
        }

        // Pair triangles into quads.
        let mut quad_of = vec![u32::MAX; triangles.len()];
        let mut diagonal = vec![false; edges.len()];
        let mut quad_count = 0usize;
        for (e, edge) in edges.iter().enumerate() {
            if let [(t0, o0), (t1, o1)] = edge.tris[..] {
                let key = Some((edge.a, edge.b));
                // Not a sliver rhombus: its short diagonal would be a needle-short, stiff shear
                // constraint across a squashed patch.
                let shaped = length(o0, o1) >= MIN_QUAD_DIAGONAL_RATIO * length(edge.a, edge.b);
                if longest[t0 as usize] == key && longest[t1 as usize] == key && shaped {
                    quad_of[t0 as usize] = t1;
                    quad_of[t1 as usize] = t0;
                    diagonal[e] = true;
                    quad_count += 1;
                }
            }
        }
        // Membrane area per edge: a quad gives half its area to each of its 4 edges' direction
        // pairs (area / 2 per edge), a lone triangle its whole area (see `crate::fabric`).
        let face_share = |t: u32| -> f32 {
            let pair = quad_of[t as usize];
            if pair == u32::MAX {
                areas[t as usize]
            } else {
                0.5 * (areas[t as usize] + areas[pair as usize])
            }
        };

        let mut stretch = Vec::new();
        let mut shear = Vec::new();
        let mut bending = Vec::new();
        for (e, edge) in edges.iter().enumerate() {
            let rest_length = length(edge.a, edge.b);
            if diagonal[e] {
                let [(t0, o0), (t1, o1)] = [edge.tris[0], edge.tris[1]];
                let quad_area = areas[t0 as usize] + areas[t1 as usize];
                shear.push(DistanceStencil {
                    vertices: [edge.a, edge.b],
                    rest_length,
                    area: 2.0 * quad_area,
                });
                if o0 != o1 && !is_edge(&half, o0, o1) {
                    shear.push(DistanceStencil {
                        vertices: [o0.min(o1), o0.max(o1)],
                        rest_length: length(o0, o1),
                        area: 2.0 * quad_area,
                    });
                }
            } else {
                let area = edge.tris.iter().map(|&(t, _)| face_share(t)).sum::<f32>();
                stretch.push(DistanceStencil {
                    vertices: [edge.a, edge.b],
                    rest_length,
                    area,
                });
            }
            if let [(_, o0), (_, o1)] = edge.tris[..]
                && o0 != o1
            {
                bending.push([edge.a, edge.b, o0, o1]);
            }
        }
        Self {
            stretch,
            shear,
            bending,
            quad_count,
        }
    }

    /// Long-range attachments (Kim et al. 2012): each vertex that is not attached is tied to
    /// up to `per_vertex` nearest attached vertices by rest geodesic distance (Dijkstra over
    /// stretch and shear segments, so quad cross diagonals shorten zig-zag paths).
    /// Vertices with no path to an attachment get no tether.
    pub fn tethers(&self, vertex_count: usize, attached: &[u32], per_vertex: usize) -> Vec<Tether> {
        if per_vertex == 0 || attached.is_empty() {
            return Vec::new();
        }
        // CSR adjacency.
        let mut degree = vec![0u32; vertex_count + 1];
        let segments = self.stretch.iter().chain(self.shear.iter());
        for s in segments.clone() {
            degree[s.vertices[0] as usize] += 1;
            degree[s.vertices[1] as usize] += 1;
        }
        let mut start = vec![0u32; vertex_count + 1];
        for v in 0..vertex_count {
            start[v + 1] = start[v] + degree[v];
        }
        let mut fill = start.clone();
        let mut neighbours = vec![(0u32, 0f32); start[vertex_count] as usize];
        for s in segments {
            let [a, b] = s.vertices;
            neighbours[fill[a as usize] as usize] = (b, s.rest_length);
            fill[a as usize] += 1;
            neighbours[fill[b as usize] as usize] = (a, s.rest_length);
            fill[b as usize] += 1;
        }

        let mut is_attached = vec![false; vertex_count];
        for &a in attached {
            is_attached[a as usize] = true;
        }
        // Settled (anchor, distance) labels per vertex, at most `per_vertex` distinct anchors.
        let mut labels: Vec<Vec<(u32, f32)>> = vec![Vec::new(); vertex_count];
        // Non-negative f32 bit patterns order like the values.
        let mut heap: BinaryHeap<Reverse<(u32, u32, u32)>> = BinaryHeap::new();
        for &a in attached {
            heap.push(Reverse((0f32.to_bits(), a, a)));
        }
        while let Some(Reverse((bits, vertex, anchor))) = heap.pop() {
            let label = &mut labels[vertex as usize];
            if label.len() >= per_vertex || label.iter().any(|&(s, _)| s == anchor) {
                continue;
            }
            let distance = f32::from_bits(bits);
            label.push((anchor, distance));
            for &(next, len) in
                &neighbours[start[vertex as usize] as usize..start[vertex as usize + 1] as usize]
            {
                if is_attached[next as usize] {
                    continue;
                }
                let l = &labels[next as usize];
                if l.len() < per_vertex && !l.iter().any(|&(s, _)| s == anchor) {
                    heap.push(Reverse(((distance + len).to_bits(), next, anchor)));
                }
            }
        }
        let mut tethers = Vec::new();
        for (vertex, label) in labels.iter().enumerate() {
            if is_attached[vertex] {
                continue;
            }
            for &(anchor, rest_length) in label {
                tethers.push(Tether {
                    vertex: vertex as u32,
                    anchor,
                    rest_length,
                });
            }
        }
        tethers
    }
}

/// Whether `a`–`b` is a mesh edge, by binary search in the sorted half-edge list.
fn is_edge(half: &[(u32, u32, u32, u32)], a: u32, b: u32) -> bool {
    let key = (a.min(b), a.max(b));
    let i = half.partition_point(|h| (h.0, h.1) < key);
    i < half.len() && (half[i].0, half[i].1) == key
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_pairs_every_cell_into_a_quad() {
        let mesh = ClothMesh::grid(Vec3::ZERO, Vec3::X, Vec3::Y, 4, 3).unwrap();
        let topo = MeshTopology::new(&mesh);
        assert_eq!(topo.quad_count, 12);
        // 4×4 horizontal + 5×3 vertical edges.
        assert_eq!(topo.stretch.len(), 4 * 4 + 5 * 3);
        assert_eq!(topo.shear.len(), 24);
        // Interior edges: all edges minus the boundary (2·4 + 2·3) ones, diagonals included.
        assert_eq!(topo.bending.len(), 31 + 12 - 14);
        // A square cell of side 0.25 × 1/3: stretch area of an interior horizontal edge is
        // two half quads.
        let cell = 0.25 * (1.0 / 3.0);
        let interior = topo.stretch.iter().find(|s| s.vertices == [6, 7]).unwrap();
        assert!((interior.area - cell).abs() < 1e-6);
    }

    #[test]
    fn a_squashed_rhombus_is_two_triangles_not_a_quad() {
        // Two triangles on a 2 cm edge; their apexes `height` either side of its middle.
        let rhombus = |height: f32| {
            let p = vec![
                Vec3::ZERO,
                Vec3::new(0.02, 0.0, 0.0),
                Vec3::new(0.01, height, 0.0),
                Vec3::new(0.01, -height, 0.0),
            ];
            MeshTopology::new(&ClothMesh::new(p, vec![[0, 1, 2], [1, 0, 3]]).unwrap())
        };
        // Diagonals 2 cm and 1.4 cm (ratio 0.7): a quad, with both shear diagonals.
        let square = rhombus(0.007);
        assert_eq!((square.quad_count, square.shear.len()), (1, 2));
        assert_eq!(square.stretch.len(), 4);
        // 2 cm and 1.4 mm (a sewn armhole's sliver): no quad, five stretch edges.
        let sliver = rhombus(0.0007);
        assert_eq!((sliver.quad_count, sliver.shear.len()), (0, 0));
        assert_eq!(sliver.stretch.len(), 5);
        assert_eq!(sliver.bending.len(), 1);
    }

    #[test]
    fn tethers_follow_the_geodesic_to_the_nearest_anchors() {
        let mesh = ClothMesh::grid(Vec3::ZERO, Vec3::X, Vec3::Y, 4, 4).unwrap();
        let topo = MeshTopology::new(&mesh);
        let tethers = topo.tethers(mesh.vertex_count(), &[0, 4], 1);
        assert_eq!(tethers.len(), 23);
        let far = tethers.iter().find(|t| t.vertex == 24).unwrap();
        // Vertex 24 is (1, 1); the nearest anchor (1, 0) is 1 m away along the edge column.
        assert_eq!(far.anchor, 4);
        assert!((far.rest_length - 1.0).abs() < 1e-5);
    }

    #[test]
    fn bad_meshes_are_refused() {
        let p = vec![Vec3::ZERO, Vec3::X, Vec3::Y];
        assert!(matches!(
            ClothMesh::new(p.clone(), vec![[0, 1, 3]]),
            Err(ClothError::IndexOutOfRange { .. })
        ));
        assert!(matches!(
            ClothMesh::new(p.clone(), vec![[0, 1, 1]]),
            Err(ClothError::RepeatedVertex { .. })
        ));
        assert!(matches!(
            ClothMesh::new(vec![Vec3::ZERO, Vec3::X, 2.0 * Vec3::X], vec![[0, 1, 2]]),
            Err(ClothError::DegenerateTriangle { .. })
        ));
        assert!(matches!(
            ClothMesh::new(vec![Vec3::NAN, Vec3::X, Vec3::Y], vec![[0, 1, 2]]),
            Err(ClothError::NonFiniteVertex { .. })
        ));
    }
}
