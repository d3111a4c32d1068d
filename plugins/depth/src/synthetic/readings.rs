//! The error model per pixel, in two parts. What depends only on the surface a pixel sees
//! (its depth, obliquity and edge flags) is worked out once per surface
//! ([`NoiseTables::coefficients`]): the σ of its axial error in raw steps, its lateral σ level,
//! whether it is beside a jump, and the raw value it can be read as. A still room's
//! coefficients are kept from frame to frame. What is drawn anew each frame is then one
//! branch-free pass ([`NoiseTables::readings`]): per pixel a hash, two table reads
//! ([`super::tables`]: the pixel its lateral error lands on, its normal sample), the reading
//! of that pixel, and the quantisation.
//!
//! A pixel without a reading whatever its noise (nothing seen, a part one pixel thin, a
//! surface too oblique) has a `NaN` σ, and a pixel that cannot be read (nothing, projector
//! shadow, out of range) a `NaN` raw value: the reading is then `NaN`, outside the raw scale,
//! and the pixel reads nothing, without a branch.

use super::NoiseSettings;
use super::edges::{JUMP, SHADOW, THIN};
use super::spans::Spans;
use super::tables::{
    LATERAL_ENTRIES, LATERAL_LEVELS, NORMALS, axial_sigma_raw, facing_angle, lateral_level,
    lateral_pairs, lateral_sigma_of_level, lowbias32, normal_quantiles,
};
use crate::camera::{self, DepthCamera, HEIGHT, RAW_NO_VALUE, WIDTH};
use crate::noise::{GRAZING_LIMIT, grazing_factor, lateral_sigma_px};

/// In a pixel's class: beside a jump (lost on the coin's toss); the low bits are its lateral
/// σ level.
const BESIDE_JUMP: u8 = 0x80;

/// Steps of the facing table.
const FACING_STEPS: usize = 1024;

/// Raw values, with [`RAW_NO_VALUE`].
const RAW_VALUES: usize = RAW_NO_VALUE as usize + 1;

/// The border of [`Coefficients::source`] around the image: the largest lateral offset, in
/// pixels (the tables' are at most 5).
pub(super) const PAD: usize = 8;
/// A row of [`Coefficients::source`].
pub(super) const PADDED_WIDTH: usize = WIDTH + 2 * PAD;
const PADDED_PIXELS: usize = PADDED_WIDTH * (HEIGHT + 2 * PAD);
/// The length of [`Coefficients::source`]: the padded image, rounded up to a power of two so
/// that an index masked into it needs no test.
const SOURCE_LEN: usize = PADDED_PIXELS.next_power_of_two();

/// The error model's tables, built once per camera.
pub struct NoiseTables {
    normals: Box<[f32; NORMALS]>,
    /// Per `cos² θ` in 1/1024 steps: the lateral σ level and the grazing factor
    /// `θ² / (π/2 - θ)²` of the axial σ, so no pixel computes an arc cosine.
    facing_table: Vec<(u8, f32)>,
    /// Per lateral σ level, the pixel read for a lateral error on each axis, as an offset
    /// in [`Coefficients::source`] ([`lateral_pairs`]): a pixel's lateral error is one
    /// table read.
    lateral_offsets: Box<[[i16; LATERAL_ENTRIES]; LATERAL_LEVELS]>,
    /// The same, all zero: the offsets without lateral error.
    no_offsets: Box<[[i16; LATERAL_ENTRIES]; LATERAL_LEVELS]>,
    /// Per raw value: the axial σ facing the camera and its grazing coefficient, in raw
    /// steps (see [`axial_sigma_raw`]).
    axial_table: Vec<(f32, f32)>,
    /// Millimetres per raw value ([`camera::raw_mm_table`]; 0 for [`RAW_NO_VALUE`]).
    mm_of_raw: Box<[u16; RAW_VALUES]>,
    /// `1 / |r|²` of each pixel's ray (see [`super::raster::DepthBuffer::normal_dot_ray`]),
    /// for the camera of [`Self::camera`].
    inverse_ray2: Vec<f32>,
    /// Per image column, a fixed hash ([`lowbias32`] of its index) that each row's salt and
    /// one more round make the pixel's hash.
    columns: [u32; WIDTH],
    camera: DepthCamera,
}

