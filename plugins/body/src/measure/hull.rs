//! The tape measure: the convex hull of a cross-section and its perimeter, the girth of seed 002
//! (Uğur 2008, parametric bodies for virtual dressing) §4.2 (the tape bridges concavities; EN 13402
//! / ISO 8559-1 girths). The hull is a hand-written Andrew monotone chain (O(n log n)).

use glam::Vec2;

fn cross(o: Vec2, a: Vec2, b: Vec2) -> f32 {
    (a - o).perp_dot(b - o)
}

/// The convex hull of `points`, counter-clockwise, without collinear points (Andrew's
/// monotone chain).
pub fn convex_hull(points: &[Vec2]) -> Vec<Vec2> {
    let mut p: Vec<Vec2> = points.iter().copied().filter(|q| q.is_finite()).collect();
    p.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    p.dedup();
    if p.len() < 3 {
        return p;
    }
    let mut hull: Vec<Vec2> = Vec::with_capacity(p.len() + 1);
    let turns_left = |h: &[Vec2], q: Vec2| cross(h[h.len() - 2], h[h.len() - 1], q) > 0.0;
    // Lower hull left to right.
    for &q in &p {
        while hull.len() >= 2 && !turns_left(&hull, q) {
            hull.pop();
        }
        hull.push(q);
    }
    // Upper hull right to left, never popping the lower hull.
    let lower = hull.len() + 1;
    for &q in p.iter().rev().skip(1) {
        while hull.len() >= lower && !turns_left(&hull, q) {
            hull.pop();
        }
        hull.push(q);
    }
    hull.pop();
    hull
}

/// Perimeter of the convex hull of `points` (twice the length for two points, 0 for fewer).
pub fn hull_perimeter(points: &[Vec2]) -> f32 {
    let h = convex_hull(points);
    if h.len() < 2 {
        return 0.0;
    }
    (0..h.len())
        .map(|i| h[i].distance(h[(i + 1) % h.len()]))
        .sum()
}
