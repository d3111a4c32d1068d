//! The person's pixels in a depth frame, from depth alone:
//!
//! 1. the floor plane ([`crate::floor`]), kept from frame to frame while it still fits;
//! 2. every reading above the floor band is joined to its 4-neighbours whose depth is within
//!    a few centimetres (a depth edge separates objects), giving connected components;
//! 3. a component is a person if its size and extent are a person's: top 0.9-2.3 m above the
//!    floor, feet near it (or cut off by the image's bottom edge), at most 2 m wide and 1.2 m
//!    deep, and enough pixels for its distance;
//! 4. of the people, the one who overlaps the last frame's person most is kept (so someone
//!    walking behind does not take over); without one, the person nearest the centre of the
//!    interaction area.
//!
//! The result is the user map the Kinect SDK gave seed 000 (libfreenect has none).

use fitroom_depth::noise::axial_sigma_with_grazing_m;
use fitroom_depth::{DepthFrame, HEIGHT, PIXELS, WIDTH};
use glam::Vec3;
use serde::Serialize;

use crate::floor::{FloorSettings, Plane, fit_floor, floor_samples};

/// How the person is found.
#[derive(Clone, Copy, Debug)]
pub struct SegmentSettings {
    pub floor: FloorSettings,
    /// Readings this close to the floor (plus three times the sensor's noise at their depth)
    /// are floor, metres.
    pub floor_band_m: f32,
    /// Neighbouring readings closer in depth than this plus 3 % of the depth are one surface.
    pub join_m: f32,
    /// Where a person stands to use the kiosk: sensor-space x and z, metres.
    pub centre_x_m: f32,
    pub centre_z_m: f32,
    /// Least visible frontal area of a person, m² (a person standing is about 0.6 m²).
    pub min_area_m2: f32,
}

impl Default for SegmentSettings {
    fn default() -> Self {
        Self {
            floor: FloorSettings::default(),
            floor_band_m: 0.02,
            join_m: 0.04,
            centre_x_m: 0.0,
            centre_z_m: 2.5,
            min_area_m2: 0.08,
        }
    }
}

/// The person found in a frame.
#[derive(Clone, Debug, Serialize)]
pub struct Segmentation {
    /// Per pixel, whether it sees the person.
    #[serde(skip)]
    pub mask: Vec<bool>,
    pub pixels: usize,
    /// Mean of the person's points, sensor space, metres.
    pub centroid: Vec3,
    /// Top of the person above the floor, metres.
    pub top_m: f32,
    /// Pixel box: first column, first row, last column, last row.
    pub bbox: [u16; 4],
    /// Components that looked like people (the chosen one included).
    pub people: usize,
    pub floor: Plane,
}

/// Finds the person frame after frame (the floor and the last person are remembered).
#[derive(Default)]
pub struct Segmenter {
    pub settings: SegmentSettings,
    floor: Option<(Plane, usize)>,
    previous: Option<Vec<bool>>,
    /// Scratch: component of each pixel (0: none), and the depth of each reading above the
    /// floor band (0: none).
    component: Vec<u32>,
    depth: Vec<f32>,
    stack: Vec<u32>,
}

/// What is gathered per component.
#[derive(Clone, Copy, Debug, Default)]
struct Stats {
    pixels: usize,
    sum: Vec3,
    min: Vec3,
    max: Vec3,
    top_m: f32,
    bottom_m: f32,
    touches_bottom_row: bool,
    /// Frontal area of the component's pixels, m² (each pixel covers (z/f)²).
    area_m2: f32,
    overlap: usize,
    bbox: [u16; 4],
}

impl Stats {
    fn new() -> Self {
        Self {
            min: Vec3::splat(f32::INFINITY),
            max: Vec3::splat(f32::NEG_INFINITY),
            top_m: f32::NEG_INFINITY,
            bottom_m: f32::INFINITY,
            bbox: [u16::MAX, u16::MAX, 0, 0],
            ..Self::default()
        }
    }

    fn looks_like_a_person(&self, settings: &SegmentSettings) -> bool {
        let extent = self.max - self.min;
        self.area_m2 >= settings.min_area_m2
            && (0.9..2.3).contains(&self.top_m)
            && (self.bottom_m < 0.5 || self.touches_bottom_row)
            && extent.x < 2.0
            && extent.z < 1.2
    }
}

impl Segmenter {
    pub fn new(settings: SegmentSettings) -> Self {
        Self {
            settings,
            ..Self::default()
        }
    }

    /// Forgets the last person (the next one is chosen by the interaction area).
    pub fn reset(&mut self) {
        self.previous = None;
    }

