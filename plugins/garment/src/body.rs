//! The body surface a garment is placed on and bound to: the shaped MakeHuman body's vertices,
//! normals and triangles, its measurements and landmarks, the body region of each vertex, and
//! a uniform grid for nearest-triangle queries (closest point on a triangle after Ericson,
//! "Real-Time Collision Detection", 2005, §5.1.5).
//!
//! Inside and outside are decided by the interpolated vertex normal at the closest surface
//! point: a point is outside when `(p - closest) · normal > 0`.

use fitroom_body::{BodyModel, Measurements, RestPose, ShapedBody};
use fitroom_math::CellGrid;
use glam::Vec3;
use serde::Deserialize;

use crate::error::GarmentError;

/// A part of the body, from the dominant skin bone of each vertex (the first of the bone's
/// ancestors, itself included, that names a part).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BodyPart {
    /// Pelvis, spine, clavicles (the trunk without neck, head, arms and legs).
    Torso,
    Neck,
    Head,
    ArmLeft,
    ArmRight,
    LegLeft,
    LegRight,
}

/// A set of body parts that a garment wraps around or follows.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Region {
    /// Torso and neck: bodices, straps, shirt bodies.
    Torso,
    /// Torso and both legs: skirts and the skirt of a dress (a tube around both legs).
    Trunk,
    LegLeft,
    LegRight,
    ArmLeft,
    ArmRight,
    /// Every part except the head.
    Body,
}

impl Region {
    /// Whether this region includes `part`.
    pub fn contains(self, part: BodyPart) -> bool {
        use BodyPart as P;
        match self {
            Region::Torso => matches!(part, P::Torso | P::Neck),
            Region::Trunk => matches!(part, P::Torso | P::Neck | P::LegLeft | P::LegRight),
            Region::LegLeft => part == P::LegLeft,
            Region::LegRight => part == P::LegRight,
            Region::ArmLeft => part == P::ArmLeft,
            Region::ArmRight => part == P::ArmRight,
            Region::Body => part != P::Head,
        }
    }
}

/// A height on the body used to anchor garments (EN 13402 / ISO 8559-1 landmarks as
/// [`fitroom_body::Landmarks`] finds them).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Landmark {
    /// The floor under the feet.
    Sole,
    Crotch,
    Axilla,
    Bust,
    Underbust,
    Waist,
    Navel,
    Hip,
    Thigh,
    Calf,
    NeckBase,
    /// Mean of the left and right acromion heights.
    Acromion,
    Elbow,
    Wrist,
}

/// The closest point of the body surface to a query point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePoint {
    /// Body triangle index.
    pub triangle: u32,
    /// Barycentric coordinates of the closest point in that triangle.
    pub barycentric: [f32; 3],
    /// The closest point.
    pub point: Vec3,
    /// Interpolated unit vertex normal there.
    pub normal: Vec3,
    /// Signed distance: positive outside the body (along the normal), negative inside.
    pub signed_distance: f32,
}

/// The shaped body in its rest pose, ready for garment placement and binding.
#[derive(Clone, Debug)]
pub struct BodySurface {
    /// Body vertex positions (helpers excluded), model space, metres.
    pub positions: Vec<Vec3>,
    /// Unit vertex normals.
    pub normals: Vec<Vec3>,
    /// Body triangles, counter-clockwise from outside.
    pub triangles: Vec<[u32; 3]>,
    /// Body part of each vertex.
    pub part_of_vertex: Vec<BodyPart>,
    /// Skin joints and weights per body vertex (copied from the model).
    pub skin_joints: Vec<[u16; 4]>,
    pub skin_weights: Vec<[f32; 4]>,
    /// Measurements of this body (girths in cm, landmark heights in cm above the sole).
    pub measurements: Measurements,
    /// Model-space height of the sole (lowest body vertex), metres.
    pub sole_y: f32,
    /// The rig's rest pose on this body.
    pub rest_pose: RestPose,
    /// Bone names, index-aligned with the rest pose.
    pub bone_names: Vec<String>,
    grid: CellGrid,
}

