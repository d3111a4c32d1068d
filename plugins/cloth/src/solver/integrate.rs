//! The particles' part of a substep: the velocity from the positions, the prediction with
//! gravity, external and aerodynamic forces, the moving body frame's fictitious forces and
//! damping (the PBD loop of Müller et al. 2007, "Position based dynamics"), attached
//! particles following their targets; eight particles at a time where they can.

use glam::Vec3A;

use super::model::{EIGHT_ATTACHED, EIGHT_FREE};
use super::program::group_chunks;
use super::report::ItemHealth;
use super::step::{StepConstants, StepContext};
use crate::simd::{Isa, LANES, Lanes, V3, dispatch_lanes, offset};

impl StepContext<'_> {
    /// Finishes substep `sub - 1` (if `sub > 0`) and predicts substep `sub` for every chunk of
    /// particle group `group`; the first substep first gathers the aerodynamic forces (the
    /// positions are read back from the mesh-ordered copy in `step`, and only when edited).
    #[inline(always)]
    pub(super) fn group_particles(&self, sub: u32, group: usize) {
        let o = &self.model.order;
        for c in group_chunks(o, group) {
            let range = o.chunk_start[c] as usize..o.chunk_start[c + 1] as usize;
            if sub == 0 {
                self.load(range.clone());
            }
            self.particles(sub.checked_sub(1), Some(sub), range);
        }
    }

    /// Finishes the last substep of particle group `group`, checks its health, and writes its
    /// positions and velocities in mesh order.
    #[inline(always)]
    pub(super) fn finish_group(&self, group: usize) {
        let o = &self.model.order;
        let chunks = group_chunks(o, group);
        for c in chunks.clone() {
            let range = o.chunk_start[c] as usize..o.chunk_start[c + 1] as usize;
            self.particles(Some(self.k.substeps - 1), None, range);
        }
        let range = o.chunk_start[chunks.start] as usize..o.chunk_start[chunks.end] as usize;
        let mut h = ItemHealth {
            max_speed2: 0.0,
            fastest: 0,
            first_non_finite: u32::MAX,
        };
        for i in range {
            let m = o.to_mesh[i];
            // SAFETY: particle `i` (mesh vertex `m`) belongs to this group.
            let (p, vel) = unsafe {
                let (p, vel) = (self.xs.get(i), self.vs.get(i));
                self.x.set(m as usize, p);
                self.v.set(m as usize, vel);
                (p, vel)
            };
            if !p.is_finite() || !vel.is_finite() {
                h.first_non_finite = h.first_non_finite.min(m);
                continue;
            }
            let s2 = vel.length_squared();
            if s2 > h.max_speed2 {
                h.max_speed2 = s2;
                h.fastest = m;
            }
        }
        // SAFETY: slot `group` belongs to this item.
        unsafe { self.group_health.set(group, h) };
    }

    /// Finishes substep `finish` (tethers, collision, velocity) and then predicts substep
    /// `predict` for the particles of `range` (a chunk).
    #[inline(always)]
    pub(super) fn particles(
        &self,
        finish: Option<u32>,
        predict: Option<u32>,
        range: std::ops::Range<usize>,
    ) {
        let k = &self.k;
        let m = self.model;
        if let Some(sub) = finish {
            self.tethers_and_collisions(sub, range.clone());
        }
        let fast = finish.is_some() && predict.is_some();
        let mut i = range.start;
        while i < range.end {
            let flags = m.eight_at(i, range.end);
            if fast && flags & EIGHT_FREE != 0 {
                // SAFETY: particles `i..i + 8` belong to this item.
                unsafe {
                    integrate_free(
                        k.isa,
                        [self.xs.as_ptr().add(i), self.xs_prev.as_ptr().add(i)],
                        self.external.as_ptr().add(i),
                        k,
                    )
                };
                i += LANES;
                continue;
            }
            if finish.is_some() && predict.is_none() && flags & EIGHT_FREE != 0 {
                // SAFETY: particles `i..i + 8` belong to this item.
                unsafe {
                    finish_free(
                        k.isa,
                        [
                            self.xs.as_ptr().add(i),
                            self.xs_prev.as_ptr().add(i),
                            self.vs.as_ptr().add(i),
                        ],
                        k.inv_h,
                        k.max_velocity,
                    )
                };
                i += LANES;
                continue;
            }
            if let Some(sub) = predict
                && flags & EIGHT_ATTACHED != 0
                && m.attach_slot[i..i + LANES]
                    .iter()
                    .all(|&slot| (slot as usize) < self.target_start.len())
            {
                let slots = &m.attach_slot[i..i + LANES];
                let anchors = self.anchors_of(sub);
                // SAFETY: particles `i..i + 8` belong to this item; their slots index the
                // attachments (checked above).
                unsafe {
                    follow_anchors(
                        k.isa,
                        [
                            self.xs.as_ptr().add(i),
                            self.xs_prev.as_ptr().add(i),
                            self.vs.as_ptr().add(i),
                        ],
                        anchors.as_ptr(),
                        slots,
                        k.inv_h,
                    )
                };
                i += LANES;
                continue;
            }
            let range = i..i + 1;
            i += 1;
            for i in range {
                // SAFETY: particle `i` belongs to this item; nothing else touches it in this phase.
                unsafe {
                    let p = self.xs.get(i);
                    if m.inverse_mass[i] == 0.0 {
                        if let Some(sub) = predict {
                            let target = self.anchor(m.attach_slot[i], sub);
                            self.xs_prev.set(i, p);
                            self.xs.set(i, target);
                            self.vs.set(i, (target - p) * k.inv_h);
                        }
                        continue;
                    }
                    let mut vel = if finish.is_some() {
                        let vel = (p - self.xs_prev.get(i)) * k.inv_h;
                        let speed2 = vel.length_squared();
                        if speed2 > k.max_velocity * k.max_velocity {
                            vel * (k.max_velocity / speed2.sqrt())
                        } else {
                            vel
                        }
                    } else {
                        self.vs.get(i)
                    };
                    if predict.is_some() {
                        vel = predict_velocity(k, p, vel, self.external.get(i));
                        self.xs_prev.set(i, p);
                        self.xs.set(i, p + vel * k.h);
                    }
                    self.vs.set(i, vel);
                }
            }
        }
    }
}