/// Per pixel, what the noise pass needs of the surface seen there ([`NoiseTables::coefficients`]).
#[derive(Clone, Debug)]
pub struct Coefficients {
    /// The lateral σ level, and [`BESIDE_JUMP`].
    pub class: Vec<u8>,
    /// The axial σ in raw steps (0 without axial error); `NaN` where the pixel reads nothing
    /// whatever its noise.
    pub sigma: Vec<f32>,
    /// The continuous raw value a pixel whose lateral error lands here reads; `NaN` where
    /// there is nothing to read. With a border of [`PAD`] pixels repeating the image's edge
    /// ([`padded`]), so that a lateral error that leaves the image reads its edge without
    /// a test per pixel.
    pub source: Box<[f32; SOURCE_LEN]>,
}

/// The index in [`Coefficients::source`] of pixel `k`.
#[inline]
fn padded(k: usize) -> usize {
    (k / WIDTH + PAD) * PADDED_WIDTH + k % WIDTH + PAD
}

impl Default for Coefficients {
    fn default() -> Self {
        let pixels = WIDTH * HEIGHT;
        Self {
            class: vec![0; pixels],
            sigma: vec![f32::NAN; pixels],
            // (Not `Box::new([..])`: 2 MB through the stack.)
            source: vec![f32::NAN; SOURCE_LEN]
                .into_boxed_slice()
                .try_into()
                .unwrap_or_else(|_| unreachable!("the length is SOURCE_LEN")),
        }
    }
}

impl Coefficients {
    /// Copies `from`'s coefficients of the pixels of `spans`.
    pub fn copy_spans(&mut self, from: &Coefficients, spans: &Spans) {
        for (j, r) in spans.iter() {
            let base = padded(j * WIDTH);
            let p = base + r.start..base + r.end;
            self.source[p.clone()].copy_from_slice(&from.source[p]);
            let r = j * WIDTH + r.start..j * WIDTH + r.end;
            self.class[r.clone()].copy_from_slice(&from.class[r.clone()]);
            self.sigma[r.clone()].copy_from_slice(&from.sigma[r]);
        }
        self.pad(spans);
    }

    /// Repeats the image's edge into the border of [`Self::source`] where the pixels of
    /// `spans` reach it.
    fn pad(&mut self, spans: &Spans) {
        for (j, r) in spans.iter() {
            let (first, last) = (padded(j * WIDTH), padded(j * WIDTH + WIDTH - 1));
            if r.start == 0 {
                let v = self.source[first];
                self.source[first - PAD..first].fill(v);
            }
            if r.end == WIDTH {
                let v = self.source[last];
                self.source[last + 1..=last + PAD].fill(v);
            }
        }
        let (top, bottom) = (!spans.row(0).is_empty(), !spans.row(HEIGHT - 1).is_empty());
        let row = |j: usize| (j + PAD) * PADDED_WIDTH..(j + PAD + 1) * PADDED_WIDTH;
        for (edge, border) in [(0, 0..PAD), (HEIGHT - 1, HEIGHT + PAD..HEIGHT + 2 * PAD)] {
            if (edge == 0 && top) || (edge != 0 && bottom) {
                let edge_row = row(edge);
                for b in border {
                    let start = b * PADDED_WIDTH;
                    self.source.copy_within(edge_row.clone(), start);
                }
            }
        }
    }
}

impl NoiseTables {
    pub fn new(camera: DepthCamera) -> Self {
        let normals = normal_quantiles::<NORMALS>();
        let lateral_offsets = Box::new(std::array::from_fn(|level| {
            lateral_pairs(f64::from(lateral_sigma_of_level(level)))
        }));
        let mm = camera::raw_mm_table();
        Self {
            normals,
            facing_table: (0..=FACING_STEPS)
                .map(|k| {
                    let theta = facing_angle((k as f32 / FACING_STEPS as f32).sqrt());
                    (
                        lateral_level(lateral_sigma_px(theta)),
                        grazing_factor(theta),
                    )
                })
                .collect(),
            lateral_offsets,
            no_offsets: Box::new([[0; LATERAL_ENTRIES]; LATERAL_LEVELS]),
            axial_table: (0..=RAW_NO_VALUE).map(axial_sigma_raw).collect(),
            mm_of_raw: Box::new(std::array::from_fn(|r| mm.get(r).copied().unwrap_or(0))),
            inverse_ray2: super::raster::inverse_ray_length_squared(&camera),
            columns: std::array::from_fn(|i| lowbias32(i as u32)),
            camera,
        }
    }

    /// The camera the tables were built for.
    pub fn camera(&self) -> DepthCamera {
        self.camera
    }