impl BodySurface {
    /// The body of `model` morphed to `shaped`, measured.
    pub fn new(model: &BodyModel, shaped: &ShapedBody) -> Result<Self, GarmentError> {
        let measurements = model.measure(&shaped.positions)?;
        let body = model.body_vertex_count as usize;
        let positions = shaped.positions[..body.min(shaped.positions.len())].to_vec();
        let normals = if shaped.normals.len() >= positions.len() {
            shaped.normals[..positions.len()].to_vec()
        } else {
            fitroom_body::compute_normals(&positions, &model.triangles)
        };
        let part_of_bone = bone_parts(model);
        let part_of_vertex = model
            .skin_joints
            .iter()
            .take(positions.len())
            .map(|j| {
                part_of_bone
                    .get(j[0] as usize)
                    .copied()
                    .unwrap_or(BodyPart::Torso)
            })
            .collect();
        let sole_y = positions.iter().map(|p| p.y).fold(f32::INFINITY, f32::min);
        let grid = triangle_grid(&positions, &model.triangles, 0.03);
        Ok(Self {
            positions,
            normals,
            triangles: model.triangles.clone(),
            part_of_vertex,
            skin_joints: model.skin_joints.clone(),
            skin_weights: model.skin_weights.clone(),
            measurements,
            sole_y,
            rest_pose: shaped.rest_pose.clone(),
            bone_names: model.bones.iter().map(|b| b.name.clone()).collect(),
            grid,
        })
    }

    /// Number of body vertices.
    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }

    /// Model-space height (metres) of a landmark.
    pub fn landmark_y(&self, landmark: Landmark) -> f32 {
        let l = &self.measurements.landmarks;
        let cm = match landmark {
            Landmark::Sole => 0.0,
            Landmark::Crotch => l.crotch_cm,
            Landmark::Axilla => l.axilla_cm,
            Landmark::Bust => l.bust_cm,
            Landmark::Underbust => l.underbust_cm,
            Landmark::Waist => l.waist_cm,
            Landmark::Navel => l.navel_cm,
            Landmark::Hip => l.hip_cm,
            Landmark::Thigh => l.thigh_cm,
            Landmark::Calf => l.calf_cm,
            Landmark::NeckBase => l.neck_base_cm,
            Landmark::Acromion => 0.5 * (l.acromion_left_cm + l.acromion_right_cm),
            Landmark::Elbow => l.elbow_cm,
            Landmark::Wrist => l.wrist_cm,
        };
        self.sole_y + cm / 100.0
    }

    /// Index of the bone called `name`.
    pub fn bone_index(&self, name: &str) -> Option<usize> {
        self.bone_names.iter().position(|b| b == name)
    }

    /// Body part of a triangle: that of its first vertex's part that two or three corners share,
    /// else the first corner's.
    pub fn part_of_triangle(&self, t: usize) -> BodyPart {
        let [a, b, c] = self.triangles[t].map(|v| self.part_of_vertex[v as usize]);
        if b == c { b } else { a }
    }

    /// The closest surface point to `p` on the triangles of `region` (all triangles when
    /// `None`). `None` only if no triangle qualifies.
    pub fn nearest(&self, p: Vec3, region: Option<Region>) -> Option<SurfacePoint> {
        let filter = |t: u32| match region {
            None => true,
            Some(r) => r.contains(self.part_of_triangle(t as usize)),
        };
        let (t, bary, q) =
            nearest_triangle(&self.grid, (&self.positions, &self.triangles), p, filter)?;
        let [a, b, c] = self.triangles[t as usize].map(|v| self.normals[v as usize]);
        let n = (a * bary[0] + b * bary[1] + c * bary[2]).normalize_or_zero();
        let n = if n == Vec3::ZERO {
            face_normal(&self.positions, self.triangles[t as usize])
        } else {
            n
        };
        Some(SurfacePoint {
            triangle: t,
            barycentric: bary,
            point: q,
            normal: n,
            signed_distance: (p - q).dot(n).signum() * p.distance(q),
        })
    }

    /// Signed distance from `p` to the body surface (positive outside).
    pub fn signed_distance(&self, p: Vec3) -> f32 {
        self.nearest(p, None)
            .map_or(f32::INFINITY, |s| s.signed_distance)
    }
}

/// Unit normal of a triangle (zero for a degenerate one).
pub(crate) fn face_normal(positions: &[Vec3], t: [u32; 3]) -> Vec3 {
    let [a, b, c] = t.map(|v| positions[v as usize]);
    (b - a).cross(c - a).normalize_or_zero()
}

/// Body part of each bone: the first of its ancestors (itself included) that names one, as
/// `fitroom_body::measure` assigns them.
fn bone_parts(model: &BodyModel) -> Vec<BodyPart> {
    let mut out: Vec<BodyPart> = Vec::with_capacity(model.bones.len());
    for b in &model.bones {
        let n = b.name.as_str();
        let part = if n.starts_with("upperarm_l") {
            BodyPart::ArmLeft
        } else if n.starts_with("upperarm_r") {
            BodyPart::ArmRight
        } else if n.starts_with("thigh_l") {
            BodyPart::LegLeft
        } else if n.starts_with("thigh_r") {
            BodyPart::LegRight
        } else if n.starts_with("neck") {
            BodyPart::Neck
        } else if n == "head" {
            BodyPart::Head
        } else {
            b.parent
                .and_then(|p| out.get(p).copied())
                .unwrap_or(BodyPart::Torso)
        };
        out.push(part);
    }
    out
}

