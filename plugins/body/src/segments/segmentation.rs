//! The body's segmentation (after seed 002 (Uğur 2008, parametric bodies for virtual dressing) §4.3
//! "Segmentation Tool"): each body vertex gets the core segment of its dominant skin bone, the
//! torso is cut into bands at the waist, hip and crotch landmarks, and each segment gets the axis
//! it scales about; and the local morph of the body (§4.4, eq. 4.6 with a target per segment).

use glam::Vec3;
use serde::Serialize;

use super::{AreaBlend, BodySegment, MeshGraph, Propagation, SegmentError, SegmentWeights};
use crate::model::{BodyModel, JointPlacement};

/// The heights (cm above the sole of the base mesh) that cut the torso into bands.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct TorsoCuts {
    /// Chest above, waist below: the waist line plus half its height above the hip line.
    pub chest_waist_cm: f32,
    /// Waist above, hip below: the middle of the waist and hip lines.
    pub waist_hip_cm: f32,
    /// Legs below (thigh vertices above it belong to the hip band).
    pub crotch_cm: f32,
}

/// The axis a segment is scaled about by [`SegmentTarget::RadialScale`].
#[derive(Clone, Debug, PartialEq)]
enum SegmentAxis {
    /// The vertical line through the centroid of the core (torso bands, head and neck).
    Vertical,
    /// The line through the segment's bone chain ends (limbs).
    Bone {
        from: JointPlacement,
        to: JointPlacement,
    },
}

/// Kind of body part a bone drives.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    Torso,
    HeadNeck,
    UpperArm,
    Forearm,
    Hand,
    Thigh,
    Shank,
    Foot,
}

fn kind_of_name(name: &str) -> Option<Kind> {
    let n = name.to_ascii_lowercase();
    if n.starts_with("upperarm") {
        Some(Kind::UpperArm)
    } else if n.starts_with("lowerarm") {
        Some(Kind::Forearm)
    } else if n.starts_with("hand") {
        Some(Kind::Hand)
    } else if n.starts_with("thigh") {
        Some(Kind::Thigh)
    } else if n.starts_with("calf") {
        Some(Kind::Shank)
    } else if n.starts_with("foot") {
        Some(Kind::Foot)
    } else if n.starts_with("neck") || n == "head" {
        Some(Kind::HeadNeck)
    } else {
        None
    }
}

fn limb_segment(kind: Kind, left: bool) -> Option<BodySegment> {
    use BodySegment::*;
    Some(match (kind, left) {
        (Kind::UpperArm, true) => UpperArmLeft,
        (Kind::UpperArm, false) => UpperArmRight,
        (Kind::Forearm, true) => ForearmLeft,
        (Kind::Forearm, false) => ForearmRight,
        (Kind::Hand, true) => HandLeft,
        (Kind::Hand, false) => HandRight,
        (Kind::Thigh, true) => ThighLeft,
        (Kind::Thigh, false) => ThighRight,
        (Kind::Shank, true) => ShankLeft,
        (Kind::Shank, false) => ShankRight,
        (Kind::Foot, true) => FootLeft,
        (Kind::Foot, false) => FootRight,
        _ => return None,
    })
}

/// The body's segments: one core segment per body vertex, the mesh graph, and the axes
/// segments scale about. Topological, so one segmentation of the base mesh serves every
/// morph of it.
#[derive(Clone, Debug, PartialEq)]
pub struct BodySegmentation {
    graph: MeshGraph,
    segment_of: Vec<BodySegment>,
    axes: Vec<SegmentAxis>,
    /// Number of vertices of the whole mesh (helpers included), which morphs take and return.
    mesh_vertex_count: usize,
    /// Where the torso bands were cut.
    pub cuts: TorsoCuts,
}

