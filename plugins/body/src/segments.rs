//! Segment-local morphing of the body and its roughness measure, after seed 002 (B. Uğur,
//! *Parametric Human Body Modeling for Virtual Dressing*, 2008) §4.3 "Segmentation Tool",
//! §4.4 "Local Morphing" and §7.1 "Smoothness Measure for Morphed Objects".
//!
//! # Segments (§4.3)
//!
//! The body is marked with anthropometric *segments*: each has a *core* vertex set, and the
//! cores partition the body vertices, so that every vertex belongs to exactly one core. They are
//! derived from the mesh and the rig, never from vertex lists ([`BodySegmentation::new`]):
//!
//! 1. Each body vertex goes to the segment kind of its *dominant skin bone* (its largest weight)
//!    or, if that bone names none, of its nearest ancestor that does: `upperarm*` → upper arm,
//!    `lowerarm*` (with the twist half) → forearm, `hand*` (with the fingers) → hand, `thigh*`
//!    → thigh, `calf*` → shank, `foot*` (with `ball*`) → foot, `neck*` / `head` → head and neck;
//!    everything else (`Root`, `pelvis`, `spine_*`, `clavicle_*`) is the torso.
//! 2. Left and right: the side of the x of that bone's head in the rest pose (+X is the body's
//!    left).
//! 3. The torso, and the thigh vertices above the crotch, are cut into three horizontal bands by
//!    the waist, hip and crotch landmarks that [`BodyModel::measure`] finds on the base mesh
//!    (heights above the sole): the *waist* band is centred on the waist line and as tall as the
//!    waist line is above the hip line (half that distance up and half down); the *chest* is
//!    everything above it (under-bust, bust, shoulders), the *hip* everything below. The legs
//!    start at the crotch height: a thigh vertex above it belongs to the hip band.
//!
//! On the MakeHuman base mesh (waist line 108.3 cm, hip line 87.6 cm) the waist band spans 98.0
//! to 118.7 cm above the sole, about ten edge rings at the torso's 2 cm edges.
//!
//! # Propagation (§4.3, eq. 4.1, Figure 4.8)
//!
//! From a core set, a breadth-first search over the mesh edge graph reaches the vertices at
//! `k = 1, 2, ...` hops (the *depth of the vertex*: its shortest graph distance to the core) up
//! to the *propagation depth* `d`. Each gets the weight `f(k, d)`, 1 on the core (`k = 0`), 0
//! beyond `d`. With `p = d + 1` (so that the last reached ring keeps a non-zero weight and
//! `d = 0` is the hard segment, the core alone):
//!
//! | [`Decay`] | `f(k, d)` for `0 <= k <= d` | seed Figure 4.8 |
//! | --- | --- | --- |
//! | `Linear` | `1 - k / p` | (a) `w = (p - d) / p` |
//! | `Square` | `1 - k² / p²` | (b) `w = 1 - d²/p²` |
//! | `Gaussian` | `exp(-k² / (2σ²))`, `σ = p / 3` | (c) `w = exp(-d²/2σ²)`, `σ = p·c`, here `c = 1/3` |
//!
//! The Gaussian's constant `c = 1/3` puts the first vertex that is *not* reached three standard
//! deviations out, where the curve has fallen to `exp(-4.5) = 0.011`, so cutting it there leaves
//! almost no step.
//!
//! # Local morphing (§4.4, eqs. 4.5 and 4.6)
//!
//! A source body `S` morphs towards a target `T` by amounts `u_j` per segment `j`. A vertex `k`
//! reached by the segments `j` with weights `w_kj` moves by the weighted mean (eq. 4.6):
//!
//! ```text
//! B(u)'_k = s_k + (t_k - s_k) · Σ_j u_j w_kj / Σ_j w_kj
//! ```
//!
//! Every segment takes part, the ones not being edited with `u_j = 0`: their weights in the
//! denominator are what makes the boundary regions blend. A vertex reached by one segment only
//! moves by that segment's `u_j` (the seed's special case, which the formula already gives);
//! with all `u_j = 1` every vertex morphs completely, the seed's requirement. [`AreaBlend`] does
//! this on any mesh; [`BodySegmentation::morph`] on the body, where the target may also be given
//! per segment (a girth scaling about the segment's own axis, [`SegmentTarget::RadialScale`],
//! the horizontal scaling at a girth position of §4.1.2 / §4.2): then `t_k - s_k` becomes
//! segment `j`'s displacement `δ_kj` inside the sum, `s_k + Σ_j u_j w_kj δ_kj / Σ_j w_kj`, which
//! is eq. 4.6 when all segments share one target. Helper vertices (tights, hair...) are copied
//! unchanged.
//!
//! [`SegmentMorph`] edits one segment with the rest of the body held (`u = 0`), and
//! [`SegmentMorph::edit_girth`] / [`edit_waist_girth`] are the designer's local edits: they find
//! the radial scale factor that brings the measured girth of the segment (waist, hip, bust...)
//! to the requested value, by secant steps on [`BodyModel::measure`], since the neighbours'
//! weights dilute the edit near the core's edges.
//!
//! # Roughness (§7.1, eqs. 7.1 and 7.2)
//!
//! The Laplacian coordinate of a vertex is the mean of its 1-ring neighbours (the uniform
//! Laplacian, eq. 7.1); the roughness of a vertex set is the mean distance of its vertices from
//! their Laplacian coordinates (eq. 7.2 divided by the vertex count, as the seed's figures
//! plot), [`MeshGraph::roughness_m`]. A vertex on an open boundary has a Laplacian in the
//! tangent plane too, so a flat grid is exactly 0 on its interior only.
//!
//! [`roughness_study`] repeats the seed's Figures 7.3-7.5: two neighbouring segments interpolated
//! separately and together towards a target, the roughness of their region against the amount,
//! for increasing propagation depths and each decay.

