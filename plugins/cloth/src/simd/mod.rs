//! SIMD lanes for the batched kernels: constraint projection ([`crate::constraints`]),
//! tethers, particle integration and aerodynamics ([`crate::solver`], [`crate::wind`]).
//!
//! A batch holds eight independent items (constraints, particles), one per lane, in
//! structure-of-arrays form. Particle positions stay `Vec3A` (16 bytes, one aligned load
//! each): a gather loads the positions of eight particles and transposes them into `x`, `y`,
//! `z` lanes, a scatter transposes back and stores. Batches address particles by byte offset
//! (index × 16), which the processor adds to the array's address without a multiplication.
//!
//! The kernels are written once over the `Lanes` trait and compiled twice: with two SSE2
//! registers per batch (the x86-64 baseline; plain arrays on other architectures) and with
//! one AVX register on processors of the x86-64-v3 level (AVX2, FMA, BMI1/2, LZCNT, POPCNT:
//! every Intel processor with AVX2 since 2013, AMD since 2015), chosen at run time
//! (`Isa::detect`). Only IEEE-754 additions,
//! multiplications, fused multiply-adds, divisions and square roots are used — no
//! approximate reciprocals — each rounded exactly once, so every implementation gives the
//! same bits: the AVX kernels fuse with the processor's FMA instructions, the baseline lane
//! by lane with `f32::mul_add` (slower, but only processors without AVX and FMA run it).
//! (Fused multiply-add was tried in session 4 and dropped because the baseline rounded twice;
//! rounding once there too keeps the kernels' bit-for-bit agreement.) The baseline's eight
//! lanes are two four-lane SSE2 halves (`F4`).

use std::ops::{Add, Mul, Neg, Sub};

use glam::Vec3A;

/// Lanes of a constraint batch ([`Lanes`]).
pub(crate) const LANES: usize = 8;

#[cfg(target_arch = "x86_64")]
mod sse;

#[cfg(not(target_arch = "x86_64"))]
use portable as imp;
#[cfg(not(target_arch = "x86_64"))]
pub(crate) use portable::Scalar8;
#[cfg(target_arch = "x86_64")]
use sse as imp;

pub(crate) use imp::{F4, M4};

impl Add for F4 {
    type Output = F4;
    #[inline(always)]
    fn add(self, o: F4) -> F4 {
        self.add_(o)
    }
}

impl Sub for F4 {
    type Output = F4;
    #[inline(always)]
    fn sub(self, o: F4) -> F4 {
        self.sub_(o)
    }
}

impl Mul for F4 {
    type Output = F4;
    #[inline(always)]
    fn mul(self, o: F4) -> F4 {
        self.mul_(o)
    }
}

impl Neg for F4 {
    type Output = F4;
    #[inline(always)]
    fn neg(self) -> F4 {
        self.neg_()
    }
}

/// Eight `f32` lanes: the lane type of the constraint kernels, which are written once,
/// generically, and compiled for each implementation ([`Sse8`] everywhere on x86-64, [`Avx8`]
/// where the processor has AVX, [`Scalar8`] elsewhere). Masks are lanes with all bits set
/// (true) or clear (false). Every implementation rounds each operation exactly once, so all
/// give the same bits.
pub(crate) trait Lanes:
    Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + Neg<Output = Self>
{
    fn splat(v: f32) -> Self;
    fn load(a: &[f32; LANES]) -> Self;
    fn to_array(self) -> [f32; LANES];
    fn div(self, o: Self) -> Self;
    fn sqrt(self) -> Self;
    /// `self · a + b`, rounded once (a fused multiply-add).
    fn mul_add(self, a: Self, b: Self) -> Self;
    /// `!(self < o)` (true when either is NaN).
    fn not_lt(self, o: Self) -> Self;
    /// `self > o` (false when either is NaN).
    fn gt(self, o: Self) -> Self;
    /// `self <= o` (false when either is NaN).
    fn le(self, o: Self) -> Self;
    /// `!(self > o)` (true when either is NaN).
    fn not_gt(self, o: Self) -> Self;
    /// Bitwise or of masks.
    fn or(self, o: Self) -> Self;
    /// `self && !o` for masks.
    fn and_not(self, o: Self) -> Self;
    /// `self != self`.
    fn is_nan(self) -> Self;
    /// Bitwise and (of masks, or of a value with a mask).
    fn and(self, mask: Self) -> Self;
    /// `mask ? a : b` per lane.
    fn select(mask: Self, a: Self, b: Self) -> Self;
    /// Bit `l` set when mask lane `l` is true.
    fn bits(self) -> u32;
    /// Loads the positions at byte offsets `offset[l]` from `x` (particle index × 16, see
    /// [`offset`]) into x, y and z lanes.
    ///
    /// # Safety
    /// Every offset is that of an element of the allocation `x` points into, and no other
    /// thread writes those elements during the current phase.
    unsafe fn gather(x: *const Vec3A, offset: &[u32; LANES]) -> V3<Self>;
    /// Stores lanes at byte offsets `offset[l]` from `x` (w = 0); if an offset repeats, the
    /// last lane wins.
    ///
    /// # Safety
    /// As [`Lanes::gather`], and no other thread reads those elements in this phase.
    unsafe fn scatter(x: *mut Vec3A, offset: &[u32; LANES], v: V3<Self>);
}

