//! Anthropometric measurement of a (morphed) body mesh, after seed 002 Table 4.1 (EN 13402)
//! and ISO 8559-1.
//!
//! A girth is the perimeter of the convex hull of a plane cross-section of the mesh (seed 002
//! §4.2: the tape measure bridges concavities), restricted to the loops of the body part being
//! measured (the torso without the arms for the chest, the left leg for the thigh...). Loops
//! are assigned to body parts by the skin weights of the vertices whose edges they cross.
//! Landmarks (heights) are searched on the mesh itself, scanning cross-sections; the rig's
//! rest pose (derived from the same mesh) only bounds the search regions, and gives the elbow
//! and wrist joint centres for the arm length.
//!
//! | measure | definition here |
//! | --- | --- |
//! | stature | top of the head to the sole (body vertices' y extent) |
//! | crotch height | lowest point of the surface in the body's mid-sagittal plane (between the legs) above the floor |
//! | arm length | left acromion -> elbow joint -> wrist joint (ISO: over the elbow to the wrist) |
//! | shoulder width | biacromial breadth: distance between the two acromion points (the corner of the frontal shoulder silhouette between the shoulder slope and the arm) |
//! | neck | neck base girth: section perpendicular to the neck (neck joint to head joint) through the neck joint, which the rig derives from the mesh at the neck's base |
//! | bust / chest | largest trunk girth between 1 cm and 35% of the trunk height (armpit to crotch) below the armpits (EN 13402-1: under the armpits, across the shoulder blades and the bust points): at the bust points on a female body, just under the armpits on a flat chest |
//! | under-bust | torso girth at the fold below the breast: the deepest point of the front profile under the chord from the bust point (the highest peak of the front profile below the armpits) to the waist |
//! | waist | smallest torso girth between the hips and the under-bust |
//! | navel waist | trunk girth at the navel (omphalion; ANSUR II's waist): the deepest pit, within ±2.5 cm, of the mid-sagittal front profile between the hip and 4 cm above the natural waist |
//! | hip | girth of the trunk (arms and hands excluded) at the buttocks' greatest posterior prominence above the crotch |
//! | thigh | largest girth of the left thigh below the crotch (just below the gluteal fold) |
//! | calf | largest girth of the left lower leg between ankle and knee |
//!
//! The convex hull is a hand-written Andrew monotone chain (O(n log n)).

use glam::{Vec2, Vec3};
use serde::Serialize;

use crate::model::BodyModel;

/// One connected piece of a plane cross-section of a mesh.
#[derive(Clone, Debug, PartialEq)]
pub struct SectionLoop {
    /// Points in order along the cut, in the plane's 2D coordinates (metres).
    pub points: Vec<Vec2>,
    /// The same points in 3D.
    pub points_3d: Vec<Vec3>,
    /// The mesh edge each point lies on (vertex indices, smaller first).
    pub edges: Vec<(u32, u32)>,
    /// Whether the chain closes on itself (it does on a closed mesh).
    pub closed: bool,
}

impl SectionLoop {
    /// Length along the cut (the tape laid on the skin, concavities followed).
    pub fn length(&self) -> f32 {
        let mut l: f32 = self.points.windows(2).map(|w| w[0].distance(w[1])).sum();
        if self.closed && self.points.len() > 2 {
            l += self.points[self.points.len() - 1].distance(self.points[0]);
        }
        l
    }

    /// Whether `p` is inside the polygon of the points (even-odd rule; an open chain is
    /// closed by its last-to-first edge).
    pub fn contains(&self, p: Vec2) -> bool {
        let n = self.points.len();
        let mut inside = false;
        for i in 0..n {
            let (a, b) = (self.points[i], self.points[(i + 1) % n]);
            if (a.y > p.y) != (b.y > p.y) && p.x < a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x) {
                inside = !inside;
            }
        }
        inside
    }

    /// Centroid of the points.
    pub fn centroid(&self) -> Vec2 {
        self.points.iter().copied().sum::<Vec2>() / self.points.len().max(1) as f32
    }
}

/// A cutting plane with an orthonormal 2D frame: 2D coordinates are `(dot(p - origin, u),
/// dot(p - origin, v))`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plane {
    pub origin: Vec3,
    pub normal: Vec3,
    pub u: Vec3,
    pub v: Vec3,
}

impl Plane {
    /// The horizontal plane y = `h`; 2D coordinates are `(x, z)`.
    pub fn horizontal(h: f32) -> Self {
        Self {
            origin: Vec3::new(0.0, h, 0.0),
            normal: Vec3::Y,
            u: Vec3::X,
            v: Vec3::Z,
        }
    }

    /// The plane through `origin` with normal `normal` (normalised here); the 2D frame's `u`
    /// is the model X axis made perpendicular to the normal (or Z if the normal is along X).
    pub fn new(origin: Vec3, normal: Vec3) -> Self {
        let normal = normal.normalize();
        let seed = if normal.x.abs() < 0.9 {
            Vec3::X
        } else {
            Vec3::Z
        };
        let u = (seed - normal * seed.dot(normal)).normalize();
        let v = normal.cross(u);
        Self {
            origin,
            normal,
            u,
            v,
        }
    }

    fn distance(&self, p: Vec3) -> f32 {
        (p - self.origin).dot(self.normal)
    }

    fn project(&self, p: Vec3) -> Vec2 {
        let d = p - self.origin;
        Vec2::new(d.dot(self.u), d.dot(self.v))
    }
}

/// Cuts the triangles with `plane` and joins the pieces into loops. A vertex exactly on the
/// plane counts as on its positive side, so each crossed edge gives exactly one point and
/// loops of a closed mesh close.
pub fn cross_section(
    positions: &[Vec3],
    triangles: &[[u32; 3]],
    plane: &Plane,
) -> Vec<SectionLoop> {
    cross_section_of(positions, triangles.iter(), plane)
}

