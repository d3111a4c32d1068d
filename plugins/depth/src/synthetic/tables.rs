//! The error model's tables, built once per camera ([`super::readings::NoiseTables`]): what
//! a frame's per-pixel noise reads instead of computing a transcendental per pixel. Each is
//! a distribution drawn by a uniform index (a pixel's hash bits): the axial error from the
//! normal's quantiles, the lateral error from a table of pixel offsets in which every
//! whole-pixel pair appears in proportion to its probability.

use super::readings::{PAD, PADDED_WIDTH};
use crate::camera;
use crate::noise::axial_sigma_with_grazing_m;

/// Entries of the table of normal quantiles a frame's axial errors are read from (the top 11
/// bits of a pixel's hash): a table read per sample instead of a transcendental, from a
/// table small enough to stay in the first-level cache (8 kB).
pub(super) const NORMALS: usize = 1 << 11;

/// Entries of a lateral offset table (the low 10 bits of a pixel's hash).
pub(super) const LATERAL_ENTRIES: usize = 1 << 10;
/// Lateral σ levels, from 0.8 px (facing the camera) up (see [`lateral_level`]).
pub(super) const LATERAL_LEVELS: usize = 16;

/// The axial σ of Nguyen et al. ([`crate::noise`]) at the depth of raw value `raw`, in raw
/// steps: facing the camera, and per unit of the grazing factor. A depth error `e` small
/// against `z` moves the raw value by `e / (0.00307 z²)`; the spread facing the camera is
/// about half a raw step at every depth (the matcher's sub-pixel precision).
pub(super) fn axial_sigma_raw(raw: u16) -> (f32, f32) {
    let Some(z) = camera::raw_to_metres(raw) else {
        return (0.0, 0.0);
    };
    let step = camera::raw_step_m(z);
    let facing = axial_sigma_with_grazing_m(z, 0.0);
    let per_grazing = axial_sigma_with_grazing_m(z, 1.0) - facing;
    (facing / step, per_grazing / step)
}

/// A lateral error of σ px on each axis as a table: each whole-pixel pair `(di, dj)` (each
/// `round(σ g)` for a standard normal `g`, independently, the tails folded into ±[`PAD`])
/// appears in proportion to its probability, to 1/[`LATERAL_ENTRIES`] (largest remainders),
/// as the offset `dj · PADDED_WIDTH + di` of the pixel read: a uniformly drawn entry is a
/// draw of the pixel read, in one table read per pixel.
pub(super) fn lateral_pairs(sigma: f64) -> [i16; LATERAL_ENTRIES] {
    let most = PAD as i32;
    let cdf = |x: f64| 0.5 * libm::erfc(-x / std::f64::consts::SQRT_2);
    // P(round(σ g) = k).
    let p: Vec<f64> = (-most..=most)
        .map(|k| {
            let below = if k == -most {
                0.0
            } else {
                cdf((f64::from(k) - 0.5) / sigma)
            };
            let upto = if k == most {
                1.0
            } else {
                cdf((f64::from(k) + 0.5) / sigma)
            };
            upto - below
        })
        .collect();
    let n = LATERAL_ENTRIES as f64;
    let mut cells: Vec<(i32, i32, usize, f64)> = Vec::new();
    for (a, pa) in (-most..=most).zip(&p) {
        for (b, pb) in (-most..=most).zip(&p) {
            let want = pa * pb * n;
            cells.push((a, b, want.floor() as usize, want - want.floor()));
        }
    }
    let mut left = LATERAL_ENTRIES - cells.iter().map(|c| c.2).sum::<usize>();
    let mut order: Vec<usize> = (0..cells.len()).collect();
    order.sort_by(|&x, &y| cells[y].3.total_cmp(&cells[x].3));
    for &c in &order {
        if left == 0 {
            break;
        }
        cells[c].2 += 1;
        left -= 1;
    }
    let mut table = [0i16; LATERAL_ENTRIES];
    let entries = cells.iter().flat_map(|&(di, dj, count, _)| {
        std::iter::repeat_n((dj * PADDED_WIDTH as i32 + di) as i16, count)
    });
    for (t, e) in table.iter_mut().zip(entries) {
        *t = e;
    }
    table
}

/// The `N` quantiles of the standard normal at `(m + 1/2) / N`, scaled to a unit second
/// moment (the table is then a distribution of exactly σ = 1, truncated at about 3.3 σ for
/// 2,048 entries): a uniformly drawn entry is a normal sample, stratified, with none of a
/// random table's error in its spread.
pub(super) fn normal_quantiles<const N: usize>() -> Box<[f32; N]> {
    let quantiles: Vec<f64> = (0..N)
        .map(|m| normal_quantile((m as f64 + 0.5) / N as f64))
        .collect();
    let scale = (quantiles.iter().map(|q| q * q).sum::<f64>() / N as f64)
        .sqrt()
        .recip();
    Box::new(std::array::from_fn(|m| (quantiles[m] * scale) as f32))
}