use std::collections::VecDeque;
use std::fmt::Write as _;

use glam::Vec3;
use serde::{Deserialize, Serialize};

use crate::measure::{MeasureError, Measurements};
use crate::model::{BodyModel, JointPlacement};
use crate::modifiers::{Shape, ShapeError};

/// Why a segmentation, a local morph, a girth edit or a roughness study cannot be made.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SegmentError {
    #[error(
        "triangles[{triangle}] names vertex {vertex}, past the {vertex_count} vertices of the \
         mesh graph; pass the triangles of the same mesh (body triangles only for a body)"
    )]
    TriangleIndex {
        triangle: usize,
        vertex: u32,
        vertex_count: usize,
    },
    #[error(
        "{field} names vertex {vertex}, past the {vertex_count} vertices of the mesh graph; \
         vertex indices must be below the graph's vertex count"
    )]
    VertexIndex {
        field: &'static str,
        vertex: u32,
        vertex_count: usize,
    },
    #[error("{field} has {got} entries, expected {expected}; {fix}")]
    Length {
        field: &'static str,
        got: usize,
        expected: usize,
        fix: &'static str,
    },
    #[error("{field} is {value}, expected {expected}")]
    BadValue {
        field: &'static str,
        value: f32,
        expected: &'static str,
    },
    #[error("the body model is invalid: {0}; re-import it with the body importer")]
    InvalidModel(String),
    #[error(
        "segment `{0}` has no core vertex: the rig lacks the bone it is derived from (see the \
         segmentation rules in the segments module), or the landmarks put its band outside the \
         body; check the rig's bone names and the body's measurements"
    )]
    EmptySegment(BodySegment),
    #[error("the landmarks for the torso bands could not be measured on the base mesh: {0}")]
    Measure(#[from] MeasureError),
    #[error("the study target shape cannot be applied: {0}")]
    Shape(#[from] ShapeError),
    #[error(
        "segment `{0}` is edited twice in one morph; give each segment at most one edit (combine \
         the amounts)"
    )]
    DuplicateEdit(BodySegment),
    #[error(
        "segment `{0}` has no girth that the body measurement reports; girth edits work on \
         head-neck (neck), chest (bust), waist, hip, thigh-left (thigh) and shank-left (calf)"
    )]
    NoGirth(BodySegment),
    #[error(
        "the requested {segment} girth {requested_cm:.2} cm is {ratio:.2} times the current \
         {current_cm:.2} cm; request between 0.5 and 2 times the current girth"
    )]
    GirthOutOfReach {
        segment: BodySegment,
        requested_cm: f32,
        current_cm: f32,
        ratio: f32,
    },
    #[error(
        "the {segment} girth edit stopped at {achieved_cm:.3} cm instead of {requested_cm:.3} cm \
         (scale factor {factor}); a deeper propagation or a smaller change may reach it"
    )]
    GirthNotReached {
        segment: BodySegment,
        requested_cm: f32,
        achieved_cm: f32,
        factor: f32,
    },
    #[error("roughness study: {0}")]
    StudyConfig(String),
}

// ---------------------------------------------------------------------------------------------
// Mesh graph, propagation, roughness

/// The vertex adjacency of a triangle mesh (its edge graph), as compressed rows: the seed's
/// winged-edge table answers the same 1-ring queries.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshGraph {
    offsets: Vec<u32>,
    neighbours: Vec<u32>,
}

