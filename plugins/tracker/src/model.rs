//! The body the tracker fits to depth: the MakeHuman rig with the body's own tapered capsules
//! (the cloth's colliders, [`BodyColliders`], fitted to the skin rather than inset), posed by a
//! root transform (rotation, translation, one uniform scale for the person's size) and local
//! bone rotations. Only the bones that shape the silhouette move ([`TRACKED`]); elbows and
//! knees are hinges; the rest keep their rest pose relative to their parent.
//!
//! A capsule is round about its axis, so a limb's twist is invisible to depth: it is left
//! where the damping keeps it and only matters for the orientations reported.

use fitroom_body::colliders::{BodyColliders, ColliderOptions};
use fitroom_body::{BodyModel, MODEL_TO_SENSOR, RigidTransform, compute_normals};
use fitroom_sensor::KinectJoint;
use glam::{Affine3A, Quat, Vec3};
use serde::Serialize;

use crate::kinect::{DRIVER_BONES, JOINT_BONES, head_joint};
use crate::surface::BoneSurface;

/// How a tracked bone may turn relative to its parent.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum JointKind {
    /// Any rotation within `max_angle` of rest.
    Ball,
    /// About one bone-local axis only, from `min` to `max` radians (positive bends the limb:
    /// the knee backwards, the elbow forwards).
    Hinge { axis: Vec3, min: f32, max: f32 },
}

/// A bone the fit moves.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrackedJoint {
    pub bone: usize,
    pub kind: JointKind,
    /// Largest rotation from rest, radians.
    pub max_angle: f32,
    /// Largest twist about the bone's own axis, radians: a round capsule shows no twist, and
    /// an untwisted thigh keeps the knee from bending sideways under a skirt.
    pub max_twist: f32,
    /// How strongly a step of this bone is damped (relative to the fit's base damping):
    /// bones the depth sees poorly (the clavicle, the hand) move reluctantly.
    pub stiffness: f32,
}

/// A tapered capsule bound to a bone: ends in the bone's rest frame, radii in metres at the
/// model's scale.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Capsule {
    pub bone: usize,
    pub a: Vec3,
    pub b: Vec3,
    pub radius_a: f32,
    pub radius_b: f32,
}

/// The tracked bones: (name, ball or hinge, largest angle and largest twist in degrees,
/// stiffness).
const TRACKED: [(&str, bool, f32, f32, f32); 18] = [
    ("spine_01", false, 40.0, 30.0, 2.0),
    ("spine_03", false, 40.0, 30.0, 2.0),
    ("neck_01", false, 60.0, 60.0, 2.0),
    ("clavicle_l", false, 20.0, 10.0, 8.0),
    ("upperarm_l", false, 180.0, 90.0, 1.0),
    ("lowerarm_l", true, 150.0, 0.0, 1.0),
    ("hand_l", false, 70.0, 45.0, 4.0),
    ("clavicle_r", false, 20.0, 10.0, 8.0),
    ("upperarm_r", false, 180.0, 90.0, 1.0),
    ("lowerarm_r", true, 150.0, 0.0, 1.0),
    ("hand_r", false, 70.0, 45.0, 4.0),
    ("thigh_l", false, 130.0, 30.0, 1.0),
    ("calf_l", true, 150.0, 0.0, 1.0),
    ("foot_l", false, 50.0, 20.0, 3.0),
    ("thigh_r", false, 130.0, 30.0, 1.0),
    ("calf_r", true, 150.0, 0.0, 1.0),
    ("foot_r", false, 50.0, 20.0, 3.0),
    // Stiff: the lower back bends with spine_01. (The head is not turned on its own: a
    // sphere shows no nod, and the Kinect's head joint follows the neck.)
    ("spine_02", false, 15.0, 15.0, 6.0),
];

/// The trunk's bones: the forearms and hands are kept out of their skin.
pub const TRUNK_BONES: [&str; 4] = ["pelvis", "spine_01", "spine_02", "spine_03"];

/// The bones a shirt covers: the trunk, the clavicles and the upper arms (the clothing layer
/// of [`TrackBody::clothe`] and of the measurement's fit).
pub const CLOTHED_BONES: [&str; 8] = [
    "pelvis",
    "spine_01",
    "spine_02",
    "spine_03",
    "clavicle_l",
    "clavicle_r",
    "upperarm_l",
    "upperarm_r",
];