/// [`cross_section`] of the triangles `triangles` yields (a subset of a mesh's triangles that
/// holds every triangle the plane crosses, e.g. from a [`HeightIndex`]).
pub fn cross_section_of<'t>(
    positions: &[Vec3],
    triangles: impl Iterator<Item = &'t [u32; 3]>,
    plane: &Plane,
) -> Vec<SectionLoop> {
    let side = |i: u32| plane.distance(positions[i as usize]) >= 0.0;
    // Segments as pairs of crossed edges.
    let mut segments: Vec<[(u32, u32); 2]> = Vec::new();
    for t in triangles {
        let s = [side(t[0]), side(t[1]), side(t[2])];
        if s[0] == s[1] && s[1] == s[2] {
            continue;
        }
        let mut crossed = [(0, 0); 2];
        let mut n = 0;
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            if s[k] != s[(k + 1) % 3] {
                crossed[n] = (a.min(b), a.max(b));
                n += 1;
            }
        }
        segments.push(crossed);
    }
    loops_from_segments(positions, plane, &segments)
}

/// Triangles binned by height, so that a horizontal cross-section visits only the triangles
/// that can cross its plane (a body has ~26k triangles; a section crosses ~300).
#[derive(Clone, Debug)]
pub struct HeightIndex {
    y0: f32,
    bin_m: f32,
    bins: Vec<Vec<u32>>,
}

impl HeightIndex {
    /// Bins of 1 cm over the vertical extent of `triangles`.
    pub fn new(positions: &[Vec3], triangles: &[[u32; 3]]) -> Self {
        let bin_m = 0.01;
        let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
        for t in triangles {
            for &v in t {
                let y = positions[v as usize].y;
                lo = lo.min(y);
                hi = hi.max(y);
            }
        }
        if !(lo.is_finite() && hi.is_finite()) {
            return Self {
                y0: 0.0,
                bin_m,
                bins: Vec::new(),
            };
        }
        let n = ((hi - lo) / bin_m).floor() as usize + 1;
        let mut bins = vec![Vec::new(); n];
        for (i, t) in triangles.iter().enumerate() {
            let ys = t.map(|v| positions[v as usize].y);
            let (a, b) = (ys[0].min(ys[1]).min(ys[2]), ys[0].max(ys[1]).max(ys[2]));
            let (ba, bb) = (
                (((a - lo) / bin_m).floor() as usize).min(n - 1),
                (((b - lo) / bin_m).floor() as usize).min(n - 1),
            );
            for bin in &mut bins[ba..=bb] {
                bin.push(i as u32);
            }
        }
        Self {
            y0: lo,
            bin_m,
            bins,
        }
    }

    /// Indices of the triangles whose height range may contain `h`.
    pub fn candidates(&self, h: f32) -> &[u32] {
        let f = ((h - self.y0) / self.bin_m).floor();
        if !(f >= 0.0 && (f as usize) < self.bins.len()) {
            return &[];
        }
        &self.bins[f as usize]
    }

    /// The horizontal cross-section at height `h`.
    pub fn slice(&self, positions: &[Vec3], triangles: &[[u32; 3]], h: f32) -> Vec<SectionLoop> {
        cross_section_of(
            positions,
            self.candidates(h).iter().map(|&t| &triangles[t as usize]),
            &Plane::horizontal(h),
        )
    }
}

fn loops_from_segments(
    positions: &[Vec3],
    plane: &Plane,
    segments: &[[(u32, u32); 2]],
) -> Vec<SectionLoop> {
    // Each edge is shared by at most two segments (manifold mesh): sort the (edge, segment,
    // slot) triples and link the pairs.
    let key = |e: (u32, u32)| ((e.0 as u64) << 32) | e.1 as u64;
    let mut ends: Vec<(u64, u32, u8)> = Vec::with_capacity(segments.len() * 2);
    for (i, s) in segments.iter().enumerate() {
        ends.push((key(s[0]), i as u32, 0));
        ends.push((key(s[1]), i as u32, 1));
    }
    ends.sort_unstable();
    let mut links = vec![[usize::MAX; 2]; segments.len()];
    for w in ends.windows(2) {
        if w[0].0 == w[1].0 {
            links[w[0].1 as usize][w[0].2 as usize] = w[1].1 as usize;
            links[w[1].1 as usize][w[1].2 as usize] = w[0].1 as usize;
        }
    }
    let point = |e: (u32, u32)| {
        let (pa, pb) = (positions[e.0 as usize], positions[e.1 as usize]);
        let (da, db) = (plane.distance(pa), plane.distance(pb));
        let t = if da == db { 0.5 } else { da / (da - db) };
        pa.lerp(pb, t)
    };
    let other = |seg: usize, e: (u32, u32)| -> Option<usize> {
        let slot = if segments[seg][0] == e { 0 } else { 1 };
        let o = links[seg][slot];
        (o != usize::MAX && o != seg).then_some(o)
    };
    let mut used = vec![false; segments.len()];
    let mut loops = Vec::new();
    let mut walk = |start: usize, entry: (u32, u32), used: &mut Vec<bool>| {
        let mut edges = vec![entry];
        let (mut cur, mut entry) = (start, entry);
        loop {
            used[cur] = true;
            let s = segments[cur];
            let exit = if s[0] == entry { s[1] } else { s[0] };
            edges.push(exit);
            match other(cur, exit) {
                Some(next) if !used[next] => {
                    cur = next;
                    entry = exit;
                }
                _ => break,
            }
        }
        let closed = edges.len() > 2 && edges.first() == edges.last();
        if closed {
            edges.pop();
        }
        let points_3d: Vec<Vec3> = edges.iter().map(|&e| point(e)).collect();
        loops.push(SectionLoop {
            points: points_3d.iter().map(|&p| plane.project(p)).collect(),
            points_3d,
            edges,
            closed,
        });
    };
    // Open chains first (from an end: an edge crossed by one segment only), then loops.
    for i in 0..segments.len() {
        if used[i] {
            continue;
        }
        if let Some(&end) = segments[i].iter().find(|&&e| other(i, e).is_none()) {
            walk(i, end, &mut used);
        }
    }
    for i in 0..segments.len() {
        if !used[i] {
            walk(i, segments[i][0], &mut used);
        }
    }
    loops
}

