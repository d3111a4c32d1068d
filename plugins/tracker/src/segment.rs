//! The person's pixels in a depth frame, from depth alone:
//!
//! 1. the floor plane ([`crate::floor`]), kept from frame to frame while it still fits;
//! 2. every reading above the floor band is joined to its 4-neighbours whose depth is within
//!    a few centimetres (a depth edge separates objects), giving connected components
//!    (module `components`: a scanline labelling, row by row, exactly a flood fill's result);
//! 3. a component is a person if its size and extent are a person's: top 0.9-2.3 m above the
//!    floor, feet near it (or cut off by the image's bottom edge), at most 2 m wide and 2 m
//!    deep, and enough pixels for its distance (the person of the last frame may be lower,
//!    bowed or crouched, or higher off the floor, leaping);
//! 4. of the people, the one who overlaps the last frame's person most is kept (so someone
//!    walking behind does not take over); without one, the pieces the last frame's person
//!    was parted into (a deep bow), if together they look like a person; else the person
//!    nearest the centre of the interaction area;
//! 5. the parts of that person a depth edge cut off (the far arm seen past their back, a
//!    hand held out, the trunk of a deep bow) are added to them (module `parts`).
//!
//! The result is the user map the Kinect SDK gave seed 000 (libfreenect has none).

use fitroom_depth::noise::axial_sigma_with_grazing_m;
use fitroom_depth::{DepthFrame, HEIGHT, PIXELS, WIDTH};
use glam::Vec3;
use serde::Serialize;

use crate::floor::{
    FloorSettings, Plane, fit_floor, fit_plane, floor_samples_into, wall_samples_into,
};

mod components;
mod parts;

use components::Components;

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
    /// Whether parts of the person a depth edge cut off (an arm seen past their back, a
    /// hand held out) are added to them (module `parts`).
    pub join_parts: bool,
    /// Whether the wall behind the interaction area, if one is seen, is taken out as the
    /// floor is (readings within its band are no one's): a foot or hand stretched back to
    /// within a few centimetres of it no longer joins the person to the wall.
    pub wall: bool,
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
            join_parts: true,
            wall: true,
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
    /// The wall behind the interaction area and its support, and the frames until it is
    /// looked for again when there is none.
    wall: Option<(Plane, usize)>,
    wall_wait: u32,
    /// The last frame's person and their pixel count.
    previous: Option<(Vec<bool>, usize)>,
    /// Scratch, kept so that a frame allocates only the mask it returns.
    scratch: Scratch,
}

/// Per-frame working memory of [`Segmenter::segment`].
#[derive(Default)]
struct Scratch {
    /// Per pixel, the depth of a reading above the floor band (0: none), metres.
    depth: Vec<f32>,
    /// Per image column, the column term of a ray's height factor (above the floor, in
    /// front of the wall).
    column: Vec<f32>,
    wall_column: Vec<f32>,
    components: Components,
    /// Per component (index 0 unused), what was gathered.
    stats: Vec<Stats>,
    /// One row's points (x, y), heights, pixel areas, and per column `cx - i`.
    row: Vec<f32>,
    /// Per component, the greatest and least x and z of the ends of its runs, metres.
    ends: Vec<[f32; 4]>,
    /// The points the floor (the wall) is fitted to or checked against.
    floor_samples: Vec<Vec3>,
    wall_samples: Vec<Vec3>,
    /// The person's parts cut off by a depth edge, with their bordering pixels.
    parts: Vec<(u32, usize)>,
}

/// The wall taken out lies at least this far behind the interaction area's centre, metres
/// (a person standing there is never taken for it).
const WALL_BEHIND_M: f32 = 0.6;
/// Frames between searches for a wall while none is seen.
const WALL_WAIT_FRAMES: u32 = 30;

/// A person is narrower than this (sensor x), metres.
const MAX_WIDTH_M: f32 = 2.0;
/// A person is shallower than this (sensor z), metres: as deep as they are tall at most (it
/// was 1.2 m, and a dancer's walkover, legs split along the view, measured 1.4 m and was no
/// one in 8 of 150 frames of CMU 05_06).
const MAX_DEPTH_M: f32 = 2.0;