/// Per body vertex of `model`, whether a shirt covers it: its dominant bone is one of
/// [`CLOTHED_BONES`].
pub fn clothed_vertices(model: &BodyModel) -> Vec<bool> {
    let bones: Vec<usize> = CLOTHED_BONES
        .iter()
        .filter_map(|name| model.bone_index(name))
        .collect();
    model
        .skin_joints
        .iter()
        .zip(&model.skin_weights)
        .take(model.body_vertex_count as usize)
        .map(|(j, w)| w[0] > 0.0 && bones.contains(&usize::from(j[0])))
        .collect()
}

/// Why a body cannot be tracked.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ModelError {
    #[error("the rig has no bone `{0}`, which the tracker needs")]
    MissingBone(String),
    #[error("the body's capsules: {0}")]
    Colliders(String),
}

/// The rig and capsules of one body, ready to pose.
#[derive(Clone, Debug)]
pub struct TrackBody {
    pub parents: Vec<Option<usize>>,
    /// Per bone: the rest transform from its parent's frame (for a root, from model space).
    offsets: Vec<RigidTransform>,
    pub capsules: Vec<Capsule>,
    /// Per bone, its skin in its rest frame (empty for bones without capsules).
    pub surfaces: Vec<BoneSurface>,
    pub joints: Vec<TrackedJoint>,
    /// Per bone: the tracked joints on its chain (itself and its ancestors), root first.
    pub chains: Vec<Vec<usize>>,
    /// Per Kinect joint: the bone and the point in its frame.
    pub kinect: [(usize, Vec3); KinectJoint::COUNT],
    /// Per Kinect joint: the bone that turns the Kinect bone ending there.
    pub drivers: [usize; KinectJoint::COUNT],
    /// The bone at the root of the rig (the pelvis).
    pub root: usize,
    /// The bones a shirt covers ([`CLOTHED_BONES`]), for [`TrackBody::clothe`].
    pub clothed: Vec<usize>,
    /// The trunk's bones ([`TRUNK_BONES`]), which the arms may not pass into.
    pub trunk: Vec<usize>,
    /// The clothing layer [`TrackBody::clothe`] put on, metres (0: bare).
    pub layer_m: f32,
    /// Sole to the top of the head, metres.
    pub height_m: f32,
    /// The lowest body vertex's model-space height (the soles).
    pub sole_y: f32,
    /// Rest world rotations of the drivers when the body stands facing the sensor.
    pub rest_driver_rotations: [Quat; KinectJoint::COUNT],
}

/// A pose of a [`TrackBody`] in sensor space: `x -> translation + rotation * (scale * x)`
/// takes the model's space to the sensor's, the bones turn by `local` from rest.
#[derive(Clone, Debug, PartialEq)]
pub struct Pose {
    pub rotation: Quat,
    pub translation: Vec3,
    pub scale: f32,
    pub local: Vec<Quat>,
}

impl Pose {
    pub fn is_finite(&self) -> bool {
        self.rotation.is_finite()
            && self.translation.is_finite()
            && self.scale.is_finite()
            && self.local.iter().all(|q| q.is_finite())
    }
}

/// A pose evaluated: each bone's frame in sensor space (bone-local to sensor, with the
/// scale), its world rotation, and the capsules in sensor space.
#[derive(Clone, Debug, Default)]
pub struct Posed {
    pub frames: Vec<Affine3A>,
    pub rotations: Vec<Quat>,
    /// `(a, b, radius_a, radius_b)` per capsule, sensor space, metres.
    pub capsules: Vec<(Vec3, Vec3, f32, f32)>,
}

impl Posed {
    /// Where bone `bone`'s head is, sensor space.
    pub fn head(&self, bone: usize) -> Vec3 {
        self.frames[bone].translation.into()
    }
}

impl TrackBody {
    /// This body with a layer of clothing `t` metres thick on the bones a shirt covers
    /// ([`CLOTHED_BONES`]): their skin moved out along its normals, their capsules' radii
    /// grown.
    pub fn clothe(&mut self, t: f32) {
        if t <= 0.0 {
            return;
        }
        self.layer_m += t;
        for &b in &self.clothed {
            if let Some(s) = self.surfaces.get(b) {
                let points = s
                    .points
                    .iter()
                    .zip(&s.normals)
                    .map(|(p, n)| *p + *n * t)
                    .collect();
                self.surfaces[b] = BoneSurface::new(points, s.normals.clone());
            }
            for c in self.capsules.iter_mut().filter(|c| c.bone == b) {
                c.radius_a += t;
                c.radius_b += t;
            }
        }
    }