    /// The coefficients of the pixels of `spans` (all pixels: `None`), from the inverse
    /// depth `iz`, `|n · r|` and the edge flags of the surface each pixel sees.
    pub fn coefficients(
        &self,
        n: NoiseSettings,
        images: (&[f32], &[f32], &[u8]),
        spans: Option<&Spans>,
        out: &mut Coefficients,
    ) {
        let all;
        let spans = match spans {
            Some(spans) => spans,
            None => {
                all = Spans::all();
                &all
            }
        };
        coefficients_of(self, n, images, spans, out);
    }

    /// [`Self::coefficients`] of the pixels of `spans`, inlined into each of
    /// [`coefficients_of`]'s versions.
    #[inline(always)]
    fn coefficients_inlined(
        &self,
        n: NoiseSettings,
        (iz, normal_dot_ray, flags): (&[f32], &[f32], &[u8]),
        spans: &Spans,
        out: &mut Coefficients,
    ) {
        let cos2_limit = GRAZING_LIMIT.cos().powi(2);
        let (iz_far, iz_near) = (1.0 / self.camera.max_m, 1.0 / self.camera.min_m);
        let (range_on, grazing_on, axial_on) = (n.range, n.grazing, n.axial);
        // Per pixel of a row, the indices into the two tables, then the table reads, then
        // the arithmetic on them: three loops, of which the compiler vectorises the first and
        // the last (table reads in the same loop keep it from vectorising any of it).
        let mut facing_index = [0u32; WIDTH];
        let mut axial_index = [0u32; WIDTH];
        let mut level = [0u8; WIDTH];
        let mut grazing = [0f32; WIDTH];
        let mut axial = [0f32; WIDTH];
        // Row by row, the pixels `lo..hi` of row `j`, over slices (no index tests per pixel).
        // (A loop, not a closure called per row: a closure is compiled on its own, without
        // the instruction set of the version it is called from.)
        for (j, r) in spans.iter() {
            let (lo, hi) = (r.start, r.end);
            let (a, b) = (j * WIDTH + lo, j * WIDTH + hi);
            let p = padded(j * WIDTH);
            let (iz, normal_dot_ray, flags) = (&iz[a..b], &normal_dot_ray[a..b], &flags[a..b]);
            let inverse_ray2 = &self.inverse_ray2[a..b];
            let n = b - a;
            let indices = iz
                .iter()
                .zip(normal_dot_ray.iter().zip(inverse_ray2))
                .zip(facing_index[..n].iter_mut().zip(&mut axial_index[..n]));
            for ((&here, (&d, &inverse_ray2)), (facing, axial)) in indices {
                // How squarely the surface here faces its ray (the neighbour a lateral error
                // reads is, but at edges, the same surface).
                let cos2 = (d * d * inverse_ray2).min(1.0);
                *facing = round_small(cos2 * FACING_STEPS as f32).min(FACING_STEPS as u32);
                // The axial σ at this pixel's own depth (the one read is within a pixel or
                // two; σ changes little over that).
                let raw = camera::inverse_metres_to_raw_f32(here);
                *axial = round_small(raw.clamp(0.0, f32::from(RAW_NO_VALUE)));
            }
            let reads = facing_index[..n].iter().zip(&axial_index[..n]).zip(
                level[..n]
                    .iter_mut()
                    .zip(&mut grazing[..n])
                    .zip(&mut axial[..n]),
            );
            for ((&f, &r), ((level, grazing), axial)) in reads {
                let (l, g) = self.facing_table[f as usize % (FACING_STEPS + 1)];
                let (facing, per_grazing) = self.axial_table[r as usize % RAW_VALUES];
                (*level, *grazing) = (l, g);
                *axial = if axial_on {
                    facing + per_grazing * g
                } else {
                    0.0
                };
            }
            let pixels = iz
                .iter()
                .zip(normal_dot_ray.iter().zip(inverse_ray2))
                .zip(flags.iter().zip(level[..n].iter().zip(&axial[..n])))
                .zip(out.class[a..b].iter_mut().zip(&mut out.sigma[a..b]))
                .zip(&mut out.source[p + lo..p + hi]);
            for (
                (((&here, (&d, &inverse_ray2)), (&f, (&level, &axial))), (class, sigma)),
                source,
            ) in pixels
            {
                // Without branches (edges make them unpredictable): everything is computed
                // for every pixel, and a pixel without a reading gets `NaN`.
                let raw = camera::inverse_metres_to_raw_f32(here);
                // The raw value this surface is read as, if the projector lights it and it
                // is within range (the range is the surface's: where the pattern is matched,
                // not where the noisy reading lands).
                let readable = (here != 0.0)
                    & (f & SHADOW == 0)
                    & (!range_on | (here >= iz_far) & (here <= iz_near));
                *source = if readable { raw } else { f32::NAN };
                // No reading whatever the noise: nothing here, a part one pixel thin, or a
                // surface too oblique.
                let cos2 = (d * d * inverse_ray2).min(1.0);
                let lost = (here == 0.0) | (f & THIN != 0) | (grazing_on & (cos2 < cos2_limit));
                *sigma = if lost { f32::NAN } else { axial };
                let jump = if f & JUMP != 0 { BESIDE_JUMP } else { 0 };
                *class = if lost { 0 } else { level | jump };
            }
        }
        out.pad(spans);
    }

