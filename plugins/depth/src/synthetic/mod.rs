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

/// Compiles the function it wraps twice, for any x86-64 and for x86-64-v3 (AVX2, FMA: CPUs
/// since 2013), the CPU's version chosen when first called (the `multiversion` crate: one
/// binary, no `unsafe` here). For the per-pixel passes: measured on the dressed frame, 13-20 %
/// faster once they were free of unpredictable branches. Callees are compiled with the
/// version's instructions only if inlined into it (`#[inline(always)]`; a closure is a function
/// of its own).
macro_rules! for_this_cpu {
    ($(#[$attr:meta])* $vis:vis fn $($rest:tt)*) => {
        $(#[$attr])*
        #[multiversion::multiversion(targets(
            "x86_64+avx+avx2+fma+bmi1+bmi2+lzcnt+popcnt+f16c+movbe"
        ))]
        $vis fn $($rest)*
    };
}

pub mod edges;
pub mod raster;
mod readings;
mod spans;
mod still;
mod tables;

use std::sync::Arc;

use glam::Vec3;

use crate::camera::{DepthCamera, PIXELS, WIDTH};
use crate::frame::DepthFrame;
pub use raster::DepthBuffer;
use readings::NoiseTables;
pub use readings::{next_unit, splitmix64};
use spans::Spans;
use still::{Layer, Still};

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
    /// How many of the first meshes stand still from frame to frame (the room): the camera
    /// keeps their image and draws only the others each frame. It checks that they did not
    /// change (a changed one is drawn anew), so this is a promise about speed only: the
    /// frames are the same, bit for bit, whatever its value.
    pub still: usize,
}

impl Scene {
    /// A floor at sensor-space height `floor_y` (negative: below the sensor) and a back
    /// wall at depth `wall_z`, both 8 m wide, [`Self::still`].
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
        scene.still = scene.meshes.len();
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

/// The synthetic depth camera.
pub struct SyntheticCamera {
    pub camera: DepthCamera,
    pub noise: NoiseSettings,
    seed: u64,
    frames: u64,
    tables: NoiseTables,
    /// The frame's frame-independent images ([`still::Layer`]).
    work: Layer,
    still: Still,
    /// Whether `work` is the still layer but in `dirty` (else it is anything).
    on_still: bool,
    /// The pixels where `work` differs from the still layer.
    dirty: Spans,
    /// Scratch: the pixels where `work` changed since the last frame, and a frame's
    /// neighbours of its moving meshes.
    changed: Spans,
    scratch: Spans,
    /// The last frame's images, reused when the caller has dropped them (no fresh pages
    /// per frame).
    spare: Option<SyntheticFrame>,
}

impl SyntheticCamera {
    pub fn new(camera: DepthCamera, noise: NoiseSettings, seed: u64) -> Self {
        Self {
            camera,
            noise,
            seed,
            frames: 0,
            tables: NoiseTables::new(camera),
            work: Layer::default(),
            still: Still::default(),
            on_still: false,
            dirty: Spans::empty(),
            changed: Spans::empty(),
            scratch: Spans::empty(),
            spare: None,
        }
    }

    /// Renders the next frame of `scene`, `time_s` seconds into the stream. The scene's
    /// [`Scene::still`] meshes are drawn once and kept while they stay the same; the others
    /// are drawn every frame.
    pub fn render(&mut self, scene: &Scene, time_s: f64) -> SyntheticFrame {
        let index = self.frames;
        self.frames += 1;
        let stream = splitmix64(self.seed ^ index.wrapping_mul(0x9e37_79b9_7f4a_7c15));
        let (cam, n) = (self.camera, self.noise);
        if self.tables.camera() != cam {
            self.tables = NoiseTables::new(cam);
        }
        // Where the frame-independent images change since the last frame (`None`: all).
        let still_meshes = scene.still.min(scene.meshes.len());
        let (still, moving) = scene.meshes.split_at(still_meshes);
        let layer = if still.is_empty() {
            None
        } else {
            self.still.layer(still, &cam, n, &self.tables)
        };
        let changed = match layer {
            Some((layer, made)) => {
                let whole = made || !self.on_still;
                if whole {
                    self.work.clone_from(layer);
                } else {
                    self.work.copy_spans(layer, &self.dirty);
                }
                let spans = (&mut self.scratch, &mut self.changed);
                self.work
                    .render_over(moving, layer, &cam, n, &self.tables, spans);
                // The pixels that changed: those drawn last frame, and this frame's.
                std::mem::swap(&mut self.dirty, &mut self.changed);
                self.changed.union(&self.dirty);
                self.on_still = true;
                (!whole).then_some(&self.changed)
            }
            None => {
                self.work.render_all(&scene.meshes, &cam, n, &self.tables);
                self.on_still = false;
                None
            }
        };
        let mut images = Images::take(self.spare.take());
        let view = &self.work.view;
        let true_z = Arc::make_mut(&mut images.true_z);
        let labels = Arc::make_mut(&mut images.labels);
        // The recycled images are the last frame's: only what changed is written.
        let (true_spans, label_spans) = (
            changed.filter(|_| images.recycled_true_z),
            changed.filter(|_| images.recycled_labels),
        );
        copy_rows(true_z, &view.inverse_z, true_spans, |v| {
            if v > 0.0 { 1.0 / v } else { f32::INFINITY }
        });
        copy_rows(labels, &view.label, label_spans, |l| l);
        // Unique by construction (`Images::take`): no copy is made here.
        let out_mm = Arc::make_mut(&mut images.depth_mm);
        let out_raw = Arc::make_mut(&mut images.raw);
        self.tables
            .readings(n, &self.work.coefficients, stream, out_raw, out_mm);
        let frame = images.into_frame(cam, time_s, index as u32);
        self.spare = Some(frame.clone());
        frame
    }
}

/// `to[k] = f(from[k])` over the pixels of `spans` (all pixels: `None`).
fn copy_rows<T: Copy, U>(to: &mut [U], from: &[T], spans: Option<&Spans>, f: impl Fn(T) -> U) {
    let mut rows = |r: std::ops::Range<usize>| {
        for (t, &v) in to[r.clone()].iter_mut().zip(&from[r]) {
            *t = f(v);
        }
    };
    match spans {
        None => rows(0..PIXELS),
        Some(spans) => {
            for (j, r) in spans.iter() {
                rows(j * WIDTH + r.start..j * WIDTH + r.end);
            }
        }
    }
}

/// A frame's images, recycled from the frame before when its caller has dropped them.
struct Images {
    depth_mm: Arc<[u16]>,
    raw: Arc<[u16]>,
    labels: Arc<[u8]>,
    true_z: Arc<[f32]>,
    /// Whether `labels` and `true_z` are the last frame's.
    recycled_labels: bool,
    recycled_true_z: bool,
}

impl Images {
    fn take(spare: Option<SyntheticFrame>) -> Self {
        fn reuse<T: Copy>(a: Option<Arc<[T]>>, zero: T) -> (Arc<[T]>, bool) {
            match a {
                // The caller has dropped its frame: this is the only reference.
                Some(a) if Arc::strong_count(&a) == 1 && Arc::weak_count(&a) == 0 => (a, true),
                _ => (vec![zero; PIXELS].into(), false),
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
        let ((labels, recycled_labels), (true_z, recycled_true_z)) = (reuse(l, 0), reuse(t, 0.0));
        Self {
            depth_mm: reuse(d, 0).0,
            raw: reuse(r, 0).0,
            labels,
            true_z,
            recycled_labels,
            recycled_true_z,
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