fn cross(o: Vec2, a: Vec2, b: Vec2) -> f32 {
    (a - o).perp_dot(b - o)
}

/// The convex hull of `points`, counter-clockwise, without collinear points (Andrew's
/// monotone chain).
pub fn convex_hull(points: &[Vec2]) -> Vec<Vec2> {
    let mut p: Vec<Vec2> = points.iter().copied().filter(|q| q.is_finite()).collect();
    p.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    p.dedup();
    if p.len() < 3 {
        return p;
    }
    let mut hull: Vec<Vec2> = Vec::with_capacity(p.len() + 1);
    let turns_left = |h: &[Vec2], q: Vec2| cross(h[h.len() - 2], h[h.len() - 1], q) > 0.0;
    // Lower hull left to right.
    for &q in &p {
        while hull.len() >= 2 && !turns_left(&hull, q) {
            hull.pop();
        }
        hull.push(q);
    }
    // Upper hull right to left, never popping the lower hull.
    let lower = hull.len() + 1;
    for &q in p.iter().rev().skip(1) {
        while hull.len() >= lower && !turns_left(&hull, q) {
            hull.pop();
        }
        hull.push(q);
    }
    hull.pop();
    hull
}

/// Perimeter of the convex hull of `points` (twice the length for two points, 0 for fewer).
pub fn hull_perimeter(points: &[Vec2]) -> f32 {
    let h = convex_hull(points);
    if h.len() < 2 {
        return 0.0;
    }
    (0..h.len())
        .map(|i| h[i].distance(h[(i + 1) % h.len()]))
        .sum()
}

/// Body measurements (centimetres), after seed 002 Table 4.1 / ISO 8559-1; see the
/// [module docs](self) for the definitions.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Measurements {
    pub stature_cm: f32,
    pub crotch_height_cm: f32,
    pub arm_length_cm: f32,
    pub shoulder_width_cm: f32,
    pub neck_cm: f32,
    pub bust_cm: f32,
    pub underbust_cm: f32,
    pub waist_cm: f32,
    pub navel_waist_cm: f32,
    pub hip_cm: f32,
    pub thigh_cm: f32,
    pub calf_cm: f32,
    pub landmarks: Landmarks,
}

/// The name of one measurement of [`Measurements`], as used on the command line, in shape
/// fits and in size charts (`stature`, `inside-leg`, `bust`...).
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, serde::Deserialize,
)]
#[serde(rename_all = "kebab-case")]
pub enum Measure {
    Stature,
    /// Crotch height.
    InsideLeg,
    ArmLength,
    /// Biacromial breadth.
    ShoulderWidth,
    /// Neck base girth.
    Neck,
    /// Chest (male) or bust (female) girth.
    Bust,
    Underbust,
    /// Natural waist (EN 13402): the narrowest trunk girth.
    Waist,
    /// Waist at the navel (omphalion), as ANSUR II measures it.
    NavelWaist,
    Hip,
    Thigh,
    Calf,
}

impl Measure {
    pub const ALL: [Measure; 12] = [
        Measure::Stature,
        Measure::InsideLeg,
        Measure::ArmLength,
        Measure::ShoulderWidth,
        Measure::Neck,
        Measure::Bust,
        Measure::Underbust,
        Measure::Waist,
        Measure::NavelWaist,
        Measure::Hip,
        Measure::Thigh,
        Measure::Calf,
    ];

    /// The kebab-case name (`inside-leg`).
    pub fn name(self) -> &'static str {
        match self {
            Measure::Stature => "stature",
            Measure::InsideLeg => "inside-leg",
            Measure::ArmLength => "arm-length",
            Measure::ShoulderWidth => "shoulder-width",
            Measure::Neck => "neck",
            Measure::Bust => "bust",
            Measure::Underbust => "underbust",
            Measure::Waist => "waist",
            Measure::NavelWaist => "navel-waist",
            Measure::Hip => "hip",
            Measure::Thigh => "thigh",
            Measure::Calf => "calf",
        }
    }

    /// The measure named `name` (kebab-case; `chest` is accepted for `bust`, `crotch-height`
    /// for `inside-leg`, `hips` for `hip`).
    pub fn from_name(name: &str) -> Option<Measure> {
        let n = name.trim().to_ascii_lowercase().replace('_', "-");
        match n.as_str() {
            "chest" => return Some(Measure::Bust),
            "crotch-height" => return Some(Measure::InsideLeg),
            "hips" => return Some(Measure::Hip),
            "under-bust" => return Some(Measure::Underbust),
            "omphalion-waist" => return Some(Measure::NavelWaist),
            _ => {}
        }
        Measure::ALL.into_iter().find(|m| m.name() == n)
    }

    /// All names, comma-separated, for error messages.
    pub fn names() -> String {
        Measure::ALL.map(Measure::name).join(", ")
    }

    /// This measurement of `m`, cm.
    pub fn of(self, m: &Measurements) -> f32 {
        match self {
            Measure::Stature => m.stature_cm,
            Measure::InsideLeg => m.crotch_height_cm,
            Measure::ArmLength => m.arm_length_cm,
            Measure::ShoulderWidth => m.shoulder_width_cm,
            Measure::Neck => m.neck_cm,
            Measure::Bust => m.bust_cm,
            Measure::Underbust => m.underbust_cm,
            Measure::Waist => m.waist_cm,
            Measure::NavelWaist => m.navel_waist_cm,
            Measure::Hip => m.hip_cm,
            Measure::Thigh => m.thigh_cm,
            Measure::Calf => m.calf_cm,
        }
    }

    /// Values an adult human body can have, cm: wider than the 0.1st-99.9th percentiles of the
    /// ANSUR II survey (6,068 US Army adults), so a value outside is a typing error (a 3 m
    /// waist, a girth in mm), not a rare body.
    pub fn plausible_range_cm(self) -> (f32, f32) {
        match self {
            Measure::Stature => (120.0, 230.0),
            Measure::InsideLeg => (50.0, 110.0),
            Measure::ArmLength => (40.0, 90.0),
            Measure::ShoulderWidth => (25.0, 55.0),
            Measure::Neck => (25.0, 60.0),
            Measure::Bust => (60.0, 160.0),
            Measure::Underbust => (55.0, 150.0),
            Measure::Waist | Measure::NavelWaist => (45.0, 170.0),
            Measure::Hip => (65.0, 170.0),
            Measure::Thigh => (35.0, 95.0),
            Measure::Calf => (22.0, 60.0),
        }
    }
}

