//! A CPU z-buffer rasteriser for triangle meshes in sensor space, seen by the depth camera.
//!
//! Inverse depth is linear in screen space, and so is the dot product of a triangle's normal
//! with the (unnormalised) ray `((cx - u) / fx, (cy - v) / fy, 1)` of pixel `(u, v)`: both are
//! stepped per pixel, and the second gives the surface's obliquity without a per-pixel
//! normal. Vertices are projected once per mesh. Small triangles (most of an avatar's) are
//! filled by testing the pixels of their bounding box against the three edge functions; large
//! ones row by row, each row one span whose ends come from the edge functions.
//! A mesh marked closed skips the triangles facing away from the camera.

use glam::{Vec2, Vec3};

use super::spans::Spans;
use crate::camera::{DepthCamera, HEIGHT, PIXELS, WIDTH};

/// Triangles nearer than this are left out (the device sees nothing nearer than 0.5 m; a
/// scene has nothing there), metres.
const NEAR_M: f32 = 0.1;

/// Bounding boxes up to this many pixels wide are filled pixel by pixel.
const SMALL_WIDTH: f32 = 8.0;

/// Edge functions down to `-SLACK` (pixels along x) count as inside: the z-test decides
/// between triangles sharing an edge, and no pixel centre on a shared edge is missed.
const SLACK: f32 = 1e-4;

/// The nearest surface per pixel: its inverse depth, what it belongs to and how squarely it
/// faces the camera.
#[derive(Clone, Debug)]
pub struct DepthBuffer {
    /// `1 / z` (z along the optical axis, metres); 0 where nothing was drawn.
    pub inverse_z: Vec<f32>,
    /// The label of the mesh drawn (0 where nothing was).
    pub label: Vec<u8>,
    /// `|n · r|` for the unit normal `n` of the surface drawn and the pixel's ray
    /// `r = ((cx - u) / fx, (cy - v) / fy, 1)`; see [`Self::facing`].
    pub normal_dot_ray: Vec<f32>,
    /// Projected vertices of the mesh being drawn (pixel position, inverse depth).
    projected: Vec<(Vec2, f32)>,
    /// The pixels triangles may have been drawn into since [`Self::clear`] (each row's
    /// hull of the triangles' pixel boxes or spans): all a frame's moving meshes can change.
    pub(crate) touched: Spans,
}

impl Default for DepthBuffer {
    fn default() -> Self {
        Self {
            inverse_z: vec![0.0; PIXELS],
            label: vec![0; PIXELS],
            normal_dot_ray: vec![0.0; PIXELS],
            projected: Vec::new(),
            touched: Spans::empty(),
        }
    }
}

/// `1 / |r|²` of every pixel's ray `r` (see [`DepthBuffer::normal_dot_ray`]), row-major.
pub fn inverse_ray_length_squared(camera: &DepthCamera) -> Vec<f32> {
    let mut out = Vec::with_capacity(PIXELS);
    for j in 0..HEIGHT {
        let b = (camera.cy - j as f32) / camera.fy;
        for i in 0..WIDTH {
            let a = (camera.cx - i as f32) / camera.fx;
            out.push(1.0 / (a * a + b * b + 1.0));
        }
    }
    out
}

impl DepthBuffer {
    pub fn clear(&mut self) {
        self.inverse_z.fill(0.0);
        self.label.fill(0);
        self.touched.clear();
    }

    /// Depth at pixel `k`, metres (infinite where nothing was drawn).
    pub fn z(&self, k: usize) -> f32 {
        1.0 / self.inverse_z[k]
    }

    /// `|cos|` of the angle between the surface's normal at pixel `(i, j)` and its ray (1
    /// where nothing was drawn).
    pub fn facing(&self, camera: &DepthCamera, i: usize, j: usize) -> f32 {
        let k = j * WIDTH + i;
        if self.inverse_z[k] == 0.0 {
            return 1.0;
        }
        let ray = camera.unproject(i as f32, j as f32, 1.0);
        (self.normal_dot_ray[k] / ray.length()).min(1.0)
    }