impl BodySegmentation {
    /// Segments the base mesh of `model` by the rules of the [module docs](super).
    pub fn new(model: &BodyModel) -> Result<Self, SegmentError> {
        model.validate().map_err(SegmentError::InvalidModel)?;
        let body = model.body_vertex_count as usize;
        let graph = MeshGraph::new(body, &model.triangles)?;
        let base = &model.positions;
        let measured = model.measure(base)?;
        let floor = base[..body]
            .iter()
            .map(|p| p.y)
            .fold(f32::INFINITY, f32::min);
        let l = &measured.landmarks;
        let half_band_cm = 0.5 * (l.waist_cm - l.hip_cm);
        let cuts = TorsoCuts {
            chest_waist_cm: l.waist_cm + half_band_cm,
            waist_hip_cm: l.waist_cm - half_band_cm,
            crotch_cm: l.crotch_cm,
        };
        let rest = model.rest_pose(base);

        // Kind of each bone: its own, or its nearest ancestor's (parents come first).
        let mut kind = vec![Kind::Torso; model.bones.len()];
        for (i, b) in model.bones.iter().enumerate() {
            kind[i] =
                kind_of_name(&b.name).unwrap_or_else(|| b.parent.map_or(Kind::Torso, |p| kind[p]));
        }
        // The segment a bone's vertices go to before the torso is banded; `None`: torso.
        let bone_segment: Vec<Option<BodySegment>> = (0..model.bones.len())
            .map(|i| match kind[i] {
                Kind::Torso => None,
                Kind::HeadNeck => Some(BodySegment::HeadNeck),
                k => limb_segment(k, rest.heads[i].x > 0.0),
            })
            .collect();

        let band = |y_cm: f32| {
            if y_cm >= cuts.chest_waist_cm {
                BodySegment::Chest
            } else if y_cm >= cuts.waist_hip_cm {
                BodySegment::Waist
            } else {
                BodySegment::Hip
            }
        };
        let segment_of: Vec<BodySegment> = (0..body)
            .map(|v| {
                let bone = model.skin_joints[v][0] as usize;
                let y_cm = (base[v].y - floor) * 100.0;
                match bone_segment[bone] {
                    None => band(y_cm),
                    Some(_) if kind[bone] == Kind::Thigh && y_cm >= cuts.crotch_cm => band(y_cm),
                    Some(s) => s,
                }
            })
            .collect();
        let mut counts = [0usize; 16];
        for s in &segment_of {
            counts[s.index()] += 1;
        }
        if let Some(s) = BodySegment::ALL
            .into_iter()
            .find(|s| counts[s.index()] == 0)
        {
            return Err(SegmentError::EmptySegment(s));
        }

        // Axes: a limb's bone chain from the head of its first bone to the tail of the last
        // bone reached by first children of the same segment.
        let mut children: Vec<Vec<usize>> = vec![Vec::new(); model.bones.len()];
        for (i, b) in model.bones.iter().enumerate() {
            if let Some(p) = b.parent {
                children[p].push(i);
            }
        }
        let mut axes = vec![SegmentAxis::Vertical; 16];
        for s in BodySegment::ALL.into_iter().filter(|s| !s.is_torso_band()) {
            let Some(root) = (0..model.bones.len()).find(|&i| {
                bone_segment[i] == Some(s)
                    && model.bones[i]
                        .parent
                        .is_none_or(|p| bone_segment[p] != Some(s))
            }) else {
                return Err(SegmentError::EmptySegment(s));
            };
            let mut last = root;
            while let Some(&c) = children[last].iter().find(|&&c| bone_segment[c] == Some(s)) {
                last = c;
            }
            axes[s.index()] = SegmentAxis::Bone {
                from: model.bones[root].head_placement.clone(),
                to: model.bones[last].tail_placement.clone(),
            };
        }
        Ok(Self {
            graph,
            segment_of,
            axes,
            mesh_vertex_count: model.positions.len(),
            cuts,
        })
    }

    /// The body's edge graph.
    pub fn graph(&self) -> &MeshGraph {
        &self.graph
    }

    /// The core segment of every body vertex.
    pub fn labels(&self) -> &[BodySegment] {
        &self.segment_of
    }

    /// The core vertex set of `segment`, sorted.
    pub fn core(&self, segment: BodySegment) -> Vec<u32> {
        self.segment_of
            .iter()
            .enumerate()
            .filter(|(_, s)| **s == segment)
            .map(|(v, _)| v as u32)
            .collect()
    }

    /// The propagated weights of `segment`.
    pub fn weights(
        &self,
        segment: BodySegment,
        propagation: Propagation,
    ) -> Result<SegmentWeights, SegmentError> {
        self.graph.propagate(&self.core(segment), propagation)
    }

    /// All sixteen segments propagated alike, area `j` being `BodySegment::ALL[j]`, for
    /// [`BodySegmentation::morph`].
    pub fn blend(&self, propagation: Propagation) -> Result<AreaBlend, SegmentError> {
        self.blend_each(|_| propagation)
    }

    /// All sixteen segments, each with its own propagation.
    pub fn blend_each(
        &self,
        propagation: impl Fn(BodySegment) -> Propagation,
    ) -> Result<AreaBlend, SegmentError> {
        let areas = BodySegment::ALL
            .into_iter()
            .map(|s| self.weights(s, propagation(s)))
            .collect::<Result<Vec<_>, _>>()?;
        AreaBlend::new(self.graph.vertex_count(), &areas)
    }