    /// One frame's readings: per pixel, from its hash in the frame's `stream`, the coin of a
    /// pixel beside a jump, its lateral offsets and its axial error; the raw value read and
    /// its millimetres into `out_raw` and `out_mm` ([`RAW_NO_VALUE`] and 0: none).
    pub fn readings(
        &self,
        n: NoiseSettings,
        c: &Coefficients,
        stream: u64,
        out_raw: &mut [u16],
        out_mm: &mut [u16],
    ) {
        readings_of(self, n, c, stream, (out_raw, out_mm));
    }

    /// [`Self::readings`], inlined into each of [`readings_of`]'s versions.
    #[inline(always)]
    fn readings_inlined(
        &self,
        n: NoiseSettings,
        c: &Coefficients,
        stream: u64,
        (out_raw, out_mm): (&mut [u16], &mut [u16]),
    ) {
        let offsets = if n.lateral {
            &self.lateral_offsets
        } else {
            &self.no_offsets
        };
        let rows = c
            .class
            .chunks_exact(WIDTH)
            .zip(c.sigma.chunks_exact(WIDTH))
            .zip(
                out_raw
                    .chunks_exact_mut(WIDTH)
                    .zip(out_mm.chunks_exact_mut(WIDTH)),
            )
            .enumerate();
        // One hash per pixel gives its lateral offsets, its normal sample and its coin, so
        // that one pixel's fate does not shift the noise of the others. A row at a time, in
        // three loops: the hashes (32-bit arithmetic), the table reads (the surface each
        // pixel's lateral error lands on, its normal sample), then the arithmetic on them.
        // The first and the last the compiler vectorises, which it cannot with the table
        // reads in the same loop.
        let mut row = Row {
            hashes: [0; WIDTH],
            entry: [0; WIDTH],
            seen: [0.0; WIDTH],
            normal: [0.0; WIDTH],
        };
        // Raw values are linear in inverse depth: the reading as a continuous raw value, its
        // axial error added in raw steps; lost beside a jump on the coin's toss (the class's
        // top bit and the hash's bit 20).
        let reading = |h: u32, class: u8, seen: f32, sigma: f32, normal: f32| {
            let kept = (u32::from(class) & (h >> 13) & u32::from(BESIDE_JUMP)) == 0;
            (seen + sigma * normal, kept)
        };
        for (j, ((class, sigma), (out_raw, out_mm))) in rows {
            self.sample_row(offsets, c, stream, j, class, &mut row);
            let Row {
                hashes,
                seen,
                normal,
                ..
            } = &row;
            if !n.quantise {
                for i in 0..WIDTH {
                    let (raw, kept) = reading(hashes[i], class[i], seen[i], sigma[i], normal[i]);
                    let z = kept.then(|| camera::raw_f32_to_metres(raw)).flatten();
                    (out_mm[i], out_raw[i]) = match z {
                        Some(z) => (
                            (z * 1000.0 + 0.5).min(f32::from(u16::MAX)) as u16,
                            camera::metres_to_raw(z).unwrap_or(RAW_NO_VALUE),
                        ),
                        None => (0, RAW_NO_VALUE),
                    };
                }
                continue;
            }
            let pixels = out_raw
                .iter_mut()
                .zip(hashes.iter().zip(class))
                .zip(seen.iter().zip(sigma).zip(normal));
            for ((out, (&h, &class)), ((&seen, &sigma), &normal)) in pixels {
                let (raw, kept) = reading(h, class, seen, sigma, normal);
                // The nearest raw value, if the scale holds it: a select by mask, not a
                // branch (beside jumps the coin makes it unpredictable; `NaN` fails both
                // comparisons, and `max` then gives 0).
                let on_scale = kept & (raw >= -0.5) & (raw < f32::from(RAW_NO_VALUE) - 0.5);
                let mask = u32::from(on_scale).wrapping_neg();
                let r = (round_small(raw.max(0.0)) & mask) | (u32::from(RAW_NO_VALUE) & !mask);
                *out = r as u16;
            }
            for (mm, &r) in out_mm.iter_mut().zip(out_raw.iter()) {
                *mm = self.mm_of_raw[usize::from(r) % RAW_VALUES];
            }
        }
    }
}

