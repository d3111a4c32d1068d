//! Plane geometry and binary-image operations on small windows: convex hull, polygon
//! area, 3x3 dilation and erosion, outer contour tracing and convexity defects (the OpenCV
//! operations seed 000's App. C names, written for our windows).

use glam::Vec2;

/// The convex hull of `points` (Andrew's monotone chain), counter-clockwise in a y-up frame
/// (clockwise on an image whose y grows downwards); collinear points dropped.
pub fn convex_hull(points: &[Vec2]) -> Vec<Vec2> {
    let idx = hull_indices(points);
    idx.into_iter().map(|i| points[i]).collect()
}

/// [`convex_hull`] as indices into `points`.
pub fn hull_indices(points: &[Vec2]) -> Vec<usize> {
    let mut order: Vec<usize> = (0..points.len()).collect();
    order.sort_by(|&a, &b| {
        points[a]
            .x
            .total_cmp(&points[b].x)
            .then(points[a].y.total_cmp(&points[b].y))
    });
    order.dedup_by(|a, b| points[*a] == points[*b]);
    if order.len() < 3 {
        return order;
    }
    let cross = |o: Vec2, a: Vec2, b: Vec2| (a - o).perp_dot(b - o);
    let mut hull: Vec<usize> = Vec::with_capacity(2 * order.len());
    for pass in 0..2 {
        let start = hull.len();
        let iter: Box<dyn Iterator<Item = &usize>> = if pass == 0 {
            Box::new(order.iter())
        } else {
            Box::new(order.iter().rev())
        };
        for &i in iter {
            while hull.len() >= start + 2
                && cross(
                    points[hull[hull.len() - 2]],
                    points[hull[hull.len() - 1]],
                    points[i],
                ) <= 0.0
            {
                hull.pop();
            }
            hull.push(i);
        }
        hull.pop();
    }
    hull
}

/// The area of a simple polygon (shoelace), always positive.
pub fn polygon_area(polygon: &[Vec2]) -> f32 {
    let n = polygon.len();
    if n < 3 {
        return 0.0;
    }
    let twice: f32 = (0..n)
        .map(|i| polygon[i].perp_dot(polygon[(i + 1) % n]))
        .sum();
    0.5 * twice.abs()
}

/// The closed polygon's perimeter.
pub fn perimeter(polygon: &[Vec2]) -> f32 {
    let n = polygon.len();
    if n < 2 {
        return 0.0;
    }
    (0..n)
        .map(|i| polygon[i].distance(polygon[(i + 1) % n]))
        .sum()
}

/// A binary image, row-major.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Binary {
    pub width: usize,
    pub height: usize,
    pub on: Vec<bool>,
}

impl Binary {
    pub fn new(width: usize, height: usize) -> Self {
        Self {
            width,
            height,
            on: vec![false; width * height],
        }
    }

    pub fn get(&self, x: i64, y: i64) -> bool {
        x >= 0
            && y >= 0
            && (x as usize) < self.width
            && (y as usize) < self.height
            && self.on[y as usize * self.width + x as usize]
    }

    pub fn count(&self) -> usize {
        self.on.iter().filter(|&&b| b).count()
    }

    /// 3x3 dilation (a pixel is on if any of its 8 neighbours or itself is).
    pub fn dilated(&self) -> Self {
        self.morph(true)
    }

    /// 3x3 erosion (a pixel stays on only if all 9 are on; outside the image is off).
    pub fn eroded(&self) -> Self {
        self.morph(false)
    }

    fn morph(&self, dilate: bool) -> Self {
        let mut out = Self::new(self.width, self.height);
        for y in 0..self.height as i64 {
            for x in 0..self.width as i64 {
                let mut any = false;
                let mut all = true;
                for dy in -1..=1 {
                    for dx in -1..=1 {
                        let b = self.get(x + dx, y + dy);
                        any |= b;
                        all &= b;
                    }
                }
                out.on[y as usize * self.width + x as usize] = if dilate { any } else { all };
            }
        }
        out
    }

