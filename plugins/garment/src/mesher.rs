//! The panel mesher: a constrained Delaunay triangulation of the panel's resampled outline,
//! refined (Ruppert's algorithm as implemented by the `spade` crate) until every triangle is
//! below the area of an equilateral triangle of the target edge and no angle is below 30°
//! where the boundary allows, then smoothed (Laplacian, interior vertices only, each move kept
//! only if no incident triangle gets worse than the mesh's minimum angle).
//!
//! The boundary vertices are never moved nor split (`keep_constraint_edges`): they are the
//! resampled edge points that seams match one to one.

use glam::Vec2;
use spade::handles::FixedVertexHandle;
use spade::{
    AngleLimit, ConstrainedDelaunayTriangulation, Point2, RefinementParameters, Triangulation,
};

/// A triangulated panel in its 2D pattern plane.
#[derive(Clone, Debug, PartialEq)]
pub struct PanelMesh {
    /// Vertices, cm: the boundary points first, in the order given, then interior points.
    pub vertices: Vec<Vec2>,
    /// Counter-clockwise triangles.
    pub triangles: Vec<[u32; 3]>,
    /// Number of boundary vertices (the first ones).
    pub boundary_count: usize,
}

/// Why a panel could not be meshed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum MeshError {
    #[error("the outline has {0} points after resampling; at least 3 are needed")]
    TooFewPoints(usize),
    #[error("outline point {index} ({x}, {y}) cannot be triangulated: {reason}")]
    BadPoint {
        index: usize,
        x: f32,
        y: f32,
        reason: String,
    },
    #[error(
        "outline points {0} and {1} coincide after resampling; lengthen the short edge or lower target_edge_cm"
    )]
    Coincident(usize, usize),
    #[error(
        "the resampled outline crosses itself at segment {0}; the panel is too thin for the target edge length"
    )]
    SelfCrossing(usize),
    #[error("the triangulation has no triangle inside the outline")]
    Empty,
}