/// The byte offset of particle `index` in a `Vec3A` array, as the batches store it (the
/// processor adds it to the array's address without a multiplication).
#[inline(always)]
pub(crate) const fn offset(index: u32) -> u32 {
    index * 16
}

/// Three-vectors in eight lanes.
#[derive(Clone, Copy, Debug)]
pub(crate) struct V3<L> {
    pub x: L,
    pub y: L,
    pub z: L,
}

impl<L: Lanes> V3<L> {
    #[inline(always)]
    pub fn load(a: &[[f32; LANES]; 3]) -> Self {
        V3 {
            x: L::load(&a[0]),
            y: L::load(&a[1]),
            z: L::load(&a[2]),
        }
    }
    #[inline(always)]
    pub fn to_arrays(self) -> [[f32; LANES]; 3] {
        [self.x.to_array(), self.y.to_array(), self.z.to_array()]
    }
    #[inline(always)]
    pub fn scale(self, s: L) -> Self {
        V3 {
            x: self.x * s,
            y: self.y * s,
            z: self.z * s,
        }
    }
    #[inline(always)]
    pub fn dot(self, o: Self) -> L {
        self.x * o.x + self.y * o.y + self.z * o.z
    }
    /// `self · s + c` per component, each rounded once.
    #[inline(always)]
    pub fn mul_add(self, s: L, c: Self) -> Self {
        V3 {
            x: self.x.mul_add(s, c.x),
            y: self.y.mul_add(s, c.y),
            z: self.z.mul_add(s, c.z),
        }
    }
    /// The dot product with fused multiply-adds (`x·x' + (y·y' + z·z')`, two roundings
    /// fewer).
    #[inline(always)]
    pub fn dot_fused(self, o: Self) -> L {
        self.x.mul_add(o.x, self.y.mul_add(o.y, self.z * o.z))
    }
    #[inline(always)]
    pub fn cross(self, o: Self) -> Self {
        V3 {
            x: self.y * o.z - self.z * o.y,
            y: self.z * o.x - self.x * o.z,
            z: self.x * o.y - self.y * o.x,
        }
    }
    /// `mask ? a : b` per lane.
    #[inline(always)]
    pub fn select(mask: L, a: Self, b: Self) -> Self {
        V3 {
            x: L::select(mask, a.x, b.x),
            y: L::select(mask, a.y, b.y),
            z: L::select(mask, a.z, b.z),
        }
    }
    /// The same vector in every lane.
    #[inline(always)]
    pub fn splat(v: Vec3A) -> Self {
        V3 {
            x: L::splat(v.x),
            y: L::splat(v.y),
            z: L::splat(v.z),
        }
    }
    /// Lanes of `self` where `mask`, zero elsewhere.
    #[inline(always)]
    pub fn and(self, mask: L) -> Self {
        V3 {
            x: self.x.and(mask),
            y: self.y.and(mask),
            z: self.z.and(mask),
        }
    }
}

impl<L: Lanes> Add for V3<L> {
    type Output = Self;
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        V3 {
            x: self.x + o.x,
            y: self.y + o.y,
            z: self.z + o.z,
        }
    }
}

impl<L: Lanes> Sub for V3<L> {
    type Output = Self;
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        V3 {
            x: self.x - o.x,
            y: self.y - o.y,
            z: self.z - o.z,
        }
    }
}

