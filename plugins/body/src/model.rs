//! The body model as the product uses it: mesh, skeleton, skin weights and morph targets.
//!
//! Model space: metres, +Y up, the body faces +Z, +X is the body's left. This is MakeHuman's
//! mesh space scaled from decimetres to metres.

use glam::{Affine3A, Quat, Vec2, Vec3};
use serde::{Deserialize, Serialize};

/// Turns model space (facing +Z, +X the body's left) into Kinect sensor space so the body faces
/// the sensor (-Z): a half turn about +Y.
pub const MODEL_TO_SENSOR: Quat = Quat::from_xyzw(0.0, 1.0, 0.0, 0.0);

/// Where a rig places a bone end on the mesh (MakeHuman rig `strategy`), so the skeleton
/// follows any morphed body.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum JointPlacement {
    /// Mean of a set of vertices (`CUBE`: a `joint-*` vertex group; `MEAN`: listed vertices).
    Mean(Vec<u32>),
    /// One vertex (`VERTEX`).
    Vertex(u32),
    /// A point at fraction `t` between two other placements' positions (used for the split
    /// forearm: the middle of elbow and wrist).
    Lerp {
        from: Box<JointPlacement>,
        to: Box<JointPlacement>,
        t: f32,
    },
}

/// One bone. Bones are stored parents-first.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Bone {
    pub name: String,
    pub parent: Option<usize>,
    pub head_placement: JointPlacement,
    pub tail_placement: JointPlacement,
    /// Blender bone roll (radians) about the head->tail axis, in MakeHuman's Blender space.
    pub roll: f32,
}

/// The rest pose of a skeleton derived from one (possibly morphed) mesh.
#[derive(Clone, Debug, PartialEq)]
pub struct RestPose {
    /// Bone head positions in model space, metres.
    pub heads: Vec<Vec3>,
    /// Bone tail positions in model space, metres.
    pub tails: Vec<Vec3>,
    /// Bone frames in model space: +Y from head to tail, roll applied as Blender does.
    pub rotations: Vec<Quat>,
}

/// A sparse morph target: only moved vertices, quantised.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MorphTarget {
    /// MakeHuman's path-like name, e.g. `macrodetails/universal-female-young-averagemuscle-averageweight`.
    pub name: String,
    /// Vertex indices into the full mesh (body and helper vertices share one index space),
    /// strictly increasing. Serialised as gaps (first index, then differences).
    #[serde(with = "crate::codec::index_gaps")]
    pub indices: Vec<u32>,
    /// Displacements as `i16` triples (parallel to `indices`); metres = value * `scale_m`.
    /// Serialised planar (all x, then all y, then all z), each plane as wrapping `i16`
    /// differences from the previous entry, which compresses far better.
    #[serde(with = "crate::codec::planar_differences")]
    pub deltas: Vec<[i16; 3]>,
    /// Metres per quantisation step: `max |component| / 32767` of the target (0 if empty).
    pub scale_m: f32,
}

/// Helper geometry from the MakeHuman base mesh (tights, skirt, hair, eyes, teeth...), kept
/// for garment fitting later: one per `helper-*` vertex group. The joint cubes are not kept as
/// helpers (the rig's [`JointPlacement`]s already name their vertices).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct HelperGroup {
    pub name: String,
    /// Inclusive vertex index range into the full mesh that spans the group. Most groups are
    /// exactly this range; the eyelash groups interleave, so theirs overlap.
    pub first_vertex: u32,
    pub last_vertex: u32,
    /// Triangles (indices into the full mesh).
    pub triangles: Vec<[u32; 3]>,
}