impl std::fmt::Display for Measure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for Measure {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Measure::from_name(s)
            .ok_or_else(|| format!("unknown measurement `{s}`; known: {}", Measure::names()))
    }
}

/// Where the measurements were taken: heights above the sole (the lowest body vertex), cm.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Landmarks {
    pub crotch_cm: f32,
    pub axilla_cm: f32,
    pub bust_cm: f32,
    /// The most anterior point of the chest (the bust point on a female body).
    pub bust_point_cm: f32,
    pub underbust_cm: f32,
    pub waist_cm: f32,
    /// The navel (omphalion).
    pub navel_cm: f32,
    pub hip_cm: f32,
    pub thigh_cm: f32,
    pub calf_cm: f32,
    /// Neck base: height of the centre of the neck base section.
    pub neck_base_cm: f32,
    /// Left and right acromion points.
    pub acromion_left_cm: f32,
    pub acromion_right_cm: f32,
    pub elbow_cm: f32,
    pub wrist_cm: f32,
}

/// Why a body cannot be measured.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum MeasureError {
    #[error("the rig has no bone `{0}`, which measurement uses to bound its search regions")]
    MissingBone(&'static str),
    #[error("positions has {got} vertices, the model {expected}")]
    VertexCount { got: usize, expected: usize },
    #[error("could not find the {0} on the mesh")]
    LandmarkNotFound(&'static str),
}

/// Body part of a vertex, from its dominant skin bone.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Part {
    Torso,
    Head,
    Arm,
    Leg,
}

const CM: f32 = 100.0;
/// Scan step for landmark searches (metres).
const STEP: f32 = 0.0025;
/// First pass of [`scan_best`] (metres).
const COARSE_STEP: f32 = 0.01;

struct Measurer<'a> {
    positions: &'a [Vec3],
    triangles: &'a [[u32; 3]],
    index: HeightIndex,
    part: Vec<Part>,
    mid_x: f32,
}

impl Measurer<'_> {
    fn slice(&self, h: f32) -> Vec<SectionLoop> {
        self.index.slice(self.positions, self.triangles, h)
    }

    fn is_arm(&self, l: &SectionLoop) -> bool {
        let arm = l
            .edges
            .iter()
            .flat_map(|&(a, b)| [a, b])
            .filter(|&v| self.part[v as usize] == Part::Arm)
            .count();
        arm > l.edges.len()
    }

    /// Points of the loops at height `h` that `keep` accepts.
    fn points(&self, h: f32, keep: impl Fn(&Self, &SectionLoop) -> bool) -> Vec<Vec2> {
        self.slice(h)
            .iter()
            .filter(|l| keep(self, l))
            .flat_map(|l| l.points.iter().copied())
            .collect()
    }

    /// Girth of everything but the arms at height `h`.
    fn trunk_girth(&self, h: f32) -> f32 {
        hull_perimeter(&self.points(h, |m, l| !m.is_arm(l)))
    }

    /// Girth of the left leg (+X side, not an arm) at `h`.
    fn left_leg_girth(&self, h: f32) -> f32 {
        hull_perimeter(&self.points(h, |m, l| !m.is_arm(l) && l.centroid().x > m.mid_x))
    }

    /// The most posterior z of the non-arm loops at `h`.
    fn back(&self, h: f32) -> f32 {
        self.points(h, |m, l| !m.is_arm(l))
            .iter()
            .map(|p| p.y)
            .fold(f32::INFINITY, f32::min)
    }

    /// The most anterior z of the non-arm loops at `h`.
    fn front(&self, h: f32) -> f32 {
        self.points(h, |m, l| !m.is_arm(l))
            .iter()
            .map(|p| p.y)
            .fold(f32::NEG_INFINITY, f32::max)
    }
}

/// `(h, f(h))` for h from `lo` to `hi` in [`STEP`]s.
fn scan(lo: f32, hi: f32, f: impl Fn(f32) -> f32) -> Vec<(f32, f32)> {
    let n = ((hi - lo) / STEP).ceil().max(1.0) as usize;
    (0..=n)
        .map(|i| {
            let h = lo + (hi - lo) * i as f32 / n as f32;
            (h, f(h))
        })
        .collect()
}

