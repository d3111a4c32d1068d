//! Four `f32` lanes in one SSE register (`F4`, with its mask `M4`): the halves of the
//! baseline's eight lanes on x86-64 (`Sse8`), and the loads and stores that transpose four
//! particles' positions into x, y and z lanes.

use std::arch::x86_64::*;

/// Four `f32` lanes.
#[derive(Clone, Copy, Debug)]
#[repr(transparent)]
pub(crate) struct F4(pub __m128);

/// A lane mask: all bits set (true) or clear (false) per lane.
#[derive(Clone, Copy, Debug)]
#[repr(transparent)]
pub(crate) struct M4(__m128);

// SAFETY (whole module): SSE2 is part of the x86-64 baseline.
impl F4 {
    #[inline(always)]
    pub fn splat(v: f32) -> Self {
        // SAFETY: SSE and SSE2 are part of the x86-64 baseline, so every processor this runs on
        // has this instruction; it reads and writes registers only.
        Self(unsafe { _mm_set1_ps(v) })
    }
    #[inline(always)]
    pub fn load(a: &[f32; 4]) -> Self {
        // SAFETY: SSE is in the x86-64 baseline; `a` is a valid, readable `[f32; 4]` (an unaligned
        // load).
        Self(unsafe { _mm_loadu_ps(a.as_ptr()) })
    }
    #[inline(always)]
    pub fn store(self, a: &mut [f32; 4]) {
        // SAFETY: SSE is in the x86-64 baseline; `a` is a valid, writable `[f32; 4]` (an unaligned
        // store).
        unsafe { _mm_storeu_ps(a.as_mut_ptr(), self.0) }
    }
    #[inline(always)]
    pub fn to_array(self) -> [f32; 4] {
        let mut a = [0.0; 4];
        self.store(&mut a);
        a
    }
    #[inline(always)]
    pub fn div(self, o: Self) -> Self {
        // SAFETY: SSE and SSE2 are part of the x86-64 baseline, so every processor this runs on
        // has this instruction; it reads and writes registers only.
        Self(unsafe { _mm_div_ps(self.0, o.0) })
    }
    #[inline(always)]
    pub fn sqrt(self) -> Self {
        // SAFETY: SSE and SSE2 are part of the x86-64 baseline, so every processor this runs on
        // has this instruction; it reads and writes registers only.
        Self(unsafe { _mm_sqrt_ps(self.0) })
    }
    /// `self > o` (false when either is NaN).
    #[inline(always)]
    pub fn gt(self, o: Self) -> M4 {
        // SAFETY: SSE and SSE2 are part of the x86-64 baseline, so every processor this runs on
        // has this instruction; it reads and writes registers only.
        M4(unsafe { _mm_cmpgt_ps(self.0, o.0) })
    }
    /// `!(self < o)` (true when either is NaN).
    #[inline(always)]
    pub fn not_lt(self, o: Self) -> M4 {
        // SAFETY: SSE and SSE2 are part of the x86-64 baseline, so every processor this runs on
        // has this instruction; it reads and writes registers only.
        M4(unsafe { _mm_cmpnlt_ps(self.0, o.0) })
    }
    /// `self <= o` (false when either is NaN).
    #[inline(always)]
    pub fn le(self, o: Self) -> M4 {
        // SAFETY: SSE and SSE2 are part of the x86-64 baseline, so every processor this runs on
        // has this instruction; it reads and writes registers only.
        M4(unsafe { _mm_cmple_ps(self.0, o.0) })
    }
    /// `!(self > o)` (true when either is NaN).
    #[inline(always)]
    pub fn not_gt(self, o: Self) -> M4 {
        // SAFETY: SSE and SSE2 are part of the x86-64 baseline, so every processor this runs on
        // has this instruction; it reads and writes registers only.
        M4(unsafe { _mm_cmpngt_ps(self.0, o.0) })
    }
    /// `self != self`.
    #[inline(always)]
    pub fn is_nan(self) -> M4 {
        // SAFETY: SSE and SSE2 are part of the x86-64 baseline, so every processor this runs on
        // has this instruction; it reads and writes registers only.
        M4(unsafe { _mm_cmpunord_ps(self.0, self.0) })
    }
    /// Lanes of `self` where `mask`, zero elsewhere.
    #[inline(always)]
    pub fn and(self, mask: M4) -> Self {
        // SAFETY: SSE and SSE2 are part of the x86-64 baseline, so every processor this runs on
        // has this instruction; it reads and writes registers only.
        Self(unsafe { _mm_and_ps(self.0, mask.0) })
    }
    /// `mask ? a : b` per lane.
    #[inline(always)]
    pub fn select(mask: M4, a: Self, b: Self) -> Self {
        // SAFETY: SSE and SSE2 are part of the x86-64 baseline, so every processor this runs on
        // has this instruction; it reads and writes registers only.
        Self(unsafe { _mm_or_ps(_mm_and_ps(mask.0, a.0), _mm_andnot_ps(mask.0, b.0)) })
    }
    #[inline(always)]
    pub(super) fn add_(self, o: Self) -> Self {
        // SAFETY: SSE and SSE2 are part of the x86-64 baseline, so every processor this runs on
        // has this instruction; it reads and writes registers only.
        Self(unsafe { _mm_add_ps(self.0, o.0) })
    }
    #[inline(always)]
    pub(super) fn sub_(self, o: Self) -> Self {
        // SAFETY: SSE and SSE2 are part of the x86-64 baseline, so every processor this runs on
        // has this instruction; it reads and writes registers only.
        Self(unsafe { _mm_sub_ps(self.0, o.0) })
    }
    #[inline(always)]
    pub(super) fn mul_(self, o: Self) -> Self {
        // SAFETY: SSE and SSE2 are part of the x86-64 baseline, so every processor this runs on
        // has this instruction; it reads and writes registers only.
        Self(unsafe { _mm_mul_ps(self.0, o.0) })
    }
    #[inline(always)]
    pub(super) fn neg_(self) -> Self {
        // SAFETY: SSE and SSE2 are part of the x86-64 baseline, so every processor this runs on
        // has this instruction; it reads and writes registers only.
        Self(unsafe { _mm_xor_ps(self.0, _mm_set1_ps(-0.0)) })
    }
}

