//! A synthetic Kinect v1: triangle meshes in sensor space (the posed avatar, its garment, a
//! room, boxes) rendered into depth frames with the device's published error
//! ([`crate::noise`], [`crate::camera`]), seeded (same seed, same frames), with the exact
//! depth and what each pixel sees as ground truth.
//!
//! Per pixel, in order:
//! 1. the nearest surface, by z-buffer ([`raster`]);
//! 2. lateral error: the pixel reads the surface `N(0, σL(θ))` pixels away on each axis, so
//!    edges wander as they do on the device;
//! 3. no reading where the surface is more oblique than [`crate::noise::GRAZING_LIMIT`];
//! 4. the projector's shadow: no reading where the projector, 7.5 cm to the sensor's right,
//!    cannot light the point (found per row, `edges::mark_shadow`);
//!    beside a foreground edge at `z1` over a background at `z2` that band is
//!    `f b (1/z1 - 1/z2)` pixels wide, on the image's left of the edge;
//! 5. no reading where the surface is outside the camera's range (0.8-4 m);
//! 6. axial error `N(0, σz(z, θ))`;
//! 7. the 11-bit raw quantisation (about 1/8 px of disparity);
//! 8. dropouts where the correlation window straddles a depth edge: half the pixels next to
//!    a jump, and every pixel of a part one pixel thin.

pub mod edges;
pub mod raster;

use std::sync::Arc;

use glam::Vec3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

use crate::camera::{self, DepthCamera, HEIGHT, PIXELS, RAW_NO_VALUE, WIDTH};
use crate::frame::DepthFrame;
use crate::noise::{GRAZING_LIMIT, axial_sigma_with_grazing_m, grazing_factor, lateral_sigma_px};
pub use raster::DepthBuffer;

/// What a surface is, for the per-pixel ground truth.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum Label {
    Nothing = 0,
    Body = 1,
    Garment = 2,
    Room = 3,
    Other = 4,
}

/// A triangle mesh in sensor space.
#[derive(Clone, Debug)]
pub struct SceneMesh {
    pub positions: Vec<Vec3>,
    pub triangles: Vec<[u32; 3]>,
    pub label: Label,
    /// A closed mesh with outward (counter-clockwise) faces, such as the body: the faces
    /// turned away from the camera are skipped. Open meshes (a garment, a wall) are seen
    /// from both sides.
    pub closed: bool,
}

/// What the synthetic camera sees.
#[derive(Clone, Debug, Default)]
pub struct Scene {
    pub meshes: Vec<SceneMesh>,
}

impl Scene {
    /// A floor at sensor-space height `floor_y` (negative: below the sensor) and a back
    /// wall at depth `wall_z`, both 8 m wide.
    pub fn room(floor_y: f32, wall_z: f32) -> Self {
        let mut scene = Self::default();
        let (w, top) = (4.0, floor_y + 3.0);
        scene.add_quad(
            [
                Vec3::new(w, floor_y, 0.3),
                Vec3::new(-w, floor_y, 0.3),
                Vec3::new(-w, floor_y, wall_z),
                Vec3::new(w, floor_y, wall_z),
            ],
            Label::Room,
        );
        scene.add_wall(wall_z, w, floor_y, top);
        scene
    }

    /// A wall facing the camera at depth `z`, `half_width` either side, from `bottom` to `top`.
    pub fn add_wall(&mut self, z: f32, half_width: f32, bottom: f32, top: f32) {
        self.add_quad(
            [
                Vec3::new(half_width, bottom, z),
                Vec3::new(-half_width, bottom, z),
                Vec3::new(-half_width, top, z),
                Vec3::new(half_width, top, z),
            ],
            Label::Room,
        );
    }

    /// An axis-aligned box.
    pub fn add_box(&mut self, centre: Vec3, half: Vec3, label: Label) {
        let corner = |i: usize| {
            centre
                + half
                    * Vec3::new(
                        if i & 1 == 0 { -1.0 } else { 1.0 },
                        if i & 2 == 0 { -1.0 } else { 1.0 },
                        if i & 4 == 0 { -1.0 } else { 1.0 },
                    )
        };
        let faces = [
            [0, 1, 3, 2],
            [4, 6, 7, 5],
            [0, 4, 5, 1],
            [2, 3, 7, 6],
            [0, 2, 6, 4],
            [1, 5, 7, 3],
        ];
        for f in faces {
            self.add_quad(f.map(corner), label);
        }
    }