/// A person first seen has their top at least this high above the floor, metres ...
const MIN_TOP_M: f32 = 0.9;
/// ... and their lowest point at most this high (or cut off by the image's bottom edge).
const MAX_BOTTOM_M: f32 = 0.5;
/// A person followed from the last frame may have their top this low, metres (a small
/// woman bowed deep reaches 0.89 m: CMU 05_06) ...
const FOLLOWED_TOP_M: f32 = 0.6;
/// ... and their lowest point this high (a dancer's leap: 0.50 m), metres.
const FOLLOWED_BOTTOM_M: f32 = 1.0;

/// Bordering components are told apart in depth by at least this much, metres.
const NEARER_M: f32 = 0.05;
/// The image's top edge meets a person's head lower than this above the floor, metres (it may
/// meet their raised hands higher).
const MAX_CUT_TOP_M: f32 = 2.0;
/// Fewer bordered row sides than this say nothing of what is in front.
const MIN_SIDES: u32 = 8;

/// What is gathered per component.
#[derive(Clone, Copy, Debug, Default)]
struct Stats {
    /// Certainly wider or deeper than a person, from a few of its pixels: nothing else was
    /// gathered.
    too_large: bool,
    pixels: usize,
    sum: Vec3,
    min: Vec3,
    max: Vec3,
    top_m: f32,
    bottom_m: f32,
    touches_bottom_row: bool,
    /// Its pixels in the image's top row.
    top_row_pixels: usize,
    /// Frontal area of the component's pixels, m² (each pixel covers (z/f)²).
    area_m2: f32,
    overlap: usize,
    bbox: [u16; 4],
    /// Row sides where another component borders this one (directly or across pixels with
    /// no reading, the projector's shadow), and those where that one is the nearer.
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

    /// Whether its size and extent are a person's; one `followed` from the last frame may
    /// also be bowed or crouched lower, or leap higher off the floor.
    fn looks_like_a_person(&self, settings: &SegmentSettings, followed: bool) -> bool {
        let extent = self.max - self.min;
        let (lowest_top, highest_bottom) = match followed {
            false => (MIN_TOP_M, MAX_BOTTOM_M),
            true => (FOLLOWED_TOP_M, FOLLOWED_BOTTOM_M),
        };
        !self.too_large
            && self.area_m2 >= settings.min_area_m2
            && (lowest_top..2.3).contains(&self.top_m)
            && (self.bottom_m < highest_bottom || self.touches_bottom_row)
            && extent.x < MAX_WIDTH_M
            && extent.z < MAX_DEPTH_M
            && !self.mostly_behind()
            && !self.cut_like_a_wall()
    }

    /// Cut off by the image's top edge across its whole width (nine tenths of it: the sensor
    /// drops a few readings), and that edge meets it higher than a person's head: a wall, not
    /// a person (whose raised hands and head the edge may cut, across four fifths of a tall
    /// man's width at most).
    fn cut_like_a_wall(&self) -> bool {
        let width = usize::from(self.bbox[2].saturating_sub(self.bbox[0])) + 1;
        self.top_m > MAX_CUT_TOP_M && self.top_row_pixels * 10 > width * 9
    }

    /// Takes in `part`'s pixels and overlap (not its border counts, used before).
    fn add(&mut self, part: &Stats) {
        self.pixels += part.pixels;
        self.overlap += part.overlap;
        self.sum += part.sum;
        self.area_m2 += part.area_m2;
        self.min = self.min.min(part.min);
        self.max = self.max.max(part.max);
        self.top_m = self.top_m.max(part.top_m);
        self.bottom_m = self.bottom_m.min(part.bottom_m);
        self.touches_bottom_row |= part.touches_bottom_row;
        self.top_row_pixels += part.top_row_pixels;
        self.bbox = [
            self.bbox[0].min(part.bbox[0]),
            self.bbox[1].min(part.bbox[1]),
            self.bbox[2].max(part.bbox[2]),
            self.bbox[3].max(part.bbox[3]),
        ];
    }

