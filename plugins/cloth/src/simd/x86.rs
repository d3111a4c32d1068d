//! The eight-lane [`Lanes`] of x86-64: two SSE registers (`Sse8`, the baseline) or one
//! AVX register (`Avx8`, on x86-64-v3 processors, see [`Isa::detect`]).

use super::*;
use std::arch::x86_64::*;

/// Eight lanes as two SSE registers (the x86-64 baseline).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Sse8(F4, F4);

/// Mask `F4` from raw bits (`M4` keeps its register private).
#[inline(always)]
fn m4(v: F4) -> M4 {
    // SAFETY: both are a transparent `__m128`.
    unsafe { std::mem::transmute::<F4, M4>(v) }
}

#[inline(always)]
fn f4(m: M4) -> F4 {
    // SAFETY: both are a transparent `__m128`.
    unsafe { std::mem::transmute::<M4, F4>(m) }
}

impl Sse8 {
    #[inline(always)]
    fn add_(self, o: Self) -> Self {
        Sse8(self.0 + o.0, self.1 + o.1)
    }
    #[inline(always)]
    fn sub_(self, o: Self) -> Self {
        Sse8(self.0 - o.0, self.1 - o.1)
    }
    #[inline(always)]
    fn mul_(self, o: Self) -> Self {
        Sse8(self.0 * o.0, self.1 * o.1)
    }
    #[inline(always)]
    fn neg_(self) -> Self {
        Sse8(-self.0, -self.1)
    }
}
lane_ops!(Sse8);

impl Lanes for Sse8 {
    #[inline(always)]
    fn splat(v: f32) -> Self {
        Sse8(F4::splat(v), F4::splat(v))
    }
    #[inline(always)]
    fn load(a: &[f32; LANES]) -> Self {
        let (lo, hi) = a.split_at(4);
        Sse8(
            F4::load(lo.try_into().expect("4 lanes")),
            F4::load(hi.try_into().expect("4 lanes")),
        )
    }
    #[inline(always)]
    fn to_array(self) -> [f32; LANES] {
        let (lo, hi) = (self.0.to_array(), self.1.to_array());
        std::array::from_fn(|l| if l < 4 { lo[l] } else { hi[l - 4] })
    }
    #[inline(always)]
    fn div(self, o: Self) -> Self {
        Sse8(self.0.div(o.0), self.1.div(o.1))
    }
    #[inline(always)]
    fn mul_add(self, a: Self, b: Self) -> Self {
        // Without FMA in the baseline, lane by lane (`f32::mul_add` rounds once).
        let (s, a, b) = (self.to_array(), a.to_array(), b.to_array());
        Self::load(&std::array::from_fn(|l| s[l].mul_add(a[l], b[l])))
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        Sse8(self.0.sqrt(), self.1.sqrt())
    }
    #[inline(always)]
    fn not_lt(self, o: Self) -> Self {
        Sse8(f4(self.0.not_lt(o.0)), f4(self.1.not_lt(o.1)))
    }
    #[inline(always)]
    fn gt(self, o: Self) -> Self {
        Sse8(f4(self.0.gt(o.0)), f4(self.1.gt(o.1)))
    }
    #[inline(always)]
    fn le(self, o: Self) -> Self {
        Sse8(f4(self.0.le(o.0)), f4(self.1.le(o.1)))
    }
    #[inline(always)]
    fn not_gt(self, o: Self) -> Self {
        Sse8(f4(self.0.not_gt(o.0)), f4(self.1.not_gt(o.1)))
    }
    #[inline(always)]
    fn or(self, o: Self) -> Self {
        Sse8(f4(m4(self.0).or(m4(o.0))), f4(m4(self.1).or(m4(o.1))))
    }
    #[inline(always)]
    fn and_not(self, o: Self) -> Self {
        Sse8(
            f4(m4(self.0).and_not(m4(o.0))),
            f4(m4(self.1).and_not(m4(o.1))),
        )
    }
    #[inline(always)]
    fn is_nan(self) -> Self {
        Sse8(f4(self.0.is_nan()), f4(self.1.is_nan()))
    }
    #[inline(always)]
    fn and(self, mask: Self) -> Self {
        Sse8(self.0.and(m4(mask.0)), self.1.and(m4(mask.1)))
    }
    #[inline(always)]
    fn select(mask: Self, a: Self, b: Self) -> Self {
        Sse8(
            F4::select(m4(mask.0), a.0, b.0),
            F4::select(m4(mask.1), a.1, b.1),
        )
    }
    #[inline(always)]
    fn bits(self) -> u32 {
        m4(self.0).bits() | (m4(self.1).bits() << 4)
    }
    #[inline(always)]
    unsafe fn gather(x: *const Vec3A, offset: &[u32; LANES]) -> V3<Self> {
        let base = x as *const u8;
        // SAFETY: see the trait.
        let p = offset.map(|o| unsafe { base.add(o as usize) as *const Vec3A });
        // SAFETY: every offset is that of an element of `x`'s allocation (the trait's contract),
        // so the eight pointers are valid, 16-byte aligned `Vec3A` reads that no other thread
        // writes in this phase.
        let (a, b) = unsafe {
            (
                imp::gather4([p[0], p[1], p[2], p[3]]),
                imp::gather4([p[4], p[5], p[6], p[7]]),
            )
        };
        V3 {
            x: Sse8(a[0], b[0]),
            y: Sse8(a[1], b[1]),
            z: Sse8(a[2], b[2]),
        }
    }
    #[inline(always)]
    unsafe fn scatter(x: *mut Vec3A, offset: &[u32; LANES], v: V3<Self>) {
        let base = x as *mut u8;
        // SAFETY: see the trait.
        let p = offset.map(|o| unsafe { base.add(o as usize) as *mut Vec3A });
        // SAFETY: as in `gather`: the eight pointers are valid, aligned `Vec3A` elements that no
        // other thread reads or writes in this phase.
        unsafe {
            imp::scatter4([p[0], p[1], p[2], p[3]], [v.x.0, v.y.0, v.z.0]);
            imp::scatter4([p[4], p[5], p[6], p[7]], [v.x.1, v.y.1, v.z.1]);
        }
    }
}

