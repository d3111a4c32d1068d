//! The forearm-twist measurement of the split forearm (seed 000 §4.4.3 "Bone Splitting",
//! Figure 4.3: a -90° yaw of the forearm with single- and double-boned skinning).
//!
//! Linear blend skinning averages bone matrices: a vertex weighted half to two bones whose
//! frames differ by a rotation of φ about the forearm axis is moved by `(I + R(φ)) / 2`, which
//! shrinks its distance to the axis by `cos(φ/2)`. A cross-section made of such vertices keeps
//! its shape but its area is scaled by `cos²(φ/2)` (the "candy-wrapper" collapse). In general,
//! weights `w0 + w1 = 1` scale the area by `det(w0 I + w1 R(φ)) = w0² + w1² + 2 w0 w1 cos φ`.
//!
//! This module measures it on a mesh: a plane perpendicular to the arm cuts the body triangles;
//! the closed loop around the arm (the arm's own, chosen as the smallest closed loop that
//! encloses the axis point) is kept as points on mesh edges, so the same material points can be
//! followed after skinning (skin the edge ends, re-interpolate), and its area is measured in the
//! plane before and after (after: projected on the plane perpendicular to the posed axis).
//!
//! [`forearm_twist_study`] compares three ways of applying one twist angle to the left forearm:
//! (a) a single forearm bone with the original weights, (b) the split forearm with the whole
//! twist on the distal bone (the literal reading of §4.4.3), (c) the split forearm with half the
//! twist on each half.

use glam::{Quat, Vec2, Vec3};
use serde::{Deserialize, Serialize};

use crate::model::BodyModel;
use crate::skinning::{RigidTransform, forward_kinematics, skin_positions};

/// A plane through `point` with unit `normal`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SectionPlane {
    pub point: Vec3,
    pub normal: Vec3,
}

/// A point on the mesh edge `a`-`b`: `p = p_a + s (p_b - p_a)`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct EdgePoint {
    pub a: u32,
    pub b: u32,
    pub s: f32,
}

impl EdgePoint {
    pub fn position(&self, positions: &[Vec3]) -> Vec3 {
        let pa = positions[self.a as usize];
        pa + (positions[self.b as usize] - pa) * self.s
    }
}

/// A closed cross-section loop of a mesh, as points on its edges (in order around the loop).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SectionLoop {
    pub points: Vec<EdgePoint>,
}

impl SectionLoop {
    /// The loop's points for the given (rest or deformed) vertex positions.
    pub fn positions(&self, positions: &[Vec3]) -> Vec<Vec3> {
        self.points.iter().map(|p| p.position(positions)).collect()
    }

    /// Area enclosed by the loop projected on the plane with unit normal `normal`, m².
    pub fn area(&self, positions: &[Vec3], normal: Vec3) -> f32 {
        polygon_area(&self.positions(positions), normal).abs()
    }
}

/// Signed area of a closed 3D polygon projected on the plane with unit normal `normal`
/// (positive when counter-clockwise seen from the normal's tip).
pub fn polygon_area(points: &[Vec3], normal: Vec3) -> f32 {
    let Some(&origin) = points.first() else {
        return 0.0;
    };
    let mut sum = Vec3::ZERO;
    for (i, &p) in points.iter().enumerate() {
        let q = points[(i + 1) % points.len()];
        sum += (p - origin).cross(q - origin);
    }
    0.5 * sum.dot(normal)
}

fn plane_basis(normal: Vec3) -> (Vec3, Vec3) {
    let u = normal.any_orthonormal_vector();
    (u, normal.cross(u))
}

/// Winding number of the 2D polygon around `p` (non-zero: inside).
fn winding_number(polygon: &[Vec2], p: Vec2) -> i32 {
    let mut w = 0;
    for (i, &a) in polygon.iter().enumerate() {
        let b = polygon[(i + 1) % polygon.len()];
        let cross = (b - a).perp_dot(p - a);
        if a.y <= p.y {
            if b.y > p.y && cross > 0.0 {
                w += 1;
            }
        } else if b.y <= p.y && cross < 0.0 {
            w -= 1;
        }
    }
    w
}

