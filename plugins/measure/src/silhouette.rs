//! Distance outside the person's silhouette, in pixels: what pulls a body that is wider than
//! the person back inside (the surface points only say where the person is, not where they
//! are not). A two-pass chamfer transform (Borgefors 1986, 3-4 weights: within 8 % of the
//! Euclidean distance), then its gradient by central differences.

use fitroom_depth::camera::{HEIGHT, WIDTH};
use glam::Vec2;

/// Per pixel, the distance to the nearest silhouette pixel (0 inside).
#[derive(Clone, Debug)]
pub struct OutsideDistance {
    pub pixels: Vec<f32>,
}

impl OutsideDistance {
    pub fn new(mask: &[bool]) -> Self {
        const FAR: u32 = u32::MAX / 4;
        let mut d: Vec<u32> = mask.iter().map(|&m| if m { 0 } else { FAR }).collect();
        let at = |u: usize, v: usize| v * WIDTH + u;
        for v in 0..HEIGHT {
            for u in 0..WIDTH {
                let mut best = d[at(u, v)];
                if u > 0 {
                    best = best.min(d[at(u - 1, v)] + 3);
                }
                if v > 0 {
                    best = best.min(d[at(u, v - 1)] + 3);
                    if u > 0 {
                        best = best.min(d[at(u - 1, v - 1)] + 4);
                    }
                    if u + 1 < WIDTH {
                        best = best.min(d[at(u + 1, v - 1)] + 4);
                    }
                }
                d[at(u, v)] = best;
            }
        }
        for v in (0..HEIGHT).rev() {
            for u in (0..WIDTH).rev() {
                let mut best = d[at(u, v)];
                if u + 1 < WIDTH {
                    best = best.min(d[at(u + 1, v)] + 3);
                }
                if v + 1 < HEIGHT {
                    best = best.min(d[at(u, v + 1)] + 3);
                    if u + 1 < WIDTH {
                        best = best.min(d[at(u + 1, v + 1)] + 4);
                    }
                    if u > 0 {
                        best = best.min(d[at(u - 1, v + 1)] + 4);
                    }
                }
                d[at(u, v)] = best;
            }
        }
        Self {
            pixels: d.iter().map(|&x| x as f32 / 3.0).collect(),
        }
    }

    /// The distance at the pixel nearest `(u, v)` and its gradient (pixels per pixel);
    /// `None` outside the image.
    pub fn at(&self, u: f32, v: f32) -> Option<(f32, Vec2)> {
        let (iu, iv) = (u.round(), v.round());
        if !(1.0..(WIDTH - 1) as f32).contains(&iu) || !(1.0..(HEIGHT - 1) as f32).contains(&iv) {
            return None;
        }
        let (iu, iv) = (iu as usize, iv as usize);
        let d = |u: usize, v: usize| self.pixels[v * WIDTH + u];
        let g = Vec2::new(
            (d(iu + 1, iv) - d(iu - 1, iv)) * 0.5,
            (d(iu, iv + 1) - d(iu, iv - 1)) * 0.5,
        );
        Some((d(iu, iv), g))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Against the exact Euclidean distance to a disc: within the chamfer's 8 %.
    #[test]
    fn distance_outside_a_disc_is_near_euclidean() {
        let (cu, cv, r) = (320.0f32, 240.0f32, 50.0f32);
        let mask: Vec<bool> = (0..WIDTH * HEIGHT)
            .map(|i| {
                let (u, v) = ((i % WIDTH) as f32, (i / WIDTH) as f32);
                (u - cu).hypot(v - cv) <= r
            })
            .collect();
        let d = OutsideDistance::new(&mask);
        for (u, v) in [
            (420.0, 240.0),
            (320.0, 340.0),
            (400.0, 320.0),
            (330.0, 250.0),
        ] {
            let exact = ((u - cu).hypot(v - cv) - r).max(0.0);
            let (got, g) = d.at(u, v).expect("in the image");
            assert!(
                (got - exact).abs() <= 0.08 * exact + 1.0,
                "({u}, {v}): {got} vs {exact}"
            );
            if exact > 2.0 {
                // The gradient points away from the disc.
                let out = Vec2::new(u - cu, v - cv).normalize();
                assert!(g.normalize().dot(out) > 0.9, "gradient {g} at ({u}, {v})");
            }
        }
    }
}
