//! A CPU z-buffer rasteriser for triangle meshes in sensor space, seen by the depth camera.
//!
//! Inverse depth is linear in screen space and is stepped per pixel; the dot product of a
//! triangle's unit normal with the (unnormalised) ray `((cx - u) / fx, (cy - v) / fy, 1)` of
//! pixel `(u, v)`, which gives the surface's obliquity, is that inverse depth times the
//! plane's distance from the camera, found from the inverse depth's plane (no normal in
//! sensor space, no test per triangle but on its projection). Vertices are projected once
//! per mesh. Triangles are filled row by row, each row one span whose ends come from the
//! edge functions.
//! A mesh marked closed skips the triangles facing away from the camera.

use glam::{Vec2, Vec3, Vec4};

use super::spans::Spans;
use crate::camera::{DepthCamera, HEIGHT, PIXELS, WIDTH};

/// Triangles nearer than this are left out (the device sees nothing nearer than 0.5 m; a
/// scene has nothing there), metres.
const NEAR_M: f32 = 0.1;

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
        draw_mesh(self, camera, (positions, triangles), label, closed);
    }

    /// [`Self::draw`], inlined into each of [`draw_mesh`]'s versions.
    #[inline(always)]
    fn draw_inlined(
        &mut self,
        camera: &DepthCamera,
        (positions, triangles): (&[Vec3], &[[u32; 3]]),
        label: u8,
        closed: bool,
    ) {
        let mut projected = std::mem::take(&mut self.projected);
        projected.clear();
        // A vertex that cannot be drawn (nearer than `NEAR_M`, behind the camera, not
        // finite) projects to `NaN`: every triangle with it has a `NaN` area and is skipped,
        // with no test per triangle.
        projected.extend(positions.iter().map(|p| {
            let iz = 1.0 / p.z;
            if p.is_finite() && p.z >= NEAR_M {
                (
                    Vec2::new(
                        camera.cx - camera.fx * p.x * iz,
                        camera.cy - camera.fy * p.y * iz,
                    ),
                    iz,
                )
            } else {
                (Vec2::NAN, f32::NAN)
            }
        }));
        for t in triangles {
            let [Some(&a), Some(&b), Some(&c)] = t.map(|i| projected.get(i as usize)) else {
                continue;
            };
            self.draw_triangle(camera, [a, b, c], closed, label);
        }
        self.projected = projected;
    }

    /// Draws one projected triangle. Its signed area in pixels has the sign of `n · a` for
    /// its normal `n = (b - a) × (c - a)` and corner `a` in sensor space (the determinant
    /// of the three corners, over their positive depths; flipping both image axes keeps
    /// the sign): negative for a face turned towards the camera.
    #[inline(always)]
    fn draw_triangle(
        &mut self,
        camera: &DepthCamera,
        [(mut pa, mut iza), (mut pb, mut izb), (pc, izc)]: [(Vec2, f32); 3],
        closed: bool,
        label: u8,
    ) {
        let mut area = cross(pb - pa, pc - pa);
        // (A face turned away from the camera, of a closed mesh: its front covers it.)
        if area.is_nan() || area.abs() < 1e-9 || (closed && area > 0.0) {
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
        // (Within the image from here: every value is in 0..640.)
        let lo = Vec2::new(ceil_float(min.x.max(0.0)), ceil_float(min.y.max(0.0)));
        let hi = max.min(limit);
        let hi = Vec2::new(floor_float(hi.x), floor_float(hi.y));
        // Most of a distant body's triangles cover no pixel centre: they end here.
        if lo.x > hi.x || lo.y > hi.y {
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
        // The surface's obliquity from the same plane, without its normal in sensor space:
        // on the plane `n · X = D` (unit `n`), a pixel's ray `r` meets it at `1/z = n · r / D`,
        // so `n / D = (-fx iz_dx, -fy iz_dy, iz_base + cx iz_dx + cy iz_dy)` and
        // `|n · r| = |D| / z`: the inverse depth times the plane's distance from the camera.
        let n_over_d = Vec3::new(
            -camera.fx * iz_dx,
            -camera.fy * iz_dy,
            iz_base + camera.cx * iz_dx + camera.cy * iz_dy,
        );
        let distance = n_over_d.length_recip();
        if !distance.is_finite() {
            return;
        }
        // Row by row, the span where every edge function is above its threshold. A row meets
        // edge e at x = c0 + cy y: an edge rising along x bounds the span's start, a falling
        // one its end, and a level one the rows. Each edge gives both a start and an end, the
        // one it does not bound left at the image's far side, so that every row takes three
        // of each without a branch on which kind an edge is (that kind changes from triangle
        // to triangle: a branch on it was mispredicted for one triangle in two, measured with
        // cachegrind). Only the pixels inside are visited.
        let (mut y_lo, mut y_hi) = (lo.y, hi.y);
        let (mut starts, mut ends) = ([(f32::MIN, 0.0); 3], [(f32::MAX, 0.0); 3]);
        for (e, (base, dx, dy, t)) in edges.into_iter().enumerate() {
            let at0 = base - t;
            if dx.abs() < 1e-12 {
                // Inside where at0 + dy y >= 0.
                let (y_min, y_max) = (lo.y - 1.0, hi.y + 1.0);
                if dy > 0.0 {
                    y_lo = y_lo.max(ceil_small((-at0 / dy).clamp(y_min, y_max)) as f32);
                } else if dy < 0.0 {
                    y_hi = y_hi.min(floor_small((at0 / -dy).clamp(y_min, y_max)) as f32);
                } else if at0 < 0.0 {
                    return;
                }
            } else {
                let per_x = -1.0 / dx;
                let (c0, cy) = (at0 * per_x, dy * per_x);
                // (By arithmetic: the compiler turns a select on floats into a branch. With
                // `far` the largest float on the side away from the span, `min` and `max` keep
                // the bound an edge gives and put the other at the far side; the slope of the
                // far one is zeroed.)
                let far = f32::MAX.copysign(dx);
                let rising = f32::from(u8::from(dx > 0.0));
                starts[e] = (c0.min(far), cy * rising);
                ends[e] = (c0.max(far), cy * (1.0 - rising));
            }
        }
        if y_lo > y_hi {
            return;
        }
        let [(s0, sy0), (s1, sy1), (s2, sy2)] = starts;
        let [(e0, ey0), (e1, ey1), (e2, ey2)] = ends;
        // (Integers from here: a float's conversion to `usize` is a dozen instructions.)
        let (fx_lo, fx_hi) = (lo.x - 1.0, hi.x + 1.0);
        // The rows' pixels the triangle may touch: its box (a row's span would need a test
        // for an empty one).
        let (box_lo, box_hi) = (lo.x as i32 as usize, hi.x as i32 as usize + 1);
        let mut y = y_lo;
        for j in y_lo as i32 as usize..y_hi as i32 as usize + 1 {
            // (Kept within the box, so that the conversions see small finite numbers.)
            let x0 = larger(
                larger(lo.x, s0 + sy0 * y),
                larger(s1 + sy1 * y, s2 + sy2 * y),
            );
            let x1 = smaller(
                smaller(hi.x, e0 + ey0 * y),
                smaller(e1 + ey1 * y, e2 + ey2 * y),
            );
            let (x0, x1) = (smaller(x0, fx_hi), larger(x1, fx_lo));
            let (x0, x1) = (ceil_small(x0), floor_small(x1));
            self.touched.add(j, box_lo, box_hi);
            let iz = iz_base + iz_dy * y + iz_dx * x0 as f32;
            // (`x0` is within 0..=640: the row's first pixel or the next row's.)
            let count = (x1 - x0 + 1).max(0) as usize;
            let span = Span {
                start: j * WIDTH + x0 as usize,
                count,
                iz,
                iz_dx,
            };
            self.fill(span, distance, label);
            y += 1.0;
        }
    }

    /// Keeps the nearer of the span's surface and what is drawn, pixel by pixel. Four
    /// pixels at a time, those past the span's end masked, so that a short span (a small
    /// triangle's row: one to three pixels) and an empty one take the same path: a loop
    /// whose length changes from row to row, or a test for an empty row, is mispredicted
    /// every few rows (measured with cachegrind: a third of the rasteriser's mispredictions
    /// each). Masked pixels are written back as they were, so pixels past the row's end
    /// are left alone.
    #[inline(always)]
    fn fill(&mut self, span: Span, distance: f32, label: u8) {
        let Span {
            mut start,
            count,
            mut iz,
            iz_dx,
        } = span;
        let mut left = count;
        loop {
            let r = start..start + LANES;
            let (Some(z), Some(d), Some(l)) = (
                self.inverse_z.get_mut(r.clone()),
                self.normal_dot_ray.get_mut(r.clone()),
                self.label.get_mut(r),
            ) else {
                // The image's last pixels: one at a time.
                let end = (start + left).min(PIXELS);
                for k in start..end {
                    if iz > self.inverse_z[k] {
                        self.inverse_z[k] = iz;
                        self.normal_dot_ray[k] = iz * distance;
                        self.label[k] = label;
                    }
                    iz += iz_dx;
                }
                return;
            };
            // (glam's `Vec4` is four SSE lanes: its comparisons and selects are masks, which
            // the compiler cannot turn back into branches.)
            let (z4, d4) = (Vec4::from_slice(z), Vec4::from_slice(d));
            // (Stepped one pixel at a time, as the scalar loop does: the same depths.)
            let b = iz + iz_dx;
            let c = b + iz_dx;
            let e = c + iz_dx;
            let iz4 = Vec4::new(iz, b, c, e);
            let nearer = iz4.cmpgt(z4) & LANE.cmplt(Vec4::splat(left as f32));
            Vec4::select(nearer, iz4, z4).write_to_slice(z);
            Vec4::select(nearer, iz4 * distance, d4).write_to_slice(d);
            let keep = BYTE_MASKS[nearer.bitmask() as usize % 16];
            let old = u32::from_le_bytes([l[0], l[1], l[2], l[3]]);
            let new = (old & !keep) | ((u32::from(label) * 0x0101_0101) & keep);
            l.copy_from_slice(&new.to_le_bytes());
            iz = e + iz_dx;
            if left <= LANES {
                return;
            }
            left -= LANES;
            start += LANES;
        }
    }
}

for_this_cpu! {
/// [`DepthBuffer::draw`], in a version for this CPU (`for_this_cpu!`).
fn draw_mesh(
    buffer: &mut DepthBuffer,
    camera: &DepthCamera,
    mesh: (&[Vec3], &[[u32; 3]]),
    label: u8,
    closed: bool,
) {
    buffer.draw_inlined(camera, mesh, label, closed);
}
}

/// Pixels [`DepthBuffer::fill`] takes at a time.
const LANES: usize = 4;

/// Each lane's index.
const LANE: Vec4 = Vec4::new(0.0, 1.0, 2.0, 3.0);

/// Per 4-bit lane mask, the bytes of the lanes set.
const BYTE_MASKS: [u32; 16] = {
    let mut masks = [0u32; 16];
    let mut m = 0;
    while m < 16 {
        let mut lane = 0;
        while lane < 4 {
            if m & (1 << lane) != 0 {
                masks[m] |= 0xff << (8 * lane);
            }
            lane += 1;
        }
        m += 1;
    }
    masks
};

/// A row's pixels inside a triangle: `count` from pixel `start` on, whose inverse depth is
/// `iz` and steps by `iz_dx`.
struct Span {
    start: usize,
    count: usize,
    iz: f32,
    iz_dx: f32,
}

/// The smaller of two numbers that are not `NaN` (the span's bounds, from finite corners):
/// one instruction, where `f32::min`, which must return the other of a `NaN` and a number,
/// takes three.
#[inline(always)]
fn smaller(a: f32, b: f32) -> f32 {
    if a < b { a } else { b }
}

/// The larger of two numbers that are not `NaN`.
#[inline(always)]
fn larger(a: f32, b: f32) -> f32 {
    if a > b { a } else { b }
}

/// `ceil(x)` for `|x|` below 2^31 (`f32::ceil` and `floor` are library calls on baseline
/// x86-64).
#[inline]
fn ceil_small(x: f32) -> i32 {
    let t = x as i32;
    t + i32::from((t as f32) < x)
}

/// `floor(x)` for `|x|` below 2^31.
#[inline]
fn floor_small(x: f32) -> i32 {
    let t = x as i32;
    t - i32::from((t as f32) > x)
}

/// `ceil(x)` for `|x|` below 2^22, without leaving floating point (a conversion to an
/// integer and back is several instructions, four per triangle's box).
#[inline]
fn ceil_float(x: f32) -> f32 {
    let r = round_float(x);
    r + if r < x { 1.0 } else { 0.0 }
}

/// `floor(x)` for `|x|` below 2^22.
#[inline]
fn floor_float(x: f32) -> f32 {
    let r = round_float(x);
    r - if r > x { 1.0 } else { 0.0 }
}

/// `x` rounded to the nearest integer (ties to even) for `|x|` below 2^22: once 1.5 · 2^23
/// is added, no bit of the sum is below the units.
#[inline]
fn round_float(x: f32) -> f32 {
    const MAGIC: f32 = 12_582_912.0;
    (x + MAGIC) - MAGIC
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

    /// A plane over the whole image, nearer than one drawn before only on the image's right
    /// half: every pixel is drawn, to the image's last (the four-pixel fill's tail there),
    /// and the nearer surface is kept on each side, to the column.
    #[test]
    fn every_pixel_to_the_last_and_the_nearer_surface_kept() {
        let camera = DepthCamera::default();
        let plane = |z_left: f32, z_right: f32| {
            let (l, r) = (-0.5, WIDTH as f32 - 0.5);
            let (t, b) = (-0.5, HEIGHT as f32 - 0.5);
            [
                camera.unproject(l, t, z_left),
                camera.unproject(r, t, z_right),
                camera.unproject(r, b, z_right),
                camera.unproject(l, b, z_left),
            ]
        };
        let quad = [[0, 1, 2], [0, 2, 3]];
        let mut buffer = DepthBuffer::default();
        buffer.draw(&camera, &plane(2.0, 2.0), &quad, 1, false);
        // Tilted: from 3 m on the left to 1 m on the right; inverse depth is linear across
        // the image, so it is at 2 m a quarter of the way (column 159.5).
        buffer.draw(&camera, &plane(3.0, 1.0), &quad, 2, false);
        assert!(buffer.label.iter().all(|&l| l != 0));
        assert_eq!(buffer.label[PIXELS - 1], 2);
        for j in [0, HEIGHT / 2, HEIGHT - 1] {
            for i in 0..WIDTH {
                let k = j * WIDTH + i;
                let tilted = 1.0 / buffer.inverse_z[k] < 2.0;
                let expected = if tilted { 2 } else { 1 };
                assert_eq!(buffer.label[k], expected, "({i}, {j})");
                assert_eq!(tilted, (i as f32) > WIDTH as f32 / 4.0 - 0.5, "({i}, {j})");
            }
        }
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
