//! The colliders swept over each substep and the attachment targets at its end,
//! interpolated between the step's start and end poses by the step's `Phase::Sweep` items,
//! and the swept colliders' bounds, eight colliders at a time.

use glam::Vec3A;

use super::ClothSolver;
use super::step::StepContext;
use crate::collision::{Shape, Sphere, SweptCollider};
use crate::simd::LANES;

impl ClothSolver {
    /// Sizes the per-substep colliders and attachment targets for `substeps` substeps. The
    /// step's `Phase::Sweep` items fill them, one substep each, inside the parallel step
    /// (made here before it, shared out, they kept the second thread idle for ~10 µs of the
    /// 4,000-particle dress's step; session 15). A substep computes the shapes at both its
    /// ends, so the results do not depend on which thread sweeps which substep.
    pub(super) fn prepare_substeps(&mut self, substeps: u32) {
        let count = self.capsules.len() + self.solo_spheres.len();
        let substeps = substeps as usize;
        let none = Shape::sphere(Vec3A::ZERO, 0.0);
        self.swept
            .resize(substeps * count, SweptCollider::new(none, none, 0.0));
        self.swept_bounds
            .resize(substeps * count.div_ceil(LANES), ColliderBounds::EMPTY);
        self.anchors
            .resize(substeps * self.target_start.len(), Vec3A::ZERO);
    }
}

/// The body's spheres at the start and end of a step, how they make colliders, and where
/// the attachment targets end: what the step's `Phase::Sweep` items read.
#[derive(Clone, Copy)]
pub(super) struct Bodies<'a> {
    pub(super) start: &'a [Sphere],
    pub(super) end: &'a [Sphere],
    pub(super) capsules: &'a [[u32; 2]],
    pub(super) solo: &'a [u32],
    pub(super) target_end: &'a [Vec3A],
}

impl Bodies<'_> {
    /// Sphere `s` at `t` of the step (0 at its start, 1 at its end).
    pub(super) fn sphere_at(&self, s: u32, t: f32) -> (Vec3A, f32) {
        let (a, b) = (self.start[s as usize], self.end[s as usize]);
        (
            Vec3A::from(a.center.lerp(b.center, t)),
            a.radius + (b.radius - a.radius) * t,
        )
    }

    /// Collider `collider` (the capsules, then the spheres alone) at `t` of the step.
    pub(super) fn shape_at(&self, collider: usize, t: f32) -> Shape {
        if let Some(&[i, j]) = self.capsules.get(collider) {
            let (a, ra) = self.sphere_at(i, t);
            let (b, rb) = self.sphere_at(j, t);
            Shape::round_cone(a, b, ra, rb)
        } else {
            let (c, r) = self.sphere_at(self.solo[collider - self.capsules.len()], t);
            Shape::sphere(c, r)
        }
    }

    /// A collider's share of the fabric's friction.
    pub(super) fn friction_of(&self, collider: usize) -> f32 {
        match self.capsules.get(collider) {
            Some(&[i, j]) => self.end[i as usize]
                .friction
                .min(self.end[j as usize].friction),
            None => self.end[self.solo[collider - self.capsules.len()] as usize].friction,
        }
    }
}

impl StepContext<'_> {
    /// Where attachment `slot` is at the end of substep `sub`.
    #[inline]
    pub(super) fn anchor(&self, slot: u32, sub: u32) -> Vec3A {
        self.anchors_of(sub)[slot as usize]
    }

    /// The attachment targets at the end of substep `sub`.
    #[inline]
    pub(super) fn anchors_of(&self, sub: u32) -> &[Vec3A] {
        let n = self.target_start.len();
        debug_assert!((sub as usize + 1) * n <= self.anchors.len());
        // SAFETY: in bounds (the sweep's slots); written by substep `sub`'s sweep item, which
        // every item that reads them waits for, and not written again in the step.
        unsafe { std::slice::from_raw_parts(self.anchors.as_ptr().add(sub as usize * n), n) }
    }

    /// The bounds of the colliders swept over substep `sub`, eight at a time.
    #[inline]
    pub(super) fn swept_bounds_of(&self, sub: u32) -> &[ColliderBounds] {
        let n = self.k.colliders.div_ceil(LANES);
        debug_assert!((sub as usize + 1) * n <= self.swept_bounds.len());
        // SAFETY: as for `anchors_of`.
        unsafe { std::slice::from_raw_parts(self.swept_bounds.as_ptr().add(sub as usize * n), n) }
    }

    /// The colliders swept over substep `sub`.
    #[inline]
    pub(super) fn swept_of(&self, sub: u32) -> &[SweptCollider] {
        let n = self.k.colliders;
        debug_assert!((sub as usize + 1) * n <= self.swept.len());
        // SAFETY: as for `anchors_of`.
        unsafe { std::slice::from_raw_parts(self.swept.as_ptr().add(sub as usize * n), n) }
    }

    /// Sweeps the colliders over substep `sub` and moves the attachment targets to its end
    /// (the `Phase::Sweep` item).
    #[inline(always)]
    pub(super) fn sweep(&self, sub: u32) {
        let b = &self.bodies;
        let (count, attachments) = (self.k.colliders, self.target_start.len());
        let substeps = self.k.substeps;
        let (t0, t1) = (
            sub as f32 / substeps as f32,
            (sub + 1) as f32 / substeps as f32,
        );
        let sub = sub as usize;
        let eights = count.div_ceil(LANES);
        for eight in 0..eights {
            let mut bounds = ColliderBounds::EMPTY;
            for (l, collider) in (eight * LANES..count.min((eight + 1) * LANES)).enumerate() {
                let c = SweptCollider::new(
                    b.shape_at(collider, t0),
                    b.shape_at(collider, t1),
                    self.k.thickness,
                )
                .with_friction(b.friction_of(collider));
                bounds.set(l, &c);
                // SAFETY: substep `sub`'s slots are written by this item alone, and read only
                // by items that wait for it.
                unsafe { self.swept.set(sub * count + collider, c) };
            }
            // SAFETY: as above.
            unsafe { self.swept_bounds.set(sub * eights + eight, bounds) };
        }
        for (slot, (a, e)) in self.target_start.iter().zip(b.target_end).enumerate() {
            // SAFETY: as above.
            unsafe { self.anchors.set(sub * attachments + slot, a.lerp(*e, t1)) };
        }
    }
}

/// The bounds of eight swept colliders, by axis (`min[axis][lane]`), so that a chunk of
/// particles picks the colliders near it eight at a time ([`overlaps8`]); a lane without a
/// collider has an empty box (the lowest corner +∞, the highest −∞), which meets nothing.
#[derive(Debug, Clone, Copy, PartialEq)]
#[repr(C, align(32))]
pub(super) struct ColliderBounds {
    pub(super) min: [[f32; LANES]; 3],
    pub(super) max: [[f32; LANES]; 3],
}

impl ColliderBounds {
    pub(super) const EMPTY: Self = Self {
        min: [[f32::INFINITY; LANES]; 3],
        max: [[f32::NEG_INFINITY; LANES]; 3],
    };

    /// Puts `collider`'s bounds in lane `l`.
    pub(super) fn set(&mut self, l: usize, collider: &SweptCollider) {
        let (lo, hi) = (collider.bounds_min, collider.bounds_max);
        for axis in 0..3 {
            self.min[axis][l] = lo[axis];
            self.max[axis][l] = hi[axis];
        }
    }
}