/// Resamples a polyline into `segments` pieces of equal arc length (both end points kept).
pub fn resample_polyline(points: &[Vec2], segments: usize) -> Vec<Vec2> {
    let segments = segments.max(1);
    let mut cumulative = Vec::with_capacity(points.len());
    let mut total = 0.0;
    cumulative.push(0.0);
    for w in points.windows(2) {
        total += w[0].distance(w[1]);
        cumulative.push(total);
    }
    let mut out = Vec::with_capacity(segments + 1);
    let mut k = 0;
    for i in 0..=segments {
        let s = total * i as f32 / segments as f32;
        while k + 2 < cumulative.len() && cumulative[k + 1] < s {
            k += 1;
        }
        let (s0, s1) = (cumulative[k], cumulative[(k + 1).min(cumulative.len() - 1)]);
        let t = if s1 > s0 {
            ((s - s0) / (s1 - s0)).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let a = points[k];
        let b = points[(k + 1).min(points.len() - 1)];
        out.push(a.lerp(b, t));
    }
    if let (Some(first), Some(last)) = (points.first(), points.last()) {
        out[0] = *first;
        out[segments] = *last;
    }
    out
}

/// Length of a polyline.
pub fn polyline_length(points: &[Vec2]) -> f32 {
    points.windows(2).map(|w| w[0].distance(w[1])).sum()
}

/// Triangulates the simple polygon `boundary` (counter-clockwise, cm, not closed: the last
/// point joins the first) with interior points at about `target_edge` spacing.
pub fn mesh_polygon(boundary: &[Vec2], target_edge: f32) -> Result<PanelMesh, MeshError> {
    let n = boundary.len();
    if n < 3 {
        return Err(MeshError::TooFewPoints(n));
    }
    for i in 0..n {
        let j = (i + 1) % n;
        if boundary[i].distance(boundary[j]) < 1e-3 * target_edge.max(1e-3) {
            return Err(MeshError::Coincident(i, j));
        }
    }
    if let Some(i) = crossing_segment(boundary) {
        return Err(MeshError::SelfCrossing(i));
    }
    let mut cdt: ConstrainedDelaunayTriangulation<Point2<f64>> =
        ConstrainedDelaunayTriangulation::new();
    let mut handles: Vec<FixedVertexHandle> = Vec::with_capacity(n);
    for (index, p) in boundary.iter().enumerate() {
        let h = cdt
            .insert(Point2::new(p.x as f64, p.y as f64))
            .map_err(|e| MeshError::BadPoint {
                index,
                x: p.x,
                y: p.y,
                reason: format!("{e:?}"),
            })?;
        if handles.contains(&h) {
            return Err(MeshError::Coincident(
                handles.iter().position(|&x| x == h).unwrap_or(0),
                index,
            ));
        }
        handles.push(h);
    }
    for i in 0..n {
        let added = cdt.try_add_constraint(handles[i], handles[(i + 1) % n]);
        if added.is_empty() {
            return Err(MeshError::SelfCrossing(i));
        }
    }
    let h = target_edge as f64;
    let equilateral = 3f64.sqrt() / 4.0 * h * h;
    let params = RefinementParameters::<f64>::new()
        .exclude_outer_faces(true)
        .keep_constraint_edges()
        .with_angle_limit(AngleLimit::from_deg(30.0))
        .with_max_allowed_area(1.2 * equilateral)
        .with_min_required_area(0.02 * equilateral)
        .with_max_additional_vertices(200_000);
    let result = cdt.refine(params);
    let excluded: std::collections::HashSet<usize> =
        result.excluded_faces.iter().map(|f| f.index()).collect();

    // Vertex numbering: the boundary in order, then the Steiner points.
    let mut index_of = vec![u32::MAX; cdt.num_vertices()];
    for (i, h) in handles.iter().enumerate() {
        index_of[h.index()] = i as u32;
    }
    let mut vertices: Vec<Vec2> = boundary.to_vec();
    let mut triangles = Vec::new();
    for face in cdt.inner_faces() {
        if excluded.contains(&face.fix().index()) {
            continue;
        }
        let mut tri = [0u32; 3];
        for (k, v) in face.vertices().iter().enumerate() {
            let slot = &mut index_of[v.fix().index()];
            if *slot == u32::MAX {
                let p = v.position();
                *slot = vertices.len() as u32;
                vertices.push(Vec2::new(p.x as f32, p.y as f32));
            }
            tri[k] = *slot;
        }
        triangles.push(tri);
    }
    if triangles.is_empty() {
        return Err(MeshError::Empty);
    }
    let mut mesh = PanelMesh {
        vertices,
        triangles,
        boundary_count: n,
    };
    smooth(&mut mesh, 6);
    Ok(mesh)
}

/// Laplacian smoothing of the interior vertices: each vertex moves to the mean of its
/// neighbours unless that lowers the smallest angle of its triangles below what it was.
fn smooth(mesh: &mut PanelMesh, iterations: usize) {
    let n = mesh.vertices.len();
    let mut neighbours: Vec<Vec<u32>> = vec![Vec::new(); n];
    let mut incident: Vec<Vec<usize>> = vec![Vec::new(); n];
    for (t, tri) in mesh.triangles.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            if !neighbours[a as usize].contains(&b) {
                neighbours[a as usize].push(b);
            }
            if !neighbours[b as usize].contains(&a) {
                neighbours[b as usize].push(a);
            }
            incident[tri[k] as usize].push(t);
        }
    }
    for _ in 0..iterations {
        for v in mesh.boundary_count..n {
            if neighbours[v].is_empty() {
                continue;
            }
            let mean = neighbours[v]
                .iter()
                .map(|&u| mesh.vertices[u as usize])
                .sum::<Vec2>()
                / neighbours[v].len() as f32;
            let before = worst_angle(mesh, &incident[v]);
            let old = mesh.vertices[v];
            mesh.vertices[v] = mean;
            let after = worst_angle(mesh, &incident[v]);
            if after < before {
                mesh.vertices[v] = old;
            }
        }
    }
}

