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
//! | bust / chest | trunk girth at the bust point: the highest peak (going down from the armpits) of the front profile |
//! | under-bust | torso girth at the fold below the breast: the deepest point of the front profile under the chord from the bust point to the waist |
//! | waist | smallest torso girth between the hips and the under-bust |
//! | hip | girth of the trunk (arms and hands excluded) at the buttocks' greatest posterior prominence above the crotch |
//! | thigh | largest girth of the left thigh below the crotch (just below the gluteal fold) |
//! | calf | largest girth of the left lower leg between ankle and knee |
//!
//! The convex hull is a hand-written Andrew monotone chain (O(n log n)).

use std::collections::HashMap;

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

fn loops_from_segments(
    positions: &[Vec3],
    plane: &Plane,
    segments: &[[(u32, u32); 2]],
) -> Vec<SectionLoop> {
    // Each edge is shared by at most two segments (manifold mesh).
    let mut by_edge: HashMap<(u32, u32), [usize; 2]> = HashMap::with_capacity(segments.len() * 2);
    for (i, s) in segments.iter().enumerate() {
        for e in s {
            by_edge
                .entry(*e)
                .and_modify(|v| v[1] = i)
                .or_insert([i, usize::MAX]);
        }
    }
    let point = |e: (u32, u32)| {
        let (pa, pb) = (positions[e.0 as usize], positions[e.1 as usize]);
        let (da, db) = (plane.distance(pa), plane.distance(pb));
        let t = if da == db { 0.5 } else { da / (da - db) };
        pa.lerp(pb, t)
    };
    let other = |seg: usize, e: (u32, u32)| -> Option<usize> {
        let v = by_edge[&e];
        let o = if v[0] == seg { v[1] } else { v[0] };
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
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Measurements {
    pub stature_cm: f32,
    pub crotch_height_cm: f32,
    pub arm_length_cm: f32,
    pub shoulder_width_cm: f32,
    pub neck_cm: f32,
    pub bust_cm: f32,
    pub underbust_cm: f32,
    pub waist_cm: f32,
    pub hip_cm: f32,
    pub thigh_cm: f32,
    pub calf_cm: f32,
    pub landmarks: Landmarks,
}

/// Where the measurements were taken: heights above the sole (the lowest body vertex), cm.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Landmarks {
    pub crotch_cm: f32,
    pub axilla_cm: f32,
    pub bust_cm: f32,
    pub underbust_cm: f32,
    pub waist_cm: f32,
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

struct Measurer<'a> {
    positions: &'a [Vec3],
    triangles: &'a [[u32; 3]],
    part: Vec<Part>,
    mid_x: f32,
}

impl Measurer<'_> {
    fn slice(&self, h: f32) -> Vec<SectionLoop> {
        cross_section(self.positions, self.triangles, &Plane::horizontal(h))
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
            part,
            mid_x: pelvis.x,
        };

        // Crotch: lowest point of the mid-sagittal section above the knees.
        let sagittal = cross_section(
            body_pos,
            &self.triangles,
            &Plane::new(Vec3::new(pelvis.x, 0.0, 0.0), Vec3::X),
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

        // Bust: the most anterior point of the chest.
        let bust_scan = scan(axilla - 0.4 * trunk, axilla - 0.005, |h| m.front(h));
        let bust_h = topmost_peak(&bust_scan, 0.003);
        let bust = m.trunk_girth(bust_h);

        // Hip: at the buttocks' greatest (posterior) prominence above the crotch.
        let hip_scan = scan(crotch + 0.005, crotch + 0.45 * trunk, |h| m.back(h));
        let hip_h = arg_best(&hip_scan, |a, b| a < b).0;
        let hip = m.trunk_girth(hip_h);

        // Waist: the smallest trunk girth between the hips and the chest.
        let waist_scan = scan(hip_h, bust_h - 0.05, |h| m.trunk_girth(h));
        let (waist_h, waist) = arg_best(&waist_scan, |a, b| a < b);

        // Under-bust: the front profile's deepest point behind the chord from the bust point to
        // the waist front (the fold under the breast).
        let (b0, w0) = (
            Vec2::new(bust_h, m.front(bust_h)),
            Vec2::new(waist_h, m.front(waist_h)),
        );
        let chord = (w0 - b0).normalize_or_zero();
        let under_scan = scan(waist_h, bust_h, |h| {
            let p = Vec2::new(h, m.front(h)) - b0;
            // Distance behind the chord (towards -z).
            -chord.perp_dot(p) * chord.x.signum()
        });
        let underbust_h = arg_best(&under_scan, |a, b| a > b).0;
        let underbust = m.trunk_girth(underbust_h);

        // Thigh: the largest girth of the left upper leg, below the crotch.
        let thigh_scan = scan(0.5 * (knee_l.y + crotch), crotch - 0.005, |h| {
            m.left_leg_girth(h)
        });
        let (thigh_h, thigh) = arg_best(&thigh_scan, |a, b| a > b);

        // Calf: the largest girth of the left lower leg.
        let calf_scan = scan(ankle_l.y, knee_l.y, |h| m.left_leg_girth(h));
        let (calf_h, calf) = arg_best(&calf_scan, |a, b| a > b);

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
        let acromion = |sign: f32, elbow: Vec3| -> Result<Vec3, MeasureError> {
            let bins = 60;
            let x0 = neck.x;
            let x1 = elbow.x;
            let mut tops: Vec<Option<Vec3>> = vec![None; bins];
            for (v, p) in body_pos.iter().enumerate() {
                if m.part[v] == Part::Head || (p.x - x0) * sign < 0.0 || p.y < elbow.y {
                    continue;
                }
                let f = (p.x - x0) / (x1 - x0);
                if !(0.0..1.0).contains(&f) {
                    continue;
                }
                let b = (f * bins as f32) as usize;
                if tops[b].is_none_or(|t| p.y > t.y) {
                    tops[b] = Some(*p);
                }
            }
            let tops: Vec<Vec3> = tops.into_iter().flatten().collect();
            let start = tops
                .iter()
                .copied()
                .max_by(|a, b| a.y.total_cmp(&b.y))
                .ok_or(MeasureError::LandmarkNotFound("shoulder"))?;
            let end = *tops
                .last()
                .ok_or(MeasureError::LandmarkNotFound("shoulder"))?;
            let (s, e) = (Vec2::new(start.x, start.y), Vec2::new(end.x, end.y));
            let d = (e - s).normalize_or_zero();
            tops.iter()
                .copied()
                .filter(|p| (p.x - start.x) * sign > 0.0)
                .max_by(|a, b| {
                    let da = d.perp_dot(Vec2::new(a.x, a.y) - s).abs();
                    let db = d.perp_dot(Vec2::new(b.x, b.y) - s).abs();
                    da.total_cmp(&db)
                })
                .ok_or(MeasureError::LandmarkNotFound("acromion"))
        };
        let acr_l = acromion(1.0, elbow_l)?;
        let acr_r = acromion(-1.0, elbow_r)?;
        let arm_length = acr_l.distance(elbow_l) + elbow_l.distance(wrist_l);
        let above = |y: f32| (y - floor) * CM;
        Ok(Measurements {
            stature_cm: (top - floor) * CM,
            crotch_height_cm: above(crotch),
            arm_length_cm: arm_length * CM,
            shoulder_width_cm: acr_l.distance(acr_r) * CM,
            neck_cm: neck_g * CM,
            bust_cm: bust * CM,
            underbust_cm: underbust * CM,
            waist_cm: waist * CM,
            hip_cm: hip * CM,
            thigh_cm: thigh * CM,
            calf_cm: calf * CM,
            landmarks: Landmarks {
                crotch_cm: above(crotch),
                axilla_cm: above(axilla),
                bust_cm: above(bust_h),
                underbust_cm: above(underbust_h),
                waist_cm: above(waist_h),
                hip_cm: above(hip_h),
                thigh_cm: above(thigh_h),
                calf_cm: above(calf_h),
                neck_base_cm: above(neck_base.y),
                acromion_left_cm: above(acr_l.y),
                acromion_right_cm: above(acr_r.y),
                elbow_cm: above(elbow_l.y),
                wrist_cm: above(wrist_l.y),
            },
        })
    }
}
