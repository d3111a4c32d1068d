//! The lanes off x86-64: four `f32` lanes as a plain array (`F4`, with its mask `M4`), and
//! eight (`Scalar8`), the baseline [`Lanes`] there.

// The same methods as on x86-64, where the four-lane kernels use more of them.
#![allow(dead_code)]

use std::ops::{Add, Mul, Neg, Sub};

use glam::Vec3A;

use super::{LANES, Lanes, V3};

/// Four `f32` lanes.
#[derive(Clone, Copy, Debug)]
pub(crate) struct F4(pub [f32; 4]);

/// A lane mask.
#[derive(Clone, Copy, Debug)]
pub(crate) struct M4([bool; 4]);

impl F4 {
    #[inline(always)]
    pub fn splat(v: f32) -> Self {
        Self([v; 4])
    }
    #[inline(always)]
    pub fn load(a: &[f32; 4]) -> Self {
        Self(*a)
    }
    #[inline(always)]
    pub fn store(self, a: &mut [f32; 4]) {
        *a = self.0;
    }
    #[inline(always)]
    pub fn to_array(self) -> [f32; 4] {
        self.0
    }
    #[inline(always)]
    pub fn div(self, o: Self) -> Self {
        Self(std::array::from_fn(|l| self.0[l] / o.0[l]))
    }
    #[inline(always)]
    pub fn sqrt(self) -> Self {
        Self(self.0.map(f32::sqrt))
    }
    #[inline(always)]
    pub fn gt(self, o: Self) -> M4 {
        M4(std::array::from_fn(|l| self.0[l] > o.0[l]))
    }
    #[inline(always)]
    pub fn not_lt(self, o: Self) -> M4 {
        M4(std::array::from_fn(|l| !(self.0[l] < o.0[l])))
    }
    #[inline(always)]
    pub fn le(self, o: Self) -> M4 {
        M4(std::array::from_fn(|l| self.0[l] <= o.0[l]))
    }
    #[inline(always)]
    pub fn not_gt(self, o: Self) -> M4 {
        M4(std::array::from_fn(|l| !(self.0[l] > o.0[l])))
    }
    #[inline(always)]
    pub fn lt(self, o: Self) -> M4 {
        M4(std::array::from_fn(|l| self.0[l] < o.0[l]))
    }
    #[inline(always)]
    pub fn max(self, o: Self) -> Self {
        // As SSE's maxps: `o` unless `self > o`.
        Self(std::array::from_fn(|l| {
            if self.0[l] > o.0[l] {
                self.0[l]
            } else {
                o.0[l]
            }
        }))
    }
    #[inline(always)]
    pub fn is_nan(self) -> M4 {
        M4(self.0.map(f32::is_nan))
    }
    #[inline(always)]
    pub fn and(self, mask: M4) -> Self {
        Self(std::array::from_fn(
            |l| if mask.0[l] { self.0[l] } else { 0.0 },
        ))
    }
    #[inline(always)]
    pub fn select(mask: M4, a: Self, b: Self) -> Self {
        Self(std::array::from_fn(
            |l| if mask.0[l] { a.0[l] } else { b.0[l] },
        ))
    }
    #[inline(always)]
    pub(super) fn add_(self, o: Self) -> Self {
        Self(std::array::from_fn(|l| self.0[l] + o.0[l]))
    }
    #[inline(always)]
    pub(super) fn sub_(self, o: Self) -> Self {
        Self(std::array::from_fn(|l| self.0[l] - o.0[l]))
    }
    #[inline(always)]
    pub(super) fn mul_(self, o: Self) -> Self {
        Self(std::array::from_fn(|l| self.0[l] * o.0[l]))
    }
    #[inline(always)]
    pub(super) fn neg_(self) -> Self {
        Self(self.0.map(|v| -v))
    }
}

impl M4 {
    #[inline(always)]
    pub fn and(self, o: Self) -> Self {
        Self(std::array::from_fn(|l| self.0[l] && o.0[l]))
    }
    #[inline(always)]
    pub fn or(self, o: Self) -> Self {
        Self(std::array::from_fn(|l| self.0[l] || o.0[l]))
    }
    #[inline(always)]
    pub fn and_not(self, o: Self) -> Self {
        Self(std::array::from_fn(|l| self.0[l] && !o.0[l]))
    }
    #[inline(always)]
    pub fn bits(self) -> u32 {
        (0..4).map(|l| (self.0[l] as u32) << l).sum()
    }
}