/// The highest `h` of `s` (sorted by increasing `h`) whose value is a peak: larger than
/// everything above it and at least `drop` larger than some value below it before any larger
/// value; the overall maximum if there is no such peak.
fn topmost_peak(s: &[(f32, f32)], drop: f32) -> f32 {
    let mut best: Option<(f32, f32)> = None;
    for &(h, v) in s.iter().rev() {
        if !v.is_finite() {
            continue;
        }
        match best {
            Some((_, b)) if v > b => best = Some((h, v)),
            Some((bh, b)) if v < b - drop => return bh,
            None => best = Some((h, v)),
            _ => {}
        }
    }
    arg_best(s, |a, b| a > b).0
}

/// The best `(h, f(h))` for h in `lo..=hi`: a 1 cm scan, then a [`STEP`] scan within 1 cm of
/// the coarse best (the girth and profile curves are smooth at the centimetre scale; this
/// visits a quarter of the heights of a full fine scan).
fn scan_best(
    lo: f32,
    hi: f32,
    f: impl Fn(f32) -> f32,
    better: impl Fn(f32, f32) -> bool + Copy,
) -> (f32, f32) {
    let n = ((hi - lo) / COARSE_STEP).ceil().max(1.0) as usize;
    let coarse: Vec<(f32, f32)> = (0..=n)
        .map(|i| {
            let h = lo + (hi - lo) * i as f32 / n as f32;
            (h, f(h))
        })
        .collect();
    let (h0, _) = arg_best(&coarse, better);
    let fine = scan((h0 - COARSE_STEP).max(lo), (h0 + COARSE_STEP).min(hi), &f);
    arg_best(&fine, better)
}

fn arg_best(s: &[(f32, f32)], better: impl Fn(f32, f32) -> bool) -> (f32, f32) {
    let mut best = s[0];
    for &p in &s[1..] {
        if p.1.is_finite() && (!best.1.is_finite() || better(p.1, best.1)) {
            best = p;
        }
    }
    best
}

impl BodyModel {
    /// Measures the body with these vertex positions (the model's own, or morphed ones from
    /// [`BodyModel::apply_targets`] / [`BodyModel::shaped`]).
    pub fn measure(&self, positions: &[Vec3]) -> Result<Measurements, MeasureError> {
        self.measure_with_probe(positions).map(|(m, _)| m)
    }

