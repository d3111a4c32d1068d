//! The person's silhouette as a field of nearest person pixels, so the fit can pull a part of
//! the model that strays outside the silhouette back towards it (the free-space term of
//! Ganapathi et al. 2012: where the camera sees past the model, the body is not).
//!
//! Computed at half resolution by two raster passes that carry each cell's nearest site
//! (Danielsson's vector propagation, as in 8SSEDT): exact for almost every cell, off by a
//! fraction of a cell for a few; the fit needs a direction and a distance, not a metric proof.

use fitroom_depth::{HEIGHT, WIDTH};

/// Cell size, pixels.
pub const STEP: usize = 2;
const W: usize = WIDTH / STEP;
const H: usize = HEIGHT / STEP;

/// Margin around the person's box within which the field is computed, cells: a part of the
/// model farther out than this is pulled towards the box's edge first.
const MARGIN: usize = 32;

/// Per half-resolution cell of the person's box (plus [`MARGIN`]), the nearest cell on the
/// person.
#[derive(Clone, Debug, Default)]
pub struct Silhouette {
    /// The computed region, cells: first column, first row, width, height.
    region: [usize; 4],
    /// Per region cell, the nearest site's cell coordinates (`NONE` in the first: none).
    nearest: Vec<[u16; 2]>,
}

const NONE: u16 = u16::MAX;

impl Silhouette {
    /// Recomputes the field for `mask` (full resolution, row-major) around `bbox` (pixels:
    /// first column, first row, last column, last row).
    pub fn update(&mut self, mask: &[bool], bbox: [u16; 4]) {
        let x0 = (usize::from(bbox[0]) / STEP).saturating_sub(MARGIN);
        let y0 = (usize::from(bbox[1]) / STEP).saturating_sub(MARGIN);
        let x1 = (usize::from(bbox[2]) / STEP + MARGIN).min(W - 1);
        let y1 = (usize::from(bbox[3]) / STEP + MARGIN).min(H - 1);
        let (w, h) = ((x1 + 1).saturating_sub(x0), (y1 + 1).saturating_sub(y0));
        self.region = [x0, y0, w, h];
        self.nearest.clear();
        self.nearest.resize(w * h, [NONE, NONE]);
        for y in 0..h {
            for x in 0..w {
                let k = (y0 + y) * STEP * WIDTH + (x0 + x) * STEP;
                if mask.get(k).copied().unwrap_or(false) {
                    self.nearest[y * w + x] = [x as u16, y as u16];
                }
            }
        }
        let nearest = &mut self.nearest;
        // Carries the neighbour's site to `c` when it is nearer than `c`'s own.
        let relax = |nearest: &mut Vec<[u16; 2]>, c: usize, other: usize, x: usize, y: usize| {
            let site = nearest[other];
            if site[0] == NONE {
                return;
            }
            let d2 = |s: [u16; 2]| {
                let (dx, dy) = (i32::from(s[0]) - x as i32, i32::from(s[1]) - y as i32);
                dx * dx + dy * dy
            };
            let mine = nearest[c];
            if mine[0] == NONE || d2(site) < d2(mine) {
                nearest[c] = site;
            }
        };
        for y in 0..h {
            for x in 0..w {
                let c = y * w + x;
                if x > 0 {
                    relax(nearest, c, c - 1, x, y);
                }
                if y > 0 {
                    relax(nearest, c, c - w, x, y);
                    if x > 0 {
                        relax(nearest, c, c - w - 1, x, y);
                    }
                    if x + 1 < w {
                        relax(nearest, c, c - w + 1, x, y);
                    }
                }
            }
            for x in (0..w.saturating_sub(1)).rev() {
                relax(nearest, y * w + x, y * w + x + 1, x, y);
            }
        }
        for y in (0..h).rev() {
            for x in (0..w).rev() {
                let c = y * w + x;
                if x + 1 < w {
                    relax(nearest, c, c + 1, x, y);
                }
                if y + 1 < h {
                    relax(nearest, c, c + w, x, y);
                    if x + 1 < w {
                        relax(nearest, c, c + w + 1, x, y);
                    }
                    if x > 0 {
                        relax(nearest, c, c + w - 1, x, y);
                    }
                }
            }
            for x in 1..w {
                relax(nearest, y * w + x, y * w + x - 1, x, y);
            }
        }
    }

    /// The nearest person pixel to pixel `(u, v)` (full resolution; outside the computed
    /// region, from the region's nearest cell), `None` when the mask was empty.
    pub fn nearest(&self, u: f32, v: f32) -> Option<[f32; 2]> {
        let [x0, y0, w, h] = self.region;
        if w == 0 || h == 0 || !(u.is_finite() && v.is_finite()) {
            return None;
        }
        let x = ((u.max(0.0) as usize) / STEP).clamp(x0, x0 + w - 1) - x0;
        let y = ((v.max(0.0) as usize) / STEP).clamp(y0, y0 + h - 1) - y0;
        let site = *self.nearest.get(y * w + x)?;
        (site[0] != NONE).then(|| {
            [
                ((x0 + usize::from(site[0])) * STEP) as f32,
                ((y0 + usize::from(site[1])) * STEP) as f32,
            ]
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nearest_site_matches_brute_force() {
        // A ring and a blob: compare every cell's distance with the exhaustive search.
        let mut mask = vec![false; WIDTH * HEIGHT];
        let mut sites = Vec::new();
        for y in 0..HEIGHT {
            for x in 0..WIDTH {
                let (dx, dy) = (x as f32 - 300.0, y as f32 - 200.0);
                let r = (dx * dx + dy * dy).sqrt();
                let blob = (x as f32 - 520.0).abs() < 30.0 && (y as f32 - 400.0).abs() < 50.0;
                if (80.0..90.0).contains(&r) || blob {
                    mask[y * WIDTH + x] = true;
                    if x % STEP == 0 && y % STEP == 0 {
                        sites.push([x as f32, y as f32]);
                    }
                }
            }
        }
        let mut field = Silhouette::default();
        field.update(&mask, [210, 110, 550, 450]);
        let mut worst = 0.0f32;
        // Within the region computed (the box and its margin).
        for y in (110 - 2 * MARGIN..HEIGHT).step_by(7) {
            for x in (210 - 2 * MARGIN..(550 + 2 * MARGIN).min(WIDTH)).step_by(5) {
                let p = [(x / STEP * STEP) as f32, (y / STEP * STEP) as f32];
                let exact = sites
                    .iter()
                    .map(|s| ((s[0] - p[0]).powi(2) + (s[1] - p[1]).powi(2)).sqrt())
                    .fold(f32::INFINITY, f32::min);
                let got = field.nearest(x as f32, y as f32).expect("a site");
                let d = ((got[0] - p[0]).powi(2) + (got[1] - p[1]).powi(2)).sqrt();
                worst = worst.max(d - exact);
            }
        }
        assert!(worst < 3.0, "worst excess {worst} px");
        field.update(&vec![false; WIDTH * HEIGHT], [0, 0, 639, 479]);
        assert_eq!(field.nearest(10.0, 10.0), None);
    }
}