    /// Whether over half of its pixels were the last frame's person's.
    fn was_theirs(&self) -> bool {
        self.overlap * 2 > self.pixels
    }

    /// A person stands in front of what surrounds them; a surface seen between nearer ones
    /// (a strip of the back wall beside a person standing close to the camera) is not one.
    fn mostly_behind(&self) -> bool {
        self.sides >= MIN_SIDES && self.behind * 2 > self.sides
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
        let s = self.settings;
        let wall = if s.wall { self.wall(frame) } else { None };
        self.above_floor(frame, &floor, wall.as_ref());
        let Scratch {
            depth, components, ..
        } = &mut self.scratch;
        components.find(depth, s.join_m);
        self.gather(frame, &floor);
        let Scratch {
            components,
            stats,
            parts,
            ..
        } = &mut self.scratch;
        let (runs, stats) = (&components.runs, &*stats);
        let people: Vec<usize> = (1..stats.len())
            .filter(|&c| stats[c].looks_like_a_person(&s, false))
            .collect();
        let distance = |c: &Stats| {
            let centroid = c.sum / c.pixels as f32;
            (centroid.x - s.centre_x_m).hypot(centroid.z - s.centre_z_m)
        };
        // The last frame's person, while a third of their pixels are still theirs; else the
        // one nearest the interaction area.
        let previous_pixels = self.previous.as_ref().map_or(0, |&(_, pixels)| pixels);
        let followed = |c: usize| previous_pixels > 0 && stats[c].overlap * 3 > previous_pixels;
        let nearest = || {
            people
                .iter()
                .copied()
                .min_by(|&a, &b| distance(&stats[a]).total_cmp(&distance(&stats[b])))
        };
        let chosen = (1..stats.len())
            .filter(|&c| followed(c) && stats[c].looks_like_a_person(&s, true))
            .max_by_key(|&c| stats[c].overlap);
        let mut person_from = |chosen: usize| {
            let join = s.join_parts.then_some(PartsOf {
                raw_mm: &frame.depth_mm,
                people: &people,
                parts: &mut *parts,
            });
            person_from(chosen, runs, stats, join)
        };
        let mut found = chosen.map(&mut person_from);
        if found.is_none() {
            // Parted by depth edges, no piece of the last frame's person may look like a
            // person by itself (bowed deep, the legs reach up to the hips only and the trunk
            // does not reach down to the floor): the piece mostly theirs that overlaps them
            // most, with the rest of them joined as its parts, if together they do and a
            // third of their pixels are still theirs.
            let piece = (1..stats.len())
                .filter(|&c| !stats[c].too_large && stats[c].was_theirs())
                .max_by_key(|&c| stats[c].overlap);
            found = piece.map(&mut person_from).filter(|(_, c)| {
                c.looks_like_a_person(&s, true) && c.overlap * 3 > previous_pixels
            });
        }
        if found.is_none() {
            found = nearest().map(&mut person_from);
        }
        let Some((mask, c)) = found else {
            self.previous = None;
            return None;
        };
        // Kept in the last frame's buffer when there is one (no allocation).
        match &mut self.previous {
            Some((previous, pixels)) => {
                previous.copy_from_slice(&mask);
                *pixels = c.pixels;
            }
            None => self.previous = Some((mask.clone(), c.pixels)),
        }
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

    /// Fills `scratch.depth`: the depth of each reading above the floor band and in front of
    /// the wall's, 0 elsewhere.
    ///
    /// A pixel's point is z times its ray `r = ((cx - i) / fx, (cy - j) / fy, 1)`, so its
    /// height is `z (n · r) + d`, and `n · r` is a column term plus a row term (the same for
    /// the distance in front of the wall). The loop has no branch, so that it vectorises.
    fn above_floor(&mut self, frame: &DepthFrame, floor: &Plane, wall: Option<&Plane>) {
        let camera = frame.camera;
        let band = self.settings.floor_band_m;
        // No wall: a plane every reading is far in front of.
        let wall = wall.copied().unwrap_or(Plane {
            normal: Vec3::ZERO,
            d: f32::MAX,
        });
        let Scratch {
            depth,
            column,
            wall_column,
            ..
        } = &mut self.scratch;
        column.clear();
        column.extend((0..WIDTH).map(|i| floor.normal.x * (camera.cx - i as f32) / camera.fx));
        wall_column.clear();
        wall_column.extend((0..WIDTH).map(|i| wall.normal.x * (camera.cx - i as f32) / camera.fx));
        depth.resize(PIXELS, 0.0);
        for (j, (out, mm)) in depth
            .chunks_exact_mut(WIDTH)
            .zip(frame.depth_mm.chunks_exact(WIDTH))
            .enumerate()
        {
            let row = floor.normal.y * (camera.cy - j as f32) / camera.fy + floor.normal.z;
            let wall_row = wall.normal.y * (camera.cy - j as f32) / camera.fy + wall.normal.z;
            for (((out, &mm), &col), &wall_col) in out
                .iter_mut()
                .zip(mm)
                .zip(column.iter())
                .zip(wall_column.iter())
            {
                let z = f32::from(mm) * 0.001;
                let noise = band + 3.0 * axial_sigma_with_grazing_m(z, 0.0);
                let above = z * (col + row) + floor.d > noise;
                let in_front = z * (wall_col + wall_row) + wall.d > noise;
                *out = if mm > 0 && above && in_front { z } else { 0.0 };
            }
        }
    }

    /// Gathers each component's stats, a row at a time: first each reading's point, height
    /// and area in a loop without branches (it vectorises: the divisions dominate), then each
    /// run's sums, least and greatest values in eight interleaved lanes (they vectorise too).
    /// Sums are therefore taken in another order than the flood fill's (which took them
    /// pixel by pixel in its own order); everything else is exact.
    ///
    /// Components that the ends of their runs alone show wider or deeper than a person (the
    /// back wall) are skipped: their extent is at least that of those pixels (the same
    /// values, and rounding is monotonic), so they would not have been people.
    fn gather(&mut self, frame: &DepthFrame, floor: &Plane) {
        let camera = frame.camera;
        let previous = self.previous.as_ref().map(|(mask, _)| mask);
        let Scratch {
            depth,
            components,
            stats,
            row,
            ends,
            ..
        } = &mut self.scratch;
        row.resize(5 * WIDTH, 0.0);
        let (x, rest) = row.split_at_mut(WIDTH);
        let (y, rest) = rest.split_at_mut(WIDTH);
        let (h, rest) = rest.split_at_mut(WIDTH);
        let (area, dx) = rest.split_at_mut(WIDTH);
        for (i, dx) in dx.iter_mut().enumerate() {
            *dx = camera.cx - i as f32;
        }
        // As `camera.unproject`, bit for bit.
        let x_at = |i: usize, z: f32| dx[i] * z / camera.fx;
        ends.clear();
        ends.resize(
            components.count + 1,
            [
                f32::NEG_INFINITY,
                f32::INFINITY,
                f32::NEG_INFINITY,
                f32::INFINITY,
            ],
        );
        for run in &components.runs {
            let e = &mut ends[run.component as usize];
            let row = usize::from(run.row) * WIDTH;
            for i in [usize::from(run.start), usize::from(run.end) - 1] {
                let (x, z) = (x_at(i, depth[row + i]), depth[row + i]);
                *e = [e[0].max(x), e[1].min(x), e[2].max(z), e[3].min(z)];
            }
        }
        stats.clear();
        stats.extend(ends.iter().map(|e| Stats {
            too_large: e[0] - e[1] >= MAX_WIDTH_M || e[2] - e[3] >= MAX_DEPTH_M,
            ..Stats::new()
        }));
        for runs in components.runs.chunk_by(|a, b| a.row == b.row) {
            let at = usize::from(runs[0].row) * WIDTH..(usize::from(runs[0].row) + 1) * WIDTH;
            border(&frame.depth_mm[at.clone()], &depth[at], runs, stats);
            let mut kept = runs
                .iter()
                .filter(|r| !stats[r.component as usize].too_large);
            let Some(first) = kept.next() else {
                continue;
            };
            let span = usize::from(first.start)..usize::from(kept.next_back().unwrap_or(first).end);
            let j = usize::from(first.row);
            let z = &depth[j * WIDTH..(j + 1) * WIDTH];
            // As `camera.unproject`, `floor.height` and `(z / fx) (z / fy)`, bit for bit.
            let dy = camera.cy - j as f32;
            for i in span {
                let p = Vec3::new(dx[i] * z[i] / camera.fx, dy * z[i] / camera.fy, z[i]);
                (x[i], y[i], h[i]) = (p.x, p.y, floor.height(p));
                area[i] = (z[i] / camera.fx) * (z[i] / camera.fy);
            }
            for run in runs {
                let c = &mut stats[run.component as usize];
                if c.too_large {
                    continue;
                }
                let pixels = usize::from(run.start)..usize::from(run.end);
                let [mx, my, mz, mh] = [&*x, &*y, z, &*h].map(|v| min_max(&v[pixels.clone()]));
                c.min = c.min.min(Vec3::new(mx.0, my.0, mz.0));
                c.max = c.max.max(Vec3::new(mx.1, my.1, mz.1));
                c.top_m = c.top_m.max(mh.1);
                c.bottom_m = c.bottom_m.min(mh.0);
                let [sx, sy, sz, sa] = [&*x, &*y, z, &*area].map(|v| sum(&v[pixels.clone()]));
                c.sum += Vec3::new(sx, sy, sz);
                c.area_m2 += sa;
                c.pixels += pixels.len();
                c.touches_bottom_row |= j + 1 == HEIGHT;
                if j == 0 {
                    c.top_row_pixels += pixels.len();
                }
                c.bbox = [
                    c.bbox[0].min(run.start),
                    c.bbox[1].min(run.row),
                    c.bbox[2].max(run.end - 1),
                    c.bbox[3].max(run.row),
                ];
                if let Some(previous) = previous {
                    c.overlap += previous[j * WIDTH..][pixels].iter().filter(|&&b| b).count();
                }
            }
        }
    }

    /// The wall behind the interaction area: a plane facing the sensor (within the floor's
    /// tilt of it) at least [`WALL_BEHIND_M`] behind the interaction area, holding a quarter
    /// of the readings of the image's upper part (a person's upper body there holds a tenth
    /// at most). As the floor: kept while it holds most of its support; when there is none,
    /// looked for again every [`WALL_WAIT_FRAMES`] frames (a search costs about a
    /// millisecond).
    fn wall(&mut self, frame: &DepthFrame) -> Option<Plane> {
        if self.wall.is_none() && self.wall_wait > 0 {
            self.wall_wait -= 1;
            return None;
        }
        let beyond = self.settings.centre_z_m + WALL_BEHIND_M;
        let samples = &mut self.scratch.wall_samples;
        let readings = wall_samples_into(frame, beyond, samples);
        let inlier = self.settings.floor.inlier_m;
        if let Some((plane, support)) = self.wall {
            let now = samples
                .iter()
                .filter(|&&p| plane.height(p).abs() < inlier)
                .count();
            if now * 10 >= support * 7 {
                return Some(plane);
            }
        }
        let settings = FloorSettings {
            min_support: 0.0,
            ..self.settings.floor
        };
        self.wall = fit_plane(samples, &settings, -Vec3::Z)
            .filter(|&(_, support)| support * 4 >= readings && readings > 0);
        if self.wall.is_none() {
            self.wall_wait = WALL_WAIT_FRAMES;
        }
        self.wall.map(|(plane, _)| plane)
    }

    /// The floor: the last one while it still holds most of its support, else fitted anew.
    fn floor(&mut self, frame: &DepthFrame) -> Option<Plane> {
        let samples = &mut self.scratch.floor_samples;
        floor_samples_into(frame, samples);
        if let Some((plane, support)) = self.floor {
            let now = samples
                .iter()
                .filter(|&&p| plane.height(p).abs() < self.settings.floor.inlier_m)
                .count();
            if now * 10 >= support * 7 {
                return Some(plane);
            }
        }
        self.floor = fit_floor(samples, &self.settings.floor);
        self.floor.map(|(plane, _)| plane)
    }
}

/// What the parts of a person are found among (module `parts`): the frame's raw depth, the
/// components that look like people, and the parts' scratch.
struct PartsOf<'a> {
    raw_mm: &'a [u16],
    people: &'a [usize],
    parts: &'a mut Vec<(u32, usize)>,
}

