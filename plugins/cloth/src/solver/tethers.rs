//! Tethers, the long-range attachments of Kim, Chentanez and Müller 2012 ("Long range
//! attachments — a method to simulate inextensible clothing in computer games"): a particle
//! farther from an attachment than its tether allows goes back to the nearest point of its
//! tethers' balls; for two tethers in closed form, eight particles at a time where they
//! can; for more, by alternating projections.

use glam::{Vec3, Vec3A};

use super::contact::ALL_LANES;
use super::step::StepContext;
use crate::simd::{Isa, LANES, Lanes, V3, dispatch_lanes, offset};

/// Alternations between the tethers of one particle.
pub(super) const TETHER_ROUNDS: usize = 6;

impl StepContext<'_> {
    /// Puts particle `i` at `p` back within its tethers (see the module documentation).
    #[inline]
    pub(super) fn apply_tethers(&self, i: usize, p: Vec3A, sub: u32) -> Vec3A {
        let m = self.model;
        let first = m.tether_start[i] as usize;
        if m.tether_start[i + 1] as usize - first == 2 {
            let a0 = self.anchor(m.tether_slot[first], sub);
            let a1 = self.anchor(m.tether_slot[first + 1], sub);
            let (r0, r1) = (m.tether_limit[first], m.tether_limit[first + 1]);
            if let Some(q) = project_on_two_balls(p, a0, r0, a1, r1) {
                return q;
            }
        }
        self.alternate_tethers(i, p, sub)
    }

    /// [`Self::apply_tethers`] for particles `i..i + 8`, which have two tethers each.
    ///
    /// # Safety
    /// Particles `i..i + 8` belong to the calling item.
    #[inline]
    pub(super) unsafe fn tethers8(&self, i: usize, sub: u32) {
        let m = self.model;
        let s = m.tether_start[i] as usize;
        let anchors = self.anchors_of(sub).as_ptr();
        let p = &mut [Vec3A::ZERO; LANES];
        // SAFETY: slots index the attachments; `i..i + 8` belong to the calling item.
        let mut fallback = unsafe {
            two_tethers(
                self.k.isa,
                self.xs.as_ptr().add(i),
                anchors,
                &m.tether_slot[s..s + 2 * LANES],
                &m.tether_limit[s..s + 2 * LANES],
                p,
            )
        };
        while fallback != 0 {
            let l = fallback.trailing_zeros() as usize;
            fallback &= fallback - 1;
            // SAFETY: as above.
            unsafe { self.xs.set(i + l, self.apply_tethers(i + l, p[l], sub)) };
        }
    }

    /// Alternating projections onto the tether balls of particle `i`.
    #[inline(never)]
    pub(super) fn alternate_tethers(&self, i: usize, mut p: Vec3A, sub: u32) -> Vec3A {
        let m = self.model;
        let tethers = m.tether_start[i] as usize..m.tether_start[i + 1] as usize;
        // Projecting onto one tether's sphere can violate another: alternate (it converges
        // to the intersection of the balls, which holds the particle's anchors' common
        // region); one round when only one tether is tight.
        for round in 0..TETHER_ROUNDS {
            let mut moved = false;
            // Later rounds only fix violations above 0.1 % (two anchors next to each other
            // make nearly equal balls, whose alternation converges slowly).
            let slack = if round == 0 { 1.0 } else { 1.0 + 2e-3 };
            for k in tethers.clone() {
                let a = self.anchor(m.tether_slot[k], sub);
                let d = p - a;
                let limit = m.tether_limit[k];
                let l2 = d.length_squared();
                if l2 > limit * limit * slack {
                    p = a + d * (limit / l2.sqrt());
                    moved = true;
                }
            }
            if !moved || tethers.len() < 2 {
                break;
            }
        }
        p
    }

    #[inline]
    pub(super) fn tether_violated(&self, i: usize, p: Vec3A, sub: u32) -> bool {
        let m = self.model;
        (m.tether_start[i] as usize..m.tether_start[i + 1] as usize).any(|k| {
            let limit = m.tether_limit[k] * (1.0 + 1e-3);
            (p - self.anchor(m.tether_slot[k], sub)).length_squared() > limit * limit
        })
    }
}

/// The nearest point to `p` in the intersection of the balls `(a0, r0)` and `(a1, r1)`;
/// `None` if they do not intersect (or nearly coincide with different radii in a way that
/// rounding makes unreliable).
///
/// The nearest point is `p` itself, or its projection onto one ball if that lies in the
/// other, or else on the circle where the two spheres meet, towards `p`.
#[inline]
pub(super) fn project_on_two_balls(
    p: Vec3A,
    a0: Vec3A,
    r0: f32,
    a1: Vec3A,
    r1: f32,
) -> Option<Vec3A> {
    let d0 = p - a0;
    let d1 = p - a1;
    let (l0, l1) = (d0.length_squared(), d1.length_squared());
    if l0.is_nan() || l1.is_nan() {
        // Let the alternating projections carry the NaN to the blow-up guard.
        return None;
    }
    let (in0, in1) = (l0 <= r0 * r0, l1 <= r1 * r1);
    if in0 && in1 {
        return Some(p);
    }
    if !in0 {
        let q = a0 + d0 * (r0 / l0.sqrt());
        if (q - a1).length_squared() <= r1 * r1 {
            return Some(q);
        }
    }
    if !in1 {
        let q = a1 + d1 * (r1 / l1.sqrt());
        if (q - a0).length_squared() <= r0 * r0 {
            return Some(q);
        }
    }
    // Both constraints are active: the circle where the spheres meet.
    let axis = a1 - a0;
    let length = axis.length();
    if length <= 1e-9 * (r0 + r1) {
        return None;
    }
    let u = axis / length;
    let along = (length * length + r0 * r0 - r1 * r1) / (2.0 * length);
    let radius2 = r0 * r0 - along * along;
    if radius2.is_nan() || radius2 < 0.0 {
        return None;
    }
    let across = d0 - d0.dot(u) * u;
    let across_length = across.length();
    let dir = if across_length > 1e-12 * r0 {
        across / across_length
    } else {
        Vec3A::from(Vec3::from(u).any_orthonormal_vector())
    };
    Some(a0 + along * u + radius2.sqrt() * dir)
}

