//! The body's skin, bone by bone, for the fit's data term: each bone's skin vertices (those it
//! or a bone without capsules below it dominates) with their normals, in the bone's rest frame,
//! binned in a dense grid. A depth point is brought into the frame of the bone it lies on and
//! matched to the nearest vertex there; the distance to that vertex's tangent plane is the
//! residual. The capsules alone put every joint where the capsule's round surface meets the
//! depth, not the body's: 2-9 cm off at the hips of a broad body, where the skin is anything
//! but round.
//!
//! Rigid per bone (no blending near the joints): a point near the elbow meets the upper arm's
//! or the forearm's skin as it stood at rest, which is what the fit moves.

use glam::Vec3;

/// Grid cell, metres (model scale).
const CELL: f32 = 0.03;

/// One bone's skin.
#[derive(Clone, Debug, Default)]
pub struct BoneSurface {
    /// Bone-frame positions and unit normals.
    pub points: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    lo: Vec3,
    dims: [usize; 3],
    /// Cell `c`'s vertices: `items[starts[c]..starts[c + 1]]`.
    starts: Vec<u32>,
    items: Vec<u32>,
}

impl BoneSurface {
    /// Bins `points` (with `normals`) of one bone, bone frame.
    pub fn new(points: Vec<Vec3>, normals: Vec<Vec3>) -> Self {
        if points.is_empty() {
            return Self::default();
        }
        let (lo, hi) = points.iter().fold(
            (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
            |(lo, hi), p| (lo.min(*p), hi.max(*p)),
        );
        let lo = lo - Vec3::splat(CELL);
        let span = ((hi - lo) / CELL).ceil() + Vec3::splat(2.0);
        let dims = [span.x as usize, span.y as usize, span.z as usize];
        let mut surface = Self {
            points,
            normals,
            lo,
            dims,
            starts: vec![0; dims[0] * dims[1] * dims[2] + 1],
            items: Vec::new(),
        };
        // Counting sort of the vertices by cell.
        let cells: Vec<usize> = surface
            .points
            .iter()
            .map(|p| surface.cell_index(*p).unwrap_or(0))
            .collect();
        for &c in &cells {
            surface.starts[c + 1] += 1;
        }
        for c in 1..surface.starts.len() {
            surface.starts[c] += surface.starts[c - 1];
        }
        let mut fill = surface.starts.clone();
        surface.items = vec![0; cells.len()];
        for (v, &c) in cells.iter().enumerate() {
            surface.items[fill[c] as usize] = v as u32;
            fill[c] += 1;
        }
        surface
    }

    fn cell(&self, p: Vec3) -> [i64; 3] {
        let c = ((p - self.lo) / CELL).floor();
        [c.x as i64, c.y as i64, c.z as i64]
    }

    fn cell_index(&self, p: Vec3) -> Option<usize> {
        let [x, y, z] = self.cell(p);
        let [dx, dy, dz] = self.dims.map(|d| d as i64);
        ((0..dx).contains(&x) && (0..dy).contains(&y) && (0..dz).contains(&z))
            .then(|| ((z * dy + y) * dx + x) as usize)
    }

    /// The vertex nearest `p` (bone frame) among those within a cell of `p`'s cell (3 to 6
    /// cm), `None` if there is none.
    pub fn nearest(&self, p: Vec3) -> Option<u32> {
        if self.points.is_empty() || !p.is_finite() {
            return None;
        }
        let [x, y, z] = self.cell(p);
        let [dx, dy, dz] = self.dims.map(|d| d as i64);
        let mut best = (f32::INFINITY, None);
        for cz in (z - 1).max(0)..=(z + 1).min(dz - 1) {
            for cy in (y - 1).max(0)..=(y + 1).min(dy - 1) {
                for cx in (x - 1).max(0)..=(x + 1).min(dx - 1) {
                    let c = ((cz * dy + cy) * dx + cx) as usize;
                    let (a, b) = (self.starts[c] as usize, self.starts[c + 1] as usize);
                    for &v in &self.items[a..b] {
                        let d = self.points[v as usize].distance_squared(p);
                        if d < best.0 {
                            best = (d, Some(v));
                        }
                    }
                }
            }
        }
        best.1
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nearest_agrees_with_brute_force_within_reach() {
        // A sphere of points; queries near it match the exhaustive search.
        let mut points = Vec::new();
        for i in 0..40 {
            for j in 0..80 {
                let (t, f) = (
                    i as f32 / 39.0 * std::f32::consts::PI,
                    j as f32 / 80.0 * std::f32::consts::TAU,
                );
                points.push(Vec3::new(t.sin() * f.cos(), t.cos(), t.sin() * f.sin()) * 0.1);
            }
        }
        let normals = points.iter().map(|p| p.normalize()).collect();
        let surface = BoneSurface::new(points.clone(), normals);
        for k in 0..200 {
            let a = k as f32 * 0.37;
            let q = Vec3::new(a.sin(), (a * 1.7).cos(), (a * 0.3).sin()).normalize()
                * (0.09 + 0.00017 * k as f32);
            let exact = points
                .iter()
                .map(|p| p.distance(q))
                .fold(f32::INFINITY, f32::min);
            let got = surface.nearest(q).map(|v| points[v as usize].distance(q));
            assert_eq!(got, Some(exact), "query {k}");
        }
        assert_eq!(surface.nearest(Vec3::splat(5.0)), None);
    }
}