impl MeshGraph {
    /// The edge graph of `triangles` over `vertex_count` vertices (indices `0..vertex_count`).
    /// Repeated edges count once; a vertex in no triangle has no neighbours.
    pub fn new(vertex_count: usize, triangles: &[[u32; 3]]) -> Result<Self, SegmentError> {
        let mut adjacency: Vec<Vec<u32>> = vec![Vec::new(); vertex_count];
        for (i, t) in triangles.iter().enumerate() {
            if let Some(&v) = t.iter().find(|&&v| v as usize >= vertex_count) {
                return Err(SegmentError::TriangleIndex {
                    triangle: i,
                    vertex: v,
                    vertex_count,
                });
            }
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                if a != b {
                    adjacency[a as usize].push(b);
                    adjacency[b as usize].push(a);
                }
            }
        }
        let mut offsets = Vec::with_capacity(vertex_count + 1);
        let mut neighbours = Vec::new();
        offsets.push(0);
        for mut ring in adjacency {
            ring.sort_unstable();
            ring.dedup();
            neighbours.extend_from_slice(&ring);
            offsets.push(neighbours.len() as u32);
        }
        Ok(Self {
            offsets,
            neighbours,
        })
    }

    /// Number of vertices.
    pub fn vertex_count(&self) -> usize {
        self.offsets.len() - 1
    }

    /// Number of (undirected) edges.
    pub fn edge_count(&self) -> usize {
        self.neighbours.len() / 2
    }

    /// The 1-ring of vertex `v`, sorted.
    ///
    /// # Panics
    /// If `v` is not below [`MeshGraph::vertex_count`].
    pub fn neighbours(&self, v: usize) -> &[u32] {
        &self.neighbours[self.offsets[v] as usize..self.offsets[v + 1] as usize]
    }

    fn check_vertices(&self, field: &'static str, vertices: &[u32]) -> Result<(), SegmentError> {
        match vertices
            .iter()
            .find(|&&v| v as usize >= self.vertex_count())
        {
            Some(&vertex) => Err(SegmentError::VertexIndex {
                field,
                vertex,
                vertex_count: self.vertex_count(),
            }),
            None => Ok(()),
        }
    }

    /// Graph distance (hops) from the set `core` of every vertex at most `max_hops` away, as
    /// `(vertex, hops)` sorted by vertex; the core itself at 0 hops. Breadth-first search.
    pub fn hops_from(&self, core: &[u32], max_hops: u32) -> Result<Vec<(u32, u32)>, SegmentError> {
        self.check_vertices("core", core)?;
        let mut hops = vec![u32::MAX; self.vertex_count()];
        let mut queue: VecDeque<u32> = VecDeque::new();
        for &v in core {
            if hops[v as usize] != 0 {
                hops[v as usize] = 0;
                queue.push_back(v);
            }
        }
        while let Some(v) = queue.pop_front() {
            let h = hops[v as usize];
            if h >= max_hops {
                continue;
            }
            for &n in self.neighbours(v as usize) {
                if hops[n as usize] == u32::MAX {
                    hops[n as usize] = h + 1;
                    queue.push_back(n);
                }
            }
        }
        Ok(hops
            .iter()
            .enumerate()
            .filter(|(_, h)| **h != u32::MAX)
            .map(|(v, &h)| (v as u32, h))
            .collect())
    }

    /// The propagation of `core` (§4.3): every vertex within `propagation.depth` hops, with its
    /// weight `f(k, d)` (1 on the core).
    pub fn propagate(
        &self,
        core: &[u32],
        propagation: Propagation,
    ) -> Result<SegmentWeights, SegmentError> {
        let reached = self.hops_from(core, propagation.depth)?;
        Ok(SegmentWeights {
            vertices: reached.iter().map(|r| r.0).collect(),
            hops: reached.iter().map(|r| r.1).collect(),
            weights: reached
                .iter()
                .map(|r| propagation.decay.weight(r.1, propagation.depth))
                .collect(),
        })
    }

    /// Distance (metres) of vertex `v` from its Laplacian coordinate, the mean of its 1-ring
    /// (seed eq. 7.1); `None` for a vertex without neighbours.
    ///
    /// # Panics
    /// If `v` or one of its neighbours is not an index into `positions`.
    pub fn laplacian_distance_m(&self, positions: &[Vec3], v: usize) -> Option<f32> {
        let ring = self.neighbours(v);
        if ring.is_empty() {
            return None;
        }
        let mean = ring.iter().map(|&n| positions[n as usize]).sum::<Vec3>() / ring.len() as f32;
        Some(mean.distance(positions[v]))
    }

    /// Roughness of the vertex set `region` (seed §7.1, eq. 7.2 as a mean): the mean distance
    /// (metres) of its vertices from their Laplacian coordinates. Vertices without neighbours
    /// are left out; an empty region has roughness 0.
    pub fn roughness_m(&self, positions: &[Vec3], region: &[u32]) -> Result<f32, SegmentError> {
        self.check_positions(positions)?;
        self.check_vertices("region", region)?;
        let (sum, count) = region
            .iter()
            .filter_map(|&v| self.laplacian_distance_m(positions, v as usize))
            .fold((0.0f64, 0usize), |(s, c), d| (s + d as f64, c + 1));
        Ok(if count == 0 {
            0.0
        } else {
            (sum / count as f64) as f32
        })
    }

    /// Roughness (metres) of the whole mesh: [`MeshGraph::roughness_m`] over every vertex.
    pub fn mesh_roughness_m(&self, positions: &[Vec3]) -> Result<f32, SegmentError> {
        let all: Vec<u32> = (0..self.vertex_count() as u32).collect();
        self.roughness_m(positions, &all)
    }

    fn check_positions(&self, positions: &[Vec3]) -> Result<(), SegmentError> {
        if positions.len() < self.vertex_count() {
            return Err(SegmentError::Length {
                field: "positions",
                got: positions.len(),
                expected: self.vertex_count(),
                fix: "pass the positions of the mesh the graph was built from (at least one per \
                      graph vertex)",
            });
        }
        Ok(())
    }
}

/// How propagation weights fall off with the graph distance from the core (seed Figure 4.8);
/// see the [module docs](self) for the formulas.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Decay {
    Linear,
    Square,
    Gaussian,
}

impl Decay {
    pub const ALL: [Decay; 3] = [Decay::Linear, Decay::Square, Decay::Gaussian];

    /// The weight `f(k, d)` of a vertex `hops` = k hops from the core in a propagation of depth
    /// `depth` = d: 1 at `k = 0`, 0 for `k > d`, decreasing in between.
    pub fn weight(self, hops: u32, depth: u32) -> f32 {
        if hops == 0 {
            return 1.0;
        }
        if hops > depth {
            return 0.0;
        }
        let x = hops as f32 / (depth as f32 + 1.0);
        match self {
            Decay::Linear => 1.0 - x,
            Decay::Square => 1.0 - x * x,
            // σ = (d + 1) / 3: k² / (2σ²) = 4.5 x².
            Decay::Gaussian => (-4.5 * x * x).exp(),
        }
    }

    /// The kebab-case name (`gaussian`).
    pub fn name(self) -> &'static str {
        match self {
            Decay::Linear => "linear",
            Decay::Square => "square",
            Decay::Gaussian => "gaussian",
        }
    }
}

impl std::fmt::Display for Decay {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for Decay {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Decay::ALL
            .into_iter()
            .find(|d| d.name() == s.trim().to_ascii_lowercase())
            .ok_or_else(|| format!("unknown decay `{s}`; known: linear, square, gaussian"))
    }
}

/// A propagation: how many hops out from the core, and how the weights fall off.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct Propagation {
    /// Propagation depth `d` in hops (0: the hard segment, its core alone).
    pub depth: u32,
    pub decay: Decay,
}