/// `x` with `Φ(x) = p` for `0 < p < 1`, by bisection on `Φ(x) = erfc(-x / √2) / 2`.
pub(super) fn normal_quantile(p: f64) -> f64 {
    let (mut lo, mut hi) = (-10.0f64, 10.0f64);
    for _ in 0..64 {
        let mid = 0.5 * (lo + hi);
        if 0.5 * libm::erfc(-mid / std::f64::consts::SQRT_2) < p {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// A 32-bit integer hash of good avalanche ("lowbias32", Wellons 2018: two multiply-xorshift
/// rounds), a bijection: the columns' hashes are all different, and so (the row's salt and
/// the round are bijections too) are the hashes of a row's pixels.
#[inline]
pub(super) fn lowbias32(x: u32) -> u32 {
    let mut x = x ^ (x >> 16);
    x = x.wrapping_mul(0x7feb_352d);
    x ^= x >> 15;
    x = x.wrapping_mul(0x846c_a68b);
    x ^ (x >> 16)
}

/// The level whose σ is nearest above `sigma` px (levels step 0.02 px from 0.8 px).
pub(super) fn lateral_level(sigma: f32) -> u8 {
    (((sigma - 0.8) / 0.02).ceil().max(0.0) as usize).min(LATERAL_LEVELS - 1) as u8
}

pub(super) fn lateral_sigma_of_level(level: usize) -> f32 {
    0.8 + 0.02 * level as f32
}

/// The angle between a surface's normal and the ray from its `|cos|`.
pub(super) fn facing_angle(facing: f32) -> f32 {
    facing.clamp(0.0, 1.0).acos()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The quantiles against the normal's tabulated values, and the table as a distribution:
    /// mean 0, σ 1, 68.27 % within one σ and 95.45 % within two (independent of how it was
    /// made).
    #[test]
    fn the_normal_table_is_a_unit_normal() {
        for (p, x) in [
            (0.5, 0.0),
            (0.841_344_746, 1.0),
            (0.975, 1.959_964),
            (0.001, -3.090_232),
        ] {
            assert!(
                (normal_quantile(p) - x).abs() < 1e-5,
                "{p}: {}",
                normal_quantile(p)
            );
        }
        let table = normal_quantiles::<NORMALS>();
        let n = NORMALS as f64;
        let mean = table.iter().map(|&g| f64::from(g)).sum::<f64>() / n;
        let var = table.iter().map(|&g| f64::from(g).powi(2)).sum::<f64>() / n;
        assert!(
            mean.abs() < 1e-6 && (var - 1.0).abs() < 1e-5,
            "{mean} {var}"
        );
        let within = |k: f32| table.iter().filter(|g| g.abs() < k).count() as f64 / n;
        assert!((within(1.0) - 0.6827).abs() < 0.002, "{}", within(1.0));
        assert!((within(2.0) - 0.9545).abs() < 0.002, "{}", within(2.0));
    }

    /// The lateral table as a distribution, against draws of `round(σ g)` per axis from a
    /// seeded normal generator (independent of how the table was made): per axis the share
    /// of 0, ±1 and ±2 px, and the axes independent.
    #[test]
    fn the_lateral_table_draws_both_axes_independently() {
        use rand::SeedableRng;
        use rand_distr::{Distribution, StandardNormal};
        let sigma = 0.8;
        let table = lateral_pairs(sigma);
        let split = |o: i16| {
            let o = i32::from(o);
            let dj = (o + 8 * PADDED_WIDTH as i32 + 8).div_euclid(PADDED_WIDTH as i32) - 8;
            (o - dj * PADDED_WIDTH as i32, dj)
        };
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let draws = 200_000;
        let mut counted = [[0usize; 5]; 2];
        for _ in 0..draws {
            for axis in &mut counted {
                let g: f64 = StandardNormal.sample(&mut rng);
                let k = (sigma * g).round() as i32;
                if k.abs() <= 2 {
                    axis[(k + 2) as usize] += 1;
                }
            }
        }
        let n = LATERAL_ENTRIES as f64;
        for k in -2..=2i32 {
            let share_di = table.iter().filter(|&&o| split(o).0 == k).count() as f64 / n;
            let share_dj = table.iter().filter(|&&o| split(o).1 == k).count() as f64 / n;
            let drawn = (counted[0][(k + 2) as usize] + counted[1][(k + 2) as usize]) as f64
                / (2 * draws) as f64;
            assert!(
                (share_di - drawn).abs() < 0.01,
                "di = {k}: {share_di} vs {drawn}"
            );
            assert!(
                (share_dj - drawn).abs() < 0.01,
                "dj = {k}: {share_dj} vs {drawn}"
            );
        }
        let zero = table.iter().filter(|&&o| split(o).0 == 0).count() as f64 / n;
        let both = table.iter().filter(|&&o| o == 0).count() as f64 / n;
        assert!((both - zero * zero).abs() < 0.005, "{both} vs {zero}²");
    }
}