    /// [`BodyModel::measure`], and a [`MeasureProbe`] that re-measures nearby shapes fast at
    /// the landmarks found here.
    pub fn measure_with_probe(
        &self,
        positions: &[Vec3],
    ) -> Result<(Measurements, MeasureProbe), MeasureError> {
        if positions.len() != self.positions.len() {
            return Err(MeasureError::VertexCount {
                got: positions.len(),
                expected: self.positions.len(),
            });
        }
        let body = self.body_vertex_count as usize;
        let rest = self.rest_pose(positions);
        let bone =
            |name: &'static str| self.bone_index(name).ok_or(MeasureError::MissingBone(name));
        let head_of = |name: &'static str| bone(name).map(|b| rest.heads[b]);
        let placement =
            |name: &'static str| bone(name).map(|b| self.bones[b].head_placement.clone());
        let pelvis = head_of("pelvis")?;
        let neck = head_of("neck_01")?;
        let head = head_of("head")?;
        let shoulder_l = head_of("upperarm_l")?;
        let elbow_l = head_of("lowerarm_l")?;
        let wrist_l = head_of("hand_l")?;
        let knee_l = head_of("calf_l")?;
        let ankle_l = head_of("foot_l")?;
        let elbow_r = head_of("lowerarm_r")?;

        // Part of each bone: the first of its ancestors (itself included) that names one.
        let mut bone_part = vec![Part::Torso; self.bones.len()];
        for (i, b) in self.bones.iter().enumerate() {
            let n = b.name.as_str();
            bone_part[i] = if n.starts_with("upperarm") {
                Part::Arm
            } else if n.starts_with("thigh") {
                Part::Leg
            } else if n.starts_with("neck") || n == "head" {
                Part::Head
            } else {
                b.parent.map_or(Part::Torso, |p| bone_part[p])
            };
        }
        let part: Vec<Part> = (0..body)
            .map(|v| bone_part[self.skin_joints[v][0] as usize])
            .collect();

        let body_pos = &positions[..body];
        let floor = body_pos.iter().map(|p| p.y).fold(f32::INFINITY, f32::min);
        let top = body_pos
            .iter()
            .map(|p| p.y)
            .fold(f32::NEG_INFINITY, f32::max);
        let m = Measurer {
            positions: body_pos,
            triangles: &self.triangles,
            index: HeightIndex::new(body_pos, &self.triangles),
            part,
            mid_x: pelvis.x,
        };

        // Crotch: lowest point of the mid-sagittal section above the knees.
        let crotch_x = pelvis.x;
        let sagittal = cross_section(
            body_pos,
            &self.triangles,
            &Plane::new(Vec3::new(crotch_x, 0.0, 0.0), Vec3::X),
        );
        let crotch = sagittal
            .iter()
            .flat_map(|l| l.points_3d.iter())
            .map(|p| p.y)
            .filter(|&y| y > knee_l.y && y < pelvis.y)
            .fold(f32::INFINITY, f32::min);
        if !crotch.is_finite() {
            return Err(MeasureError::LandmarkNotFound("crotch"));
        }

        // Axilla: going down from the shoulder joints, the first height at which both arms
        // are loops of their own.
        let arms_apart = |h: f32| {
            let loops = m.slice(h);
            let arms: Vec<f32> = loops
                .iter()
                .filter(|l| m.is_arm(l))
                .map(|l| l.centroid().x - m.mid_x)
                .collect();
            arms.iter().any(|&x| x > 0.0) && arms.iter().any(|&x| x < 0.0)
        };
        let mut hi = shoulder_l.y;
        let mut lo = hi;
        while !arms_apart(lo) {
            hi = lo;
            lo -= 0.01;
            if lo < crotch {
                return Err(MeasureError::LandmarkNotFound("axilla"));
            }
        }
        for _ in 0..12 {
            let mid = 0.5 * (lo + hi);
            if arms_apart(mid) {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let axilla = lo;
        let trunk = axilla - crotch;

        // Bust / chest: the largest trunk girth of the chest (seed 002 Table 4.1: the convex
        // hull at chest / bust height), between 1 cm and 35% of the trunk below the armpits:
        // over the breasts, or across a man's chest just below the armpits.
        let (bust_h, bust) = scan_best(
            axilla - 0.35 * trunk,
            axilla - 0.01,
            |h| m.trunk_girth(h),
            |a, b| a > b,
        );

        // Hip: at the buttocks' greatest (posterior) prominence above the crotch.
        let hip_h = scan_best(
            crotch + 0.005,
            crotch + 0.45 * trunk,
            |h| m.back(h),
            |a, b| a < b,
        )
        .0;
        let hip = m.trunk_girth(hip_h);

        // Waist: the smallest trunk girth between the hips and the chest.
        let (waist_h, waist) = scan_best(hip_h, bust_h - 0.05, |h| m.trunk_girth(h), |a, b| a < b);

        // Navel: the deepest small pit (within ±2.5 cm) of the mid-sagittal front profile
        // between the hip level and 4 cm above the natural waist.
        let navel_h = {
            let (lo, hi) = (hip_h, waist_h + 0.04);
            let pts: Vec<Vec2> = sagittal
                .iter()
                .flat_map(|l| l.points_3d.iter())
                .filter(|p| p.y > lo && p.y < hi)
                .map(|p| Vec2::new(p.y, p.z))
                .collect();
            let zmid = pts.iter().map(|p| p.y).fold(f32::NEG_INFINITY, f32::max) * 0.5
                + pts.iter().map(|p| p.y).fold(f32::INFINITY, f32::min) * 0.5;
            let mut front: Vec<Vec2> = pts.into_iter().filter(|p| p.y > zmid).collect();
            front.sort_by(|a, b| a.x.total_cmp(&b.x));
            let window = 0.025;
            let mut best = (0.0f32, waist_h);
            for (i, p) in front.iter().enumerate() {
                let below = front[..i].iter().filter(|a| a.x > p.x - window);
                for a in below {
                    for b in front[i + 1..].iter().take_while(|b| b.x < p.x + window) {
                        if b.x - a.x < 1e-4 {
                            continue;
                        }
                        let chord = a.y + (b.y - a.y) * (p.x - a.x) / (b.x - a.x);
                        if chord - p.y > best.0 {
                            best = (chord - p.y, p.x);
                        }
                    }
                }
            }
            best.1
        };
        let navel_waist = m.trunk_girth(navel_h);

        // Under-bust: the front profile's deepest point behind the chord from the bust point to
        // the waist front (the fold under the breast).
        // The bust point: the highest peak of the chest's front profile going down from the
        // armpits.
        let front_scan = scan(axilla - 0.4 * trunk, axilla - 0.005, |h| m.front(h));
        let bust_point_h = topmost_peak(&front_scan, 0.003);
        let (b0, w0) = (
            Vec2::new(bust_point_h, m.front(bust_point_h)),
            Vec2::new(waist_h, m.front(waist_h)),
        );
        let chord = (w0 - b0).normalize_or_zero();
        let under_scan = scan(waist_h, bust_point_h, |h| {
            let p = Vec2::new(h, m.front(h)) - b0;
            // Distance behind the chord (towards -z).
            -chord.perp_dot(p) * chord.x.signum()
        });
        let underbust_h = arg_best(&under_scan, |a, b| a > b).0;
        let underbust = m.trunk_girth(underbust_h);

        // Thigh: the largest girth of the left upper leg, below the crotch.
        let (thigh_h, thigh) = scan_best(
            0.5 * (knee_l.y + crotch),
            crotch - 0.005,
            |h| m.left_leg_girth(h),
            |a, b| a > b,
        );

        // Calf: the largest girth of the left lower leg.
        let (calf_h, calf) = scan_best(ankle_l.y, knee_l.y, |h| m.left_leg_girth(h), |a, b| a > b);

        // Neck base: the section perpendicular to the neck (neck joint -> head joint) through
        // the neck joint, which the rig places at the neck's base (C7/T1) from the mesh; the
        // loop around the neck's axis.
        let axis = (head - neck).normalize_or_zero();
        let neck_loops = cross_section(body_pos, &self.triangles, &Plane::new(neck, axis));
        let neck_g = neck_loops
            .iter()
            .find(|l| l.contains(Vec2::ZERO))
            .map(|l| hull_perimeter(&l.points))
            .ok_or(MeasureError::LandmarkNotFound("neck base"))?;
        let neck_base = neck;

        // Acromion: the corner of the frontal silhouette of the shoulder, between the shoulder
        // slope and the arm.
        let acromion = |sign: f32, elbow: Vec3| -> Result<u32, MeasureError> {
            let bins = 60;
            let x0 = neck.x;
            let x1 = elbow.x;
            let mut tops: Vec<Option<(u32, Vec3)>> = vec![None; bins];
            for (v, p) in body_pos.iter().enumerate() {
                if m.part[v] == Part::Head || (p.x - x0) * sign < 0.0 || p.y < elbow.y {
                    continue;
                }
                let f = (p.x - x0) / (x1 - x0);
                if !(0.0..1.0).contains(&f) {
                    continue;
                }
                let b = (f * bins as f32) as usize;
                if tops[b].is_none_or(|t| p.y > t.1.y) {
                    tops[b] = Some((v as u32, *p));
                }
            }
            let tops: Vec<(u32, Vec3)> = tops.into_iter().flatten().collect();
            let start = tops
                .iter()
                .map(|t| t.1)
                .max_by(|a, b| a.y.total_cmp(&b.y))
                .ok_or(MeasureError::LandmarkNotFound("shoulder"))?;
            let end = tops
                .last()
                .ok_or(MeasureError::LandmarkNotFound("shoulder"))?
                .1;
            let (s, e) = (Vec2::new(start.x, start.y), Vec2::new(end.x, end.y));
            let d = (e - s).normalize_or_zero();
            tops.iter()
                .copied()
                .filter(|(_, p)| (p.x - start.x) * sign > 0.0)
                .max_by(|(_, a), (_, b)| {
                    let da = d.perp_dot(Vec2::new(a.x, a.y) - s).abs();
                    let db = d.perp_dot(Vec2::new(b.x, b.y) - s).abs();
                    da.total_cmp(&db)
                })
                .map(|(v, _)| v)
                .ok_or(MeasureError::LandmarkNotFound("acromion"))
        };
        let acr_l_v = acromion(1.0, elbow_l)?;
        let acr_r_v = acromion(-1.0, elbow_r)?;
        let (acr_l, acr_r) = (body_pos[acr_l_v as usize], body_pos[acr_r_v as usize]);
        let arm_length = acr_l.distance(elbow_l) + elbow_l.distance(wrist_l);
        let above = |y: f32| (y - floor) * CM;

        // The probe: what was used where, to re-measure nearby shapes fast.
        let band = |h: f32, half: f32| -> Vec<u32> {
            let mut t: Vec<u32> = Vec::new();
            let mut y = h - half;
            while y <= h + half + 0.01 {
                t.extend_from_slice(m.index.candidates(y));
                y += 0.01;
            }
            t.sort_unstable();
            t.dedup();
            t
        };
        let girth = |h: f32, leg: bool| -> GirthProbe {
            let tris = band(h, 0.03);
            // The vertex of the crossing triangles nearest to the plane anchors the height.
            let vertex = tris
                .iter()
                .flat_map(|&t| self.triangles[t as usize])
                .filter(|&v| m.part[v as usize] != Part::Arm)
                .min_by(|&a, &b| {
                    (body_pos[a as usize].y - h)
                        .abs()
                        .total_cmp(&(body_pos[b as usize].y - h).abs())
                })
                .unwrap_or(0);
            GirthProbe {
                vertex,
                dy: h - body_pos[vertex as usize].y,
                tris,
                leg,
            }
        };
        let neck_tris: Vec<u32> = self
            .triangles
            .iter()
            .enumerate()
            .filter(|(_, t)| {
                t.iter()
                    .any(|&v| body_pos[v as usize].distance(neck) < 0.12)
            })
            .map(|(i, _)| i as u32)
            .collect();
        let mut probe = MeasureProbe {
            top: (0..body as u32)
                .filter(|&v| body_pos[v as usize].y > top - 0.02)
                .collect(),
            sole: (0..body as u32)
                .filter(|&v| body_pos[v as usize].y < floor + 0.02)
                .collect(),
            crotch_x,
            crotch_tris: band(crotch, 0.04),
            girths: [
                girth(bust_h, false),
                girth(underbust_h, false),
                girth(waist_h, false),
                girth(navel_h, false),
                girth(hip_h, false),
                girth(thigh_h, true),
                girth(calf_h, true),
            ],
            neck_tris,
            neck: placement("neck_01")?,
            head: placement("head")?,
            acromion: [acr_l_v, acr_r_v],
            elbow: placement("lowerarm_l")?,
            wrist: placement("hand_l")?,
            part: m.part.clone(),
            mid_x: m.mid_x,
            vertices: Vec::new(),
        };
        probe.vertices = probe.collect_vertices(&self.triangles);

        let measurements = Measurements {
            stature_cm: (top - floor) * CM,
            crotch_height_cm: above(crotch),
            arm_length_cm: arm_length * CM,
            shoulder_width_cm: acr_l.distance(acr_r) * CM,
            neck_cm: neck_g * CM,
            bust_cm: bust * CM,
            underbust_cm: underbust * CM,
            waist_cm: waist * CM,
            navel_waist_cm: navel_waist * CM,
            hip_cm: hip * CM,
            thigh_cm: thigh * CM,
            calf_cm: calf * CM,
            landmarks: Landmarks {
                crotch_cm: above(crotch),
                axilla_cm: above(axilla),
                bust_cm: above(bust_h),
                bust_point_cm: above(bust_point_h),
                underbust_cm: above(underbust_h),
                waist_cm: above(waist_h),
                navel_cm: above(navel_h),
                hip_cm: above(hip_h),
                thigh_cm: above(thigh_h),
                calf_cm: above(calf_h),
                neck_base_cm: above(neck_base.y),
                acromion_left_cm: above(acr_l.y),
                acromion_right_cm: above(acr_r.y),
                elbow_cm: above(elbow_l.y),
                wrist_cm: above(wrist_l.y),
            },
        };
        Ok((measurements, probe))
    }
}

/// One horizontal girth of a [`MeasureProbe`].
#[derive(Clone, Debug)]
struct GirthProbe {
    /// The plane's height is this vertex's height plus `dy`.
    vertex: u32,
    dy: f32,
    /// The triangles within 3 cm of the landmark (the plane stays among them).
    tris: Vec<u32>,
    /// The left leg's loop (thigh, calf) rather than the trunk's.
    leg: bool,
}

/// A fast re-measurement of bodies near the one [`BodyModel::measure_with_probe`] measured,
/// for shape fitting: the landmarks are not searched again but carried along by the mesh (each
/// girth plane at a fixed offset from its nearest vertex, the acromion points as their
/// vertices, the crotch in the same sagittal plane), and only the triangles near each landmark
/// are cut. At the measured body it gives exactly [`BodyModel::measure`]'s values; nearby, the
/// values of the same anatomical landmarks (which the full measure could place a few
/// millimetres elsewhere as the shape changes, e.g. the narrowest waist moving up).
#[derive(Clone, Debug)]
pub struct MeasureProbe {
    top: Vec<u32>,
    sole: Vec<u32>,
    crotch_x: f32,
    crotch_tris: Vec<u32>,
    /// Bust, under-bust, waist, navel waist, hip, thigh, calf.
    girths: [GirthProbe; 7],
    neck_tris: Vec<u32>,
    neck: crate::model::JointPlacement,
    head: crate::model::JointPlacement,
    acromion: [u32; 2],
    elbow: crate::model::JointPlacement,
    wrist: crate::model::JointPlacement,
    part: Vec<Part>,
    mid_x: f32,
    vertices: Vec<u32>,
}

fn placement_vertices(p: &crate::model::JointPlacement, out: &mut Vec<u32>) {
    use crate::model::JointPlacement;
    match p {
        JointPlacement::Mean(v) => out.extend_from_slice(v),
        JointPlacement::Vertex(v) => out.push(*v),
        JointPlacement::Lerp { from, to, .. } => {
            placement_vertices(from, out);
            placement_vertices(to, out);
        }
    }
}

impl MeasureProbe {
    /// Every vertex the probe reads, sorted: only these need to be up to date in the
    /// positions given to [`MeasureProbe::measure`].
    pub fn vertices(&self) -> &[u32] {
        &self.vertices
    }

    fn collect_vertices(&self, triangles: &[[u32; 3]]) -> Vec<u32> {
        let mut v: Vec<u32> = Vec::new();
        v.extend_from_slice(&self.top);
        v.extend_from_slice(&self.sole);
        let tris = self
            .girths
            .iter()
            .flat_map(|g| g.tris.iter())
            .chain(&self.crotch_tris)
            .chain(&self.neck_tris);
        for &t in tris {
            v.extend_from_slice(&triangles[t as usize]);
        }
        v.extend(self.girths.iter().map(|g| g.vertex));
        v.extend_from_slice(&self.acromion);
        for p in [&self.neck, &self.head, &self.elbow, &self.wrist] {
            placement_vertices(p, &mut v);
        }
        v.sort_unstable();
        v.dedup();
        v
    }

    /// The measurements (cm, in [`Measure::ALL`] order) of the body with these positions
    /// (the whole mesh's index space; only [`MeasureProbe::vertices`] are read).
    pub fn measure(&self, positions: &[Vec3], triangles: &[[u32; 3]]) -> [f32; 12] {
        let y = |v: u32| positions[v as usize].y;
        let top = self
            .top
            .iter()
            .map(|&v| y(v))
            .fold(f32::NEG_INFINITY, f32::max);
        let floor = self
            .sole
            .iter()
            .map(|&v| y(v))
            .fold(f32::INFINITY, f32::min);
        let tris = |list: &'_ [u32]| -> Vec<[u32; 3]> {
            list.iter().map(|&t| triangles[t as usize]).collect()
        };
        let crotch = cross_section_of(
            positions,
            self.crotch_tris.iter().map(|&t| &triangles[t as usize]),
            &Plane::new(Vec3::new(self.crotch_x, 0.0, 0.0), Vec3::X),
        )
        .iter()
        .flat_map(|l| l.points_3d.iter())
        .map(|p| p.y)
        .fold(f32::INFINITY, f32::min);
        let is_arm = |l: &SectionLoop| {
            let arm = l
                .edges
                .iter()
                .flat_map(|&(a, b)| [a, b])
                .filter(|&v| self.part.get(v as usize) == Some(&Part::Arm))
                .count();
            arm > l.edges.len()
        };
        let girth = |g: &GirthProbe| -> f32 {
            let h = y(g.vertex) + g.dy;
            let loops = cross_section_of(
                positions,
                g.tris.iter().map(|&t| &triangles[t as usize]),
                &Plane::horizontal(h),
            );
            let points: Vec<Vec2> = loops
                .iter()
                .filter(|l| !is_arm(l) && (!g.leg || l.centroid().x > self.mid_x))
                .flat_map(|l| l.points.iter().copied())
                .collect();
            hull_perimeter(&points)
        };
        let neck = self.neck.resolve(positions);
        let head = self.head.resolve(positions);
        let neck_tris = tris(&self.neck_tris);
        let neck_g = cross_section(
            positions,
            &neck_tris,
            &Plane::new(neck, (head - neck).normalize_or_zero()),
        )
        .iter()
        .find(|l| l.contains(Vec2::ZERO))
        .map_or(f32::NAN, |l| hull_perimeter(&l.points));
        let [al, ar] = self.acromion.map(|v| positions[v as usize]);
        let (elbow, wrist) = (self.elbow.resolve(positions), self.wrist.resolve(positions));
        let g = self.girths.each_ref().map(girth);
        [
            (top - floor) * CM,
            (crotch - floor) * CM,
            (al.distance(elbow) + elbow.distance(wrist)) * CM,
            al.distance(ar) * CM,
            neck_g * CM,
            g[0] * CM,
            g[1] * CM,
            g[2] * CM,
            g[3] * CM,
            g[4] * CM,
            g[5] * CM,
            g[6] * CM,
        ]
    }
}