impl Propagation {
    /// The hard segment: the core alone, weight 1.
    pub const HARD: Propagation = Propagation {
        depth: 0,
        decay: Decay::Gaussian,
    };

    pub fn new(depth: u32, decay: Decay) -> Self {
        Self { depth, decay }
    }
}

/// The weights of one segment after propagation (the seed's `AREAS` record): parallel lists,
/// sorted by vertex.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SegmentWeights {
    pub vertices: Vec<u32>,
    /// Graph distance of each vertex from the core (0 on the core).
    pub hops: Vec<u32>,
    /// Membership weight of each vertex, `f(hops, depth)`.
    pub weights: Vec<f32>,
}

impl SegmentWeights {
    /// The weight of vertex `v` (0 if the propagation does not reach it).
    pub fn weight_of(&self, v: u32) -> f32 {
        self.vertices
            .binary_search(&v)
            .map_or(0.0, |i| self.weights[i])
    }

    /// Number of vertices reached (core included).
    pub fn len(&self) -> usize {
        self.vertices.len()
    }

    pub fn is_empty(&self) -> bool {
        self.vertices.is_empty()
    }
}

// ---------------------------------------------------------------------------------------------
// Eq. 4.6 on any mesh

/// The segments' weights per vertex, ready for the weighted-mean morph of seed eq. 4.6.
#[derive(Clone, Debug, PartialEq)]
pub struct AreaBlend {
    vertex_count: usize,
    area_count: usize,
    offsets: Vec<u32>,
    /// `(area, weight)` per vertex, rows given by `offsets`.
    entries: Vec<(u32, f32)>,
}

impl AreaBlend {
    /// Collects `areas` (area `j` is `areas[j]`) over `vertex_count` vertices.
    pub fn new(vertex_count: usize, areas: &[SegmentWeights]) -> Result<Self, SegmentError> {
        let mut rows: Vec<Vec<(u32, f32)>> = vec![Vec::new(); vertex_count];
        for (j, area) in areas.iter().enumerate() {
            if area.weights.len() != area.vertices.len() {
                return Err(SegmentError::Length {
                    field: "SegmentWeights::weights",
                    got: area.weights.len(),
                    expected: area.vertices.len(),
                    fix: "give one weight per vertex",
                });
            }
            for (&v, &w) in area.vertices.iter().zip(&area.weights) {
                let Some(row) = rows.get_mut(v as usize) else {
                    return Err(SegmentError::VertexIndex {
                        field: "SegmentWeights::vertices",
                        vertex: v,
                        vertex_count,
                    });
                };
                if !(w.is_finite() && w >= 0.0) {
                    return Err(SegmentError::BadValue {
                        field: "SegmentWeights::weights",
                        value: w,
                        expected: "a finite weight >= 0",
                    });
                }
                if w > 0.0 {
                    row.push((j as u32, w));
                }
            }
        }
        let mut offsets = Vec::with_capacity(vertex_count + 1);
        let mut entries = Vec::new();
        offsets.push(0);
        for row in rows {
            entries.extend_from_slice(&row);
            offsets.push(entries.len() as u32);
        }
        Ok(Self {
            vertex_count,
            area_count: areas.len(),
            offsets,
            entries,
        })
    }

    pub fn vertex_count(&self) -> usize {
        self.vertex_count
    }

    pub fn area_count(&self) -> usize {
        self.area_count
    }

    /// The `(area, weight)` memberships of vertex `v`.
    ///
    /// # Panics
    /// If `v` is not below [`AreaBlend::vertex_count`].
    pub fn memberships(&self, v: usize) -> &[(u32, f32)] {
        &self.entries[self.offsets[v] as usize..self.offsets[v + 1] as usize]
    }

    fn check_amounts(&self, amounts: &[f32]) -> Result<(), SegmentError> {
        if amounts.len() != self.area_count {
            return Err(SegmentError::Length {
                field: "amounts",
                got: amounts.len(),
                expected: self.area_count,
                fix: "give one amount per area (0 for the areas that do not morph)",
            });
        }
        if let Some(&u) = amounts.iter().find(|u| !u.is_finite()) {
            return Err(SegmentError::BadValue {
                field: "amounts",
                value: u,
                expected: "a finite morph amount (0 to 1 interpolates)",
            });
        }
        Ok(())
    }

    /// The multiplier `Σ_j u_j w_kj / Σ_j w_kj` of eq. 4.6 for each vertex `k` (0 where no area
    /// reaches), for the amounts `u_j` = `amounts[j]`.
    pub fn multipliers(&self, amounts: &[f32]) -> Result<Vec<f32>, SegmentError> {
        self.check_amounts(amounts)?;
        Ok((0..self.vertex_count)
            .map(|k| {
                let (mut num, mut den) = (0.0f32, 0.0f32);
                for &(j, w) in self.memberships(k) {
                    num += amounts[j as usize] * w;
                    den += w;
                }
                if den > 0.0 { num / den } else { 0.0 }
            })
            .collect())
    }

    /// Eq. 4.6 towards one target model: `b_k = s_k + (t_k - s_k) · multiplier_k`. Vertices at
    /// and past [`AreaBlend::vertex_count`] (helpers) and vertices with multiplier 0 are copied
    /// from `source` exactly.
    pub fn morph_towards(
        &self,
        source: &[Vec3],
        target: &[Vec3],
        amounts: &[f32],
    ) -> Result<Vec<Vec3>, SegmentError> {
        self.check_source(source)?;
        if target.len() != source.len() {
            return Err(SegmentError::Length {
                field: "target",
                got: target.len(),
                expected: source.len(),
                fix: "give the target model's positions, one per source vertex",
            });
        }
        let a = self.multipliers(amounts)?;
        let mut out = source.to_vec();
        for (k, &a) in a.iter().enumerate() {
            if a != 0.0 {
                out[k] = source[k] + (target[k] - source[k]) * a;
            }
        }
        Ok(out)
    }