/// Closest point on triangle `abc` to `p` and its barycentric coordinates (Ericson 2005).
pub(crate) fn closest_on_triangle(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> (Vec3, [f32; 3]) {
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    let d1 = ab.dot(ap);
    let d2 = ac.dot(ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return (a, [1.0, 0.0, 0.0]);
    }
    let bp = p - b;
    let d3 = ab.dot(bp);
    let d4 = ac.dot(bp);
    if d3 >= 0.0 && d4 <= d3 {
        return (b, [0.0, 1.0, 0.0]);
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return (a + ab * v, [1.0 - v, v, 0.0]);
    }
    let cp = p - c;
    let d5 = ab.dot(cp);
    let d6 = ac.dot(cp);
    if d6 >= 0.0 && d5 <= d6 {
        return (c, [0.0, 0.0, 1.0]);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return (a + ac * w, [1.0 - w, 0.0, w]);
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (b + (c - b) * w, [0.0, 1.0 - w, w]);
    }
    let denom = va + vb + vc;
    if denom.abs() < f32::MIN_POSITIVE {
        return (a, [1.0, 0.0, 0.0]);
    }
    let v = vb / denom;
    let w = vc / denom;
    (a + ab * v + ac * w, [1.0 - v - w, v, w])
}

/// Triangles binned in a uniform grid of `cell`-metre cells by their bounding boxes.
fn triangle_grid(positions: &[Vec3], triangles: &[[u32; 3]], cell: f32) -> CellGrid {
    let mut grid = CellGrid::new(cell);
    for (t, tri) in triangles.iter().enumerate() {
        let [a, b, c] = tri.map(|v| positions[v as usize]);
        grid.insert_box(t as u32, a.min(b).min(c), a.max(b).max(c));
    }
    grid
}

/// The triangle of `grid` nearest to `p` among those passing `filter`: its index, the
/// closest point's barycentric coordinates, and the point.
fn nearest_triangle(
    grid: &CellGrid,
    (positions, triangles): (&[Vec3], &[[u32; 3]]),
    p: Vec3,
    filter: impl Fn(u32) -> bool,
) -> Option<(u32, [f32; 3], Vec3)> {
    let closest = |t: u32| {
        let [a, b, c] = triangles[t as usize].map(|v| positions[v as usize]);
        closest_on_triangle(p, a, b, c)
    };
    let (t, _) = grid.nearest(p, |t| filter(t).then(|| p.distance_squared(closest(t).0)))?;
    let (q, bary) = closest(t);
    Some((t, bary, q))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn closest_point_regions() {
        let (a, b, c) = (Vec3::ZERO, Vec3::X, Vec3::Y);
        let (q, bary) = closest_on_triangle(Vec3::new(0.2, 0.2, 1.0), a, b, c);
        assert!((q - Vec3::new(0.2, 0.2, 0.0)).length() < 1e-6);
        assert!((bary[0] - 0.6).abs() < 1e-6);
        let (q, _) = closest_on_triangle(Vec3::new(-1.0, -1.0, 0.0), a, b, c);
        assert_eq!(q, a);
        let (q, bary) = closest_on_triangle(Vec3::new(1.0, 1.0, 0.0), a, b, c);
        assert!((q - Vec3::new(0.5, 0.5, 0.0)).length() < 1e-6);
        assert!((bary[1] - 0.5).abs() < 1e-6 && (bary[2] - 0.5).abs() < 1e-6);
    }

    #[test]
    fn grid_finds_the_nearest_triangle() {
        // Two triangles far apart; the grid must find the far one when filtered.
        let positions = vec![
            Vec3::ZERO,
            Vec3::X * 0.1,
            Vec3::Y * 0.1,
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(1.1, 0.0, 0.0),
            Vec3::new(1.0, 0.1, 0.0),
        ];
        let triangles = vec![[0, 1, 2], [3, 4, 5]];
        let grid = triangle_grid(&positions, &triangles, 0.05);
        let p = Vec3::new(0.02, 0.02, 0.01);
        let mesh = (positions.as_slice(), triangles.as_slice());
        let (t, ..) = nearest_triangle(&grid, mesh, p, |_| true).expect("found");
        assert_eq!(t, 0);
        let (t, ..) = nearest_triangle(&grid, mesh, p, |t| t == 1).expect("found");
        assert_eq!(t, 1);
    }
}