    /// The tracker's body from a (shaped) MakeHuman body: all of its vertex `positions`.
    pub fn new(model: &BodyModel, positions: &[Vec3]) -> Result<Self, ModelError> {
        let bone = |name: &str| {
            model
                .bone_index(name)
                .ok_or_else(|| ModelError::MissingBone(name.to_string()))
        };
        if positions.len() < model.positions.len() {
            return Err(ModelError::Colliders(format!(
                "{} vertex positions for a model of {}",
                positions.len(),
                model.positions.len()
            )));
        }
        let rest = model.rest_pose(positions);
        let globals = rest.global_transforms();
        let parents: Vec<Option<usize>> = model
            .bones
            .iter()
            .enumerate()
            .map(|(i, b)| b.parent.filter(|&p| p < i))
            .collect();
        let offsets: Vec<RigidTransform> = (0..globals.len())
            .map(|i| match parents[i] {
                Some(p) => globals[p].inverse() * globals[i],
                None => globals[i],
            })
            .collect();
        // Capsules on the skin: the radius is the median distance of the bone's skin from its
        // axis (the cloth's colliders sit inside the skin; these should touch it).
        let options = ColliderOptions {
            radius_percentile: 0.5,
            inset_m: 0.0,
        };
        let colliders = BodyColliders::fit(model, positions, &rest, &options)
            .map_err(|e| ModelError::Colliders(e.to_string()))?;
        let body_vertices = (model.body_vertex_count as usize).min(positions.len());
        let mut rest_capsules: Vec<Capsule> = colliders
            .capsules
            .iter()
            .map(|c| Capsule {
                bone: c.bone,
                a: c.a,
                b: c.b,
                radius_a: c.radius_a,
                radius_b: c.radius_b,
            })
            .collect();
        // Each skin vertex belongs to the capsules of its dominant bone (or of the nearest
        // ancestor that has capsules: the fingers to the hand).
        let has_capsule = |b: usize| rest_capsules.iter().any(|c| c.bone == b);
        let owners: Vec<Option<usize>> = (0..body_vertices)
            .map(|v| {
                let (j, w) = (model.skin_joints.get(v)?, model.skin_weights.get(v)?);
                let mut best = 0;
                for k in 1..4 {
                    if w[k] > w[best] {
                        best = k;
                    }
                }
                let mut at = Some(j[best] as usize);
                while let Some(b) = at {
                    if has_capsule(b) {
                        return Some(b);
                    }
                    at = parents.get(b).copied().flatten();
                }
                None
            })
            .collect();
        fit_to_skin(&mut rest_capsules, &positions[..body_vertices], &owners);
        let normals = compute_normals(&positions[..body_vertices], &model.triangles);
        let mut skin: Vec<(Vec<Vec3>, Vec<Vec3>)> = vec![Default::default(); globals.len()];
        for (v, owner) in owners.iter().enumerate() {
            if let (Some(b), Some(n)) = (*owner, normals.get(v)) {
                skin[b]
                    .0
                    .push(globals[b].inverse_transform_point(positions[v]));
                skin[b]
                    .1
                    .push((globals[b].rotation.inverse() * *n).normalize_or_zero());
            }
        }
        let surfaces = skin
            .into_iter()
            .map(|(points, normals)| BoneSurface::new(points, normals))
            .collect();
        let capsules = rest_capsules
            .iter()
            .map(|c| Capsule {
                a: globals[c.bone].inverse_transform_point(c.a),
                b: globals[c.bone].inverse_transform_point(c.b),
                ..*c
            })
            .collect();
        let facing = Vec3::Z; // model space: the body faces +Z
        let mut joints = Vec::new();
        for (name, hinge, max_deg, twist_deg, stiffness) in TRACKED {
            let b = bone(name)?;
            let kind = if hinge {
                // The hinge axis: the bone-local axis (X or Z) about which a bend moves the
                // limb's end most along the facing direction; its sign so that a positive
                // bend takes the knee's end backwards and the elbow's forwards.
                let tail = globals[b].inverse_transform_point(rest.tails[b]);
                let mut best = (Vec3::X, 0.0f32);
                for axis in [Vec3::X, Vec3::Z] {
                    let turned = Quat::from_axis_angle(axis, 0.3) * tail - tail;
                    let along = (globals[b].rotation * turned).dot(facing);
                    if along.abs() > best.1.abs() {
                        best = (axis, along);
                    }
                }
                let forwards = name.starts_with("lowerarm");
                let axis = if (best.1 > 0.0) == forwards {
                    best.0
                } else {
                    -best.0
                };
                JointKind::Hinge {
                    axis,
                    min: -5f32.to_radians(),
                    max: max_deg.to_radians(),
                }
            } else {
                JointKind::Ball
            };
            joints.push(TrackedJoint {
                bone: b,
                kind,
                max_angle: max_deg.to_radians(),
                max_twist: twist_deg.to_radians(),
                stiffness,
            });
        }
        let chains = (0..parents.len())
            .map(|b| {
                let mut chain = Vec::new();
                let mut at = Some(b);
                while let Some(i) = at {
                    if let Some(j) = joints.iter().position(|j| j.bone == i) {
                        chain.push(j);
                    }
                    at = parents[i];
                }
                chain.reverse();
                chain
            })
            .collect();
        let mut kinect = [(0usize, Vec3::ZERO); KinectJoint::COUNT];
        for (k, (joint, name)) in JOINT_BONES.iter().enumerate() {
            let b = bone(name)?;
            let mut local = Vec3::ZERO;
            if *joint == KinectJoint::Head {
                let neck = rest.heads[bone("neck_01")?];
                let up = head_joint(rest.heads[b], neck) - rest.heads[b];
                local = globals[b].rotation.inverse() * up;
            }
            kinect[k] = (b, local);
        }
        let mut drivers = [0usize; KinectJoint::COUNT];
        let mut rest_driver_rotations = [Quat::IDENTITY; KinectJoint::COUNT];
        for (k, name) in DRIVER_BONES.iter().enumerate() {
            drivers[k] = bone(name)?;
            rest_driver_rotations[k] = (MODEL_TO_SENSOR * globals[drivers[k]].rotation).normalize();
        }
        let body = (model.body_vertex_count as usize).min(positions.len());
        let (lo, hi) = positions[..body]
            .iter()
            .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), p| {
                (lo.min(p.y), hi.max(p.y))
            });
        let root = parents.iter().position(|p| p.is_none()).unwrap_or(0);
        Ok(Self {
            parents,
            offsets,
            capsules,
            surfaces,
            joints,
            chains,
            kinect,
            drivers,
            root: bone("pelvis").unwrap_or(root),
            clothed: CLOTHED_BONES
                .iter()
                .filter_map(|name| model.bone_index(name))
                .collect(),
            trunk: TRUNK_BONES
                .iter()
                .filter_map(|name| model.bone_index(name))
                .collect(),
            layer_m: 0.0,
            height_m: (hi - lo).max(0.1),
            sole_y: if lo.is_finite() { lo } else { 0.0 },
            rest_driver_rotations,
        })
    }

    /// The rest pose standing facing the sensor with its soles at `spot` (sensor space), at
    /// `scale`.
    pub fn standing(&self, spot: Vec3, scale: f32) -> Pose {
        let rotation = MODEL_TO_SENSOR;
        Pose {
            rotation,
            translation: spot - rotation * (Vec3::Y * self.sole_y * scale),
            scale,
            local: vec![Quat::IDENTITY; self.parents.len()],
        }
    }

    /// How high above the floor (`up`, through `floor_point`) the top of `posed`'s outline
    /// lies as the sensor (at the origin) sees it, and the bone that skin is on: the highest
    /// skin facing the sensor. Seen from a sensor at chest height, the top of the head's
    /// outline lies on the forehead's slope, about a centimetre under the crown at 3 m; the
    /// person's highest reading lies a little under the outline (its edge pixels drop out):
    /// on five MakeHuman builds at rest at 2.6 and 3.2 m, 0.0-0.4 % of the height under it on
    /// noisy synthetic frames. (Not tested for occlusion: a standing person's top is seen.)
    pub fn seen_top(&self, posed: &Posed, floor_point: Vec3, up: Vec3) -> Option<(f32, usize)> {
        let mut top: Option<(f32, usize)> = None;
        for (b, surface) in self.surfaces.iter().enumerate() {
            let (Some(frame), Some(&turn)) = (posed.frames.get(b), posed.rotations.get(b)) else {
                continue;
            };
            for (&point, &normal) in surface.points.iter().zip(&surface.normals) {
                let p = frame.transform_point3(point);
                let h = (p - floor_point).dot(up);
                if top.is_none_or(|(t, _)| h > t) && (turn * normal).dot(p) < 0.0 {
                    top = Some((h, b));
                }
            }
        }
        top
    }

    /// [`Self::seen_top`] of the rest pose at scale 1 standing on the floor at `spot` (its up
    /// `up`); the body's height if no skin qualifies.
    pub fn rest_seen_top(&self, spot: Vec3, up: Vec3) -> f32 {
        let pose = self.standing_on(spot, up, 1.0);
        self.seen_top(&self.pose(&pose), spot, up)
            .map_or(self.height_m, |(h, _)| h)
    }

    /// The rest pose facing the sensor, at `scale`, standing with its soles at `spot` on a
    /// floor whose up is `up` (sensor space).
    pub fn standing_on(&self, spot: Vec3, up: Vec3, scale: f32) -> Pose {
        let mut pose = self.standing(Vec3::ZERO, scale);
        pose.rotation = (Quat::from_rotation_arc(Vec3::Y, up) * pose.rotation).normalize();
        pose.translation = spot - pose.rotation * (Vec3::Y * self.sole_y * scale);
        pose
    }

    /// Evaluates `pose` into `out` (its storage reused).
    pub fn pose_into(&self, pose: &Pose, out: &mut Posed) {
        let n = self.parents.len();
        out.frames.clear();
        out.rotations.clear();
        // Model-space rigid frames first, then the root transform on top.
        let mut model: Vec<RigidTransform> = Vec::with_capacity(n);
        for i in 0..n {
            let local = RigidTransform::new(
                pose.local.get(i).copied().unwrap_or(Quat::IDENTITY),
                Vec3::ZERO,
            );
            let g = match self.parents[i] {
                Some(p) => model[p] * self.offsets[i] * local,
                None => self.offsets[i] * local,
            };
            model.push(g);
            let rotation = (pose.rotation * g.rotation).normalize();
            out.rotations.push(rotation);
            out.frames.push(Affine3A::from_scale_rotation_translation(
                Vec3::splat(pose.scale),
                rotation,
                pose.translation + pose.rotation * (g.translation * pose.scale),
            ));
        }
        out.capsules.clear();
        out.capsules.extend(self.capsules.iter().map(|c| {
            let f = out.frames[c.bone];
            (
                f.transform_point3(c.a),
                f.transform_point3(c.b),
                c.radius_a * pose.scale,
                c.radius_b * pose.scale,
            )
        }));
    }

    pub fn pose(&self, pose: &Pose) -> Posed {
        let mut out = Posed::default();
        self.pose_into(pose, &mut out);
        out
    }

    /// The 20 Kinect joints of a posed body, sensor space, in [`KinectJoint::ALL`] order.
    pub fn kinect_joints(&self, posed: &Posed) -> [Vec3; KinectJoint::COUNT] {
        let mut out = [Vec3::ZERO; KinectJoint::COUNT];
        for (k, (bone, local)) in self.kinect.iter().enumerate() {
            out[k] = posed.frames[*bone].transform_point3(*local);
        }
        out
    }

    /// The world rotation by which each Kinect bone's driver has turned from the rest pose
    /// facing the sensor (for the skeleton frame's orientations).
    pub fn driver_turns(&self, posed: &Posed) -> [Quat; KinectJoint::COUNT] {
        let mut out = [Quat::IDENTITY; KinectJoint::COUNT];
        for (k, turn) in out.iter_mut().enumerate() {
            *turn = (posed.rotations[self.drivers[k]] * self.rest_driver_rotations[k].inverse())
                .normalize();
        }
        out
    }

    /// Clamps each tracked joint's rotation to its kind and range.
    pub fn clamp(&self, pose: &mut Pose) {
        for joint in &self.joints {
            let Some(q) = pose.local.get_mut(joint.bone) else {
                continue;
            };
            let mut r = q.normalize();
            if !r.is_finite() {
                r = Quat::IDENTITY;
            }
            match joint.kind {
                JointKind::Hinge { axis, min, max } => {
                    // The rotation's component about the hinge axis, clamped.
                    let v = Vec3::new(r.x, r.y, r.z);
                    let angle = 2.0 * v.dot(axis).atan2(r.w);
                    let angle = wrap(angle).clamp(min, max);
                    r = Quat::from_axis_angle(axis, angle);
                }
                JointKind::Ball => {
                    // Twist about the bone's axis (+Y) first (swing-twist decomposition),
                    // then the whole turn.
                    let twist = Quat::from_xyzw(0.0, r.y, 0.0, r.w).normalize();
                    if twist.is_finite() {
                        let angle = wrap(2.0 * twist.y.atan2(twist.w));
                        if angle.abs() > joint.max_twist {
                            let swing = r * twist.inverse();
                            r = (swing * Quat::from_rotation_y(joint.max_twist * angle.signum()))
                                .normalize();
                        }
                    }
                    let (axis, angle) = r.to_axis_angle();
                    let angle = wrap(angle);
                    if angle.abs() > joint.max_angle {
                        r = Quat::from_axis_angle(axis, joint.max_angle * angle.signum());
                    }
                }
            }
            *q = r;
        }
    }
}

