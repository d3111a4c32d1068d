//! Geometry of panel outlines (cm, counter-clockwise polygons): signed area, simple-polygon
//! test, the horizontal extent of a row, the vertical range, and an edge's polyline.

use glam::Vec2;

use super::PanelEdge;

/// Twice-free signed area (positive counter-clockwise), cm².
pub(crate) fn signed_area(poly: &[Vec2]) -> f32 {
    let n = poly.len();
    0.5 * (0..n)
        .map(|i| poly[i].perp_dot(poly[(i + 1) % n]))
        .sum::<f32>()
}

/// The first pair of non-adjacent segments that intersect, if any.
pub(super) fn self_intersection(poly: &[Vec2]) -> Option<(usize, usize)> {
    let n = poly.len();
    for i in 0..n {
        for j in i + 1..n {
            if j == i + 1 || (i == 0 && j == n - 1) {
                continue;
            }
            let (a, b) = (poly[i], poly[(i + 1) % n]);
            let (c, d) = (poly[j], poly[(j + 1) % n]);
            if segments_intersect(a, b, c, d) {
                return Some((i, j));
            }
        }
    }
    None
}

fn segments_intersect(a: Vec2, b: Vec2, c: Vec2, d: Vec2) -> bool {
    let o = |p: Vec2, q: Vec2, r: Vec2| (q - p).perp_dot(r - p);
    let (d1, d2) = (o(c, d, a), o(c, d, b));
    let (d3, d4) = (o(a, b, c), o(a, b, d));
    ((d1 > 0.0) != (d2 > 0.0))
        && ((d3 > 0.0) != (d4 > 0.0))
        && d1 != 0.0
        && d2 != 0.0
        && d3 != 0.0
        && d4 != 0.0
}

/// The horizontal extent `(min x, max x)` of the outline at height `y` (its row), or `None`
/// when `y` is outside the outline's vertical range.
pub fn row_extent(outline: &[Vec2], y: f32) -> Option<(f32, f32)> {
    let n = outline.len();
    let mut lo = f32::INFINITY;
    let mut hi = f32::NEG_INFINITY;
    for i in 0..n {
        let (a, b) = (outline[i], outline[(i + 1) % n]);
        if y < a.y.min(b.y) || y > a.y.max(b.y) {
            continue;
        }
        if (b.y - a.y).abs() < 1e-6 {
            lo = lo.min(a.x.min(b.x));
            hi = hi.max(a.x.max(b.x));
        } else {
            let x = a.x + (b.x - a.x) * (y - a.y) / (b.y - a.y);
            lo = lo.min(x);
            hi = hi.max(x);
        }
    }
    (lo <= hi).then_some((lo, hi))
}

/// The outline's vertical range `(min y, max y)`.
pub fn y_range(outline: &[Vec2]) -> (f32, f32) {
    outline
        .iter()
        .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(p.y), hi.max(p.y))
        })
}

/// The points of an edge's polyline, from its start point to its end point inclusive.
pub fn edge_polyline(outline: &[Vec2], edge: &PanelEdge) -> Vec<Vec2> {
    let n = outline.len();
    let mut out = vec![outline[edge.start]];
    let mut k = edge.start;
    loop {
        k = (k + 1) % n;
        out.push(outline[k]);
        if k == edge.end {
            break;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn row_extent_of_a_trapezoid() {
        let poly = [
            Vec2::new(-20.0, -10.0),
            Vec2::new(20.0, -10.0),
            Vec2::new(10.0, 0.0),
            Vec2::new(-10.0, 0.0),
        ];
        assert_eq!(row_extent(&poly, -5.0), Some((-15.0, 15.0)));
        assert_eq!(row_extent(&poly, 0.0), Some((-10.0, 10.0)));
        assert_eq!(row_extent(&poly, 1.0), None);
        assert!(signed_area(&poly) > 0.0);
        assert_eq!(self_intersection(&poly), None);
    }
}
