//! The isometric bending stencil of Bergou, Wardetzky, Harmon, Zorin and Grinspun 2006 ("A
//! quadratic bending model for inextensible surfaces"): its cotangent weights from the rest
//! shape, and the stencil's own frame, in which a curved rest shape keeps its rest value.

use glam::Vec3A;

use super::NONE;

/// An isometric bending stencil before packing.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct BendConstraint {
    pub(super) v: [u32; 4],
    pub(super) k: [f32; 4],
    pub(super) w: [f32; 4],
    pub(super) rest: [f32; 3],
    /// The distance constraints of pairs 0 (`v₀v₁`) and 1 (`v₂v₃`) solved with it (indices,
    /// or `NONE`).
    pub(super) pairs: [u32; 2],
}

pub(super) fn cot(a: glam::Vec3, b: glam::Vec3) -> f32 {
    let cross = a.cross(b).length();
    if cross < 1e-20 { 0.0 } else { a.dot(b) / cross }
}

pub(super) fn bend_stencil(
    rest: &[glam::Vec3],
    v: [u32; 4],
    w: [f32; 4],
) -> Option<BendConstraint> {
    let [x0, x1, x2, x3] = v.map(|i| rest[i as usize]);
    let e0 = x1 - x0;
    let e1 = x2 - x0;
    let e2 = x3 - x0;
    let e3 = x2 - x1;
    let e4 = x3 - x1;
    let c01 = cot(e0, e1);
    let c02 = cot(e0, e2);
    let c03 = cot(-e0, e3);
    let c04 = cot(-e0, e4);
    let a0 = 0.5 * e0.cross(e1).length();
    let a1 = 0.5 * e0.cross(e2).length();
    if a0 + a1 <= 0.0 || (a0 + a1).is_nan() {
        return None;
    }
    let scale = (3.0 / (a0 + a1)).sqrt();
    let k = [
        scale * (c03 + c04),
        scale * (c01 + c02),
        scale * (-c01 - c03),
        scale * (-c02 - c04),
    ];
    if !k.iter().all(|k| k.is_finite()) {
        return None;
    }
    // Relative to x₀ (the weights sum to zero) to keep rounding small.
    let y = k[1] * e0 + k[2] * e1 + k[3] * e2;
    let frame = stencil_frame(
        Vec3A::from(x0),
        Vec3A::from(x1),
        Vec3A::from(x2),
        Vec3A::from(x3),
    )?;
    let y = Vec3A::from(y);
    // Flat at rest: the weighted sum vanishes up to rounding (it is dimensionless, about
    // the dihedral angle in radians).
    let rest_value = if y.length() < 1e-4 {
        [0.0; 3]
    } else {
        [y.dot(frame.0), y.dot(frame.1), y.dot(frame.2)]
    };
    Some(BendConstraint {
        v,
        k,
        w,
        rest: rest_value,
        pairs: [NONE; 2],
    })
}

/// Edge direction, mean normal and binormal of a bending stencil, if not degenerate.
#[inline]
pub(super) fn stencil_frame(
    p0: Vec3A,
    p1: Vec3A,
    p2: Vec3A,
    p3: Vec3A,
) -> Option<(Vec3A, Vec3A, Vec3A)> {
    let e0 = p1 - p0;
    let normal = e0.cross(p2 - p0) + (p3 - p0).cross(e0);
    let el = e0.length();
    let nl = normal.length();
    if !(el > 1e-12 && nl > 1e-9 * el * el) {
        return None;
    }
    let t = e0 / el;
    let n = normal / nl;
    Some((t, n, t.cross(n)))
}