    /// The outer contour (Moore-neighbour tracing, clockwise on the image) of the
    /// 8-connected component that contains the on pixel nearest `near`; empty if no pixel
    /// is on.
    pub fn outer_contour(&self, near: (i64, i64)) -> Vec<(i64, i64)> {
        // The start: the component's first pixel in raster order, so its left neighbour is
        // off. Find the component by flood fill from the nearest on pixel.
        let Some(start_px) = (0..self.on.len()).filter(|&k| self.on[k]).min_by_key(|&k| {
            let (x, y) = ((k % self.width) as i64, (k / self.width) as i64);
            (x - near.0).pow(2) + (y - near.1).pow(2)
        }) else {
            return Vec::new();
        };
        let mut comp = vec![false; self.on.len()];
        let mut stack = vec![start_px];
        comp[start_px] = true;
        while let Some(k) = stack.pop() {
            let (x, y) = ((k % self.width) as i64, (k / self.width) as i64);
            for (dx, dy) in MOORE {
                let (nx, ny) = (x + dx, y + dy);
                if self.get(nx, ny) {
                    let nk = ny as usize * self.width + nx as usize;
                    if !comp[nk] {
                        comp[nk] = true;
                        stack.push(nk);
                    }
                }
            }
        }
        let Some(first) = comp.iter().position(|&b| b) else {
            return Vec::new();
        };
        let on = |x: i64, y: i64| {
            x >= 0
                && y >= 0
                && (x as usize) < self.width
                && (y as usize) < self.height
                && comp[y as usize * self.width + x as usize]
        };
        let start = ((first % self.width) as i64, (first / self.width) as i64);
        let mut contour = vec![start];
        // We came into `start` from its left (west, direction 4 in MOORE order).
        let mut current = start;
        let mut backtrack = 4usize;
        let limit = 4 * self.on.len() + 8;
        for _ in 0..limit {
            let mut next = None;
            for step in 1..=8 {
                let d = (backtrack + step) % 8;
                let (nx, ny) = (current.0 + MOORE[d].0, current.1 + MOORE[d].1);
                if on(nx, ny) {
                    next = Some(((nx, ny), d));
                    break;
                }
            }
            let Some((p, d)) = next else {
                break; // a single pixel
            };
            if p == start && contour.len() > 1 {
                break;
            }
            contour.push(p);
            current = p;
            // Search next from the neighbour after the one we came from.
            backtrack = (d + 4) % 8;
        }
        contour
    }
}

/// The 8 neighbours in clockwise order on the image (y down), starting east.
const MOORE: [(i64, i64); 8] = [
    (1, 0),
    (1, 1),
    (0, 1),
    (-1, 1),
    (-1, 0),
    (-1, -1),
    (0, -1),
    (1, -1),
];

/// The depths of the contour's convexity defects (OpenCV's `convexityDefects`): for each
/// edge of the contour's hull, the farthest distance of the contour between the edge's ends
/// from the edge, in pixels; sorted deepest first.
pub fn convexity_defects(contour: &[(i64, i64)]) -> Vec<f32> {
    let points: Vec<Vec2> = contour
        .iter()
        .map(|&(x, y)| Vec2::new(x as f32, y as f32))
        .collect();
    let mut hull = hull_indices(&points);
    if hull.len() < 3 {
        return Vec::new();
    }
    hull.sort_unstable();
    let n = points.len();
    let mut depths = Vec::with_capacity(hull.len());
    for (k, &a) in hull.iter().enumerate() {
        let b = hull[(k + 1) % hull.len()];
        let (pa, pb) = (points[a], points[b]);
        let edge = pb - pa;
        let len = edge.length();
        if len < 1e-6 {
            continue;
        }
        let mut deepest = 0.0f32;
        let mut i = (a + 1) % n;
        while i != b {
            deepest = deepest.max((points[i] - pa).perp_dot(edge).abs() / len);
            i = (i + 1) % n;
        }
        depths.push(deepest);
    }
    depths.sort_by(|x, y| y.total_cmp(x));
    depths
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_hull_of_a_square_with_inner_points_is_its_corners() {
        let mut pts = vec![
            Vec2::new(0.0, 0.0),
            Vec2::new(4.0, 0.0),
            Vec2::new(4.0, 4.0),
            Vec2::new(0.0, 4.0),
        ];
        pts.extend([
            Vec2::new(1.0, 2.0),
            Vec2::new(2.0, 2.0),
            Vec2::new(2.0, 0.0),
        ]);
        let hull = convex_hull(&pts);
        assert_eq!(hull.len(), 4);
        assert!((polygon_area(&hull) - 16.0).abs() < 1e-5);
        assert!((perimeter(&hull) - 16.0).abs() < 1e-5);
    }

    /// A "U": two 3-wide prongs 10 high joined by a 3-high base, 9 wide. Its only deep
    /// defect is the gap between the prongs, 7 deep (10 - 3 on the pixel centres' grid).
    #[test]
    fn a_u_has_one_defect_as_deep_as_its_gap() {
        let mut img = Binary::new(13, 14);
        for y in 2..12 {
            for x in 2..11 {
                let prong = !(5..8).contains(&x);
                if prong || y >= 9 {
                    img.on[y * 13 + x] = true;
                }
            }
        }
        let contour = img.outer_contour((5, 10));
        // The outline of 9x10 box minus the gap: every contour pixel is on and borders off.
        assert!(contour.iter().all(|&(x, y)| img.get(x, y)));
        let defects = convexity_defects(&contour);
        assert!((defects[0] - 7.0).abs() < 0.01, "{defects:?}");
        assert!(defects[1] < 0.01, "{defects:?}");
        // Dilation closes the 3-wide gap from both sides to 1; erosion reopens it to 3.
        let closed = img.dilated().dilated().eroded();
        assert!(closed.count() > img.count());
    }
}