/// [`ClothSolver`]'s tethers for eight consecutive particles with two tethers each, at `x`
/// (updated in place); `slots` and `limits` are their tethers' attachment slots and lengths
/// (two per particle), `anchors` the attachments' positions. Lanes whose bit is set in the
/// result need the scalar [`StepContext::apply_tethers`], from their positions left in
/// `before` (NaN, degenerate balls, a point on the axis).
///
/// # Safety
/// `x` points at eight particles that the calling item owns; the slots index `anchors`.
#[inline]
pub(super) unsafe fn two_tethers(
    isa: Isa,
    x: *mut Vec3A,
    anchors: *const Vec3A,
    slots: &[u32],
    limits: &[f32],
    before: &mut [Vec3A; LANES],
) -> u32 {
    dispatch_lanes!(
        isa,
        two_tethers_with(
            x: *mut Vec3A,
            anchors: *const Vec3A,
            slots: &[u32],
            limits: &[f32],
            before: &mut [Vec3A; LANES],
        ) -> u32
    )
}

#[inline(always)]
pub(super) unsafe fn two_tethers_with<L: Lanes>(
    x: *mut Vec3A,
    anchors: *const Vec3A,
    slots: &[u32],
    limits: &[f32],
    before: &mut [Vec3A; LANES],
) -> u32 {
    let index: [u32; LANES] = std::array::from_fn(|l| offset(l as u32));
    let slot0: [u32; LANES] = std::array::from_fn(|l| offset(slots[2 * l]));
    let slot1: [u32; LANES] = std::array::from_fn(|l| offset(slots[2 * l + 1]));
    let r0 = L::load(&std::array::from_fn(|l| limits[2 * l]));
    let r1 = L::load(&std::array::from_fn(|l| limits[2 * l + 1]));
    // SAFETY: the caller's contract.
    unsafe {
        let a0 = L::gather(anchors, &slot0);
        let a1 = L::gather(anchors, &slot1);
        let p = L::gather(x, &index);
        let (q, fallback, moved) = project_on_two_balls_lanes(p, a0, r0, a1, r1);
        if moved {
            L::scatter(x, &index, q);
        }
        if fallback != 0 {
            let (px, py, pz) = (p.x.to_array(), p.y.to_array(), p.z.to_array());
            *before = std::array::from_fn(|l| Vec3A::new(px[l], py[l], pz[l]));
        }
        fallback
    }
}

/// [`project_on_two_balls`] for eight points at once; lanes whose bit is set in the returned
/// mask need the scalar function (NaN, degenerate balls, a point on the axis). The flag is
/// false when every point was inside both balls (the points are returned unchanged).
#[inline(always)]
pub(super) fn project_on_two_balls_lanes<L: Lanes>(
    p: V3<L>,
    a0: V3<L>,
    r0: L,
    a1: V3<L>,
    r1: L,
) -> (V3<L>, u32, bool) {
    let d0 = p - a0;
    let d1 = p - a1;
    let (l0, l1) = (d0.dot(d0), d1.dot(d1));
    let (r0r0, r1r1) = (r0 * r0, r1 * r1);
    let in0 = l0.le(r0r0);
    let in1 = l1.le(r1r1);
    let inside = in0.and(in1);
    if inside.bits() == ALL_LANES {
        return (p, 0, false);
    }
    let nan = l0.is_nan().or(l1.is_nan()).bits();
    let q0 = a0 + d0.scale(r0r0.div(l0).sqrt());
    let e0 = q0 - a1;
    let ok0 = e0.dot(e0).le(r1r1).and_not(in0);
    let q1 = a1 + d1.scale(r1r1.div(l1).sqrt());
    let e1 = q1 - a0;
    let ok1 = e1.dot(e1).le(r0r0).and_not(in1);
    let settled = inside.or(ok0).or(ok1);
    let mut q = V3::select(ok0, q0, V3::select(ok1, q1, p));
    let mut fallback = nan;
    if settled.bits() != ALL_LANES {
        // The circle where the spheres meet: centre a0 + along·û, radius √radius2.
        let axis = a1 - a0;
        let length2 = axis.dot(axis);
        let inv_length2 = L::splat(1.0).div(length2);
        let twice_along_length = length2 + r0r0 - r1r1;
        let centre = a0 + axis.scale(L::splat(0.5) * twice_along_length * inv_length2);
        let radius2 = r0r0 - L::splat(0.25) * twice_along_length * twice_along_length * inv_length2;
        let across = d0 - axis.scale(d0.dot(axis) * inv_length2);
        let across2 = across.dot(across);
        let circle = centre + across.scale(radius2.div(across2).sqrt());
        let tiny = L::splat(1e-9) * (r0 + r1);
        let circle_ok = length2
            .gt(tiny * tiny)
            .and(radius2.not_lt(L::splat(0.0)).and_not(radius2.is_nan()))
            .and(across2.gt(L::splat(1e-24) * r0r0));
        q = V3::select(settled, q, circle);
        fallback |= !circle_ok.or(settled).bits() & ALL_LANES;
    }
    (V3::select(inside, p, q), fallback, true)
}