    /// Draws `triangles` of `positions` (sensor space), keeping the nearest surface per pixel.
    /// Pixel `(i, j)` samples the scene at the continuous point `(i, j)`. With `closed`, the
    /// mesh is taken to be closed with counter-clockwise (outward) faces, and faces turned
    /// away from the camera are skipped: the front of the same mesh covers them.
    pub fn draw(
        &mut self,
        camera: &DepthCamera,
        positions: &[Vec3],
        triangles: &[[u32; 3]],
        label: u8,
        closed: bool,
    ) {
        let mut projected = std::mem::take(&mut self.projected);
        projected.clear();
        projected.extend(positions.iter().map(|p| {
            let iz = 1.0 / p.z;
            (
                Vec2::new(
                    camera.cx - camera.fx * p.x * iz,
                    camera.cy - camera.fy * p.y * iz,
                ),
                iz,
            )
        }));
        for t in triangles {
            let [Some(&a), Some(&b), Some(&c)] = t.map(|i| positions.get(i as usize)) else {
                continue;
            };
            if a.z < NEAR_M || b.z < NEAR_M || c.z < NEAR_M {
                continue;
            }
            let n = (b - a).cross(c - a);
            // Seen from the camera (at the origin), an outward face turned away has its
            // normal along the ray to it.
            if closed && n.dot(a) >= 0.0 {
                continue;
            }
            let p = t.map(|i| projected[i as usize]);
            self.draw_triangle(camera, p, n, (a + b + c).is_finite(), label);
        }
        self.projected = projected;
    }

    fn draw_triangle(
        &mut self,
        camera: &DepthCamera,
        [(mut pa, mut iza), (mut pb, mut izb), (pc, izc)]: [(Vec2, f32); 3],
        normal: Vec3,
        finite: bool,
        label: u8,
    ) {
        let mut area = cross(pb - pa, pc - pa);
        if area.is_nan() || area.abs() < 1e-9 {
            return;
        }
        // Counter-clockwise in pixel coordinates, so that inside is where every edge is ≥ 0.
        if area < 0.0 {
            std::mem::swap(&mut pa, &mut pb);
            std::mem::swap(&mut iza, &mut izb);
            area = -area;
        }
        // The pixel box, clamped to the image (`f32::ceil` and `floor` are library calls
        // on baseline x86-64; these run once per triangle, for tens of thousands).
        let (min, max) = (pa.min(pb).min(pc), pa.max(pb).max(pc));
        let limit = Vec2::new(WIDTH as f32 - 1.0, HEIGHT as f32 - 1.0);
        if max.x < 0.0 || max.y < 0.0 || min.x > limit.x || min.y > limit.y {
            return;
        }
        let lo = Vec2::new(ceil_non_negative(min.x), ceil_non_negative(min.y));
        let hi = max.min(limit);
        let hi = Vec2::new(floor_non_negative(hi.x), floor_non_negative(hi.y));
        if lo.x > hi.x || lo.y > hi.y {
            return;
        }
        // The unit normal only now: most of a distant body's triangles cover no pixel centre
        // (a square root and a division saved on each).
        let n = normal.normalize_or_zero();
        if !(n.is_finite() && finite) {
            return;
        }
        // Edge e's function at (x, y) is base + dx x + dy y, inside down to its threshold
        // (SLACK pixels along x); its weight is it over the area.
        let edges = [(pb, pc), (pc, pa), (pa, pb)].map(|(p, q)| {
            let (dx, dy) = (-(q.y - p.y), q.x - p.x);
            let threshold = if dx.abs() < 1e-12 {
                -SLACK
            } else {
                -SLACK * dx.abs()
            };
            (-(dx * p.x + dy * p.y), dx, dy, threshold)
        });
        let inv_area = 1.0 / area;
        // Inverse depth is linear: iz(x, y) = base + dx x + dy y.
        let (mut iz_base, mut iz_dx, mut iz_dy) = (0.0f32, 0.0f32, 0.0f32);
        for (e, iz) in edges.iter().zip([iza, izb, izc]) {
            iz_base += e.0 * inv_area * iz;
            iz_dx += e.1 * inv_area * iz;
            iz_dy += e.2 * inv_area * iz;
        }
        // So is the normal's dot product with the pixel's ray.
        let (d_dx, d_dy) = (-n.x / camera.fx, -n.y / camera.fy);
        let d_base = n.x * camera.cx / camera.fx + n.y * camera.cy / camera.fy + n.z;
        let (x0, x1, y0, y1) = (lo.x as usize, hi.x as usize, lo.y as usize, hi.y as usize);
        if hi.x - lo.x < SMALL_WIDTH {
            for j in y0..=y1 {
                self.touched.add(j, x0, x1 + 1);
            }
            for j in y0..=y1 {
                let y = j as f32;
                let row = j * WIDTH;
                for i in x0..=x1 {
                    let x = i as f32;
                    // Without branches: which pixels of a small triangle's box are inside is
                    // a coin toss for the branch predictor.
                    let inside = edges.iter().fold(true, |inside, &(base, dx, dy, t)| {
                        inside & (base + dx * x + dy * y >= t)
                    });
                    let k = row + i;
                    let iz = iz_base + iz_dx * x + iz_dy * y;
                    let take = inside & (iz > self.inverse_z[k]);
                    let d = (d_base + d_dx * x + d_dy * y).abs();
                    self.inverse_z[k] = if take { iz } else { self.inverse_z[k] };
                    self.label[k] = if take { label } else { self.label[k] };
                    self.normal_dot_ray[k] = if take { d } else { self.normal_dot_ray[k] };
                }
            }
            return;
        }
        for j in y0..=y1 {
            let y = j as f32;
            // The span where every edge function is above its threshold.
            let (mut x0, mut x1) = (lo.x, hi.x);
            for &(base, dx, dy, t) in &edges {
                let at_y = base + dy * y - t;
                if dx.abs() < 1e-12 {
                    if at_y < 0.0 {
                        x1 = -1.0;
                    }
                } else if dx > 0.0 {
                    x0 = x0.max((-at_y / dx).ceil());
                } else {
                    x1 = x1.min((-at_y / dx).floor());
                }
            }
            if x0 > x1 {
                continue;
            }
            self.touched.add(j, x0 as usize, x1 as usize + 1);
            let row = j * WIDTH;
            let mut iz = iz_base + iz_dy * y + iz_dx * x0;
            let mut d = d_base + d_dy * y + d_dx * x0;
            for i in x0 as usize..=x1 as usize {
                self.write(row + i, iz, label, d);
                iz += iz_dx;
                d += d_dx;
            }
        }
    }