    /// The generalised eq. 4.6 with one displacement field per area:
    /// `b_k = s_k + Σ_j u_j w_kj δ_j(k) / Σ_j w_kj`, where `displacement(j, k)` = `δ_j(k)` is
    /// asked only where `u_j ≠ 0`. With `δ_j(k) = t_k - s_k` for every `j` this is
    /// [`AreaBlend::morph_towards`].
    pub fn morph_with(
        &self,
        source: &[Vec3],
        amounts: &[f32],
        mut displacement: impl FnMut(usize, usize) -> Vec3,
    ) -> Result<Vec<Vec3>, SegmentError> {
        self.check_source(source)?;
        self.check_amounts(amounts)?;
        let mut out = source.to_vec();
        for (k, out_k) in out.iter_mut().enumerate().take(self.vertex_count) {
            let ms = self.memberships(k);
            if ms.iter().all(|&(j, _)| amounts[j as usize] == 0.0) {
                continue;
            }
            let mut num = Vec3::ZERO;
            let mut den = 0.0f32;
            for &(j, w) in ms {
                let u = amounts[j as usize];
                if u != 0.0 {
                    num += displacement(j as usize, k) * (u * w);
                }
                den += w;
            }
            *out_k = source[k] + num / den;
        }
        Ok(out)
    }

    fn check_source(&self, source: &[Vec3]) -> Result<(), SegmentError> {
        if source.len() < self.vertex_count {
            return Err(SegmentError::Length {
                field: "source",
                got: source.len(),
                expected: self.vertex_count,
                fix: "pass the positions of the mesh the areas were built on",
            });
        }
        Ok(())
    }
}

// ---------------------------------------------------------------------------------------------
// The body's segments

/// An anthropometric segment of the body (seed §4.3: one measurement area per girth or length
/// of Table 4.1). See the [module docs](self) for how their cores are found.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum BodySegment {
    /// Head and neck (neck girth).
    HeadNeck,
    /// Torso above the waist band, shoulders included (bust and under-bust girths).
    Chest,
    /// Torso band centred on the waist girth.
    Waist,
    /// Torso band below the middle of the waist and hip heights, down to the crotch (hip girth).
    Hip,
    UpperArmLeft,
    UpperArmRight,
    ForearmLeft,
    ForearmRight,
    HandLeft,
    HandRight,
    ThighLeft,
    ThighRight,
    /// Lower leg, knee to ankle.
    ShankLeft,
    ShankRight,
    FootLeft,
    FootRight,
}

impl BodySegment {
    pub const ALL: [BodySegment; 16] = [
        BodySegment::HeadNeck,
        BodySegment::Chest,
        BodySegment::Waist,
        BodySegment::Hip,
        BodySegment::UpperArmLeft,
        BodySegment::UpperArmRight,
        BodySegment::ForearmLeft,
        BodySegment::ForearmRight,
        BodySegment::HandLeft,
        BodySegment::HandRight,
        BodySegment::ThighLeft,
        BodySegment::ThighRight,
        BodySegment::ShankLeft,
        BodySegment::ShankRight,
        BodySegment::FootLeft,
        BodySegment::FootRight,
    ];

    /// Position in [`BodySegment::ALL`] (the area index in the body's [`AreaBlend`]).
    pub fn index(self) -> usize {
        self as usize
    }

    /// The kebab-case name (`upper-arm-left`).
    pub fn name(self) -> &'static str {
        match self {
            BodySegment::HeadNeck => "head-neck",
            BodySegment::Chest => "chest",
            BodySegment::Waist => "waist",
            BodySegment::Hip => "hip",
            BodySegment::UpperArmLeft => "upper-arm-left",
            BodySegment::UpperArmRight => "upper-arm-right",
            BodySegment::ForearmLeft => "forearm-left",
            BodySegment::ForearmRight => "forearm-right",
            BodySegment::HandLeft => "hand-left",
            BodySegment::HandRight => "hand-right",
            BodySegment::ThighLeft => "thigh-left",
            BodySegment::ThighRight => "thigh-right",
            BodySegment::ShankLeft => "shank-left",
            BodySegment::ShankRight => "shank-right",
            BodySegment::FootLeft => "foot-left",
            BodySegment::FootRight => "foot-right",
        }
    }

    /// The segment named `name` (kebab-case, as [`BodySegment::name`]).
    pub fn from_name(name: &str) -> Option<BodySegment> {
        let n = name.trim().to_ascii_lowercase().replace('_', "-");
        BodySegment::ALL.into_iter().find(|s| s.name() == n)
    }

    fn is_torso_band(self) -> bool {
        matches!(
            self,
            BodySegment::HeadNeck | BodySegment::Chest | BodySegment::Waist | BodySegment::Hip
        )
    }

    /// Which girth of [`BodyModel::measure`] belongs to this segment, if any.
    fn girth(self) -> Option<fn(&Measurements) -> f32> {
        match self {
            BodySegment::HeadNeck => Some(|m| m.neck_cm),
            BodySegment::Chest => Some(|m| m.bust_cm),
            BodySegment::Waist => Some(|m| m.waist_cm),
            BodySegment::Hip => Some(|m| m.hip_cm),
            BodySegment::ThighLeft => Some(|m| m.thigh_cm),
            BodySegment::ShankLeft => Some(|m| m.calf_cm),
            _ => None,
        }
    }
}