/// Every closed loop where `plane` cuts the triangles (open chains, at mesh borders, are
/// dropped). A vertex exactly on the plane counts as on its positive side, so every triangle
/// is cut by 0 or 2 of its edges and loops never pass through vertices.
pub fn section_loops(
    positions: &[Vec3],
    triangles: &[[u32; 3]],
    plane: SectionPlane,
) -> Vec<SectionLoop> {
    use std::collections::HashMap;
    let distance = |v: u32| (positions[v as usize] - plane.point).dot(plane.normal);
    // Segments between two cut edges; each edge keyed by its sorted vertex pair.
    let mut segments: Vec<[(u32, u32); 2]> = Vec::new();
    let mut edge_segments: HashMap<(u32, u32), Vec<usize>> = HashMap::new();
    for t in triangles {
        if t.iter().any(|&v| v as usize >= positions.len()) {
            continue;
        }
        let d = t.map(distance);
        let mut cut = [(0u32, 0u32); 2];
        let mut k = 0;
        for e in 0..3 {
            let (i, j) = (e, (e + 1) % 3);
            if (d[i] >= 0.0) != (d[j] >= 0.0) {
                if k < 2 {
                    cut[k] = (t[i].min(t[j]), t[i].max(t[j]));
                }
                k += 1;
            }
        }
        if k == 2 {
            let id = segments.len();
            segments.push(cut);
            for e in cut {
                edge_segments.entry(e).or_default().push(id);
            }
        }
    }
    let edge_point = |(a, b): (u32, u32)| {
        let (da, db) = (distance(a), distance(b));
        EdgePoint {
            a,
            b,
            s: (da / (da - db)).clamp(0.0, 1.0),
        }
    };
    let mut used = vec![false; segments.len()];
    let mut loops = Vec::new();
    for start in 0..segments.len() {
        if used[start] {
            continue;
        }
        used[start] = true;
        let first_edge = segments[start][0];
        let mut edges = vec![first_edge];
        let mut at = segments[start][1];
        let closed = loop {
            if at == first_edge {
                break true;
            }
            edges.push(at);
            let next = edge_segments
                .get(&at)
                .and_then(|s| s.iter().copied().find(|&s| !used[s]));
            // No way on: the chain ends at a mesh border (or a non-manifold edge).
            let Some(next) = next else {
                break false;
            };
            used[next] = true;
            at = if segments[next][0] == at {
                segments[next][1]
            } else {
                segments[next][0]
            };
        };
        if closed && edges.len() >= 3 {
            loops.push(SectionLoop {
                points: edges.into_iter().map(edge_point).collect(),
            });
        }
    }
    loops
}

/// The cross-section loop of a limb: among the closed loops where `plane` cuts the mesh, the
/// smallest one enclosing `plane.point` (the point on the limb's axis). `None` if no loop
/// encloses it.
pub fn limb_section(
    positions: &[Vec3],
    triangles: &[[u32; 3]],
    plane: SectionPlane,
) -> Option<SectionLoop> {
    let (u, v) = plane_basis(plane.normal);
    let to_2d = |p: Vec3| Vec2::new((p - plane.point).dot(u), (p - plane.point).dot(v));
    section_loops(positions, triangles, plane)
        .into_iter()
        .filter(|l| {
            let poly: Vec<Vec2> = l.positions(positions).into_iter().map(to_2d).collect();
            winding_number(&poly, Vec2::ZERO) != 0
        })
        .map(|l| (l.area(positions, plane.normal), l))
        .min_by(|a, b| a.0.total_cmp(&b.0))
        .map(|(_, l)| l)
}

/// Area of one cross-section at rest and after skinning.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SectionArea {
    pub rest_m2: f32,
    pub posed_m2: f32,
}

impl SectionArea {
    pub fn ratio(&self) -> f32 {
        self.posed_m2 / self.rest_m2
    }
}

