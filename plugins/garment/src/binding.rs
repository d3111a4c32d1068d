//! Binding garment vertices to the body surface, so that attached vertices follow the skinned
//! body in any pose, and skin weights for the static (skinned) part of a garment.
//!
//! A bound vertex stores the nearest body triangle, the barycentric coordinates of the closest
//! point on it, and the vertex's offset from that point in the triangle's local frame: normal
//! `n` (the barycentric blend of the vertex normals), tangent `t` (the first edge made
//! perpendicular to `n`) and `b = n × t`. Given the skinned body, the closest point and the
//! frame are rebuilt from the skinned corners and normals and the offset is applied, so the
//! rest pose is reproduced exactly and a rigidly moved body carries the garment rigidly.

use glam::Vec3;

use crate::body::{BodySurface, Region};
use crate::error::GarmentError;

/// One vertex bound to a body triangle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BoundVertex {
    /// The body triangle's corner vertices.
    pub corners: [u32; 3],
    pub barycentric: [f32; 3],
    /// Offset in the (tangent, bitangent, normal) frame, metres.
    pub offset: Vec3,
}

/// Attached garment vertices bound to the body surface.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Binding {
    /// Garment vertex index of each entry.
    pub vertices: Vec<u32>,
    pub entries: Vec<BoundVertex>,
}

impl Binding {
    /// Binds `points` (garment vertices `vertices`, same order) to the body triangles of
    /// `regions[i]` (any triangle when `None`).
    pub fn bind(
        body: &BodySurface,
        vertices: &[u32],
        points: &[Vec3],
        regions: &[Option<Region>],
    ) -> Result<Binding, GarmentError> {
        if points.len() != vertices.len() || regions.len() != vertices.len() {
            return Err(GarmentError::LengthMismatch {
                what: "points and regions (one per bound vertex)",
                expected: vertices.len(),
                got: points.len().min(regions.len()),
            });
        }
        let mut entries = Vec::with_capacity(points.len());
        for (&p, &region) in points.iter().zip(regions) {
            let s = body
                .nearest(p, region)
                .or_else(|| body.nearest(p, None))
                .ok_or(GarmentError::LengthMismatch {
                    what: "body triangles",
                    expected: 1,
                    got: 0,
                })?;
            let corners = body.triangles[s.triangle as usize];
            let (q, [t, b, n]) = frame(&body.positions, &body.normals, corners, s.barycentric);
            let d = p - q;
            entries.push(BoundVertex {
                corners,
                barycentric: s.barycentric,
                offset: Vec3::new(d.dot(t), d.dot(b), d.dot(n)),
            });
        }
        Ok(Binding {
            vertices: vertices.to_vec(),
            entries,
        })
    }

    /// Number of bound vertices.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// Whether nothing is bound.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// The bound vertices' positions on a body with these (skinned) vertex positions and
    /// normals, in the order of [`Binding::vertices`]. The slices may include helper vertices
    /// after the body's; they must cover every bound triangle's corners.
    pub fn positions(&self, body_positions: &[Vec3], body_normals: &[Vec3]) -> Vec<Vec3> {
        let n = body_positions.len().min(body_normals.len());
        self.entries
            .iter()
            .map(|e| {
                if e.corners.iter().any(|&c| c as usize >= n) {
                    return Vec3::NAN;
                }
                let (q, [t, b, nn]) = frame(body_positions, body_normals, e.corners, e.barycentric);
                q + t * e.offset.x + b * e.offset.y + nn * e.offset.z
            })
            .collect()
    }

    /// [`Binding::positions`], checking that the slices cover the bound triangles.
    pub fn try_positions(
        &self,
        body_positions: &[Vec3],
        body_normals: &[Vec3],
    ) -> Result<Vec<Vec3>, GarmentError> {
        let need = self
            .entries
            .iter()
            .flat_map(|e| e.corners)
            .max()
            .map_or(0, |m| m as usize + 1);
        for (what, len) in [
            ("body positions", body_positions.len()),
            ("body normals", body_normals.len()),
        ] {
            if len < need {
                return Err(GarmentError::LengthMismatch {
                    what,
                    expected: need,
                    got: len,
                });
            }
        }
        Ok(self.positions(body_positions, body_normals))
    }
}

/// The closest point and the (tangent, bitangent, normal) frame of a bound triangle.
fn frame(
    positions: &[Vec3],
    normals: &[Vec3],
    corners: [u32; 3],
    bary: [f32; 3],
) -> (Vec3, [Vec3; 3]) {
    let [a, b, c] = corners.map(|v| positions[v as usize]);
    let [na, nb, nc] = corners.map(|v| normals[v as usize]);
    let q = a * bary[0] + b * bary[1] + c * bary[2];
    let face = (b - a).cross(c - a).normalize_or_zero();
    let mut n = (na * bary[0] + nb * bary[1] + nc * bary[2]).normalize_or_zero();
    if n == Vec3::ZERO {
        n = face;
    }
    let mut t = (b - a) - n * n.dot(b - a);
    if t.length_squared() < 1e-16 {
        t = (c - a) - n * n.dot(c - a);
    }
    let t = t.normalize_or_zero();
    (q, [t, n.cross(t), n])
}

/// Skin joints and weights for garment points: the weights of the nearest body point, i.e.
/// the nearest body triangle's corner weights blended by the barycentric coordinates, then
/// the four largest kept and normalised (the nearest-vertex copy of seed 000 §3.2.1, without
/// its steps between neighbouring vertices).
pub fn skin_weights_for(body: &BodySurface, points: &[Vec3]) -> (Vec<[u16; 4]>, Vec<[f32; 4]>) {
    let mut joints = Vec::with_capacity(points.len());
    let mut weights = Vec::with_capacity(points.len());
    for &p in points {
        let mut acc: Vec<(u16, f32)> = Vec::with_capacity(12);
        if let Some(s) = body.nearest(p, None) {
            let corners = body.triangles[s.triangle as usize];
            for (k, &v) in corners.iter().enumerate() {
                let (Some(j), Some(w)) = (
                    body.skin_joints.get(v as usize),
                    body.skin_weights.get(v as usize),
                ) else {
                    continue;
                };
                for (&bone, &weight) in j.iter().zip(w) {
                    if weight <= 0.0 {
                        continue;
                    }
                    let add = weight * s.barycentric[k];
                    match acc.iter_mut().find(|(b, _)| *b == bone) {
                        Some(e) => e.1 += add,
                        None => acc.push((bone, add)),
                    }
                }
            }
        }
        acc.sort_by(|a, b| b.1.total_cmp(&a.1));
        acc.truncate(4);
        let total: f32 = acc.iter().map(|e| e.1).sum();
        let mut j = [0u16; 4];
        let mut w = [0f32; 4];
        if total > 0.0 {
            for (k, (bone, weight)) in acc.into_iter().enumerate() {
                j[k] = bone;
                w[k] = weight / total;
            }
        }
        joints.push(j);
        weights.push(w);
    }
    (joints, weights)
}