macro_rules! lane_ops {
    ($t:ty) => {
        impl Add for $t {
            type Output = $t;
            #[inline(always)]
            fn add(self, o: $t) -> $t {
                self.add_(o)
            }
        }
        impl Sub for $t {
            type Output = $t;
            #[inline(always)]
            fn sub(self, o: $t) -> $t {
                self.sub_(o)
            }
        }
        impl Mul for $t {
            type Output = $t;
            #[inline(always)]
            fn mul(self, o: $t) -> $t {
                self.mul_(o)
            }
        }
        impl Neg for $t {
            type Output = $t;
            #[inline(always)]
            fn neg(self) -> $t {
                self.neg_()
            }
        }
    };
}

#[cfg(target_arch = "x86_64")]
pub(crate) use x86::{Avx8, Sse8};
// After `lane_ops!`, which they use.
#[cfg(not(target_arch = "x86_64"))]
mod portable;
#[cfg(target_arch = "x86_64")]
mod x86;

/// Which implementation of [`Lanes`] this processor runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))]
pub(crate) enum Isa {
    /// Two SSE registers per eight lanes (or plain arrays off x86-64).
    Baseline,
    /// One AVX register per eight lanes, on an x86-64-v3 processor (AVX, AVX2, FMA, BMI1,
    /// BMI2, LZCNT, POPCNT): the kernels and the step's work items around them
    /// (`crate::solver`) are compiled for that level (`avx_features!`).
    Avx,
}

impl Isa {
    /// The best one this processor has.
    pub fn detect() -> Self {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx")
            && std::arch::is_x86_feature_detected!("avx2")
            && std::arch::is_x86_feature_detected!("fma")
            && std::arch::is_x86_feature_detected!("bmi1")
            && std::arch::is_x86_feature_detected!("bmi2")
            && std::arch::is_x86_feature_detected!("lzcnt")
            && std::arch::is_x86_feature_detected!("popcnt")
        {
            return Isa::Avx;
        }
        Isa::Baseline
    }
}

/// Gives the function item inside it the target features of [`Isa::Avx`], the ones
/// `Isa::detect` checks: every AVX function of this crate takes them from here, so that none
/// enables a feature the detection did not check.
macro_rules! avx_features {
    ($item:item) => {
        #[target_feature(enable = "avx,avx2,fma,bmi1,bmi2,lzcnt,popcnt")]
        $item
    };
}
pub(crate) use avx_features;

/// Calls the generic kernel `$kernel::<L>(args)` with the lanes `isa` names: the AVX one
/// through a wrapper compiled with AVX enabled (the kernel is `#[inline(always)]`, so it is
/// compiled with AVX inside it), the baseline one directly. The arguments are given with their
/// types, as for a function; the expansion is an unsafe call (the kernel's contract is the
/// caller's).
macro_rules! dispatch_lanes {
    ($isa:expr, $kernel:ident($($arg:ident: $ty:ty),* $(,)?) $(-> $ret:ty)?) => {{
        #[cfg(target_arch = "x86_64")]
        $crate::simd::avx_features! {
            unsafe fn avx($($arg: $ty),*) $(-> $ret)? {
                // SAFETY: the caller's contract.
                unsafe { $kernel::<$crate::simd::Avx8>($($arg),*) }
            }
        }
        // SAFETY: the caller's contract; AVX only where detected.
        unsafe {
            match $isa {
                #[cfg(target_arch = "x86_64")]
                $crate::simd::Isa::Avx => avx($($arg),*),
                _ => $kernel::<$crate::simd::Baseline8>($($arg),*),
            }
        }
    }};
}
pub(crate) use dispatch_lanes;