    /// Local morph of the body (eq. 4.6, generalised to per-segment targets): each edit moves
    /// its segment by its amount; every other segment takes part with amount 0. `positions`
    /// are the whole mesh's (helpers copied unchanged); `blend` comes from
    /// [`BodySegmentation::blend`].
    pub fn morph(
        &self,
        blend: &AreaBlend,
        positions: &[Vec3],
        edits: &[SegmentEdit],
    ) -> Result<Vec<Vec3>, SegmentError> {
        if positions.len() != self.mesh_vertex_count {
            return Err(SegmentError::Length {
                field: "positions",
                got: positions.len(),
                expected: self.mesh_vertex_count,
                fix: "pass the whole mesh (body and helper vertices), as BodyModel::positions \
                      or BodyModel::shaped give it",
            });
        }
        for (field, got, expected) in [
            (
                "blend vertices",
                blend.vertex_count(),
                self.graph.vertex_count(),
            ),
            ("blend areas", blend.area_count(), BodySegment::ALL.len()),
        ] {
            if got != expected {
                return Err(SegmentError::Length {
                    field,
                    got,
                    expected,
                    fix: "build the blend with BodySegmentation::blend of this segmentation",
                });
            }
        }
        let mut amounts = [0.0f32; 16];
        let mut seen = [false; 16];
        // Per edited segment: its displacement rule.
        let mut rules: Vec<Option<Displacement>> = vec![None; 16];
        for e in edits {
            let j = e.segment.index();
            if seen[j] {
                return Err(SegmentError::DuplicateEdit(e.segment));
            }
            seen[j] = true;
            if !e.amount.is_finite() {
                return Err(SegmentError::BadValue {
                    field: "SegmentEdit::amount",
                    value: e.amount,
                    expected: "a finite morph amount (0 to 1 interpolates)",
                });
            }
            amounts[j] = e.amount;
            rules[j] = Some(self.displacement_rule(e.segment, &e.target, positions)?);
        }
        blend.morph_with(positions, &amounts, |j, k| match &rules[j] {
            Some(rule) => rule.at(k, positions),
            None => Vec3::ZERO,
        })
    }

    fn displacement_rule<'t>(
        &self,
        segment: BodySegment,
        target: &'t SegmentTarget,
        positions: &[Vec3],
    ) -> Result<Displacement<'t>, SegmentError> {
        match target {
            SegmentTarget::Positions(t) => {
                if t.len() != positions.len() {
                    return Err(SegmentError::Length {
                        field: "SegmentTarget::Positions",
                        got: t.len(),
                        expected: positions.len(),
                        fix: "give the target model's positions for the whole mesh",
                    });
                }
                if let Some(p) = t.iter().find(|p| !p.is_finite()) {
                    return Err(SegmentError::BadValue {
                        field: "SegmentTarget::Positions",
                        value: if p.x.is_finite() { p.y } else { p.x },
                        expected: "finite coordinates",
                    });
                }
                Ok(Displacement::Towards(t))
            }
            &SegmentTarget::RadialScale { factor } => {
                if !(factor.is_finite() && factor > 0.0) {
                    return Err(SegmentError::BadValue {
                        field: "SegmentTarget::RadialScale::factor",
                        value: factor,
                        expected: "a finite scale factor > 0 (1 leaves the girth unchanged)",
                    });
                }
                let (origin, direction) = match &self.axes[segment.index()] {
                    SegmentAxis::Vertical => {
                        let core = self.core(segment);
                        let c = core.iter().map(|&v| positions[v as usize]).sum::<Vec3>()
                            / core.len().max(1) as f32;
                        (c, Vec3::Y)
                    }
                    SegmentAxis::Bone { from, to } => {
                        let (a, b) = (from.resolve(positions), to.resolve(positions));
                        (a, (b - a).normalize_or(Vec3::Y))
                    }
                };
                Ok(Displacement::Radial {
                    origin,
                    direction,
                    factor,
                })
            }
        }
    }
}

/// What a segment morphs towards.
#[derive(Clone, Debug, PartialEq)]
pub enum SegmentTarget {
    /// Scale the segment's girth by `factor` about its axis (seed §4.1.2 / §4.2: "scaling
    /// horizontally at these positions"): the distance from the axis is multiplied by `factor`,
    /// the position along it is kept. Torso bands and the head and neck scale about the
    /// vertical line through their core's centroid (horizontal scaling); limbs about their bone
    /// chain (elbow to wrist for the forearm...).
    RadialScale { factor: f32 },
    /// A target model with the same mesh (e.g. [`BodyModel::shaped`]'s positions): eq. 4.6's
    /// `T`, whole mesh.
    Positions(Vec<Vec3>),
}

/// One segment's part in a local morph.
#[derive(Clone, Debug, PartialEq)]
pub struct SegmentEdit {
    pub segment: BodySegment,
    pub target: SegmentTarget,
    /// The morph amount `u_j` (0: the source, 1: the target).
    pub amount: f32,
}

/// A segment's displacement field `δ_j(k)` at the source positions.
#[derive(Clone, Copy, Debug)]
enum Displacement<'t> {
    /// `t_k - s_k`.
    Towards(&'t [Vec3]),
    Radial {
        origin: Vec3,
        direction: Vec3,
        factor: f32,
    },
}

impl Displacement<'_> {
    /// `δ(k)` for the source `positions`.
    fn at(&self, k: usize, positions: &[Vec3]) -> Vec3 {
        match *self {
            Displacement::Towards(target) => target[k] - positions[k],
            Displacement::Radial {
                origin,
                direction,
                factor,
            } => {
                let d = positions[k] - origin;
                let perpendicular = d - direction * d.dot(direction);
                perpendicular * (factor - 1.0)
            }
        }
    }
}