    fn add_quad(&mut self, corners: [Vec3; 4], label: Label) {
        self.meshes.push(SceneMesh {
            positions: corners.to_vec(),
            triangles: vec![[0, 1, 2], [0, 2, 3]],
            label,
            closed: false,
        });
    }
}

/// Which parts of the error model apply (all by default; [`Self::exact`] for none).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NoiseSettings {
    pub lateral: bool,
    pub grazing: bool,
    pub shadow: bool,
    pub axial: bool,
    pub range: bool,
    pub quantise: bool,
    pub dropouts: bool,
}

impl Default for NoiseSettings {
    fn default() -> Self {
        Self {
            lateral: true,
            grazing: true,
            shadow: true,
            axial: true,
            range: true,
            quantise: true,
            dropouts: true,
        }
    }
}

impl NoiseSettings {
    /// The exact depth of every surface, nothing left out.
    pub fn exact() -> Self {
        Self {
            lateral: false,
            grazing: false,
            shadow: false,
            axial: false,
            range: false,
            quantise: false,
            dropouts: false,
        }
    }
}

/// A rendered frame with its ground truth.
#[derive(Clone, Debug)]
pub struct SyntheticFrame {
    pub frame: DepthFrame,
    /// What each pixel sees ([`Label`] as `u8`), before any reading is lost.
    pub labels: Arc<[u8]>,
    /// The exact depth each pixel sees, metres (infinite: nothing).
    pub true_depth_m: Arc<[f32]>,
}

/// Normal samples drawn once; a frame's noise indexes them with its own seeded stream (a
/// ChaCha8 draw and a table read per sample, instead of a transcendental per sample).
const TABLE: usize = 1 << 16;

/// A pixel without a reading, in [`SyntheticCamera::sample`].
const LOST: u32 = u32::MAX;

/// Entries of a lateral offset table (12 bits of a pixel's hash).
const LATERAL_ENTRIES: usize = 1 << 12;
/// Lateral σ levels, from 0.8 px (facing the camera) up (see [`lateral_level`]).
const LATERAL_LEVELS: usize = 16;

/// The synthetic depth camera.
pub struct SyntheticCamera {
    pub camera: DepthCamera,
    pub noise: NoiseSettings,
    seed: u64,
    frames: u64,
    normals: Vec<f32>,
    /// Per `cos² θ` in 1/1024 steps: the lateral σ level and the grazing factor
    /// `θ² / (π/2 - θ)²` of the axial σ, so no pixel computes an arc cosine.
    facing_table: Vec<(u8, f32)>,
    /// Per lateral σ level, whole-pixel offsets `round(σ g)` for normal samples `g`: a
    /// pixel's lateral error is two table reads.
    lateral_offsets: Vec<[i8; LATERAL_ENTRIES]>,
    /// Per raw value: the axial σ facing the camera and its grazing coefficient, in raw
    /// steps (see [`axial_sigma_raw`]).
    axial_table: Vec<(f32, f32)>,
    /// `1 / |r|²` of each pixel's ray (see [`raster::DepthBuffer::normal_dot_ray`]).
    inverse_ray2: Vec<f32>,
    view: DepthBuffer,
    /// Per pixel, the pixel its reading comes from ([`LOST`]: none) and its axial error in
    /// raw steps (scratch of [`Self::render`]).
    sample: Vec<u32>,
    axial_noise: Vec<f32>,
    edges: edges::EdgeFlags,
    /// The last frame's images, reused when the caller has dropped them (no fresh pages
    /// per frame).
    spare: Option<SyntheticFrame>,
}

impl SyntheticCamera {
    pub fn new(camera: DepthCamera, noise: NoiseSettings, seed: u64) -> Self {
        let mut rng = ChaCha8Rng::seed_from_u64(0x6b69_6e65_6374);
        let normals: Vec<f32> = (0..TABLE)
            .map(|_| StandardNormal.sample(&mut rng))
            .collect();
        let lateral_offsets = (0..LATERAL_LEVELS)
            .map(|level| {
                let sigma = lateral_sigma_of_level(level);
                std::array::from_fn(|m| (sigma * normals[m]).round().clamp(-127.0, 127.0) as i8)
            })
            .collect();
        Self {
            camera,
            noise,
            seed,
            frames: 0,
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
            axial_table: (0..=RAW_NO_VALUE).map(axial_sigma_raw).collect(),
            inverse_ray2: raster::inverse_ray_length_squared(&camera),
            view: DepthBuffer::default(),
            sample: vec![LOST; PIXELS],
            axial_noise: vec![0.0; PIXELS],
            edges: edges::EdgeFlags::default(),
            spare: None,
        }
    }