/// Measures one section: the loop found on the rest mesh, followed to the skinned positions,
/// its area projected on the plane perpendicular to `posed_normal`.
pub fn section_area(
    rest_positions: &[Vec3],
    posed_positions: &[Vec3],
    triangles: &[[u32; 3]],
    plane: SectionPlane,
    posed_normal: Vec3,
) -> Option<SectionArea> {
    let section = limb_section(rest_positions, triangles, plane)?;
    Some(SectionArea {
        rest_m2: section.area(rest_positions, plane.normal),
        posed_m2: section.area(posed_positions, posed_normal),
    })
}

/// One value per configuration of the study.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ConfigRatios {
    /// (a) One forearm bone with the original weights; the whole twist on it.
    pub single_bone: f32,
    /// (b) Split forearm, the whole twist on the distal (twist) bone.
    pub split_literal: f32,
    /// (c) Split forearm, half the twist on each half (the whole twist at the wrist).
    pub split_shared: f32,
}

/// The smallest area ratio along the scanned arm, and where.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct WorstSection {
    pub ratio: f32,
    /// Distance from the elbow along the arm, metres (negative: up the upper arm).
    pub offset_m: f32,
}

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ConfigWorst {
    pub single_bone: WorstSection,
    pub split_literal: WorstSection,
    pub split_shared: WorstSection,
}

/// One scanned plane.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ScanSection {
    /// Distance from the elbow along the arm, metres (negative: up the upper arm, where the
    /// plane is perpendicular to the upper arm; otherwise perpendicular to the forearm).
    pub offset_m: f32,
    pub rest_area_cm2: f32,
    pub ratios: ConfigRatios,
}

/// Result of [`forearm_twist_study`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ForearmTwistReport {
    /// The arm measured (`"left"`).
    pub side: String,
    pub twist_deg: f32,
    pub upper_arm_length_m: f32,
    pub forearm_length_m: f32,
    /// Area of the mid-forearm section at rest, cm².
    pub rest_mid_area_cm2: f32,
    /// Posed / rest area of the mid-forearm section.
    pub mid_section: ConfigRatios,
    /// The closed form for a section weighted 50/50 between the two halves (`cos²` of half
    /// the angle between the blended bones): 1, `cos²(twist/2)`, `cos²(twist/4)`.
    pub theory_mid: ConfigRatios,
    /// Smallest ratio along the scan, per configuration.
    pub worst: ConfigWorst,
    /// The scan from 15% of the upper arm above the elbow to the wrist.
    pub scan: Vec<ScanSection>,
}

/// Why the study could not run on a model.
#[derive(Debug, thiserror::Error)]
pub enum ForearmStudyError {
    #[error("the body model has no bone '{0}' (the study needs the split left forearm)")]
    MissingBone(String),
    #[error("no closed loop around the arm at {offset_m:.3} m from the elbow")]
    NoSection { offset_m: f32 },
}

/// Skin weights (joints, weights) and posed bone transforms of one configuration.
type SkinConfig<'a> = (&'a [[u16; 4]], &'a [[f32; 4]], Vec<RigidTransform>);

/// Number of planes scanned from above the elbow to the wrist.
pub const SCAN_PLANES: usize = 20;
/// The scan starts this fraction of the upper-arm length above the elbow.
pub const SCAN_ABOVE_ELBOW: f32 = 0.15;

