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
//!    cannot light the point (found per row, [`projector_shadow`]);
//!    beside a foreground edge at `z1` over a background at `z2` that band is
//!    `f b (1/z1 - 1/z2)` pixels wide, on the image's left of the edge;
//! 5. no reading where the surface is outside the camera's range (0.8-4 m);
//! 6. axial error `N(0, σz(z, θ))`;
//! 7. the 11-bit raw quantisation (about 1/8 px of disparity);
//! 8. dropouts where the correlation window straddles a depth edge: half the pixels next to
//!    a jump, and every pixel of a part one pixel thin.

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

/// The synthetic depth camera.
pub struct SyntheticCamera {
    pub camera: DepthCamera,
    pub noise: NoiseSettings,
    seed: u64,
    frames: u64,
    normals: Vec<f32>,
    /// Per `|cos θ|` in 1/1024 steps: the lateral σ (px) and the grazing factor
    /// `θ² / (π/2 - θ)²` of the axial σ, so no pixel computes an arc cosine.
    facing_table: Vec<(f32, f32)>,
    view: DepthBuffer,
}

impl SyntheticCamera {
    pub fn new(camera: DepthCamera, noise: NoiseSettings, seed: u64) -> Self {
        let mut rng = ChaCha8Rng::seed_from_u64(0x6b69_6e65_6374);
        let normals = (0..TABLE)
            .map(|_| StandardNormal.sample(&mut rng))
            .collect();
        Self {
            camera,
            noise,
            seed,
            frames: 0,
            normals,
            facing_table: (0..=FACING_STEPS)
                .map(|k| {
                    let theta = facing_angle(k as f32 / FACING_STEPS as f32);
                    (lateral_sigma_px(theta), grazing_factor(theta))
                })
                .collect(),
            view: DepthBuffer::default(),
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
                .draw(&cam, &m.positions, &m.triangles, m.label as u8);
        }
        let true_z: Vec<f32> = self.view.inverse_z.iter().map(|&iz| 1.0 / iz).collect();
        let shadow = if self.noise.shadow {
            projector_shadow(&true_z, &cam)
        } else {
            vec![false; PIXELS]
        };
        let grazing_cos = GRAZING_LIMIT.cos();
        let mut raw = vec![RAW_NO_VALUE; PIXELS];
        let mut depth_mm = vec![0u16; PIXELS];
        for j in 0..HEIGHT {
            for i in 0..WIDTH {
                let k = j * WIDTH + i;
                // One hash per pixel gives its three normal samples and its coin, so that
                // one pixel's fate does not shift the noise of the others.
                let h = splitmix64(stream ^ k as u64);
                let gauss = |shift: u32| self.normals[((h >> shift) & 0xffff) as usize];
                if self.noise.dropouts && edge_dropout(&true_z, i, j, h >> 63 == 1) {
                    continue;
                }
                // How squarely the surface here faces its ray (the neighbour a lateral error
                // reads is, but at edges, the same surface).
                let facing = self.view.facing(&cam, i, j);
                let (sigma, grazing) = self.facing_terms(facing);
                let (mut si, mut sj) = (i, j);
                if self.noise.lateral && true_z[k].is_finite() {
                    // Rounded by a cast after clamping (see `camera::metres_to_raw`).
                    let at = |c: usize, g: f32, n: usize| {
                        ((c as f32 + sigma * g).clamp(0.0, n as f32 - 1.0) + 0.5) as usize
                    };
                    si = at(i, gauss(0), WIDTH);
                    sj = at(j, gauss(16), HEIGHT);
                }
                let s = sj * WIDTH + si;
                let z = true_z[s];
                if !z.is_finite() || shadow[s] {
                    continue;
                }
                if self.noise.grazing && facing < grazing_cos {
                    continue;
                }
                // The range is the surface's: where the pattern is matched, not where the
                // noisy reading lands.
                if self.noise.range && !cam.in_range(z) {
                    continue;
                }
                let z = if self.noise.axial {
                    let sigma = axial_sigma_with_grazing_m(z, grazing);
                    z + sigma * gauss(32)
                } else {
                    z
                };
                if let Some(r) = camera::metres_to_raw(z) {
                    raw[k] = r;
                    depth_mm[k] = if self.noise.quantise {
                        camera::raw_mm_table()[usize::from(r)]
                    } else {
                        (z * 1000.0).round().min(f32::from(u16::MAX)) as u16
                    };
                }
            }
        }
        SyntheticFrame {
            frame: DepthFrame {
                depth_mm: depth_mm.into(),
                raw: Some(raw.into()),
                rgb: None,
                time_s,
                timestamp: index as u32,
                camera: cam,
            },
            labels: self.view.label.clone().into(),
            true_depth_m: true_z.into(),
        }
    }

    /// The lateral σ and the grazing factor of a surface facing its ray by `|cos|` `facing`.
    #[inline]
    fn facing_terms(&self, facing: f32) -> (f32, f32) {
        self.facing_table[(facing.clamp(0.0, 1.0) * FACING_STEPS as f32) as usize]
    }
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

/// Per pixel, whether the projector cannot light the surface the camera sees there.
///
/// The projector looks along the same axis from `b` to the sensor's right with the same
/// intrinsics, so a point seen at `(u, v)` at depth `z` is at `(u - f b / z, v)` in the
/// projector's image: the same row. Nearer points shift further left, so only points to a
/// pixel's right can hide it from the projector; sweeping each row from the right, a pixel is
/// in shadow when a point already swept lands left of it in the projector's image (the
/// ordering constraint of stereo). Surfaces the camera does not see cannot shadow here: for a
/// person in a room they are behind what it sees.
fn projector_shadow(z: &[f32], camera: &DepthCamera) -> Vec<bool> {
    let shift = camera.fx * camera.baseline_m;
    let mut shadow = vec![false; PIXELS];
    for (row_z, row_shadow) in z.chunks_exact(WIDTH).zip(shadow.chunks_exact_mut(WIDTH)) {
        let mut leftmost = f32::INFINITY;
        for i in (0..WIDTH).rev() {
            let zi = row_z[i];
            if !zi.is_finite() {
                continue;
            }
            let u = i as f32 - shift / zi;
            if u > leftmost {
                row_shadow[i] = true;
            } else {
                leftmost = u;
            }
        }
    }
    shadow
}

/// The angle between a surface's normal and the ray from its `|cos|`.
fn facing_angle(facing: f32) -> f32 {
    facing.clamp(0.0, 1.0).acos()
}

/// Whether the device loses pixel `(i, j)` at a depth edge: always for a part one pixel thin
/// (nearer than both neighbours along a row or a column), else with `coin` beside a jump.
fn edge_dropout(z: &[f32], i: usize, j: usize, coin: bool) -> bool {
    if i == 0 || j == 0 || i + 1 == WIDTH || j + 1 == HEIGHT {
        return false;
    }
    let k = j * WIDTH + i;
    let here = z[k];
    if !here.is_finite() {
        return false;
    }
    let jump = |other: f32| {
        !other.is_finite() || (here - other).abs() > 0.03_f32.max(0.02 * here.min(other))
    };
    let (l, r, u, d) = (z[k - 1], z[k + 1], z[k - WIDTH], z[k + WIDTH]);
    let (jl, jr, ju, jd) = (jump(l), jump(r), jump(u), jump(d));
    let thin = (jl && jr && l > here && r > here) || (ju && jd && u > here && d > here);
    thin || (coin && (jl || jr || ju || jd))
}