/// # Safety
/// Each pointer is valid for a read.
#[inline(always)]
pub(crate) unsafe fn gather4(p: [*const glam::Vec3A; 4]) -> [F4; 3] {
    let v = p.map(|p| unsafe { *p });
    [F4(v.map(|v| v.x)), F4(v.map(|v| v.y)), F4(v.map(|v| v.z))]
}

/// # Safety
/// Each pointer is valid for a write.
#[inline(always)]
pub(crate) unsafe fn scatter4(p: [*mut glam::Vec3A; 4], v: [F4; 3]) {
    for (l, p) in p.into_iter().enumerate() {
        unsafe { *p = glam::Vec3A::new(v[0].0[l], v[1].0[l], v[2].0[l]) };
    }
}
/// Eight lanes as a plain array (architectures other than x86-64).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Scalar8([f32; LANES]);

impl Scalar8 {
    #[inline(always)]
    fn zip(self, o: Self, f: impl Fn(f32, f32) -> f32) -> Self {
        Scalar8(std::array::from_fn(|l| f(self.0[l], o.0[l])))
    }
    #[inline(always)]
    fn mask(b: bool) -> f32 {
        if b { f32::from_bits(u32::MAX) } else { 0.0 }
    }
    #[inline(always)]
    fn add_(self, o: Self) -> Self {
        self.zip(o, |a, b| a + b)
    }
    #[inline(always)]
    fn sub_(self, o: Self) -> Self {
        self.zip(o, |a, b| a - b)
    }
    #[inline(always)]
    fn mul_(self, o: Self) -> Self {
        self.zip(o, |a, b| a * b)
    }
    #[inline(always)]
    fn neg_(self) -> Self {
        Scalar8(self.0.map(|a| -a))
    }
}

lane_ops!(Scalar8);

impl Lanes for Scalar8 {
    fn splat(v: f32) -> Self {
        Scalar8([v; LANES])
    }
    fn load(a: &[f32; LANES]) -> Self {
        Scalar8(*a)
    }
    fn to_array(self) -> [f32; LANES] {
        self.0
    }
    fn div(self, o: Self) -> Self {
        self.zip(o, |a, b| a / b)
    }
    fn mul_add(self, a: Self, b: Self) -> Self {
        Scalar8(std::array::from_fn(|l| self.0[l].mul_add(a.0[l], b.0[l])))
    }
    fn sqrt(self) -> Self {
        Scalar8(self.0.map(f32::sqrt))
    }
    fn not_lt(self, o: Self) -> Self {
        self.zip(o, |a, b| Self::mask(!(a < b)))
    }
    fn gt(self, o: Self) -> Self {
        self.zip(o, |a, b| Self::mask(a > b))
    }
    fn le(self, o: Self) -> Self {
        self.zip(o, |a, b| Self::mask(a <= b))
    }
    fn not_gt(self, o: Self) -> Self {
        self.zip(o, |a, b| Self::mask(!(a > b)))
    }
    fn or(self, o: Self) -> Self {
        self.zip(o, |a, b| f32::from_bits(a.to_bits() | b.to_bits()))
    }
    fn and_not(self, o: Self) -> Self {
        self.zip(o, |a, b| f32::from_bits(a.to_bits() & !b.to_bits()))
    }
    fn is_nan(self) -> Self {
        Scalar8(self.0.map(|a| Self::mask(a.is_nan())))
    }
    fn and(self, mask: Self) -> Self {
        self.zip(mask, |a, m| f32::from_bits(a.to_bits() & m.to_bits()))
    }
    fn select(mask: Self, a: Self, b: Self) -> Self {
        Scalar8(std::array::from_fn(|l| {
            if mask.0[l].to_bits() != 0 {
                a.0[l]
            } else {
                b.0[l]
            }
        }))
    }
    fn bits(self) -> u32 {
        (0..LANES).map(|l| (self.0[l].to_bits() >> 31) << l).sum()
    }
    unsafe fn gather(x: *const Vec3A, offset: &[u32; LANES]) -> V3<Self> {
        let v = offset.map(|o| unsafe { *x.add((o / 16) as usize) });
        V3 {
            x: Scalar8(v.map(|v| v.x)),
            y: Scalar8(v.map(|v| v.y)),
            z: Scalar8(v.map(|v| v.z)),
        }
    }
    unsafe fn scatter(x: *mut Vec3A, offset: &[u32; LANES], v: V3<Self>) {
        for (l, &o) in offset.iter().enumerate() {
            unsafe { *x.add((o / 16) as usize) = Vec3A::new(v.x.0[l], v.y.0[l], v.z.0[l]) };
        }
    }
}