    /// Renders the next frame of `scene`, `time_s` seconds into the stream.
    pub fn render(&mut self, scene: &Scene, time_s: f64) -> SyntheticFrame {
        let index = self.frames;
        self.frames += 1;
        let stream = splitmix64(self.seed ^ index.wrapping_mul(0x9e37_79b9_7f4a_7c15));
        let cam = self.camera;
        self.view.clear();
        for m in &scene.meshes {
            self.view
                .draw(&cam, &m.positions, &m.triangles, m.label as u8, m.closed);
        }
        let mut images = Images::take(self.spare.take());
        // Unique by construction (`Images::take`): no copy is made here.
        let out_mm = Arc::make_mut(&mut images.depth_mm);
        let out_raw = Arc::make_mut(&mut images.raw);
        let iz = &self.view.inverse_z;
        for (t, &v) in Arc::make_mut(&mut images.true_z).iter_mut().zip(iz) {
            *t = if v > 0.0 { 1.0 / v } else { f32::INFINITY };
        }
        Arc::make_mut(&mut images.labels).copy_from_slice(&self.view.label);
        self.edges
            .compute(iz, &cam, self.noise.shadow, self.noise.dropouts);
        let flags = &self.edges.flags;
        out_raw.fill(RAW_NO_VALUE);
        out_mm.fill(0);
        let n = self.noise;
        let cos2_limit = GRAZING_LIMIT.cos().powi(2);
        let (iz_far, iz_near) = (1.0 / cam.max_m, 1.0 / cam.min_m);
        let mm_of_raw = camera::raw_mm_table();
        let (width, height) = (WIDTH as isize, HEIGHT as isize);
        // Two passes, each with short chains of dependent reads (one long chain per pixel
        // leaves the processor waiting): first, per pixel, whether it is lost, where its
        // lateral error makes it read, and its axial error in raw steps; then the readings.
        let (sample, axial) = (&mut self.sample, &mut self.axial_noise);
        for j in 0..HEIGHT {
            for i in 0..WIDTH {
                let k = j * WIDTH + i;
                sample[k] = LOST;
                let here = iz[k];
                if here == 0.0 {
                    continue;
                }
                // One hash per pixel gives its lateral offsets, its normal sample and its
                // coin, so that one pixel's fate does not shift the noise of the others.
                let h = splitmix64(stream ^ k as u64);
                // Lost: a thin part, or beside a jump on the coin's toss. One test on the
                // combined bits: testing the coin first, as the compiler may order `||`, is a
                // branch mispredicted on every other pixel.
                let coin = (h >> 63) as u8;
                if flags[k] & (edges::THIN | (edges::JUMP * coin)) != 0 {
                    continue;
                }
                // How squarely the surface here faces its ray (the neighbour a lateral error
                // reads is, but at edges, the same surface).
                let d = self.view.normal_dot_ray[k];
                let cos2 = (d * d * self.inverse_ray2[k]).min(1.0);
                if n.grazing && cos2 < cos2_limit {
                    continue;
                }
                let (level, grazing) =
                    self.facing_table[round_small(cos2 * FACING_STEPS as f32) as usize];
                let mut s = k;
                if n.lateral {
                    let offsets = &self.lateral_offsets[usize::from(level)];
                    let di = offsets[(h & 0xfff) as usize] as isize;
                    let dj = offsets[(h >> 12 & 0xfff) as usize] as isize;
                    let si = (i as isize + di).clamp(0, width - 1);
                    let sj = (j as isize + dj).clamp(0, height - 1);
                    s = (sj * width + si) as usize;
                }
                sample[k] = s as u32;
                // The axial σ at this pixel's own depth (the one read is within a pixel or
                // two; σ changes little over that).
                axial[k] = if n.axial {
                    let raw = camera::inverse_metres_to_raw_f32(here);
                    let index = round_small(raw.clamp(0.0, f32::from(RAW_NO_VALUE)));
                    let (facing, per_grazing) = self.axial_table[index as usize];
                    (facing + per_grazing * grazing) * self.normals[(h >> 32 & 0xffff) as usize]
                } else {
                    0.0
                };
            }
        }
        for (k, (&s, &noise)) in sample.iter().zip(axial.iter()).enumerate() {
            if s == LOST {
                continue;
            }
            let s = s as usize;
            let seen = iz[s];
            if seen == 0.0 || flags[s] & edges::SHADOW != 0 {
                continue;
            }
            // The range is the surface's: where the pattern is matched, not where the noisy
            // reading lands.
            if n.range && !(iz_far..=iz_near).contains(&seen) {
                continue;
            }
            // Raw values are linear in inverse depth: the reading as a continuous raw value,
            // its axial error added in raw steps.
            let raw = camera::inverse_metres_to_raw_f32(seen) + noise;
            if n.quantise {
                // The nearest raw value, if the scale holds it.
                if (-0.5..f32::from(RAW_NO_VALUE) - 0.5).contains(&raw) {
                    let r = round_small(raw.max(0.0));
                    out_raw[k] = r as u16;
                    out_mm[k] = mm_of_raw[r as usize];
                }
            } else if let Some(z) = camera::raw_f32_to_metres(raw) {
                out_mm[k] = (z * 1000.0 + 0.5).min(f32::from(u16::MAX)) as u16;
                out_raw[k] = camera::metres_to_raw(z).unwrap_or(RAW_NO_VALUE);
            }
        }
        let frame = images.into_frame(cam, time_s, index as u32);
        self.spare = Some(frame.clone());
        frame
    }
}