/// Eight lanes in one AVX register. Only used inside functions compiled with the `avx`
/// target feature, which are only called once the processor is known to have it.
#[derive(Clone, Copy, Debug)]
#[repr(transparent)]
pub(crate) struct Avx8(__m256);

// SAFETY (every `unsafe` block below): AVX is available (see the type's documentation).
impl Avx8 {
    #[inline(always)]
    fn add_(self, o: Self) -> Self {
        // SAFETY: `Avx8` values exist only in code that runs once `Isa::detect` found AVX (the
        // `dispatch_lanes!` kernels, tests behind that check), so the processor has this
        // instruction; it reads and writes registers only.
        Avx8(unsafe { _mm256_add_ps(self.0, o.0) })
    }
    #[inline(always)]
    fn sub_(self, o: Self) -> Self {
        // SAFETY: `Avx8` values exist only in code that runs once `Isa::detect` found AVX (the
        // `dispatch_lanes!` kernels, tests behind that check), so the processor has this
        // instruction; it reads and writes registers only.
        Avx8(unsafe { _mm256_sub_ps(self.0, o.0) })
    }
    #[inline(always)]
    fn mul_(self, o: Self) -> Self {
        // SAFETY: `Avx8` values exist only in code that runs once `Isa::detect` found AVX (the
        // `dispatch_lanes!` kernels, tests behind that check), so the processor has this
        // instruction; it reads and writes registers only.
        Avx8(unsafe { _mm256_mul_ps(self.0, o.0) })
    }
    #[inline(always)]
    fn neg_(self) -> Self {
        // SAFETY: `Avx8` values exist only in code that runs once `Isa::detect` found AVX (the
        // `dispatch_lanes!` kernels, tests behind that check), so the processor has this
        // instruction; it reads and writes registers only.
        Avx8(unsafe { _mm256_xor_ps(self.0, _mm256_set1_ps(-0.0)) })
    }
}
lane_ops!(Avx8);

