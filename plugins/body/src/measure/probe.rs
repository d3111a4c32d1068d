//! The measure probe: a fast re-measurement of bodies near one that was fully measured, at the same
//! anatomical landmarks (seed 002, Uğur 2008, Table 4.1 / EN 13402, as the full measurement),
//! cutting only the triangles near each landmark; shape fitting (`crate::fit`) measures its trial
//! bodies with it.

use glam::{Vec2, Vec3};

use super::{CM, Part, Plane, SectionLoop, cross_section, cross_section_of, hull_perimeter};

/// One horizontal girth of a [`MeasureProbe`].
#[derive(Clone, Debug)]
pub(super) struct GirthProbe {
    /// The plane's height is this vertex's height plus `dy`.
    pub(super) vertex: u32,
    pub(super) dy: f32,
    /// The triangles within 3 cm of the landmark (the plane stays among them).
    pub(super) tris: Vec<u32>,
    /// The left leg's loop (thigh, calf) rather than the trunk's.
    pub(super) leg: bool,
}

/// A fast re-measurement of bodies near the one [`BodyModel::measure_with_probe`] measured,
/// for shape fitting: the landmarks are not searched again but carried along by the mesh (each
/// girth plane at a fixed offset from its nearest vertex, the acromion points as their
/// vertices, the crotch in the same sagittal plane), and only the triangles near each landmark
/// are cut. At the measured body it gives exactly [`BodyModel::measure`]'s values; nearby, the
/// values of the same anatomical landmarks (which the full measure could place a few
/// millimetres elsewhere as the shape changes, e.g. the narrowest waist moving up).
///
/// [`BodyModel::measure`]: crate::BodyModel::measure
/// [`BodyModel::measure_with_probe`]: crate::BodyModel::measure_with_probe
#[derive(Clone, Debug)]
pub struct MeasureProbe {
    pub(super) top: Vec<u32>,
    pub(super) sole: Vec<u32>,
    pub(super) crotch_x: f32,
    pub(super) crotch_tris: Vec<u32>,
    /// Bust, under-bust, waist, navel waist, hip, thigh, calf.
    pub(super) girths: [GirthProbe; 7],
    pub(super) neck_tris: Vec<u32>,
    pub(super) neck: crate::model::JointPlacement,
    pub(super) head: crate::model::JointPlacement,
    pub(super) acromion: [u32; 2],
    pub(super) elbow: crate::model::JointPlacement,
    pub(super) wrist: crate::model::JointPlacement,
    pub(super) part: Vec<Part>,
    pub(super) mid_x: f32,
    pub(super) vertices: Vec<u32>,
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

    pub(super) fn collect_vertices(&self, triangles: &[[u32; 3]]) -> Vec<u32> {
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
    ///
    /// [`Measure::ALL`]: super::Measure::ALL
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