/// Fits the capsules' radii (and a sphere's centre) to the skin: each vertex belongs to
/// its nearest capsule, and each capsule's end radii are the least-squares solution of
/// `|v - axis(t)| = r_a (1 - t) + r_b t` over its vertices; three rounds, as the vertices
/// change hands. The cloth's colliders start it (they sit inside the skin by design; the
/// tracker's model must lie on it, or every joint would sit too near the camera).
fn fit_to_skin(capsules: &mut [Capsule], vertices: &[Vec3], owners: &[Option<usize>]) {
    for _ in 0..3 {
        // Per capsule: normal equations of (r_a, r_b), and for spheres the sums of the
        // algebraic sphere fit.
        let mut normal = vec![[0.0f64; 5]; capsules.len()];
        let mut sphere = vec![(Vec3::ZERO, 0usize); capsules.len()];
        let mut owner = Vec::with_capacity(vertices.len());
        for (&v, owner_bone) in vertices.iter().zip(owners) {
            let Some(bone) = *owner_bone else {
                owner.push(usize::MAX);
                continue;
            };
            let mut best = (f32::INFINITY, usize::MAX, 0.0f32, 0.0f32);
            for (k, c) in capsules.iter().enumerate() {
                if c.bone != bone {
                    continue;
                }
                let ab = c.b - c.a;
                let l2 = ab.length_squared();
                let t = if l2 > 1e-12 {
                    ((v - c.a).dot(ab) / l2).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                let len = v.distance(c.a + ab * t);
                let d = len - (c.radius_a + (c.radius_b - c.radius_a) * t);
                if d.abs() < best.0.abs() {
                    best = (d, k, t, len);
                }
            }
            let (_, k, t, len) = best;
            owner.push(k);
            if k == usize::MAX {
                continue;
            }
            let (t, len) = (f64::from(t), f64::from(len));
            let n = &mut normal[k];
            n[0] += (1.0 - t) * (1.0 - t);
            n[1] += (1.0 - t) * t;
            n[2] += t * t;
            n[3] += (1.0 - t) * len;
            n[4] += t * len;
            sphere[k].0 += v;
            sphere[k].1 += 1;
        }
        for (k, c) in capsules.iter_mut().enumerate() {
            if c.a.distance_squared(c.b) < 1e-10 {
                // A sphere: centre at its vertices' centroid moved back onto the fit, radius
                // their mean distance from it.
                let (sum, count) = sphere[k];
                if count < 20 {
                    continue;
                }
                let centroid = sum / count as f32;
                let mut r = 0.0f32;
                for (v, _) in vertices.iter().zip(&owner).filter(|(_, o)| **o == k) {
                    r += v.distance(centroid);
                }
                c.a = centroid;
                c.b = centroid;
                c.radius_a = r / count as f32;
                c.radius_b = c.radius_a;
                continue;
            }
            let [aa, ab, bb, ya, yb] = normal[k];
            let det = aa * bb - ab * ab;
            if aa + bb < 20.0 || det.abs() < 1e-9 {
                continue;
            }
            let ra = (ya * bb - yb * ab) / det;
            let rb = (aa * yb - ab * ya) / det;
            if ra.is_finite() && rb.is_finite() {
                c.radius_a = (ra as f32).clamp(0.01, 0.25);
                c.radius_b = (rb as f32).clamp(0.01, 0.25);
            }
        }
    }
}

/// An angle in (-π, π].
fn wrap(a: f32) -> f32 {
    let mut a = a % std::f32::consts::TAU;
    if a > std::f32::consts::PI {
        a -= std::f32::consts::TAU;
    } else if a <= -std::f32::consts::PI {
        a += std::f32::consts::TAU;
    }
    a
}
