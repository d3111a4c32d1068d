//! The segmentation against the flood fill it replaced (kept here, verbatim), on synthetic
//! Kinect frames: the same person mask bit for bit, the same pixel count, box, top and
//! number of people, the same floor, and the centroid up to summation order; frame after
//! frame, so that the choice by the last frame's person is compared too.

use std::path::Path;

use fitroom_body::BodyModel;
use fitroom_depth::noise::axial_sigma_with_grazing_m;
use fitroom_depth::synthetic::{Label, NoiseSettings, Scene, SceneMesh, SyntheticCamera};
use fitroom_depth::{DepthCamera, DepthFrame, HEIGHT, PIXELS, WIDTH};
use fitroom_tracker::floor::{Plane, fit_floor, floor_samples};
use fitroom_tracker::{SegmentSettings, Segmentation, Segmenter};
use glam::{DVec3, Quat, Vec3};

const SENSOR_HEIGHT: f32 = 0.8;

/// The body standing on the floor at sensor-space `(x, z)`, turned `yaw` radians.
fn person(model: &BodyModel, x: f32, z: f32, yaw: f32, label: Label) -> SceneMesh {
    let n = model.body_vertex_count as usize;
    let standing = model.standing_in_sensor_space(&model.positions);
    let turn = Quat::from_rotation_y(yaw);
    SceneMesh {
        positions: model.positions[..n]
            .iter()
            .map(|&p| turn * standing.transform_point3(p) + Vec3::new(x, -SENSOR_HEIGHT, z))
            .collect(),
        triangles: model.triangles.clone(),
        label,
        closed: true,
    }
}

/// Asserts that `new` and `old` found the same person.
fn assert_same(
    what: &str,
    frame: &DepthFrame,
    new: Option<Segmentation>,
    old: Option<Segmentation>,
) {
    let (new, old) = match (new, old) {
        (None, None) => return,
        (Some(new), Some(old)) => (new, old),
        (new, old) => panic!("{what}: {:?} against {:?}", new.is_some(), old.is_some()),
    };
    let first_difference = (0..PIXELS).find(|&k| new.mask[k] != old.mask[k]);
    assert_eq!(first_difference, None, "{what}: the masks differ");
    assert_eq!(
        (new.pixels, new.bbox, new.top_m, new.people, new.floor),
        (old.pixels, old.bbox, old.top_m, old.people, old.floor),
        "{what}"
    );
    // Sums of tens of thousands of f32 in another order: the centroids differ by about
    // 1e-4 m; both are compared with the exact one, summed in f64.
    let exact = exact_centroid(frame, &new.mask);
    let off = |c: Vec3| (c.as_dvec3() - exact).abs().max_element();
    let (off_new, off_old) = (off(new.centroid), off(old.centroid));
    println!("{what}: centroid off by {off_new:.1e} m (flood fill: {off_old:.1e} m)");
    assert!(
        off_new < 1e-5 && off_old < 1e-3,
        "{what}: {off_new} {off_old}"
    );
}

/// The mean of the points of `mask`, summed in f64.
fn exact_centroid(frame: &DepthFrame, mask: &[bool]) -> DVec3 {
    let (mut sum, mut n) = (DVec3::ZERO, 0.0);
    for k in (0..PIXELS).filter(|&k| mask[k]) {
        let z = f32::from(frame.depth_mm[k]) * 0.001;
        let p = frame
            .camera
            .unproject((k % WIDTH) as f32, (k / WIDTH) as f32, z);
        (sum, n) = (sum + p.as_dvec3(), n + 1.0);
    }
    sum / n
}