/// Runs the forearm-twist comparison on the left arm of `model` (rest = the model's own
/// positions) for a twist of `twist_deg` degrees about the forearm axis (seed 000 uses -90).
pub fn forearm_twist_study(
    model: &BodyModel,
    twist_deg: f32,
) -> Result<ForearmTwistReport, ForearmStudyError> {
    let bone = |name: &str| {
        model
            .bone_index(name)
            .ok_or_else(|| ForearmStudyError::MissingBone(name.to_string()))
    };
    let upper = bone("upperarm_l")?;
    let proximal = bone("lowerarm_l")?;
    let twist = bone("lowerarm_twist_l")?;

    let positions = &model.positions;
    let body = (model.body_vertex_count as usize).min(positions.len());
    let rest = model.rest_pose(positions);
    let shoulder = rest.heads[upper];
    let elbow = rest.heads[proximal];
    let wrist = rest.tails[twist];
    let upper_len = shoulder.distance(elbow);
    let fore_len = elbow.distance(wrist);
    let up_dir = (elbow - shoulder).normalize_or_zero();
    let fore_dir = (wrist - elbow).normalize_or_zero();

    // The three configurations: weights and local rotations.
    let angle = twist_deg.to_radians();
    let about_axis = |a: f32| Quat::from_rotation_y(a);
    let n = model.bones.len();
    let pose = |p: f32, t: f32| {
        let mut locals = vec![Quat::IDENTITY; n];
        locals[proximal] = about_axis(p);
        locals[twist] = about_axis(t);
        forward_kinematics(&model.bones, &rest, &locals, Vec3::ZERO)
    };
    let merged = merge_bone_weights(&model.skin_joints, &model.skin_weights, twist, proximal);
    let configs: [SkinConfig; 3] = [
        (&merged.0, &merged.1, pose(angle, 0.0)),
        (&model.skin_joints, &model.skin_weights, pose(0.0, angle)),
        (
            &model.skin_joints,
            &model.skin_weights,
            pose(angle / 2.0, angle / 2.0),
        ),
    ];
    let skinned: Vec<(Vec<Vec3>, Vec<RigidTransform>)> = configs
        .into_iter()
        .map(|(j, w, g)| (skin_positions(&positions[..body], j, w, &rest, &g), g))
        .collect();

    // The posed axis of a plane: the rest axis carried by the bone it follows.
    let posed_normal = |bone: usize, normal: Vec3, globals: &[RigidTransform]| {
        let skin = globals[bone].rotation * rest.rotations[bone].inverse();
        (skin * normal).normalize()
    };
    let measure = |offset: f32| -> Result<(f32, ConfigRatios), ForearmStudyError> {
        let (plane, bone) = if offset < 0.0 {
            (
                SectionPlane {
                    point: elbow + up_dir * offset,
                    normal: up_dir,
                },
                upper,
            )
        } else {
            (
                SectionPlane {
                    point: elbow + fore_dir * offset,
                    normal: fore_dir,
                },
                proximal,
            )
        };
        let section = limb_section(positions, &model.triangles, plane)
            .ok_or(ForearmStudyError::NoSection { offset_m: offset })?;
        let rest_area = section.area(positions, plane.normal);
        let ratio = |k: usize| {
            let (posed, globals) = &skinned[k];
            section.area(posed, posed_normal(bone, plane.normal, globals)) / rest_area
        };
        Ok((
            rest_area,
            ConfigRatios {
                single_bone: ratio(0),
                split_literal: ratio(1),
                split_shared: ratio(2),
            },
        ))
    };

    let (rest_mid, mid_section) = measure(fore_len * 0.5)?;
    let start = -SCAN_ABOVE_ELBOW * upper_len;
    let mut scan = Vec::with_capacity(SCAN_PLANES);
    for k in 0..SCAN_PLANES {
        let offset = start + (fore_len - start) * k as f32 / (SCAN_PLANES - 1) as f32;
        let (rest_area, ratios) = measure(offset)?;
        scan.push(ScanSection {
            offset_m: offset,
            rest_area_cm2: rest_area * 1e4,
            ratios,
        });
    }
    let worst_of = |f: fn(&ConfigRatios) -> f32| {
        scan.iter()
            .map(|s| WorstSection {
                ratio: f(&s.ratios),
                offset_m: s.offset_m,
            })
            .min_by(|a, b| a.ratio.total_cmp(&b.ratio))
            .unwrap_or(WorstSection {
                ratio: f32::NAN,
                offset_m: 0.0,
            })
    };
    let worst = ConfigWorst {
        single_bone: worst_of(|r| r.single_bone),
        split_literal: worst_of(|r| r.split_literal),
        split_shared: worst_of(|r| r.split_shared),
    };
    let half_blend = |phi: f32| (phi / 2.0).cos().powi(2);
    Ok(ForearmTwistReport {
        side: "left".into(),
        twist_deg,
        upper_arm_length_m: upper_len,
        forearm_length_m: fore_len,
        rest_mid_area_cm2: rest_mid * 1e4,
        mid_section,
        theory_mid: ConfigRatios {
            single_bone: 1.0,
            split_literal: half_blend(angle),
            split_shared: half_blend(angle / 2.0),
        },
        worst,
        scan,
    })
}