impl NoiseTables {
    /// Row `j`'s hashes, and per pixel the surface its lateral error lands on and its
    /// normal sample (table reads only).
    #[inline(always)]
    fn sample_row(
        &self,
        offsets: &[[i16; LATERAL_ENTRIES]; LATERAL_LEVELS],
        c: &Coefficients,
        stream: u64,
        j: usize,
        class: &[u8],
        row: &mut Row,
    ) {
        // A pixel's hash: its column's (drawn once) with the row's salt, mixed by one
        // multiply-xorshift round (cheaper than hashing the pixel's index afresh).
        let salt = splitmix64(stream ^ j as u64) as u32;
        // With it, the entry of its lateral offset in the table of its σ level (the level's
        // table, then the hash's low bits): worked out here, where the compiler vectorises,
        // the table reads below take one load each.
        let hashes = row.hashes.iter_mut().zip(&mut row.entry);
        for ((h, entry), (&column, &class)) in hashes.zip(self.columns.iter().zip(class)) {
            let x = column ^ salt;
            let x = (x ^ (x >> 16)).wrapping_mul(0x7feb_352d);
            *h = x ^ (x >> 15);
            let level = u32::from(class) % LATERAL_LEVELS as u32;
            *entry = level * LATERAL_ENTRIES as u32 + (*h % LATERAL_ENTRIES as u32);
        }
        // The pixel read is `dj` rows and `di` columns away (clamped to the image by the
        // source's border).
        let p = padded(j * WIDTH);
        let offsets = offsets.as_flattened();
        let pixels = row
            .hashes
            .iter()
            .zip(&row.entry)
            .zip(row.seen.iter_mut().zip(row.normal.iter_mut()))
            .enumerate();
        for (i, ((&h, &entry), (seen, normal))) in pixels {
            let offset = offsets[entry as usize % (LATERAL_LEVELS * LATERAL_ENTRIES)];
            let s = (p + i).wrapping_add_signed(isize::from(offset));
            // (The offsets stay within the border: `s` is in the padded image.)
            *seen = c.source[s % SOURCE_LEN];
            *normal = self.normals[(h >> 21) as usize % NORMALS];
        }
    }
}

for_this_cpu! {
/// [`NoiseTables::coefficients`], in a version for this CPU (`for_this_cpu!`).
fn coefficients_of(
    tables: &NoiseTables,
    n: NoiseSettings,
    images: (&[f32], &[f32], &[u8]),
    spans: &Spans,
    out: &mut Coefficients,
) {
    tables.coefficients_inlined(n, images, spans, out);
}
}

for_this_cpu! {
/// [`NoiseTables::readings`], in a version for this CPU (`for_this_cpu!`).
fn readings_of(
    tables: &NoiseTables,
    n: NoiseSettings,
    c: &Coefficients,
    stream: u64,
    out: (&mut [u16], &mut [u16]),
) {
    tables.readings_inlined(n, c, stream, out);
}
}

/// A row's draws ([`NoiseTables::sample_row`]).
struct Row {
    hashes: [u32; WIDTH],
    /// Per pixel, its entry in the flattened table of lateral offsets.
    entry: [u32; WIDTH],
    seen: [f32; WIDTH],
    normal: [f32; WIDTH],
}

/// `x` rounded to the nearest integer (ties to even), for `0 <= x < 2^23`: the low bits of
/// `x + 2^23`, whose unit is then the float's last mantissa bit. Per pixel this replaces
/// the saturating conversion `as` compiles to, which on x86-64 is several instructions
/// and branches (measured: a third of the time of the pass that indexes the tables).
#[inline]
fn round_small(x: f32) -> u32 {
    (x + 8_388_608.0).to_bits() & 0x7f_ffff
}

/// SplitMix64 (Steele, Lea & Flood 2014): a fast, well-mixed hash of a 64-bit counter.
#[inline]
pub fn splitmix64(x: u64) -> u64 {
    let mut z = x.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// Steps the SplitMix64 sequence at `state` and reads the step as a number in [0, 1]
/// (53 bits rounded to an f32).
#[inline]
pub fn next_unit(state: &mut u64) -> f32 {
    *state = splitmix64(*state);
    (*state >> 11) as f32 / (1u64 << 53) as f32
}
