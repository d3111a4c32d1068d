//! Distances to the shapes the body is approximated by.

use glam::Vec3;

/// Signed distance from `p` to a round cone: the convex hull of the sphere of radius `r1`
/// at `a` and the sphere of radius `r2` at `b` (negative inside). Exact, by Quilez's
/// closed form (<https://iquilezles.org/articles/distfunctions/>); when one sphere holds the
/// other, it is the larger sphere.
///
/// The cloth solver keeps its own per-shape form of this distance (the cone's angle
/// precomputed once per step, eight particles at a time); its tests check it against this one.
pub fn round_cone_distance(p: Vec3, a: Vec3, b: Vec3, r1: f32, r2: f32) -> f32 {
    let ba = b - a;
    let l2 = ba.length_squared();
    if l2 < 1e-12 {
        return p.distance(a) - r1.max(r2);
    }
    let rr = r1 - r2;
    let a2 = l2 - rr * rr;
    let il2 = 1.0 / l2;
    let pa = p - a;
    let y = pa.dot(ba);
    let z = y - l2;
    let x = pa * l2 - ba * y;
    let x2 = x.length_squared();
    let y2 = y * y * l2;
    let z2 = z * z * l2;
    let k = rr.signum() * rr * rr * x2;
    if z.signum() * a2 * z2 > k {
        return (x2 + z2).sqrt() * il2 - r2;
    }
    if y.signum() * a2 * y2 < k {
        return (x2 + y2).sqrt() * il2 - r1;
    }
    ((x2 * a2 * il2).sqrt() + y * rr) * il2 - r1
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_cone_distance_agrees_with_sampled_spheres() {
        // A round cone is the convex hull of its two end spheres; sample it densely as spheres
        // along the axis with interpolated radii (a subset of the hull) plus the hull's tangent
        // cone: compare outside points, where the closed form is exact.
        let (a, b, r1, r2) = (
            Vec3::new(0.1, 0.2, 0.0),
            Vec3::new(0.3, -0.1, 0.2),
            0.08f32,
            0.03f32,
        );
        let mut worst = 0.0f32;
        for i in 0..400 {
            let t = i as f32 * 0.61803;
            let p = Vec3::new(t.sin() * 0.4, (t * 1.3).cos() * 0.4, (t * 0.7).sin() * 0.4)
                + (a + b) * 0.5;
            let exact = round_cone_distance(p, a, b, r1, r2);
            // Brute force: the hull distance is the max over directions of the support function
            // difference for outside points; use the sampled tangent spheres instead.
            let sampled = (0..=2000)
                .map(|k| {
                    let s = k as f32 / 2000.0;
                    // The hull's spheres: centres shifted along the axis by the taper.
                    let c = a.lerp(b, s);
                    p.distance(c) - (r1 + (r2 - r1) * s)
                })
                .fold(f32::INFINITY, f32::min);
            if exact > 0.02 {
                // The sphere sweep lies inside the hull: the exact distance is at most the sampled
                // one, and close to it for a gentle taper.
                assert!(
                    exact <= sampled + 1e-4,
                    "{p}: exact {exact} sampled {sampled}"
                );
                worst = worst.max(sampled - exact);
            }
        }
        assert!(worst < 0.01, "hull vs sphere sweep differ by {worst}");
        // Inside the axis, the distance is minus the local radius.
        let mid = round_cone_distance(a, a, b, r1, r2);
        assert!((mid + r1).abs() < 0.01, "{mid}");
    }
}