impl std::fmt::Display for BodySegment {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for BodySegment {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        BodySegment::from_name(s).ok_or_else(|| {
            let known: Vec<&str> = BodySegment::ALL.iter().map(|s| s.name()).collect();
            format!("unknown body segment `{s}`; known: {}", known.join(", "))
        })
    }
}

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
    /// Segments the base mesh of `model` by the rules of the [module docs](self).
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

// ---------------------------------------------------------------------------------------------
// One segment at a time: the designer's local edits

/// Local morphing of one segment with the rest of the body held (every other segment at
/// amount 0 in eq. 4.6), e.g. the waist alone.
#[derive(Clone, Debug, PartialEq)]
pub struct SegmentMorph {
    segmentation: BodySegmentation,
    blend: AreaBlend,
    segment: BodySegment,
    propagation: Propagation,
}

/// How close (cm) [`SegmentMorph::edit_girth`] brings the measured girth to the request.
pub const GIRTH_TOLERANCE_CM: f32 = 0.05;

/// Secant steps [`SegmentMorph::edit_girth`] takes before giving up.
const GIRTH_MAX_STEPS: u32 = 8;

impl SegmentMorph {
    /// Segments `model` and prepares morphs of `segment`, every segment propagated to `depth`
    /// hops with `decay`.
    pub fn new(
        model: &BodyModel,
        segment: BodySegment,
        depth: u32,
        decay: Decay,
    ) -> Result<Self, SegmentError> {
        Self::with_segmentation(
            BodySegmentation::new(model)?,
            segment,
            Propagation::new(depth, decay),
        )
    }

    /// The same from an existing segmentation (segmenting measures the body; do it once).
    pub fn with_segmentation(
        segmentation: BodySegmentation,
        segment: BodySegment,
        propagation: Propagation,
    ) -> Result<Self, SegmentError> {
        let blend = segmentation.blend(propagation)?;
        Ok(Self {
            segmentation,
            blend,
            segment,
            propagation,
        })
    }

    pub fn segment(&self) -> BodySegment {
        self.segment
    }

    pub fn propagation(&self) -> Propagation {
        self.propagation
    }

    pub fn segmentation(&self) -> &BodySegmentation {
        &self.segmentation
    }

    /// How far each body vertex follows the segment's target when the segment's amount is 1:
    /// the eq. 4.6 multiplier with every other segment at 0 (1 deep inside the core, falling
    /// to 0 outside the propagation).
    pub fn multipliers(&self) -> Vec<f32> {
        let mut amounts = [0.0f32; 16];
        amounts[self.segment.index()] = 1.0;
        self.blend
            .multipliers(&amounts)
            .expect("the blend has one area per body segment")
    }

    /// The body `positions` (whole mesh) with the segment morphed by `amount` towards `target`.
    pub fn apply(
        &self,
        positions: &[Vec3],
        target: &SegmentTarget,
        amount: f32,
    ) -> Result<Vec<Vec3>, SegmentError> {
        self.segmentation.morph(
            &self.blend,
            positions,
            &[SegmentEdit {
                segment: self.segment,
                target: target.clone(),
                amount,
            }],
        )
    }

    /// The designer's girth edit: scales the segment about its axis
    /// ([`SegmentTarget::RadialScale`], amount 1) by the factor that brings its girth, as
    /// [`BodyModel::measure`] reports it, to `target_girth_cm` (within
    /// [`GIRTH_TOLERANCE_CM`]). The neighbours' weights dilute the edit near the core's edges,
    /// so the factor is found by secant steps on the measured girth.
    pub fn edit_girth(
        &self,
        model: &BodyModel,
        positions: &[Vec3],
        target_girth_cm: f32,
    ) -> Result<GirthEdit, SegmentError> {
        let of = self
            .segment
            .girth()
            .ok_or(SegmentError::NoGirth(self.segment))?;
        let girth = |p: &[Vec3]| -> Result<f32, SegmentError> { Ok(of(&model.measure(p)?)) };
        if !(target_girth_cm.is_finite() && target_girth_cm > 0.0) {
            return Err(SegmentError::BadValue {
                field: "target_girth_cm",
                value: target_girth_cm,
                expected: "a finite girth > 0 cm",
            });
        }
        let before_cm = girth(positions)?;
        let ratio = target_girth_cm / before_cm;
        if !(0.5..=2.0).contains(&ratio) {
            return Err(SegmentError::GirthOutOfReach {
                segment: self.segment,
                requested_cm: target_girth_cm,
                current_cm: before_cm,
                ratio,
            });
        }
        let mut edit = GirthEdit {
            segment: self.segment,
            propagation: self.propagation,
            before_cm,
            requested_cm: target_girth_cm,
            achieved_cm: before_cm,
            scale_factor: 1.0,
            steps: 0,
            positions: positions.to_vec(),
        };
        if (before_cm - target_girth_cm).abs() <= GIRTH_TOLERANCE_CM {
            return Ok(edit);
        }
        let (mut f_prev, mut g_prev) = (1.0f32, before_cm);
        let mut f = ratio;
        for step in 1..=GIRTH_MAX_STEPS {
            let p = self.apply(positions, &SegmentTarget::RadialScale { factor: f }, 1.0)?;
            let g = girth(&p)?;
            edit.steps = step;
            edit.achieved_cm = g;
            edit.scale_factor = f;
            edit.positions = p;
            if (g - target_girth_cm).abs() <= GIRTH_TOLERANCE_CM {
                return Ok(edit);
            }
            let slope = (g - g_prev) / (f - f_prev);
            let next = f + (target_girth_cm - g) / slope;
            if !(slope.is_finite() && slope.abs() > 1e-3 && next.is_finite() && next > 0.0) {
                break;
            }
            (f_prev, g_prev, f) = (f, g, next);
        }
        Err(SegmentError::GirthNotReached {
            segment: self.segment,
            requested_cm: target_girth_cm,
            achieved_cm: edit.achieved_cm,
            factor: edit.scale_factor,
        })
    }
}

