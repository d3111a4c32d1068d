//! A CPU z-buffer rasteriser for triangle meshes in sensor space, seen by the depth camera.
//!
//! Inverse depth is linear in screen space, so each row of a triangle is one span whose
//! inverse depth grows by a constant per pixel: the span's ends come from the three edge
//! functions, and no pixel is tested against the edges one by one.

use glam::{Vec2, Vec3};

use crate::camera::{DepthCamera, HEIGHT, PIXELS, WIDTH};

/// Triangles nearer than this are left out (the device sees nothing nearer than 0.5 m; a
/// scene has nothing there), metres.
const NEAR_M: f32 = 0.1;

/// The nearest surface per pixel: its inverse depth, what it belongs to and which triangle it
/// is (for its normal).
#[derive(Clone, Debug)]
pub struct DepthBuffer {
    /// `1 / z` (z along the optical axis, metres); 0 where nothing was drawn.
    pub inverse_z: Vec<f32>,
    /// The label of the mesh drawn (0 where nothing was).
    pub label: Vec<u8>,
    /// Index into [`Self::normals`] of the triangle drawn.
    pub triangle: Vec<u32>,
    /// Unit normal of every triangle drawn since the last clear.
    pub normals: Vec<Vec3>,
}

impl Default for DepthBuffer {
    fn default() -> Self {
        Self {
            inverse_z: vec![0.0; PIXELS],
            label: vec![0; PIXELS],
            triangle: vec![0; PIXELS],
            normals: Vec::new(),
        }
    }
}

impl DepthBuffer {
    pub fn clear(&mut self) {
        self.inverse_z.fill(0.0);
        self.label.fill(0);
        self.normals.clear();
    }

    /// Depth at pixel `k`, metres (infinite where nothing was drawn).
    pub fn z(&self, k: usize) -> f32 {
        1.0 / self.inverse_z[k]
    }

    /// `|cos|` of the angle between the surface's normal at pixel `(i, j)` and its ray.
    pub fn facing(&self, camera: &DepthCamera, i: usize, j: usize) -> f32 {
        let k = j * WIDTH + i;
        if self.inverse_z[k] == 0.0 {
            return 1.0;
        }
        let ray = camera.unproject(i as f32, j as f32, 1.0);
        self.normals
            .get(self.triangle[k] as usize)
            .map_or(1.0, |n| n.dot(ray).abs() / ray.length())
    }

    /// Draws `triangles` of `positions` (sensor space), keeping the nearest surface per pixel.
    /// Pixel `(i, j)` samples the scene at the continuous point `(i, j)`.
    pub fn draw(
        &mut self,
        camera: &DepthCamera,
        positions: &[Vec3],
        triangles: &[[u32; 3]],
        label: u8,
    ) {
        for t in triangles {
            let [Some(&a), Some(&b), Some(&c)] = t.map(|i| positions.get(i as usize)) else {
                continue;
            };
            if a.z < NEAR_M || b.z < NEAR_M || c.z < NEAR_M || !(a + b + c).is_finite() {
                continue;
            }
            let id = self.normals.len() as u32;
            self.normals.push((b - a).cross(c - a).normalize_or_zero());
            self.draw_triangle(camera, [a, b, c], label, id);
        }
    }

    fn draw_triangle(&mut self, camera: &DepthCamera, [a, b, c]: [Vec3; 3], label: u8, id: u32) {
        let project = |p: Vec3| {
            Vec2::new(
                camera.cx - camera.fx * p.x / p.z,
                camera.cy - camera.fy * p.y / p.z,
            )
        };
        let (mut pa, mut pb, pc) = (project(a), project(b), project(c));
        let (mut iza, mut izb, izc) = (1.0 / a.z, 1.0 / b.z, 1.0 / c.z);
        let mut area = cross(pb - pa, pc - pa);
        if area.abs() < 1e-9 {
            return;
        }
        // Counter-clockwise in pixel coordinates, so that inside is where every edge is ≥ 0.
        if area < 0.0 {
            std::mem::swap(&mut pa, &mut pb);
            std::mem::swap(&mut iza, &mut izb);
            area = -area;
        }
        let lo = pa.min(pb).min(pc).ceil().max(Vec2::ZERO);
        let hi = pa
            .max(pb)
            .max(pc)
            .floor()
            .min(Vec2::new(WIDTH as f32 - 1.0, HEIGHT as f32 - 1.0));
        if lo.x > hi.x || lo.y > hi.y {
            return;
        }
        // Edge e's function at (x, y) is base + dx x + dy y; its weight is it over the area.
        let edges = [(pb, pc), (pc, pa), (pa, pb)].map(|(p, q)| {
            let (dx, dy) = (-(q.y - p.y), q.x - p.x);
            (-(dx * p.x + dy * p.y), dx, dy)
        });
        let inv_area = 1.0 / area;
        let izs = [iza, izb, izc];
        // Inverse depth is linear too: iz(x, y) = base + dx x + dy y.
        let (mut iz_base, mut iz_dx, mut iz_dy) = (0.0f32, 0.0f32, 0.0f32);
        for (e, iz) in edges.iter().zip(izs) {
            iz_base += e.0 * inv_area * iz;
            iz_dx += e.1 * inv_area * iz;
            iz_dy += e.2 * inv_area * iz;
        }
        for j in lo.y as usize..=hi.y as usize {
            let y = j as f32;
            // The span where every edge function is ≥ 0 (a little slack: the z-test decides
            // between triangles sharing an edge).
            let (mut x0, mut x1) = (lo.x, hi.x);
            for &(base, dx, dy) in &edges {
                let at_y = base + dy * y;
                if dx.abs() < 1e-12 {
                    if at_y < -1e-4 {
                        x1 = -1.0;
                    }
                } else if dx > 0.0 {
                    x0 = x0.max((-at_y / dx - 1e-4).ceil());
                } else {
                    x1 = x1.min((-at_y / dx + 1e-4).floor());
                }
            }
            if x0 > x1 {
                continue;
            }
            let row = j * WIDTH;
            let mut iz = iz_base + iz_dy * y + iz_dx * x0;
            for i in x0 as usize..=x1 as usize {
                let k = row + i;
                if iz > self.inverse_z[k] {
                    self.inverse_z[k] = iz;
                    self.label[k] = label;
                    self.triangle[k] = id;
                }
                iz += iz_dx;
            }
        }
    }
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
        buffer.draw(&camera, &corners, &[[0, 1, 2], [0, 2, 3]], 7);
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
}