/// Skin weights with bone `from` folded into bone `into` (e.g. the twist bone back into the
/// forearm, recovering single-bone weights), largest first.
pub fn merge_bone_weights(
    joints: &[[u16; 4]],
    weights: &[[f32; 4]],
    from: usize,
    into: usize,
) -> (Vec<[u16; 4]>, Vec<[f32; 4]>) {
    joints
        .iter()
        .zip(weights)
        .map(|(j, w)| {
            let mut entries: Vec<(u16, f32)> = Vec::with_capacity(4);
            for (&b, &x) in j.iter().zip(w) {
                if x == 0.0 {
                    continue;
                }
                let b = if b as usize == from { into as u16 } else { b };
                match entries.iter_mut().find(|e| e.0 == b) {
                    Some(e) => e.1 += x,
                    None => entries.push((b, x)),
                }
            }
            entries.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
            let mut jo = [0u16; 4];
            let mut wo = [0f32; 4];
            for (k, &(b, x)) in entries.iter().enumerate() {
                jo[k] = b;
                wo[k] = x;
            }
            (jo, wo)
        })
        .unzip()
}

/// The closed-form area ratio of a section weighted `w1` on a bone rotated by `phi` about the
/// section's normal relative to the other bone (weight `1 - w1`) under linear blend skinning.
pub fn lbs_area_ratio(w1: f32, phi: f32) -> f32 {
    let w0 = 1.0 - w1;
    w0 * w0 + w1 * w1 + 2.0 * w0 * w1 * phi.cos()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square_tube() -> (Vec<Vec3>, Vec<[u32; 3]>) {
        // A unit square tube along Z from 0 to 2, rings at z = 0, 1, 2.
        let ring = [
            Vec3::new(-0.5, -0.5, 0.0),
            Vec3::new(0.5, -0.5, 0.0),
            Vec3::new(0.5, 0.5, 0.0),
            Vec3::new(-0.5, 0.5, 0.0),
        ];
        let mut p = Vec::new();
        for z in 0..3 {
            p.extend(ring.iter().map(|r| *r + Vec3::Z * z as f32));
        }
        let mut t = Vec::new();
        for z in 0..2u32 {
            for k in 0..4u32 {
                let a = z * 4 + k;
                let b = z * 4 + (k + 1) % 4;
                t.push([a, b, b + 4]);
                t.push([a, b + 4, a + 4]);
            }
        }
        (p, t)
    }

    #[test]
    fn cutting_a_square_tube_gives_its_square() {
        let (p, t) = square_tube();
        let plane = SectionPlane {
            point: Vec3::new(0.0, 0.0, 0.7),
            normal: Vec3::Z,
        };
        let loops = section_loops(&p, &t, plane);
        assert_eq!(loops.len(), 1);
        assert_eq!(loops[0].points.len(), 8);
        assert!((loops[0].area(&p, Vec3::Z) - 1.0).abs() < 1e-6);
        // Through the ring of vertices at z = 1 (vertices on the plane count as above it).
        let at_ring = SectionPlane {
            point: Vec3::Z,
            normal: Vec3::Z,
        };
        let s = limb_section(&p, &t, at_ring).map(|l| l.area(&p, Vec3::Z));
        assert!(s.is_some_and(|a| (a - 1.0).abs() < 1e-6), "{s:?}");
        // A plane missing the axis point's tube finds nothing.
        let off = SectionPlane {
            point: Vec3::new(5.0, 0.0, 0.7),
            normal: Vec3::Z,
        };
        assert!(limb_section(&p, &t, off).is_none());
    }

    #[test]
    fn closed_form_matches_cos_squared_at_half() {
        let phi = -90f32.to_radians();
        assert!((lbs_area_ratio(0.5, phi) - (phi / 2.0).cos().powi(2)).abs() < 1e-6);
        assert!((lbs_area_ratio(0.0, phi) - 1.0).abs() < 1e-6);
        assert!((lbs_area_ratio(1.0, phi) - 1.0).abs() < 1e-6);
    }
}