/// Moves eight consecutive attached particles (positions, positions at the substep start and
/// velocities at `x`) to their attachment targets (`slots` into `anchors`) for the next
/// substep, as the one-particle path of [`StepContext::particles`] does.
///
/// # Safety
/// The eight particles belong to the calling item; the slots index `anchors`.
#[inline]
pub(super) unsafe fn follow_anchors(
    isa: Isa,
    x: [*mut Vec3A; 3],
    anchors: *const Vec3A,
    slots: &[u32],
    inv_h: f32,
) {
    dispatch_lanes!(
        isa,
        follow_anchors_with(x: [*mut Vec3A; 3], anchors: *const Vec3A, slots: &[u32], inv_h: f32)
    )
}

#[inline(always)]
pub(super) unsafe fn follow_anchors_with<L: Lanes>(
    [xs, xs_prev, vs]: [*mut Vec3A; 3],
    anchors: *const Vec3A,
    slots: &[u32],
    inv_h: f32,
) {
    let lanes: [u32; LANES] = std::array::from_fn(|l| offset(l as u32));
    let slots: [u32; LANES] = std::array::from_fn(|l| offset(slots[l]));
    // SAFETY: the caller's contract.
    unsafe {
        let p = L::gather(xs, &lanes);
        let target = L::gather(anchors, &slots);
        L::scatter(xs_prev, &lanes, p);
        L::scatter(xs, &lanes, target);
        L::scatter(vs, &lanes, (target - p).scale(L::splat(inv_h)));
    }
}

/// The velocity of a free particle at `p` moving at `vel` after a substep's external, frame
/// and damping terms ([`integrate_free`] does the same for eight particles).
#[inline]
pub(super) fn predict_velocity(k: &StepConstants, p: Vec3A, vel: Vec3A, external: Vec3A) -> Vec3A {
    let mut a = k.gravity + external;
    if let Some(f) = &k.frame {
        a -= f.linear + f.euler.cross(p) + f.coriolis.cross(vel);
        a -= f.centrifugal * f.omega.cross(f.omega.cross(p));
    }
    (vel + a * k.h) * k.damping
}