/// The result of a girth edit.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct GirthEdit {
    pub segment: BodySegment,
    pub propagation: Propagation,
    /// Girth of the input body.
    pub before_cm: f32,
    pub requested_cm: f32,
    /// Girth of the edited body (within [`GIRTH_TOLERANCE_CM`] of the request).
    pub achieved_cm: f32,
    /// The radial scale factor applied to the segment.
    pub scale_factor: f32,
    /// Secant steps taken (each one morph and one measurement).
    pub steps: u32,
    /// The edited body, whole mesh.
    #[serde(skip)]
    pub positions: Vec<Vec3>,
}

/// "Waist only": changes the waist girth of `positions` (whole mesh of `model`) by `change_cm`
/// (negative: slimmer), moving only the waist band and its propagation. Segments the model on
/// each call; for repeated edits make one [`SegmentMorph`] and call
/// [`SegmentMorph::edit_girth`].
pub fn edit_waist_girth(
    model: &BodyModel,
    positions: &[Vec3],
    change_cm: f32,
    propagation: Propagation,
) -> Result<GirthEdit, SegmentError> {
    if !change_cm.is_finite() {
        return Err(SegmentError::BadValue {
            field: "change_cm",
            value: change_cm,
            expected: "a finite girth change in cm",
        });
    }
    let morph = SegmentMorph::with_segmentation(
        BodySegmentation::new(model)?,
        BodySegment::Waist,
        propagation,
    )?;
    let m = model.measure(positions)?;
    morph.edit_girth(model, positions, m.waist_cm + change_cm)
}

// ---------------------------------------------------------------------------------------------
// The roughness study (seed Figures 7.3-7.5)

/// What the two segments of a [`roughness_study`] morph towards.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum StudyTarget {
    /// The whole body shaped by MakeHuman modifiers (the seed's calibrated target model).
    Shape(Shape),
    /// Each segment's girth scaled about its own axis.
    RadialScale { factor: f32 },
}

/// The parameters of a [`roughness_study`].
#[derive(Clone, Debug, PartialEq)]
pub struct RoughnessStudyConfig {
    /// Two neighbouring segments (the seed: under-bust and waist).
    pub segments: [BodySegment; 2],
    pub target: StudyTarget,
    /// Propagation depths (hops) compared; 0 is the hard segment.
    pub depths: Vec<u32>,
    pub decays: Vec<Decay>,
    /// The amount goes from 0 to 1 in this many equal steps.
    pub amount_steps: u32,
}

impl Default for RoughnessStudyConfig {
    /// Waist and chest (the band that holds the under-bust), towards MakeHuman's heaviest body
    /// (`weight` 1), depths 0, 1, 2, 4, 8, every decay, amounts in tenths.
    fn default() -> Self {
        Self {
            segments: [BodySegment::Waist, BodySegment::Chest],
            target: StudyTarget::Shape(Shape {
                weight: 1.0,
                ..Shape::default()
            }),
            depths: vec![0, 1, 2, 4, 8],
            decays: Decay::ALL.to_vec(),
            amount_steps: 10,
        }
    }
}

/// Roughness against amount for one interpolation, decay and depth: one line of the seed's
/// Figures 7.3-7.5.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RoughnessCurve {
    /// The segments that morph (amount `u`); every other segment stays (amount 0).
    pub interpolated: Vec<BodySegment>,
    pub decay: Decay,
    /// Propagation depth (hops) of every segment; 0 is the hard segment.
    pub depth: u32,
    /// Roughness of the region (mean Laplacian distance, mm), one per
    /// [`RoughnessStudy::amounts`].
    pub roughness_mm: Vec<f32>,
}

/// The seed's Figures 7.3-7.5 as data: for two neighbouring segments interpolated separately
/// and together, the roughness of their region against the interpolation amount, for each
/// decay and propagation depth.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RoughnessStudy {
    pub segments: [BodySegment; 2],
    pub target: StudyTarget,
    /// The region measured: both cores and every vertex within `region_hops` hops of them
    /// (one more than the deepest propagation, so it holds every vertex that moves).
    pub region_hops: u32,
    pub region_vertex_count: usize,
    /// Interpolation amounts `u`, 0 to 1.
    pub amounts: Vec<f32>,
    pub depths: Vec<u32>,
    pub decays: Vec<Decay>,
    /// Roughness of the region on the source body (mm): every curve's value at `u = 0`.
    pub source_roughness_mm: f32,
    /// Roughness of the region on the target body (mm), for a [`StudyTarget::Shape`]: where a
    /// global morph ends.
    pub target_roughness_mm: Option<f32>,
    /// One curve per interpolation (first segment, second, both), decay and depth, in that
    /// nesting order.
    pub curves: Vec<RoughnessCurve>,
}

impl RoughnessStudy {
    /// The curve for these interpolated segments, decay and depth.
    pub fn curve(
        &self,
        interpolated: &[BodySegment],
        decay: Decay,
        depth: u32,
    ) -> Option<&RoughnessCurve> {
        self.curves
            .iter()
            .find(|c| c.interpolated == interpolated && c.decay == decay && c.depth == depth)
    }