/// The baseline [`Lanes`] of this architecture.
#[cfg(target_arch = "x86_64")]
pub(crate) type Baseline8 = Sse8;
#[cfg(not(target_arch = "x86_64"))]
pub(crate) type Baseline8 = Scalar8;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mul_add_rounds_once_on_every_isa() {
        // (1 + 2⁻²³)² = 1 + 2⁻²² + 2⁻⁴⁶: rounded on its own it is 1 + 2⁻²², and subtracting
        // that leaves 0; fused, the exact 2⁻⁴⁶ remains (closed form).
        let a = 1.0 + f32::EPSILON;
        let c = -(1.0 + 2.0 * f32::EPSILON);
        let exact = (2.0f32).powi(-46);
        assert_eq!(a * a + c, 0.0);
        let fused = Baseline8::splat(a).mul_add(Baseline8::splat(a), Baseline8::splat(c));
        assert_eq!(fused.to_array(), [exact; LANES]);
        #[cfg(target_arch = "x86_64")]
        if Isa::detect() == Isa::Avx {
            avx_features! {
                fn avx(a: f32, c: f32) -> [f32; LANES] {
                    Avx8::splat(a)
                        .mul_add(Avx8::splat(a), Avx8::splat(c))
                        .to_array()
                }
            }
            // SAFETY: the features were detected.
            assert_eq!(unsafe { avx(a, c) }, [exact; LANES]);
        }
    }

    #[test]
    fn gather_and_scatter_transpose_exactly() {
        let x: Vec<Vec3A> = (0..8)
            .map(|k| Vec3A::new(k as f32, 10.0 + k as f32, 20.0 + k as f32))
            .collect();
        let index8 = [5, 0, 7, 2, 1, 3, 6, 4];
        let offset8 = index8.map(offset);
        // SAFETY: `offset8` holds the offsets of elements 0..8 of `x`, which has eight elements;
        // no other thread touches it.
        let v = unsafe { Baseline8::gather(x.as_ptr(), &offset8) };
        assert_eq!(v.x.to_array(), index8.map(|i| i as f32));
        assert_eq!(v.y.to_array(), index8.map(|i| 10.0 + i as f32));
        assert_eq!(v.z.to_array(), index8.map(|i| 20.0 + i as f32));
        let w = V3 {
            x: v.x * Baseline8::splat(2.0),
            y: v.y,
            z: -v.z,
        };
        let mut scattered = x.clone();
        // SAFETY: `offset8` holds the offsets of elements 0..8 of `scattered`, which has eight
        // elements.
        unsafe { Baseline8::scatter(scattered.as_mut_ptr(), &offset8, w) };
        assert_eq!(scattered[7], Vec3A::new(14.0, 17.0, -27.0));
        assert_eq!(scattered[1], Vec3A::new(2.0, 11.0, -21.0));
        let eight = |v: V3<Baseline8>| v.to_arrays();
        // SAFETY: as above.
        let g = unsafe { Baseline8::gather(x.as_ptr(), &offset8) };
        assert_eq!(eight(g)[0], index8.map(|i| x[i as usize].x));
        #[cfg(target_arch = "x86_64")]
        if Isa::detect() == Isa::Avx {
            // SAFETY: AVX was detected just above; `offset8` holds offsets of elements 0..8 of
            // `x`, which has eight.
            let a = unsafe { Avx8::gather(x.as_ptr(), &offset8) };
            assert_eq!(a.to_arrays(), g.to_arrays());
            let mut y = x.clone();
            let twice = V3 {
                x: a.x + a.x,
                y: a.y,
                z: -a.z,
            };
            // SAFETY: AVX was detected; `offset8` holds offsets of elements 0..8 of `y`, which has
            // eight.
            unsafe { Avx8::scatter(y.as_mut_ptr(), &offset8, twice) };
            let mut z = x.clone();
            let twice = V3 {
                x: g.x + g.x,
                y: g.y,
                z: -g.z,
            };
            // SAFETY: `offset8` holds offsets of elements 0..8 of `z`, which has eight.
            unsafe { Baseline8::scatter(z.as_mut_ptr(), &offset8, twice) };
            assert_eq!(y, z);
            assert_eq!(y[6], Vec3A::new(12.0, 16.0, -26.0));
            let m = Avx8::load(&[1.0, f32::NAN, -1.0, 3.0, 0.0, 5.0, f32::NAN, 2.0]);
            assert_eq!(m.is_nan().bits(), 0b0100_0010);
            assert_eq!(m.not_lt(Avx8::splat(2.0)).bits(), 0b1110_1010);
            assert_eq!(m.gt(Avx8::splat(2.0)).bits(), 0b0010_1000);
        }
        let m = F4::load(&[1.0, f32::NAN, -1.0, 3.0]);
        assert_eq!(m.is_nan().bits(), 0b0010);
        assert_eq!(m.gt(F4::splat(2.0)).bits(), 0b1000);
        assert_eq!(m.not_lt(F4::splat(2.0)).bits(), 0b1010);
    }
}