/// The pixels of component `chosen` of `runs` and its stats, with its parts when `join` says
/// where to find them.
fn person_from(
    chosen: usize,
    runs: &[components::Run],
    stats: &[Stats],
    join: Option<PartsOf>,
) -> (Vec<bool>, Stats) {
    let mut c = stats[chosen];
    let mut mask = vec![false; PIXELS];
    fill(&mut mask, runs, chosen as u32);
    if let Some(PartsOf {
        raw_mm,
        people,
        parts,
    }) = join
    {
        parts::parts_of(chosen as u32, &mut mask, raw_mm, runs, stats, people, parts);
        for &(part, _) in parts.iter() {
            c.add(&stats[part as usize]);
        }
    }
    (mask, c)
}

/// Sets the pixels of `component`'s runs in `mask`.
fn fill(mask: &mut [bool], runs: &[components::Run], component: u32) {
    for run in runs.iter().filter(|r| r.component == component) {
        let row = usize::from(run.row) * WIDTH;
        mask[row + usize::from(run.start)..row + usize::from(run.end)].fill(true);
    }
}

/// Counts, for the runs of one row, where two components border each other (next to each
/// other, or with only pixels without a reading between them) and which is the nearer.
fn border(raw_mm: &[u16], depth: &[f32], runs: &[components::Run], stats: &mut [Stats]) {
    for pair in runs.windows(2) {
        let (a, b) = (&pair[0], &pair[1]);
        let (ca, cb) = (a.component as usize, b.component as usize);
        if ca == cb
            || raw_mm[usize::from(a.end)..usize::from(b.start)]
                .iter()
                .any(|&mm| mm > 0)
        {
            continue;
        }
        let (za, zb) = (depth[usize::from(a.end) - 1], depth[usize::from(b.start)]);
        stats[ca].sides += 1;
        stats[cb].sides += 1;
        if za > zb + NEARER_M {
            stats[ca].behind += 1;
        } else if zb > za + NEARER_M {
            stats[cb].behind += 1;
        }
    }
}