/// The smallest angle (degrees) of the listed triangles; negative if one is inverted.
fn worst_angle(mesh: &PanelMesh, triangles: &[usize]) -> f32 {
    triangles
        .iter()
        .map(|&t| {
            let [a, b, c] = mesh.triangles[t].map(|v| mesh.vertices[v as usize]);
            if (b - a).perp_dot(c - a) <= 0.0 {
                -1.0
            } else {
                triangle_min_angle_deg(a, b, c)
            }
        })
        .fold(f32::INFINITY, f32::min)
}

/// The smallest interior angle of a 2D triangle, degrees.
pub fn triangle_min_angle_deg(a: Vec2, b: Vec2, c: Vec2) -> f32 {
    let angle = |p: Vec2, q: Vec2, r: Vec2| (q - p).angle_to(r - p).abs().to_degrees();
    angle(a, b, c).min(angle(b, c, a)).min(angle(c, a, b))
}

impl PanelMesh {
    /// The smallest angle of any triangle, degrees.
    pub fn min_angle_deg(&self) -> f32 {
        self.triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|v| self.vertices[v as usize]);
                triangle_min_angle_deg(a, b, c)
            })
            .fold(f32::INFINITY, f32::min)
    }

    /// Shortest and longest edge, cm.
    pub fn edge_length_range(&self) -> (f32, f32) {
        let mut lo = f32::INFINITY;
        let mut hi: f32 = 0.0;
        for t in &self.triangles {
            for k in 0..3 {
                let l =
                    self.vertices[t[k] as usize].distance(self.vertices[t[(k + 1) % 3] as usize]);
                lo = lo.min(l);
                hi = hi.max(l);
            }
        }
        (lo, hi)
    }
}

/// The first boundary segment that crosses a non-adjacent one.
fn crossing_segment(poly: &[Vec2]) -> Option<usize> {
    let n = poly.len();
    let o = |p: Vec2, q: Vec2, r: Vec2| (q - p).perp_dot(r - p);
    for i in 0..n {
        let (a, b) = (poly[i], poly[(i + 1) % n]);
        for j in i + 2..n {
            if i == 0 && j == n - 1 {
                continue;
            }
            let (c, d) = (poly[j], poly[(j + 1) % n]);
            let (d1, d2, d3, d4) = (o(c, d, a), o(c, d, b), o(a, b, c), o(a, b, d));
            if (d1 > 0.0) != (d2 > 0.0)
                && (d3 > 0.0) != (d4 > 0.0)
                && d1 * d2 < 0.0
                && d3 * d4 < 0.0
            {
                return Some(i);
            }
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resample_keeps_ends_and_spacing() {
        let line = [Vec2::ZERO, Vec2::new(10.0, 0.0), Vec2::new(10.0, 10.0)];
        let r = resample_polyline(&line, 4);
        assert_eq!(r.len(), 5);
        assert_eq!(r[0], Vec2::ZERO);
        assert_eq!(r[4], Vec2::new(10.0, 10.0));
        assert!((r[2] - Vec2::new(10.0, 0.0)).length() < 1e-5);
    }

    #[test]
    fn square_is_well_shaped() {
        let corners = [
            Vec2::new(0.0, 0.0),
            Vec2::new(40.0, 0.0),
            Vec2::new(40.0, 30.0),
            Vec2::new(0.0, 30.0),
        ];
        let mut boundary = Vec::new();
        for i in 0..4 {
            let seg = resample_polyline(&[corners[i], corners[(i + 1) % 4]], 16);
            boundary.extend_from_slice(&seg[..16]);
        }
        let mesh = mesh_polygon(&boundary, 2.5).expect("meshes");
        assert!(mesh.min_angle_deg() >= 25.0, "{}", mesh.min_angle_deg());
        let (lo, hi) = mesh.edge_length_range();
        assert!(lo > 1.0 && hi < 4.5, "{lo} {hi}");
        let area: f32 = mesh
            .triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|v| mesh.vertices[v as usize]);
                0.5 * (b - a).perp_dot(c - a)
            })
            .sum();
        assert!((area - 1200.0).abs() < 1e-2, "{area}");
    }
}
