//! The body the fit moves: a MakeHuman shape (the sliders of [`fitroom_body::fit::Param`], the
//! same ones the fit to typed-in measurements uses), posed by the rig's local rotations and
//! placed in sensor space by a rotation about its pelvis and the pelvis' position; and how its
//! skin moves with each slider.

use fitroom_body::fit::{Param, REGIONS, SLIDERS};
use fitroom_body::{
    BodyModel, RestPose, RigidTransform, Shape, ShapeError, forward_kinematics, skin_positions,
};
use glam::{Quat, Vec3};

use fitroom_sensor::KinectJoint;
use fitroom_tracker::kinect::rig_joints;

use crate::MeasureError;

/// The sliders the fit moves and the rest of the shape (age, ethnicity), which it does not.
#[derive(Clone, Debug)]
pub struct ShapeSpace {
    pub params: Vec<Param>,
    pub base: Shape,
}

impl ShapeSpace {
    /// Gender, the four other macros, the `measure-*` sliders and the region scales: every
    /// slider the fit to measurements may use, and gender (the camera does not know it).
    pub fn full() -> Self {
        let mut params = vec![
            Param::Gender,
            Param::Height,
            Param::Weight,
            Param::Muscle,
            Param::Proportions,
        ];
        params.extend(SLIDERS.iter().map(|&s| Param::Slider(s)));
        params.extend(REGIONS.iter().map(|&s| Param::Region(s)));
        Self {
            params,
            base: Shape::default(),
        }
    }

    pub fn len(&self) -> usize {
        self.params.len()
    }

    pub fn is_empty(&self) -> bool {
        self.params.is_empty()
    }

    /// The shape of slider values `x` (parallel to [`Self::params`]).
    pub fn shape(&self, x: &[f32]) -> Shape {
        let mut shape = self.base.clone();
        for (p, &v) in self.params.iter().zip(x) {
            p.set(&mut shape, v);
        }
        shape
    }

    /// The slider values of `shape`.
    pub fn values(&self, shape: &Shape) -> Vec<f32> {
        self.params.iter().map(|p| p.get(shape)).collect()
    }

    /// Every slider at rest (MakeHuman's default body).
    pub fn rest(&self) -> Vec<f32> {
        self.params.iter().map(|p| p.rest()).collect()
    }
}

/// Where the body stands: its rotation (model space to sensor space) and its pelvis (the
/// root bone's head) in sensor space. Anchoring the pelvis keeps a change of shape from
/// moving the whole body (a taller body grows up and down from the hips).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placement {
    pub rotation: Quat,
    pub pelvis: Vec3,
}

impl Placement {
    /// `by` rotated about the pelvis (sensor-space rotation vector, radians) and moved.
    pub fn moved(&self, turn: Vec3, shift: Vec3) -> Self {
        Self {
            rotation: (Quat::from_scaled_axis(turn) * self.rotation).normalize(),
            pelvis: self.pelvis + shift,
        }
    }
}

/// A shape, morphed and posed.
#[derive(Clone, Debug)]
pub struct PosedBody {
    /// The target weights of the shape.
    pub weights: Vec<(usize, f32)>,
    /// The morphed mesh at rest (all vertices, helpers included), model space.
    pub positions: Vec<Vec3>,
    pub rest: RestPose,
    /// The body's vertices posed, sensor space.
    pub vertices: Vec<Vec3>,
}

/// Poses shapes of one model in one pose.
#[derive(Clone, Debug)]
pub struct Posing<'a> {
    pub model: &'a BodyModel,
    /// Per bone, its rotation from rest (as [`forward_kinematics`] takes them).
    pub locals: Vec<Quat>,
    root: usize,
}

/// Forward-difference steps of the sliders (the macros span 0..1, the others -1..1).
fn step(p: Param) -> f32 {
    match p {
        Param::Slider(_) | Param::Region(_) => 0.05,
        _ => 0.025,
    }
}

impl<'a> Posing<'a> {
    pub fn new(model: &'a BodyModel, locals: Vec<Quat>) -> Self {
        // The pelvis (the tracker's root and the Kinect hip centre); the rig's first root
        // bone (MakeHuman's game rig has one at the floor) if it has none.
        let root = model
            .bone_index("pelvis")
            .or_else(|| model.bones.iter().position(|b| b.parent.is_none()))
            .unwrap_or(0);
        Self {
            model,
            locals,
            root,
        }
    }