/// Everything the product needs to show and pose a MakeHuman body.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BodyModel {
    /// Positions of all base-mesh vertices (body first: `0..body_vertex_count`), metres.
    pub positions: Vec<Vec3>,
    /// Number of body vertices (13,380 for hm08); the rest are helpers.
    pub body_vertex_count: u32,
    /// Body triangles (indices < `body_vertex_count`), counter-clockwise seen from outside.
    pub triangles: Vec<[u32; 3]>,
    /// Per body vertex texture coordinates, one per body vertex. On UV seams (1,122 hm08 body
    /// vertices have more than one `vt`) this is the first UV the vertex gets in OBJ face order;
    /// use [`BodyModel::triangle_uvs`] where seams matter.
    pub uvs: Vec<Vec2>,
    /// Texture coordinates of each corner of each body triangle (parallel to `triangles`):
    /// exact across UV seams.
    pub triangle_uvs: Vec<[Vec2; 3]>,
    pub helpers: Vec<HelperGroup>,
    /// Vertex groups used by joint placements are resolved at import; bones here.
    pub bones: Vec<Bone>,
    /// Per body vertex: up to 4 bone indices and weights, largest first (weights sum to 1;
    /// unused slots have bone 0 and weight 0).
    pub skin_joints: Vec<[u16; 4]>,
    pub skin_weights: Vec<[f32; 4]>,
    /// The same for the helper vertices (`body_vertex_count..positions.len()`, in order), so
    /// that tights, skirt and hair can follow the body.
    pub helper_skin_joints: Vec<[u16; 4]>,
    pub helper_skin_weights: Vec<[f32; 4]>,
    pub targets: Vec<MorphTarget>,
}

impl BodyModel {
    /// Index of the bone called `name`.
    pub fn bone_index(&self, name: &str) -> Option<usize> {
        self.bones.iter().position(|b| b.name == name)
    }

    /// Whether `bone` is `ancestor` or hangs below it in the rig (turning `ancestor` carries
    /// it). An index outside the rig descends from nothing.
    pub fn descends_from(&self, mut bone: usize, ancestor: usize) -> bool {
        loop {
            if bone == ancestor {
                return bone < self.bones.len();
            }
            match self.bones.get(bone).and_then(|b| b.parent) {
                Some(p) => bone = p,
                None => return false,
            }
        }
    }

    /// Index of the morph target called `name` (e.g. `arms/measure-lowerarm-length-incr`).
    pub fn target_index(&self, name: &str) -> Option<usize> {
        self.targets.iter().position(|t| t.name == name)
    }

    /// Model space to a body standing in sensor space: facing the sensor
    /// ([`MODEL_TO_SENSOR`]), its soles (the lowest body vertex of `positions`, the model's or
    /// a shaped body's) at `y = 0` below the origin. Add the spot it stands on.
    pub fn standing_in_sensor_space(&self, positions: &[Vec3]) -> Affine3A {
        let body = (self.body_vertex_count as usize).min(positions.len());
        let sole = positions[..body]
            .iter()
            .map(|p| p.y)
            .fold(f32::INFINITY, f32::min);
        let sole = if sole.is_finite() { sole } else { 0.0 };
        Affine3A::from_quat(MODEL_TO_SENSOR) * Affine3A::from_translation(-Vec3::Y * sole)
    }