impl M4 {
    #[inline(always)]
    pub fn or(self, o: Self) -> Self {
        // SAFETY: SSE and SSE2 are part of the x86-64 baseline, so every processor this runs on
        // has this instruction; it reads and writes registers only.
        Self(unsafe { _mm_or_ps(self.0, o.0) })
    }
    /// `self && !o`.
    #[inline(always)]
    pub fn and_not(self, o: Self) -> Self {
        // SAFETY: SSE and SSE2 are part of the x86-64 baseline, so every processor this runs on
        // has this instruction; it reads and writes registers only.
        Self(unsafe { _mm_andnot_ps(o.0, self.0) })
    }
    /// Bit `l` set when lane `l` is true.
    #[inline(always)]
    pub fn bits(self) -> u32 {
        // SAFETY: SSE and SSE2 are part of the x86-64 baseline, so every processor this runs on
        // has this instruction; it reads and writes registers only.
        unsafe { _mm_movemask_ps(self.0) as u32 }
    }
}

/// Loads four 16-byte vectors and transposes them: returns lanes of x, y and z.
///
/// # Safety
/// Each pointer is valid for a 16-byte aligned read.
#[inline(always)]
pub(crate) unsafe fn gather4(p: [*const glam::Vec3A; 4]) -> [F4; 3] {
    // SAFETY: SSE2 is in the x86-64 baseline; the caller guarantees each pointer is valid for a
    // 16-byte aligned read (`Vec3A` is 16-byte aligned).
    unsafe {
        let a = _mm_load_ps(p[0] as *const f32);
        let b = _mm_load_ps(p[1] as *const f32);
        let c = _mm_load_ps(p[2] as *const f32);
        let d = _mm_load_ps(p[3] as *const f32);
        let ab_lo = _mm_unpacklo_ps(a, b); // a0 b0 a1 b1
        let cd_lo = _mm_unpacklo_ps(c, d); // c0 d0 c1 d1
        let ab_hi = _mm_unpackhi_ps(a, b); // a2 b2 a3 b3
        let cd_hi = _mm_unpackhi_ps(c, d); // c2 d2 c3 d3
        [
            F4(_mm_movelh_ps(ab_lo, cd_lo)),
            F4(_mm_movehl_ps(cd_lo, ab_lo)),
            F4(_mm_movelh_ps(ab_hi, cd_hi)),
        ]
    }
}

/// Transposes lanes of x, y, z (and w = 0) back and stores four 16-byte vectors.
///
/// # Safety
/// Each pointer is valid for a 16-byte aligned write.
#[inline(always)]
pub(crate) unsafe fn scatter4(p: [*mut glam::Vec3A; 4], v: [F4; 3]) {
    // SAFETY: SSE2 is in the x86-64 baseline; the caller guarantees each pointer is valid for a
    // 16-byte aligned write (`Vec3A` is 16-byte aligned).
    unsafe {
        let zero = _mm_setzero_ps();
        let xy_lo = _mm_unpacklo_ps(v[0].0, v[1].0); // x0 y0 x1 y1
        let zw_lo = _mm_unpacklo_ps(v[2].0, zero); // z0 0 z1 0
        let xy_hi = _mm_unpackhi_ps(v[0].0, v[1].0); // x2 y2 x3 y3
        let zw_hi = _mm_unpackhi_ps(v[2].0, zero); // z2 0 z3 0
        _mm_store_ps(p[0] as *mut f32, _mm_movelh_ps(xy_lo, zw_lo));
        _mm_store_ps(p[1] as *mut f32, _mm_movehl_ps(zw_lo, xy_lo));
        _mm_store_ps(p[2] as *mut f32, _mm_movelh_ps(xy_hi, zw_hi));
        _mm_store_ps(p[3] as *mut f32, _mm_movehl_ps(zw_hi, xy_hi));
    }
}