    /// This pose with bone `bone` turned by `turn` (a rotation vector in model space, about
    /// the bone's head) on top of its current turn.
    pub fn turned(&self, rest: &RestPose, bone: usize, turn: Vec3) -> Vec<Quat> {
        let mut locals = self.locals.clone();
        if bone >= locals.len() {
            return locals;
        }
        let globals = forward_kinematics(&self.model.bones, rest, &locals, Vec3::ZERO);
        let g = globals[bone].rotation;
        locals[bone] =
            (locals[bone] * (g.inverse() * Quat::from_scaled_axis(turn) * g)).normalize();
        locals
    }

    /// The heads of `bones` in this pose, placed by `placement` (sensor space): what a turn
    /// of each bone (as [`Self::turned`] makes it) turns the skin about.
    pub fn bone_heads(&self, rest: &RestPose, placement: &Placement, bones: &[usize]) -> Vec<Vec3> {
        let (globals, pelvis) = self.globals(rest);
        bones
            .iter()
            .map(|&b| {
                globals.get(b).map_or(placement.pelvis, |g| {
                    placement.pelvis + placement.rotation * (g.translation - pelvis)
                })
            })
            .collect()
    }

    /// `body` (its shape as it is) in this pose.
    pub fn repose(&self, body: &PosedBody, placement: &Placement) -> PosedBody {
        PosedBody {
            vertices: self.place(&body.positions, &body.rest, placement),
            ..body.clone()
        }
    }

    /// Each bone's transform in this pose (model space, the rig's root where the rig has it),
    /// and the pelvis's position among them: what placing anchors.
    fn globals(&self, rest: &RestPose) -> (Vec<RigidTransform>, Vec3) {
        let globals = forward_kinematics(&self.model.bones, rest, &self.locals, Vec3::ZERO);
        let pelvis = globals
            .get(self.root)
            .map(|g| g.translation)
            .unwrap_or(Vec3::ZERO);
        (globals, pelvis)
    }

    /// The body vertices of the morphed mesh `positions` (model space, at rest) posed and
    /// placed.
    fn place(&self, positions: &[Vec3], rest: &RestPose, placement: &Placement) -> Vec<Vec3> {
        let m = self.model;
        let (globals, pelvis) = self.globals(rest);
        let n = (m.body_vertex_count as usize).min(positions.len());
        let skinned = skin_positions(
            &positions[..n],
            &m.skin_joints,
            &m.skin_weights,
            rest,
            &globals,
        );
        skinned
            .into_iter()
            .map(|p| placement.pelvis + placement.rotation * (p - pelvis))
            .collect()
    }

    /// The 20 Kinect joints of `body` (posed and placed as [`Self::body`] made it), sensor
    /// space: the heads of the tracker's joint bones, the head joint above the skull's base.
    pub fn kinect_joints(
        &self,
        body: &PosedBody,
        placement: &Placement,
    ) -> [Vec3; KinectJoint::COUNT] {
        let m = self.model;
        let (globals, pelvis) = self.globals(&body.rest);
        rig_joints(m, &globals).map(|p| placement.pelvis + placement.rotation * (p - pelvis))
    }

    /// `shape` morphed, posed and placed.
    pub fn body(&self, shape: &Shape, placement: &Placement) -> Result<PosedBody, ShapeError> {
        let weights = shape.target_weights(self.model)?;
        let positions = self.model.apply_targets(&weights);
        Ok(self.body_of(weights, positions, placement))
    }

    /// The rest mesh `positions` (whole mesh: a shape's, whose target weights are `weights`,
    /// perhaps with detail no shape has) in this pose, placed.
    pub fn body_of(
        &self,
        weights: Vec<(usize, f32)>,
        positions: Vec<Vec3>,
        placement: &Placement,
    ) -> PosedBody {
        let rest = self.model.rest_pose(&positions);
        let vertices = self.place(&positions, &rest, placement);
        PosedBody {
            weights,
            positions,
            rest,
            vertices,
        }
    }

    /// Target weights as one weight per target of the model.
    pub fn dense_weights(&self, weights: &[(usize, f32)]) -> Vec<f32> {
        let mut dense = vec![0.0f32; self.model.targets.len()];
        for &(t, w) in weights {
            if let Some(d) = dense.get_mut(t) {
                *d += w;
            }
        }
        dense
    }