/// The sum of `values`, in eight interleaved partial sums (so that it vectorises).
fn sum(values: &[f32]) -> f32 {
    let mut lanes = [0.0; 8];
    let chunks = values.chunks_exact(8);
    let rest: f32 = chunks.remainder().iter().sum();
    for chunk in chunks {
        for (lane, &v) in lanes.iter_mut().zip(chunk) {
            *lane += v;
        }
    }
    lanes.iter().sum::<f32>() + rest
}

/// The least and greatest of `values` (none is NaN), in eight interleaved lanes.
fn min_max(values: &[f32]) -> (f32, f32) {
    let (mut low, mut high) = ([f32::INFINITY; 8], [f32::NEG_INFINITY; 8]);
    let chunks = values.chunks_exact(8);
    for &v in chunks.remainder() {
        (low[0], high[0]) = (
            if v < low[0] { v } else { low[0] },
            if v > high[0] { v } else { high[0] },
        );
    }
    for chunk in chunks {
        for ((low, high), &v) in low.iter_mut().zip(&mut high).zip(chunk) {
            *low = if v < *low { v } else { *low };
            *high = if v > *high { v } else { *high };
        }
    }
    (
        low.into_iter().fold(f32::INFINITY, f32::min),
        high.into_iter().fold(f32::NEG_INFINITY, f32::max),
    )
}