impl Lanes for Avx8 {
    #[inline(always)]
    fn splat(v: f32) -> Self {
        // SAFETY: `Avx8` values exist only in code that runs once `Isa::detect` found AVX (the
        // `dispatch_lanes!` kernels, tests behind that check), so the processor has this
        // instruction; it reads and writes registers only.
        Avx8(unsafe { _mm256_set1_ps(v) })
    }
    #[inline(always)]
    fn load(a: &[f32; LANES]) -> Self {
        // SAFETY: AVX is available (`Avx8` exists only after `Isa::detect` found it); `a` is a
        // valid, readable `[f32; 8]` (an unaligned load).
        Avx8(unsafe { _mm256_loadu_ps(a.as_ptr()) })
    }
    #[inline(always)]
    fn to_array(self) -> [f32; LANES] {
        let mut a = [0.0; LANES];
        // SAFETY: AVX is available (`Avx8` exists only after `Isa::detect` found it); `a` is a
        // valid, writable `[f32; 8]` (an unaligned store).
        unsafe { _mm256_storeu_ps(a.as_mut_ptr(), self.0) };
        a
    }
    #[inline(always)]
    fn div(self, o: Self) -> Self {
        // SAFETY: `Avx8` values exist only in code that runs once `Isa::detect` found AVX (the
        // `dispatch_lanes!` kernels, tests behind that check), so the processor has this
        // instruction; it reads and writes registers only.
        Avx8(unsafe { _mm256_div_ps(self.0, o.0) })
    }
    #[inline(always)]
    fn mul_add(self, a: Self, b: Self) -> Self {
        // SAFETY: FMA is available too (see `Isa::Avx`).
        Avx8(unsafe { _mm256_fmadd_ps(self.0, a.0, b.0) })
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        // SAFETY: `Avx8` values exist only in code that runs once `Isa::detect` found AVX (the
        // `dispatch_lanes!` kernels, tests behind that check), so the processor has this
        // instruction; it reads and writes registers only.
        Avx8(unsafe { _mm256_sqrt_ps(self.0) })
    }
    #[inline(always)]
    fn not_lt(self, o: Self) -> Self {
        // SAFETY: `Avx8` values exist only in code that runs once `Isa::detect` found AVX (the
        // `dispatch_lanes!` kernels, tests behind that check), so the processor has this
        // instruction; it reads and writes registers only.
        Avx8(unsafe { _mm256_cmp_ps::<_CMP_NLT_UQ>(self.0, o.0) })
    }
    #[inline(always)]
    fn gt(self, o: Self) -> Self {
        // SAFETY: `Avx8` values exist only in code that runs once `Isa::detect` found AVX (the
        // `dispatch_lanes!` kernels, tests behind that check), so the processor has this
        // instruction; it reads and writes registers only.
        Avx8(unsafe { _mm256_cmp_ps::<_CMP_GT_OQ>(self.0, o.0) })
    }
    #[inline(always)]
    fn le(self, o: Self) -> Self {
        // SAFETY: `Avx8` values exist only in code that runs once `Isa::detect` found AVX (the
        // `dispatch_lanes!` kernels, tests behind that check), so the processor has this
        // instruction; it reads and writes registers only.
        Avx8(unsafe { _mm256_cmp_ps::<_CMP_LE_OQ>(self.0, o.0) })
    }
    #[inline(always)]
    fn not_gt(self, o: Self) -> Self {
        // SAFETY: `Avx8` values exist only in code that runs once `Isa::detect` found AVX (the
        // `dispatch_lanes!` kernels, tests behind that check), so the processor has this
        // instruction; it reads and writes registers only.
        Avx8(unsafe { _mm256_cmp_ps::<_CMP_NGT_UQ>(self.0, o.0) })
    }
    #[inline(always)]
    fn or(self, o: Self) -> Self {
        // SAFETY: `Avx8` values exist only in code that runs once `Isa::detect` found AVX (the
        // `dispatch_lanes!` kernels, tests behind that check), so the processor has this
        // instruction; it reads and writes registers only.
        Avx8(unsafe { _mm256_or_ps(self.0, o.0) })
    }
    #[inline(always)]
    fn and_not(self, o: Self) -> Self {
        // SAFETY: `Avx8` values exist only in code that runs once `Isa::detect` found AVX (the
        // `dispatch_lanes!` kernels, tests behind that check), so the processor has this
        // instruction; it reads and writes registers only.
        Avx8(unsafe { _mm256_andnot_ps(o.0, self.0) })
    }
    #[inline(always)]
    fn is_nan(self) -> Self {
        // SAFETY: `Avx8` values exist only in code that runs once `Isa::detect` found AVX (the
        // `dispatch_lanes!` kernels, tests behind that check), so the processor has this
        // instruction; it reads and writes registers only.
        Avx8(unsafe { _mm256_cmp_ps::<_CMP_UNORD_Q>(self.0, self.0) })
    }
    #[inline(always)]
    fn and(self, mask: Self) -> Self {
        // SAFETY: `Avx8` values exist only in code that runs once `Isa::detect` found AVX (the
        // `dispatch_lanes!` kernels, tests behind that check), so the processor has this
        // instruction; it reads and writes registers only.
        Avx8(unsafe { _mm256_and_ps(self.0, mask.0) })
    }
    #[inline(always)]
    fn select(mask: Self, a: Self, b: Self) -> Self {
        // SAFETY: `Avx8` values exist only in code that runs once `Isa::detect` found AVX (the
        // `dispatch_lanes!` kernels, tests behind that check), so the processor has this
        // instruction; it reads and writes registers only.
        Avx8(unsafe { _mm256_blendv_ps(b.0, a.0, mask.0) })
    }
    #[inline(always)]
    fn bits(self) -> u32 {
        // SAFETY: `Avx8` values exist only in code that runs once `Isa::detect` found AVX (the
        // `dispatch_lanes!` kernels, tests behind that check), so the processor has this
        // instruction; it reads and writes registers only.
        unsafe { _mm256_movemask_ps(self.0) as u32 }
    }
    #[inline(always)]
    unsafe fn gather(x: *const Vec3A, offset: &[u32; LANES]) -> V3<Self> {
        // SAFETY: AVX is available (`Avx8` exists only after `Isa::detect` found it); every offset
        // is that of an element of `x`'s allocation (the trait's contract), so the eight loads are
        // of valid, 16-byte aligned `Vec3A`s that no other thread writes in this phase.
        unsafe {
            let base = x as *const u8;
            let p = offset.map(|o| base.add(o as usize) as *const f32);
            let r0 = _mm256_set_m128(_mm_load_ps(p[4]), _mm_load_ps(p[0]));
            let r1 = _mm256_set_m128(_mm_load_ps(p[5]), _mm_load_ps(p[1]));
            let r2 = _mm256_set_m128(_mm_load_ps(p[6]), _mm_load_ps(p[2]));
            let r3 = _mm256_set_m128(_mm_load_ps(p[7]), _mm_load_ps(p[3]));
            let t0 = _mm256_unpacklo_ps(r0, r1); // x0 x1 y0 y1 | x4 x5 y4 y5
            let t1 = _mm256_unpacklo_ps(r2, r3); // x2 x3 y2 y3 | x6 x7 y6 y7
            let t2 = _mm256_unpackhi_ps(r0, r1); // z0 z1 w0 w1 | z4 z5 w4 w5
            let t3 = _mm256_unpackhi_ps(r2, r3); // z2 z3 w2 w3 | z6 z7 w6 w7
            V3 {
                x: Avx8(_mm256_shuffle_ps::<0x44>(t0, t1)),
                y: Avx8(_mm256_shuffle_ps::<0xEE>(t0, t1)),
                z: Avx8(_mm256_shuffle_ps::<0x44>(t2, t3)),
            }
        }
    }
    #[inline(always)]
    unsafe fn scatter(x: *mut Vec3A, offset: &[u32; LANES], v: V3<Self>) {
        // SAFETY: AVX is available (`Avx8` exists only after `Isa::detect` found it); every offset
        // is that of an element of `x`'s allocation (the trait's contract), so the eight stores
        // are to valid, 16-byte aligned `Vec3A`s that no other thread reads or writes in this
        // phase.
        unsafe {
            let zero = _mm256_setzero_ps();
            let t0 = _mm256_unpacklo_ps(v.x.0, v.y.0); // x0 y0 x1 y1 | x4 y4 x5 y5
            let t1 = _mm256_unpacklo_ps(v.z.0, zero); // z0 0 z1 0 | z4 0 z5 0
            let t2 = _mm256_unpackhi_ps(v.x.0, v.y.0); // x2 y2 x3 y3 | x6 y6 x7 y7
            let t3 = _mm256_unpackhi_ps(v.z.0, zero); // z2 0 z3 0 | z6 0 z7 0
            let r0 = _mm256_shuffle_ps::<0x44>(t0, t1);
            let r1 = _mm256_shuffle_ps::<0xEE>(t0, t1);
            let r2 = _mm256_shuffle_ps::<0x44>(t2, t3);
            let r3 = _mm256_shuffle_ps::<0xEE>(t2, t3);
            let base = x as *mut u8;
            let p = offset.map(|o| base.add(o as usize) as *mut f32);
            _mm_store_ps(p[0], _mm256_castps256_ps128(r0));
            _mm_store_ps(p[1], _mm256_castps256_ps128(r1));
            _mm_store_ps(p[2], _mm256_castps256_ps128(r2));
            _mm_store_ps(p[3], _mm256_castps256_ps128(r3));
            _mm_store_ps(p[4], _mm256_extractf128_ps::<1>(r0));
            _mm_store_ps(p[5], _mm256_extractf128_ps::<1>(r1));
            _mm_store_ps(p[6], _mm256_extractf128_ps::<1>(r2));
            _mm_store_ps(p[7], _mm256_extractf128_ps::<1>(r3));
        }
    }
}