    /// The study as text tables: one per interpolation and decay, a row per depth, a column
    /// per amount (mm).
    pub fn table(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(
            s,
            "Roughness (mean Laplacian distance, mm) of {} vertices: {} and {} cores and {} hops \
             around; source {:.4} mm{}",
            self.region_vertex_count,
            self.segments[0],
            self.segments[1],
            self.region_hops,
            self.source_roughness_mm,
            self.target_roughness_mm
                .map_or(String::new(), |t| format!(", target {t:.4} mm")),
        );
        let mut last: Option<(&[BodySegment], Decay)> = None;
        for c in &self.curves {
            if last != Some((&c.interpolated, c.decay)) {
                let names: Vec<&str> = c.interpolated.iter().map(|s| s.name()).collect();
                let _ = writeln!(
                    s,
                    "\ninterpolated: {} | decay: {}",
                    names.join(" + "),
                    c.decay
                );
                let _ = write!(s, "{:>6}", "depth");
                for u in &self.amounts {
                    let _ = write!(s, " {:>7}", format!("u={u:.1}"));
                }
                s.push('\n');
                last = Some((&c.interpolated, c.decay));
            }
            let _ = write!(s, "{:>6}", c.depth);
            for r in &c.roughness_mm {
                let _ = write!(s, " {r:>7.4}");
            }
            s.push('\n');
        }
        s
    }
}

/// The roughness study of `config` on the base mesh of `model` (segments it first).
pub fn roughness_study(
    model: &BodyModel,
    config: &RoughnessStudyConfig,
) -> Result<RoughnessStudy, SegmentError> {
    roughness_study_with(model, &BodySegmentation::new(model)?, config)
}

/// [`roughness_study`] with an existing segmentation of `model`.
///
/// The source is the base mesh. For each decay and depth every segment is propagated alike;
/// the segments of an interpolation morph by `u` (eq. 4.6, the others at 0), and the region's
/// roughness is measured at each amount. Eq. 4.6 is linear in `u` when the morphing segments
/// share it, so the body at `u` is the source plus `u` times the displacement at `u = 1`.
pub fn roughness_study_with(
    model: &BodyModel,
    segmentation: &BodySegmentation,
    config: &RoughnessStudyConfig,
) -> Result<RoughnessStudy, SegmentError> {
    let [first, second] = config.segments;
    if first == second {
        return Err(SegmentError::StudyConfig(format!(
            "segments are both `{first}`; give two different (neighbouring) segments"
        )));
    }
    if config.depths.is_empty() || config.decays.is_empty() {
        return Err(SegmentError::StudyConfig(
            "depths and decays must not be empty; e.g. depths 0, 1, 2, 4, 8 and every decay".into(),
        ));
    }
    const MAX_DEPTH: u32 = 64;
    if let Some(d) = config.depths.iter().find(|&&d| d > MAX_DEPTH) {
        return Err(SegmentError::StudyConfig(format!(
            "depth {d} is past the largest accepted depth {MAX_DEPTH}; the body is about 100 \
             hops from head to toe"
        )));
    }
    if !(1..=1000).contains(&config.amount_steps) {
        return Err(SegmentError::StudyConfig(format!(
            "amount_steps is {}; give 1 to 1000 steps from 0 to 1",
            config.amount_steps
        )));
    }
    let source = &model.positions;
    let graph = segmentation.graph();
    let body = graph.vertex_count();
    let (target, target_positions) = match &config.target {
        StudyTarget::Shape(shape) => {
            let t = model.shaped(shape)?.positions;
            (SegmentTarget::Positions(t.clone()), Some(t))
        }
        &StudyTarget::RadialScale { factor } => (SegmentTarget::RadialScale { factor }, None),
    };

    let mut cores = segmentation.core(first);
    cores.extend(segmentation.core(second));
    let max_depth = config.depths.iter().copied().max().unwrap_or(0);
    let region_hops = max_depth + 1;
    let region: Vec<u32> = graph
        .hops_from(&cores, region_hops)?
        .into_iter()
        .map(|r| r.0)
        .collect();
    let mm = |p: &[Vec3]| graph.roughness_m(p, &region).map(|r| r * 1000.0);
    let source_roughness_mm = mm(source)?;
    let target_roughness_mm = target_positions.as_deref().map(mm).transpose()?;

    let amounts: Vec<f32> = (0..=config.amount_steps)
        .map(|i| i as f32 / config.amount_steps as f32)
        .collect();
    let cases = [vec![first], vec![second], vec![first, second]];
    let mut curves = Vec::new();
    for case in &cases {
        for &decay in &config.decays {
            for &depth in &config.depths {
                let blend = segmentation.blend(Propagation::new(depth, decay))?;
                let edits: Vec<SegmentEdit> = case
                    .iter()
                    .map(|&segment| SegmentEdit {
                        segment,
                        target: target.clone(),
                        amount: 1.0,
                    })
                    .collect();
                let full = segmentation.morph(&blend, source, &edits)?;
                let displacement: Vec<Vec3> = (0..body).map(|k| full[k] - source[k]).collect();
                let mut at = source.clone();
                let roughness_mm = amounts
                    .iter()
                    .map(|&u| {
                        for k in 0..body {
                            at[k] = source[k] + displacement[k] * u;
                        }
                        mm(&at)
                    })
                    .collect::<Result<Vec<f32>, _>>()?;
                curves.push(RoughnessCurve {
                    interpolated: case.clone(),
                    decay,
                    depth,
                    roughness_mm,
                });
            }
        }
    }
    Ok(RoughnessStudy {
        segments: config.segments,
        target: config.target.clone(),
        region_hops,
        region_vertex_count: region.len(),
        amounts,
        depths: config.depths.clone(),
        decays: config.decays.clone(),
        source_roughness_mm,
        target_roughness_mm,
        curves,
    })
}