    /// Number of vertices in the whole mesh (body and helpers).
    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }

    /// Checks every index and length the rest of the crate relies on, so that a model read
    /// from a file cannot make later code panic. Returns what is wrong, naming the field.
    pub fn validate(&self) -> Result<(), String> {
        let n = self.positions.len();
        let body = self.body_vertex_count as usize;
        if body > n {
            return Err(format!(
                "body_vertex_count {body} exceeds the {n} positions"
            ));
        }
        if let Some(i) = self.positions.iter().position(|p| !p.is_finite()) {
            return Err(format!("positions[{i}] is not finite"));
        }
        if let Some(i) = self
            .triangles
            .iter()
            .position(|t| t.iter().any(|&v| v as usize >= body))
        {
            return Err(format!(
                "triangles[{i}] = {:?} indexes past the {body} body vertices",
                self.triangles[i]
            ));
        }
        if self.uvs.len() != body {
            return Err(format!(
                "uvs has {} entries, expected one per body vertex ({body})",
                self.uvs.len()
            ));
        }
        if self.triangle_uvs.len() != self.triangles.len() {
            return Err(format!(
                "triangle_uvs has {} entries, expected one per triangle ({})",
                self.triangle_uvs.len(),
                self.triangles.len()
            ));
        }
        for h in &self.helpers {
            if h.first_vertex > h.last_vertex || h.last_vertex as usize >= n {
                return Err(format!(
                    "helper '{}' has vertex range {}..={} outside 0..{n}",
                    h.name, h.first_vertex, h.last_vertex
                ));
            }
            if h.triangles.iter().flatten().any(|&v| v as usize >= n) {
                return Err(format!(
                    "helper '{}' has a triangle indexing past the {n} vertices",
                    h.name
                ));
            }
        }
        for (i, b) in self.bones.iter().enumerate() {
            if let Some(p) = b.parent
                && p >= i
            {
                return Err(format!(
                    "bone '{}' (#{i}) has parent #{p}, which does not come before it",
                    b.name
                ));
            }
            for (end, placement) in [("head", &b.head_placement), ("tail", &b.tail_placement)] {
                placement
                    .check(n, 0)
                    .map_err(|e| format!("bone '{}' {end}: {e}", b.name))?;
            }
            if !b.roll.is_finite() {
                return Err(format!("bone '{}' roll is not finite", b.name));
            }
        }
        let bones = self.bones.len();
        for (field, joints, weights, expected) in [
            ("skin", &self.skin_joints, &self.skin_weights, body),
            (
                "helper_skin",
                &self.helper_skin_joints,
                &self.helper_skin_weights,
                n - body,
            ),
        ] {
            if joints.len() != expected || weights.len() != expected {
                return Err(format!(
                    "{field}_joints/{field}_weights have {}/{} entries, expected {expected}",
                    joints.len(),
                    weights.len()
                ));
            }
            if let Some(i) = joints
                .iter()
                .position(|j| j.iter().any(|&b| b as usize >= bones))
            {
                return Err(format!(
                    "{field}_joints[{i}] = {:?} names a bone past the {bones} bones",
                    joints[i]
                ));
            }
            if let Some(i) = weights
                .iter()
                .position(|w| w.iter().any(|x| !x.is_finite()))
            {
                return Err(format!("{field}_weights[{i}] is not finite"));
            }
        }
        for t in &self.targets {
            if t.indices.len() != t.deltas.len() {
                return Err(format!(
                    "target '{}' has {} indices but {} deltas",
                    t.name,
                    t.indices.len(),
                    t.deltas.len()
                ));
            }
            if t.indices.windows(2).any(|w| w[0] >= w[1]) {
                return Err(format!(
                    "target '{}' indices are not strictly increasing",
                    t.name
                ));
            }
            if let Some(&i) = t.indices.iter().find(|&&i| i as usize >= n) {
                return Err(format!(
                    "target '{}' moves vertex {i}, past the {n} vertices",
                    t.name
                ));
            }
            if !t.scale_m.is_finite() || t.scale_m < 0.0 {
                return Err(format!("target '{}' scale_m is {}", t.name, t.scale_m));
            }
        }
        Ok(())
    }
}

impl JointPlacement {
    /// Deepest nesting of [`JointPlacement::Lerp`] accepted by [`BodyModel::validate`].
    pub const MAX_DEPTH: usize = 8;

    fn check(&self, vertex_count: usize, depth: usize) -> Result<(), String> {
        if depth > Self::MAX_DEPTH {
            return Err(format!("placement nested deeper than {}", Self::MAX_DEPTH));
        }
        match self {
            JointPlacement::Mean(v) if v.is_empty() => Err("mean of no vertices".into()),
            JointPlacement::Mean(v) => match v.iter().find(|&&i| i as usize >= vertex_count) {
                Some(i) => Err(format!("vertex {i} past the {vertex_count} vertices")),
                None => Ok(()),
            },
            JointPlacement::Vertex(i) if *i as usize >= vertex_count => {
                Err(format!("vertex {i} past the {vertex_count} vertices"))
            }
            JointPlacement::Vertex(_) => Ok(()),
            JointPlacement::Lerp { from, to, t } => {
                if !t.is_finite() {
                    return Err("lerp fraction is not finite".into());
                }
                from.check(vertex_count, depth + 1)?;
                to.check(vertex_count, depth + 1)
            }
        }
    }

    /// The position of this bone end on a mesh with the given vertex positions.
    ///
    /// `positions` must hold every vertex the placement names (the whole base mesh, helpers
    /// included: joint cubes are helper vertices); [`BodyModel::validate`] checks this for the
    /// model's own vertex count.
    pub fn resolve(&self, positions: &[Vec3]) -> Vec3 {
        match self {
            JointPlacement::Mean(v) => {
                let sum: Vec3 = v.iter().map(|&i| positions[i as usize]).sum();
                sum / v.len().max(1) as f32
            }
            JointPlacement::Vertex(i) => positions[*i as usize],
            JointPlacement::Lerp { from, to, t } => {
                from.resolve(positions).lerp(to.resolve(positions), *t)
            }
        }
    }
}