    /// The person in `frame`, `None` when there is no floor or no one who looks like a
    /// person.
    pub fn segment(&mut self, frame: &DepthFrame) -> Option<Segmentation> {
        if frame.depth_mm.len() != PIXELS {
            return None;
        }
        let floor = self.floor(frame)?;
        let camera = frame.camera;
        let s = self.settings;
        // Depths of the readings above the floor band (0: none). A pixel's point is z times
        // its ray `r = ((cx - i) / fx, (cy - j) / fy, 1)`, so its height is `z (n · r) + d`,
        // and `n · r` is a column term plus a row term.
        let column: Vec<f32> = (0..WIDTH)
            .map(|i| floor.normal.x * (camera.cx - i as f32) / camera.fx)
            .collect();
        self.depth.clear();
        self.depth.resize(PIXELS, 0.0);
        for (j, (out, mm)) in self
            .depth
            .chunks_exact_mut(WIDTH)
            .zip(frame.depth_mm.chunks_exact(WIDTH))
            .enumerate()
        {
            let row = floor.normal.y * (camera.cy - j as f32) / camera.fy + floor.normal.z;
            for ((out, &mm), &col) in out.iter_mut().zip(mm).zip(&column) {
                let z = f32::from(mm) * 0.001;
                let noise = axial_sigma_with_grazing_m(z, 0.0);
                let above = z * (col + row) + floor.d > s.floor_band_m + 3.0 * noise;
                *out = if mm > 0 && above { z } else { 0.0 };
            }
        }
        let depth = &self.depth;
        let point = |k: usize| {
            let z = depth[k];
            (z > 0.0).then(|| camera.unproject((k % WIDTH) as f32, (k / WIDTH) as f32, z))
        };
        self.component.clear();
        self.component.resize(PIXELS, 0);
        let mut stats = vec![Stats::new()];
        let pixel_area = |z: f32| (z / camera.fx) * (z / camera.fy);
        for seed in 0..PIXELS {
            if depth[seed] == 0.0 || self.component[seed] != 0 {
                continue;
            }
            let id = stats.len() as u32;
            let mut c = Stats::new();
            self.stack.clear();
            self.stack.push(seed as u32);
            self.component[seed] = id;
            while let Some(k) = self.stack.pop() {
                let k = k as usize;
                let Some(p) = point(k) else { continue };
                let (i, j) = (k % WIDTH, k / WIDTH);
                c.pixels += 1;
                c.sum += p;
                c.min = c.min.min(p);
                c.max = c.max.max(p);
                let h = floor.height(p);
                c.top_m = c.top_m.max(h);
                c.bottom_m = c.bottom_m.min(h);
                c.touches_bottom_row |= j + 1 == HEIGHT;
                c.area_m2 += pixel_area(p.z);
                c.bbox = [
                    c.bbox[0].min(i as u16),
                    c.bbox[1].min(j as u16),
                    c.bbox[2].max(i as u16),
                    c.bbox[3].max(j as u16),
                ];
                if self.previous.as_ref().is_some_and(|m| m[k]) {
                    c.overlap += 1;
                }
                let mut visit = |n: usize| {
                    let q = depth[n];
                    if self.component[n] == 0 && q > 0.0 && (q - p.z).abs() < s.join_m + 0.03 * p.z
                    {
                        self.component[n] = id;
                        self.stack.push(n as u32);
                    }
                };
                if i > 0 {
                    visit(k - 1);
                }
                if i + 1 < WIDTH {
                    visit(k + 1);
                }
                if j > 0 {
                    visit(k - WIDTH);
                }
                if j + 1 < HEIGHT {
                    visit(k + WIDTH);
                }
            }
            stats.push(c);
        }
        let people: Vec<usize> = (1..stats.len())
            .filter(|&c| stats[c].looks_like_a_person(&s))
            .collect();
        let distance = |c: &Stats| {
            let centroid = c.sum / c.pixels as f32;
            (centroid.x - s.centre_x_m).hypot(centroid.z - s.centre_z_m)
        };
        // The last frame's person, while a third of their pixels are still theirs; else the
        // one nearest the interaction area.
        let previous_pixels = self
            .previous
            .as_ref()
            .map_or(0, |m| m.iter().filter(|&&b| b).count());
        let chosen = people
            .iter()
            .copied()
            .filter(|&c| stats[c].overlap * 3 > previous_pixels && previous_pixels > 0)
            .max_by_key(|&c| stats[c].overlap)
            .or_else(|| {
                people
                    .iter()
                    .copied()
                    .min_by(|&a, &b| distance(&stats[a]).total_cmp(&distance(&stats[b])))
            });
        let Some(chosen) = chosen else {
            self.previous = None;
            return None;
        };
        let mask: Vec<bool> = self
            .component
            .iter()
            .map(|&c| c as usize == chosen)
            .collect();
        self.previous = Some(mask.clone());
        let c = stats[chosen];
        Some(Segmentation {
            mask,
            pixels: c.pixels,
            centroid: c.sum / c.pixels as f32,
            top_m: c.top_m,
            bbox: c.bbox,
            people: people.len(),
            floor,
        })
    }

    /// The floor: the last one while it still holds most of its support, else fitted anew.
    fn floor(&mut self, frame: &DepthFrame) -> Option<Plane> {
        let samples = floor_samples(frame);
        if let Some((plane, support)) = self.floor {
            let now = samples
                .iter()
                .filter(|&&p| plane.height(p).abs() < self.settings.floor.inlier_m)
                .count();
            if now * 10 >= support * 7 {
                return Some(plane);
            }
        }
        self.floor = fit_floor(&samples, &self.settings.floor);
        self.floor.map(|(plane, _)| plane)
    }
}