    #[inline]
    fn write(&mut self, k: usize, iz: f32, label: u8, normal_dot_ray: f32) {
        if iz > self.inverse_z[k] {
            self.inverse_z[k] = iz;
            self.label[k] = label;
            self.normal_dot_ray[k] = normal_dot_ray.abs();
        }
    }
}

/// `ceil(max(x, 0))` for `x` below 2^31.
fn ceil_non_negative(x: f32) -> f32 {
    let x = x.max(0.0);
    let t = (x as i32) as f32;
    if t < x { t + 1.0 } else { t }
}

/// `floor(x)` for `0 <= x < 2^31`.
fn floor_non_negative(x: f32) -> f32 {
    (x as i32) as f32
}

fn cross(a: Vec2, b: Vec2) -> f32 {
    a.x * b.y - a.y * b.x
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A tilted quad drawn against its exact ray-plane intersection per pixel, and its
    /// outline against the projected corners.
    #[test]
    fn depths_are_the_exact_plane_depths_inside_the_projected_outline() {
        let camera = DepthCamera::default();
        let corners = [
            Vec3::new(0.5, -0.4, 1.8),
            Vec3::new(-0.6, -0.4, 2.6),
            Vec3::new(-0.6, 0.5, 2.6),
            Vec3::new(0.5, 0.5, 1.8),
        ];
        let mut buffer = DepthBuffer::default();
        buffer.draw(&camera, &corners, &[[0, 1, 2], [0, 2, 3]], 7, false);
        let normal = (corners[1] - corners[0])
            .cross(corners[2] - corners[0])
            .normalize();
        let mut drawn = 0;
        for j in 0..HEIGHT {
            for i in 0..WIDTH {
                let k = j * WIDTH + i;
                if buffer.label[k] == 0 {
                    continue;
                }
                drawn += 1;
                let ray = camera.unproject(i as f32, j as f32, 1.0);
                let exact = normal.dot(corners[0]) / normal.dot(ray);
                assert!((buffer.z(k) - exact).abs() < 1e-4, "({i}, {j})");
                let facing = normal.dot(ray).abs() / ray.length();
                assert!((buffer.facing(&camera, i, j) - facing).abs() < 1e-4);
            }
        }
        // Every pixel strictly inside the projected outline is drawn: count the pixels of
        // the projected quad by its area (shoelace) and compare.
        let p: Vec<Vec2> = corners
            .iter()
            .map(|&c| camera.project(c).expect("in front"))
            .collect();
        let area = 0.5
            * (0..4)
                .map(|i| cross(p[i], p[(i + 1) % 4]))
                .sum::<f32>()
                .abs();
        assert!(
            (drawn as f32 - area).abs() < 0.01 * area,
            "{drawn} vs {area}"
        );
    }

    /// The same quad cut into 40x40 small triangles (filled pixel by pixel) and into two
    /// large ones (filled span by span): the same pixels, the same depths; and closed, seen
    /// from behind, nothing.
    #[test]
    fn small_and_large_triangles_fill_alike_and_back_faces_are_culled() {
        let camera = DepthCamera::default();
        let (a, b, c) = (
            Vec3::new(0.6, -0.5, 2.0),
            Vec3::new(-0.7, -0.5, 2.9),
            Vec3::new(0.6, 0.6, 2.0),
        );
        let corner = |s: f32, t: f32| a + (b - a) * s + (c - a) * t;
        let mut large = DepthBuffer::default();
        let quad = [a, b, corner(1.0, 1.0), c];
        large.draw(&camera, &quad, &[[0, 1, 2], [0, 2, 3]], 1, false);
        let n = 40;
        let mut grid = Vec::new();
        for y in 0..=n {
            for x in 0..=n {
                grid.push(corner(x as f32 / n as f32, y as f32 / n as f32));
            }
        }
        let mut tris = Vec::new();
        for y in 0..n {
            for x in 0..n {
                let k = (y * (n + 1) + x) as u32;
                let w = n as u32 + 1;
                tris.push([k, k + 1, k + w + 1]);
                tris.push([k, k + w + 1, k + w]);
            }
        }
        let mut small = DepthBuffer::default();
        small.draw(&camera, &grid, &tris, 1, false);
        let covered = large.label.iter().filter(|&&l| l == 1).count();
        let differ = (0..PIXELS)
            .filter(|&k| large.label[k] != small.label[k])
            .count();
        assert!(covered > 50_000, "{covered}");
        // Pixel centres exactly on an edge may go either way.
        assert!(differ * 1000 < covered, "{differ} of {covered}");
        for k in (0..PIXELS).filter(|&k| large.label[k] == 1 && small.label[k] == 1) {
            assert!((large.z(k) - small.z(k)).abs() < 1e-4);
        }
        // Which way the quad faces, from its winding in the grid: culled as a closed mesh
        // when it faces away, kept when it faces the camera.
        let towards = (grid[1] - grid[0])
            .cross(grid[n + 2] - grid[0])
            .dot(grid[0])
            < 0.0;
        let mut closed = DepthBuffer::default();
        closed.draw(&camera, &grid, &tris, 1, true);
        let kept = closed.label.iter().filter(|&&l| l == 1).count();
        assert_eq!(kept > 0, towards);
        let flipped: Vec<[u32; 3]> = tris.iter().map(|t| [t[0], t[2], t[1]]).collect();
        let mut other = DepthBuffer::default();
        other.draw(&camera, &grid, &flipped, 1, true);
        let kept_flipped = other.label.iter().filter(|&&l| l == 1).count();
        assert_eq!(kept_flipped > 0, !towards);
        assert_eq!(
            kept.max(kept_flipped),
            small.label.iter().filter(|&&l| l == 1).count()
        );
    }
}