/// The axial σ of Nguyen et al. ([`crate::noise`]) at the depth of raw value `raw`, in raw
/// steps: facing the camera, and per unit of the grazing factor. A depth error `e` small
/// against `z` moves the raw value by `e / (0.00307 z²)`; the spread facing the camera is
/// about half a raw step at every depth (the matcher's sub-pixel precision).
fn axial_sigma_raw(raw: u16) -> (f32, f32) {
    let Some(z) = camera::raw_to_metres(raw) else {
        return (0.0, 0.0);
    };
    let step = camera::raw_step_m(z);
    let facing = axial_sigma_with_grazing_m(z, 0.0);
    let per_grazing = axial_sigma_with_grazing_m(z, 1.0) - facing;
    (facing / step, per_grazing / step)
}

/// A frame's images, recycled from the frame before when its caller has dropped them.
struct Images {
    depth_mm: Arc<[u16]>,
    raw: Arc<[u16]>,
    labels: Arc<[u8]>,
    true_z: Arc<[f32]>,
}

impl Images {
    fn take(spare: Option<SyntheticFrame>) -> Self {
        fn reuse<T: Copy>(a: Option<Arc<[T]>>, zero: T) -> Arc<[T]> {
            match a {
                // The caller has dropped its frame: this is the only reference.
                Some(a) if Arc::strong_count(&a) == 1 && Arc::weak_count(&a) == 0 => a,
                _ => vec![zero; PIXELS].into(),
            }
        }
        let (d, r, l, t) = match spare {
            Some(f) => (
                Some(f.frame.depth_mm),
                f.frame.raw,
                Some(f.labels),
                Some(f.true_depth_m),
            ),
            None => (None, None, None, None),
        };
        Self {
            depth_mm: reuse(d, 0),
            raw: reuse(r, 0),
            labels: reuse(l, 0),
            true_z: reuse(t, 0.0),
        }
    }

    fn into_frame(self, camera: DepthCamera, time_s: f64, timestamp: u32) -> SyntheticFrame {
        SyntheticFrame {
            frame: DepthFrame {
                depth_mm: self.depth_mm,
                raw: Some(self.raw),
                rgb: None,
                time_s,
                timestamp,
                camera,
            },
            labels: self.labels,
            true_depth_m: self.true_z,
        }
    }
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
fn splitmix64(x: u64) -> u64 {
    let mut z = x.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// Steps of the facing table.
const FACING_STEPS: usize = 1024;

/// The level whose σ is nearest above `sigma` px (levels step 0.02 px from 0.8 px).
fn lateral_level(sigma: f32) -> u8 {
    (((sigma - 0.8) / 0.02).ceil().max(0.0) as usize).min(LATERAL_LEVELS - 1) as u8
}

fn lateral_sigma_of_level(level: usize) -> f32 {
    0.8 + 0.02 * level as f32
}

/// The angle between a surface's normal and the ray from its `|cos|`.
fn facing_angle(facing: f32) -> f32 {
    facing.clamp(0.0, 1.0).acos()
}