#[test]
fn the_segmentation_is_the_flood_fills() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/bodies/makehuman.fitbody");
    let model = BodyModel::read(&path).expect("the shipped body");
    // The labelling and the choice against the flood fill's; parts cut off by a depth edge
    // (added since, module `segment::parts`) are tested in `tests/segment.rs`.
    let settings = SegmentSettings {
        join_parts: false,
        wall: false,
        ..SegmentSettings::default()
    };
    let (mut new, mut old) = (Segmenter::new(settings), FloodFill::new(settings));
    let mut found = 0;
    // Alone at several distances and turns, with someone passing behind, beside a box,
    // leaving, the sensor tilted: a stream through one segmenter each, so the last person
    // counts as it does live.
    for step in 0..24u64 {
        let z = 1.6 + 0.09 * step as f32;
        let mut scene = Scene::room(-SENSOR_HEIGHT, 3.9);
        if step % 8 != 7 {
            let x = 0.5 * ((step as f32) * 0.7).sin();
            scene
                .meshes
                .push(person(&model, x, z, 0.3 * step as f32, Label::Body));
        }
        if step % 3 == 1 {
            let x = -1.6 + 0.15 * step as f32;
            scene
                .meshes
                .push(person(&model, x, z + 0.8, 0.0, Label::Other));
        }
        if step % 4 == 2 {
            scene.add_box(
                Vec3::new(-0.9, -SENSOR_HEIGHT + 0.55, 2.3),
                Vec3::new(0.25, 0.55, 0.25),
                Label::Other,
            );
        }
        if step >= 20 {
            let pitch = Quat::from_rotation_x(-(step as f32 - 17.0).to_radians() * 3.0);
            for p in scene.meshes.iter_mut().flat_map(|m| &mut m.positions) {
                *p = pitch * *p;
            }
        }
        let mut camera =
            SyntheticCamera::new(DepthCamera::default(), NoiseSettings::default(), step);
        let frame = camera.render(&scene, step as f64 / 30.0).frame;
        let (a, b) = (new.segment(&frame), old.segment(&frame));
        found += usize::from(a.is_some());
        assert_same(&format!("frame {step}"), &frame, a, b);
    }
    assert!(found >= 18, "{found} frames with a person");
}

/// The segmenter as it was before the scanline labelling (flood fill), verbatim but for its
/// name, and with the rule since added (a component seen between nearer ones is no person)
/// written pixel by pixel.
#[derive(Default)]
struct FloodFill {
    settings: SegmentSettings,
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
    top_row_pixels: usize,
    /// Frontal area of the component's pixels, m² (each pixel covers (z/f)²).
    area_m2: f32,
    overlap: usize,
    bbox: [u16; 4],
    /// Row sides where another component borders this one (next to it, or across pixels
    /// without a reading), and those where the other one is nearer by more than 5 cm.
    sides: u32,
    behind: u32,
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
            && extent.z < 2.0
            && !(self.sides >= 8 && self.behind * 2 > self.sides)
            && !(self.top_m > 2.0
                && self.top_row_pixels * 10 > (usize::from(self.bbox[2] - self.bbox[0]) + 1) * 9)
    }
}

impl FloodFill {
    fn new(settings: SegmentSettings) -> Self {
        Self {
            settings,
            ..Self::default()
        }
    }

    /// The person in `frame`, `None` when there is no floor or no one who looks like a
    /// person.
    fn segment(&mut self, frame: &DepthFrame) -> Option<Segmentation> {
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
                if j == 0 {
                    c.top_row_pixels += 1;
                }
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
        // Borders along each row: a change of component with nothing but pixels without a
        // reading between.
        for j in 0..HEIGHT {
            let mut last: Option<(usize, f32)> = None;
            for i in 0..WIDTH {
                let k = j * WIDTH + i;
                let c = self.component[k] as usize;
                if c == 0 {
                    if frame.depth_mm[k] > 0 {
                        last = None;
                    }
                    continue;
                }
                if let Some((before, z)) = last
                    && before != c
                {
                    stats[before].sides += 1;
                    stats[c].sides += 1;
                    if z > depth[k] + 0.05 {
                        stats[before].behind += 1;
                    } else if depth[k] > z + 0.05 {
                        stats[c].behind += 1;
                    }
                }
                last = Some((c, depth[k]));
            }
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
