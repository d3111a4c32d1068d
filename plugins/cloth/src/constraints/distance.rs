//! The XPBD distance constraints (stretch and shear; Macklin, Müller and Chentanez 2016),
//! projected eight at a time, with the pair projection the bending kernel shares, and the
//! stretch check of the blow-up guard.

use super::{CheckBatch, DistanceBatch};
use crate::pool::SharedSlice;
use glam::Vec3A;

use crate::simd::{Isa, LANES, Lanes, V3, dispatch_lanes};

/// Projects the distance batches `batches` (XPBD); `inverse_denominator[k]` is
/// `1 / (wᵢ + wⱼ + α̃)` of `batches[k]` ([`ConstraintSet::inverse_denominators`]) and
/// `lambda[k]` its multipliers. `first` means λ starts at zero.
///
/// # Safety
/// Every particle index of the batches is in bounds of `x`'s allocation, and the calling
/// item has exclusive access to those particles in this phase.
#[inline]
pub(crate) unsafe fn solve_distance(
    isa: Isa,
    batches: &[DistanceBatch],
    inverse_denominator: &[[f32; LANES]],
    lambda: Option<(&SharedSlice<'_, [f32; LANES]>, usize)>,
    x: *mut Vec3A,
    inv_h2: f32,
    first: bool,
) {
    dispatch_lanes!(
        isa,
        distance_kernel(
            batches: &[DistanceBatch],
            inverse_denominator: &[[f32; LANES]],
            lambda: Option<(&SharedSlice<'_, [f32; LANES]>, usize)>,
            x: *mut Vec3A,
            inv_h2: f32,
            first: bool,
        )
    )
}

#[inline(always)]
pub(super) unsafe fn distance_kernel<L: Lanes>(
    batches: &[DistanceBatch],
    inverse_denominator: &[[f32; LANES]],
    lambda: Option<(&SharedSlice<'_, [f32; LANES]>, usize)>,
    x: *mut Vec3A,
    inv_h2: f32,
    first: bool,
) {
    let inv_h2 = L::splat(inv_h2);
    for (k, (c, inv)) in batches.iter().zip(inverse_denominator).enumerate() {
        // SAFETY: see `solve_distance`.
        unsafe {
            let pi = L::gather(x, &c.i);
            let pj = L::gather(x, &c.j);
            let mut lam = None;
            if let Some((lambda, base)) = lambda
                && !first
            {
                lam = Some(L::load(&lambda.get(base + k)));
            }
            let (pi, pj, lam) = project_pair(
                (pi, pj),
                (L::load(&c.wi), L::load(&c.wj)),
                L::load(&c.rest),
                L::load(&c.compliance) * inv_h2,
                L::load(inv),
                lam,
            );
            if let Some((lambda, base)) = lambda {
                lambda.set(base + k, lam.to_array());
            }
            L::scatter(x, &c.i, pi);
            L::scatter(x, &c.j, pj);
        }
    }
}

/// One XPBD projection of eight distance constraints between `pi` and `pj` (inverse masses
/// `w`, rest length `rest`, compliance over h² `alpha`, inverse denominator `inv`, multiplier
/// `lambda` if kept): the moved particles and the new multiplier.
#[inline(always)]
pub(super) fn project_pair<L: Lanes>(
    (pi, pj): (V3<L>, V3<L>),
    (wi, wj): (L, L),
    rest: L,
    alpha: L,
    inv: L,
    lambda: Option<L>,
) -> (V3<L>, V3<L>, L) {
    let d = pi - pj;
    let len = d.dot_fused(d).sqrt();
    // Degenerate (coincident) pairs are skipped; NaN goes through (the guard sees it).
    let valid = len.not_lt(L::splat(1e-9));
    let mut residual = len - rest;
    let lam = lambda.unwrap_or(L::splat(0.0));
    if lambda.is_some() {
        residual = alpha.mul_add(lam, residual);
    }
    let dl = -(residual * inv);
    let s = dl.div(len).and(valid);
    (
        d.mul_add(wi * s, pi),
        d.mul_add(-(wj * s), pj),
        L::select(valid, lam + dl, lam),
    )
}

/// The largest squared length / rest length over `batches`, and its lane
/// (`(first_batch + k) · LANES + lane`); NaN (and the first such lane) if any is NaN;
/// `(0, u32::MAX)` if there is none.
///
/// # Safety
/// Every particle index of the batches is in bounds of `x`'s allocation, and no thread
/// writes those particles in this phase.
#[inline]
pub(crate) unsafe fn max_stretch_squared(
    isa: Isa,
    batches: &[CheckBatch],
    first_batch: usize,
    x: *const Vec3A,
) -> (f32, u32) {
    dispatch_lanes!(
        isa,
        max_stretch_squared_with(
            batches: &[CheckBatch],
            first_batch: usize,
            x: *const Vec3A,
        ) -> (f32, u32)
    )
}

#[inline(always)]
pub(super) unsafe fn max_stretch_squared_with<L: Lanes>(
    batches: &[CheckBatch],
    first_batch: usize,
    x: *const Vec3A,
) -> (f32, u32) {
    let mut worst = (0.0f32, u32::MAX);
    for (k, c) in batches.iter().enumerate() {
        // SAFETY: see `max_stretch_squared`.
        let (pi, pj) = unsafe { (L::gather(x, &c.i), L::gather(x, &c.j)) };
        let d = pi - pj;
        let rest = L::load(&c.rest);
        let ratio2 = d.dot(d).div(rest * rest);
        // (No closure: it would not inherit the caller's target features.)
        let lane_base = ((first_batch + k) * LANES) as u32;
        let nan = ratio2.is_nan().bits();
        if nan != 0 {
            return (f32::NAN, lane_base + nan.trailing_zeros());
        }
        let mut above = ratio2.gt(L::splat(worst.0)).bits();
        if above != 0 {
            let r = ratio2.to_array();
            while above != 0 {
                let lane = above.trailing_zeros();
                above &= above - 1;
                if r[lane as usize] > worst.0 {
                    worst = (r[lane as usize], lane_base + lane);
                }
            }
        }
    }
    worst
}
