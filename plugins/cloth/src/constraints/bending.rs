//! The isometric bending kernel (Bergou et al. 2006 as an XPBD constraint): eight stencils
//! at a time, flat or curved (the rest value held in the stencil's frame), each with the
//! distance constraints of its pairs.

use glam::Vec3A;

use super::distance::project_pair;
use super::{BendBatch, BendFrame, BendSide, BendTarget};
use crate::pool::SharedSlice;
#[cfg(target_arch = "x86_64")]
use crate::simd::Avx8;
use crate::simd::{Baseline8, Isa, LANES, Lanes, V3};

/// Projects the bending batches `batches` (XPBD) with their first `pairs` distance
/// constraints (solved after the bending, see "Pairs" in the module documentation), all
/// flat (`frame` is `Flat`: zero rest value) or all curved; `inverse_denominator[k]` holds the inverse denominators of `batches[k]`
/// ([`ConstraintSet::inverse_denominators`]) and `lambda[k]` its multipliers (bending x, y, z,
/// then the pairs'). `first` means λ starts at zero.
///
/// # Safety
/// As [`solve_distance`].
#[allow(clippy::too_many_arguments)]
#[inline]
pub(crate) unsafe fn solve_bend(
    isa: Isa,
    frame: BendFrame<'_, '_>,
    pairs: u8,
    (batches, side): (&[BendBatch], &[BendSide]),
    inverse_denominator: &[[[f32; LANES]; 3]],
    lambda: Option<(&SharedSlice<'_, [[f32; LANES]; 5]>, usize)>,
    x: *mut Vec3A,
    (alpha, inv_h2): (f32, f32),
    first: bool,
) {
    let (mode, targets) = match frame {
        BendFrame::Flat => (0, None),
        BendFrame::New(t, base) => (1, Some((t, base))),
        BendFrame::Held(t, base) => (2, Some((t, base))),
    };
    let args = BendArgs {
        batches,
        side,
        inverse_denominator,
        lambda,
        x,
        alpha,
        inv_h2,
        first,
        targets,
    };
    #[cfg(target_arch = "x86_64")]
    crate::simd::avx_features! {
        unsafe fn avx<const MODE: u8, const PAIRS: u8>(args: BendArgs<'_, '_>) {
            // SAFETY: the caller's contract.
            unsafe { bend_kernel::<Avx8, MODE, PAIRS>(args) }
        }
    }
    macro_rules! dispatch {
        ($($mode:literal, $pairs:literal);*) => {
            match (isa, mode, pairs) {
                $(
                    #[cfg(target_arch = "x86_64")]
                    (Isa::Avx, $mode, $pairs) => avx::<$mode, $pairs>(args),
                    (_, $mode, $pairs) => bend_kernel::<Baseline8, $mode, $pairs>(args),
                )*
                _ => unreachable!("bending runs have 0 to 2 pairs"),
            }
        };
    }
    // SAFETY: the caller's contract; AVX only where detected.
    unsafe { dispatch!(0, 0; 0, 1; 0, 2; 1, 0; 1, 1; 1, 2; 2, 0; 2, 1; 2, 2) }
}

/// The arguments of [`bend_kernel`] (see [`solve_bend`]).
#[derive(Clone, Copy)]
pub(super) struct BendArgs<'a, 's> {
    pub(super) batches: &'a [BendBatch],
    pub(super) side: &'a [BendSide],
    pub(super) inverse_denominator: &'a [[[f32; LANES]; 3]],
    pub(super) lambda: Option<(&'a SharedSlice<'s, [[f32; LANES]; 5]>, usize)>,
    pub(super) x: *mut Vec3A,
    pub(super) alpha: f32,
    pub(super) inv_h2: f32,
    pub(super) first: bool,
    pub(super) targets: Option<(&'a SharedSlice<'s, BendTarget>, usize)>,
}

/// `MODE`: 0 flat, 1 curved with a new frame, 2 curved with the held one; `PAIRS`: distance
/// constraints solved after the bending.
#[inline(always)]
pub(super) unsafe fn bend_kernel<L: Lanes, const MODE: u8, const PAIRS: u8>(a: BendArgs<'_, '_>) {
    let (lambda, x, first, targets) = (a.lambda, a.x, a.first, a.targets);
    let side = a.side;
    let alpha = L::splat(a.alpha);
    let inv_h2 = L::splat(a.inv_h2);
    for (k, (c, inv)) in a.batches.iter().zip(a.inverse_denominator).enumerate() {
        // SAFETY: see `solve_bend`.
        unsafe {
            // (No closures here: they would not inherit the caller's target features.)
            let p = [
                L::gather(x, &c.v[0]),
                L::gather(x, &c.v[1]),
                L::gather(x, &c.v[2]),
                L::gather(x, &c.v[3]),
            ];
            let kept = match lambda {
                Some((lambda, base)) if !first => Some(lambda.get(base + k)),
                _ => None,
            };
            let [p0, p1, p2, p3] = p;
            let e1 = p1 - p0;
            let mut value = (p3 - p0).mul_add(
                L::load(&c.k[3]),
                (p2 - p0).mul_add(L::load(&c.k[2]), e1.scale(L::load(&c.k[1]))),
            );
            let mut valid = None;
            if MODE == 1 {
                // The stencil frame: edge t, mean normal n (e₁ × (x₂ − x₃) is the sum of the
                // two triangles' area normals), binormal t × n.
                let normal = e1.cross(p2 - p3);
                let el = e1.dot_fused(e1).sqrt();
                let nl = normal.dot_fused(normal).sqrt();
                let framed = el.gt(L::splat(1e-12)).and(nl.gt(L::splat(1e-9) * el * el));
                // One division for both lengths: 1/el = nl/(el·nl), 1/nl = el/(el·nl).
                let inv_both = L::splat(1.0).div(el * nl);
                let t = e1.scale(nl * inv_both);
                let n = normal.scale(el * inv_both);
                let b = t.cross(n);
                let rest = V3::load(&side[k].rest);
                let target = b
                    .mul_add(rest.z, n.mul_add(rest.y, t.scale(rest.x)))
                    .and(framed);
                // A flat lane (zero rest value) needs no frame: it is always solved.
                let flat = rest.dot_fused(rest).not_gt(L::splat(0.0));
                let lanes = framed.or(flat);
                if let Some((targets, base)) = targets {
                    let [tx, ty, tz] = target.to_arrays();
                    targets.set(
                        base + k,
                        BendTarget {
                            value: [tx, ty, tz],
                            valid: lanes.to_array(),
                        },
                    );
                }
                value = value - target;
                valid = Some(lanes);
            } else if MODE == 2
                && let Some((targets, base)) = targets
            {
                let held = targets.get(base + k);
                value = value - V3::load(&held.value);
                valid = Some(L::load(&held.valid));
            }
            let mut lam = V3 {
                x: L::splat(0.0),
                y: L::splat(0.0),
                z: L::splat(0.0),
            };
            if let Some(kept) = kept {
                lam = V3::load(&[kept[0], kept[1], kept[2]]);
                value = lam.mul_add(alpha, value);
            }
            let mut dl = value.scale(-L::load(&inv[0]));
            if let Some(valid) = valid {
                dl = dl.and(valid);
            }
            let mut p = [
                dl.mul_add(L::load(&c.w[0]) * L::load(&c.k[0]), p0),
                dl.mul_add(L::load(&c.w[1]) * L::load(&c.k[1]), p1),
                dl.mul_add(L::load(&c.w[2]) * L::load(&c.k[2]), p2),
                dl.mul_add(L::load(&c.w[3]) * L::load(&c.k[3]), p3),
            ];
            let mut pair_lambda = [L::splat(0.0); 2];
            for pair in 0..PAIRS as usize {
                let (a, b) = (2 * pair, 2 * pair + 1);
                // A closure (`Option::map`) would not inherit the target features.
                #[allow(clippy::manual_map)]
                let lam = match &kept {
                    Some(kept) => Some(L::load(&kept[3 + pair])),
                    None => None,
                };
                // (The compliance only weighs a kept λ.)
                let alpha = match &kept {
                    Some(_) => L::load(&side[k].pair_compliance[pair]) * inv_h2,
                    None => L::splat(0.0),
                };
                let (pa, pb, lam) = project_pair(
                    (p[a], p[b]),
                    (L::load(&c.w[a]), L::load(&c.w[b])),
                    L::load(&c.drest[pair]),
                    alpha,
                    L::load(&inv[1 + pair]),
                    lam,
                );
                (p[a], p[b], pair_lambda[pair]) = (pa, pb, lam);
            }
            if let Some((lambda, base)) = lambda {
                let [lx, ly, lz] = (lam + dl).to_arrays();
                let (l3, l4) = (pair_lambda[0].to_array(), pair_lambda[1].to_array());
                lambda.set(base + k, [lx, ly, lz, l3, l4]);
            }
            L::scatter(x, &c.v[0], p[0]);
            L::scatter(x, &c.v[1], p[1]);
            L::scatter(x, &c.v[2], p[2]);
            L::scatter(x, &c.v[3], p[3]);
        }
    }
}