/// The velocity of substep `s` and the prediction of substep `s + 1` for eight consecutive
/// free particles, with the moving body frame's terms: the vectorised form of
/// [`StepContext::particles`]. `x` holds the positions and positions at the substep start of
/// the first particle; `external` its external acceleration. The velocity is not stored: the
/// next substep derives it from the positions, and the step's last substep (which predicts
/// nothing) stores it.
///
/// # Safety
/// The eight particles belong to the calling item.
#[inline]
pub(super) unsafe fn integrate_free(
    isa: Isa,
    x: [*mut Vec3A; 2],
    external: *const Vec3A,
    k: &StepConstants,
) {
    dispatch_lanes!(
        isa,
        integrate_free_with(x: [*mut Vec3A; 2], external: *const Vec3A, k: &StepConstants)
    )
}

#[inline(always)]
pub(super) unsafe fn integrate_free_with<L: Lanes>(
    [xs, xs_prev]: [*mut Vec3A; 2],
    external: *const Vec3A,
    k: &StepConstants,
) {
    let lanes: [u32; LANES] = std::array::from_fn(|l| offset(l as u32));
    // SAFETY: the caller's contract. (No closures here: they would not inherit the caller's
    // target features.)
    unsafe {
        let p = L::gather(xs, &lanes);
        let mut vel = (p - L::gather(xs_prev, &lanes)).scale(L::splat(k.inv_h));
        let speed2 = vel.dot(vel);
        let max = L::splat(k.max_velocity);
        let fast = speed2.gt(max * max);
        if fast.bits() != 0 {
            vel = V3::select(fast, vel.scale(max.div(speed2.sqrt())), vel);
        }
        let mut a = V3::splat(k.gravity) + L::gather(external, &lanes);
        if let Some(f) = &k.frame {
            // The fictitious accelerations of the moving body frame, as in the one-particle
            // path of `StepContext::particles`.
            let omega = V3::splat(f.omega);
            a = a
                - (V3::splat(f.linear)
                    + V3::splat(f.euler).cross(p)
                    + V3::splat(f.coriolis).cross(vel));
            a = a - omega.cross(omega.cross(p)).scale(L::splat(f.centrifugal));
        }
        let vel = (vel + a.scale(L::splat(k.h))).scale(L::splat(k.damping));
        L::scatter(xs_prev, &lanes, p);
        L::scatter(xs, &lanes, p + vel.scale(L::splat(k.h)));
    }
}

/// The velocity of the step's last substep for eight consecutive free particles (`x`: their
/// positions, positions at the substep start and velocities), as the one-particle path of
/// [`StepContext::particles`] finishes it: what [`integrate_free`] computes before its
/// prediction.
///
/// # Safety
/// The eight particles belong to the calling item.
#[inline]
pub(super) unsafe fn finish_free(isa: Isa, x: [*mut Vec3A; 3], inv_h: f32, max_velocity: f32) {
    dispatch_lanes!(
        isa,
        finish_free_with(x: [*mut Vec3A; 3], inv_h: f32, max_velocity: f32)
    )
}

#[inline(always)]
pub(super) unsafe fn finish_free_with<L: Lanes>(
    [xs, xs_prev, vs]: [*mut Vec3A; 3],
    inv_h: f32,
    max_velocity: f32,
) {
    let lanes: [u32; LANES] = std::array::from_fn(|l| offset(l as u32));
    // SAFETY: the caller's contract.
    unsafe {
        let p = L::gather(xs, &lanes);
        let mut vel = (p - L::gather(xs_prev, &lanes)).scale(L::splat(inv_h));
        let speed2 = vel.dot(vel);
        let max = L::splat(max_velocity);
        let fast = speed2.gt(max * max);
        if fast.bits() != 0 {
            vel = V3::select(fast, vel.scale(max.div(speed2.sqrt())), vel);
        }
        L::scatter(vs, &lanes, vel);
    }
}