    /// The morphed rest mesh `positions` (of the shape `x`, whose dense target weights are
    /// `base`) with slider `k` stepped by its forward-difference step (inwards at its upper
    /// bound), and the step taken.
    pub fn stepped(
        &self,
        space: &ShapeSpace,
        x: &[f32],
        positions: &[Vec3],
        base: &[f32],
        k: usize,
    ) -> Result<(Vec<Vec3>, f32), MeasureError> {
        let p = space.params[k];
        let (lo, hi) = p.bounds();
        let h = step(p);
        let h = if x[k] + h > hi && x[k] - h >= lo {
            -h
        } else {
            h
        };
        let mut moved = x.to_vec();
        moved[k] += h;
        let weights = self.dense_weights(&space.shape(&moved).target_weights(self.model)?);
        let change: Vec<(usize, f32)> = weights
            .iter()
            .zip(base)
            .enumerate()
            .filter(|(_, (a, b))| a != b)
            .map(|(t, (a, b))| (t, a - b))
            .collect();
        let mut out = positions.to_vec();
        self.model.add_targets(&mut out, &change);
        Ok((out, h))
    }
}

/// Per body vertex (of `count`), per bone of `bones`, the vertex's skin weight that a
/// turn of the bone carries: its weight on the bone and on every bone below it.
/// Vertex-major (`[vertex * bones.len() + k]`); it depends on the rig only, not on a pose.
pub fn carried_weights(m: &BodyModel, bones: &[usize], count: usize) -> Vec<f32> {
    let carries: Vec<Vec<bool>> = bones
        .iter()
        .map(|&b| (0..m.bones.len()).map(|j| m.descends_from(j, b)).collect())
        .collect();
    let mut out = vec![0.0f32; count * bones.len()];
    for (v, (joints, weights)) in m
        .skin_joints
        .iter()
        .zip(&m.skin_weights)
        .take(count)
        .enumerate()
    {
        for (k, carried) in carries.iter().enumerate() {
            out[v * bones.len() + k] = joints
                .iter()
                .zip(weights)
                .filter(|(j, _)| carried.get(usize::from(**j)).copied().unwrap_or(false))
                .map(|(_, w)| w)
                .sum();
        }
    }
    out
}

/// How the posed vertices of the shape `x` move per unit of each slider of `space`, in each
/// of several poses: per pose, per vertex, its derivative along each slider (vertex-major:
/// `[vertex * space.len() + k]`, what a residual at a vertex reads), by forward differences (exact for the linear targets; the joints move with the mesh). `body` is the
/// shape morphed (any pose: its rest mesh and weights are used), `poses` the posings with
/// their placement and the vertices they put the shape at. The morph is shared by the poses
/// (it is the costly part); spread over `threads`.
pub fn shape_jacobians(
    space: &ShapeSpace,
    x: &[f32],
    body: &PosedBody,
    poses: &[(&Posing, &Placement, &[Vec3])],
    threads: usize,
) -> Result<Vec<Vec<Vec3>>, MeasureError> {
    let Some((first, _, _)) = poses.first() else {
        return Ok(Vec::new());
    };
    let base = first.dense_weights(&body.weights);
    let column = |k: usize| -> Result<Vec<Vec<Vec3>>, MeasureError> {
        let (positions, h) = first.stepped(space, x, &body.positions, &base, k)?;
        let rest = first.model.rest_pose(&positions);
        Ok(poses
            .iter()
            .map(|(posing, placement, at)| {
                posing
                    .place(&positions, &rest, placement)
                    .iter()
                    .zip(*at)
                    .map(|(a, b)| (*a - *b) / h)
                    .collect()
            })
            .collect())
    };
    let n = space.len();
    let threads = threads.clamp(1, n.max(1));
    let mut columns: Vec<Option<Result<Vec<Vec<Vec3>>, MeasureError>>> =
        (0..n).map(|_| None).collect();
    std::thread::scope(|scope| {
        let workers: Vec<_> = (0..threads)
            .map(|t| {
                let column = &column;
                scope.spawn(move || {
                    (t..n)
                        .step_by(threads)
                        .map(|k| (k, column(k)))
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        for w in workers {
            if let Ok(done) = w.join() {
                for (k, c) in done {
                    columns[k] = Some(c);
                }
            }
        }
    });
    // Slider-major to vertex-major, per pose.
    let mut out: Vec<Vec<Vec3>> = poses
        .iter()
        .map(|(_, _, at)| vec![Vec3::ZERO; at.len() * n])
        .collect();
    for (k, c) in columns.into_iter().enumerate() {
        for (pose, col) in c
            .unwrap_or(Err(MeasureError::Worker))?
            .into_iter()
            .enumerate()
        {
            for (v, d) in col.into_iter().enumerate() {
                out[pose][v * n + k] = d;
            }
        }
    }
    Ok(out)
}
