//! The landmark search and the full measurement of a body (after seed 002, Uğur 2008, Table 4.1,
//! EN 13402 and ISO 8559-1; the definitions are the table in the [module docs](super)): heights
//! found by scanning horizontal cross-sections of the mesh (crotch, axilla, bust, under-bust,
//! waist, navel, hip, thigh, calf), the neck base section and the acromion points, with the rig's
//! rest pose only bounding the search regions.

use glam::{Vec2, Vec3};

use super::probe::{GirthProbe, MeasureProbe};
use super::{
    CM, HeightIndex, Landmarks, MeasureError, Measurements, Part, Plane, SectionLoop,
    cross_section, hull_perimeter,
};
use crate::model::BodyModel;

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
            // The corner: the top farthest above the chord from the slope's highest point
            // to the arm's end (signed: the neck's slope can sag below the chord, and a
            // point there, taken by its distance alone, halved the shoulder width of some
            // bodies).
            let slope = (end.y - start.y) / (end.x - start.x);
            let above = |p: &Vec3| p.y - (start.y + (p.x - start.x) * slope);
            if !slope.is_finite() {
                return Err(MeasureError::LandmarkNotFound("acromion"));
            }
            tops.iter()
                .copied()
                .filter(|(_, p)| (p.x - start.x) * sign > 0.0)
                .max_by(|(_, a), (_, b)| above(a).total_cmp(&above(b)))
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
