//! A person's calibration, as the synthetic Kinect v1 films it: a body of a known shape
//! standing in the calibration pose (arms a little away from the body) somewhere 2-3 m in
//! front of the sensor, swaying by a few millimetres, for a second (30 frames), with the
//! sensor's noise; and the truth beside it (the person's pixels, skeleton, pose).

use fitroom_body::{BodyModel, MODEL_TO_SENSOR, RestPose, Shape, forward_kinematics};
use fitroom_depth::synthetic::{
    Label, NoiseSettings, Scene, SceneMesh, SyntheticCamera, next_unit,
};
use fitroom_depth::{DepthCamera, HEIGHT};
use glam::{Quat, Vec3};

use crate::MeasureError;
use crate::posed::{Placement, PosedBody, Posing};
use crate::view::CalibrationFrame;
use fitroom_tracker::Plane;

/// Where and how the person stands (drawn per subject from the seed).
#[derive(Clone, Copy, Debug, serde::Serialize, serde::Deserialize)]
pub struct Stance {
    /// From the sensor to the pelvis, metres.
    pub distance_m: f32,
    /// Sideways offset, metres.
    pub offset_m: f32,
    /// Turn about the vertical, degrees (0: facing the sensor).
    pub yaw_deg: f32,
    /// The arms' lift from the model's rest, degrees (each arm its own; negative: lowered).
    pub arm_left_deg: f32,
    pub arm_right_deg: f32,
    /// The sensor's height above the floor, metres.
    pub sensor_height_m: f32,
}

impl Stance {
    /// A stance drawn from `seed`: 2.5-3 m away (a level Kinect v1, 43° of vertical view,
    /// sees a standing adult whole from about 2.5 m; [`record`] moves a tall one further
    /// back until they are whole in view), up to 25 cm aside, turned up to 8°,
    /// the arms lowered 10-20° from the rest pose's (MakeHuman rests with them about 25°
    /// below the horizontal: the calibration pose has them a hand's width from the hips),
    /// the sensor 0.9-1.0 m high.
    pub fn drawn(seed: u64) -> Self {
        let mut state = seed ^ 0x5eed_5eed;
        let mut uniform = || next_unit(&mut state);
        Self {
            distance_m: 2.5 + 0.5 * uniform(),
            offset_m: (uniform() - 0.5) * 0.5,
            yaw_deg: (uniform() - 0.5) * 16.0,
            arm_left_deg: -10.0 - 10.0 * uniform(),
            arm_right_deg: -10.0 - 10.0 * uniform(),
            sensor_height_m: 0.9 + 0.1 * uniform(),
        }
    }
}

/// The calibration's second view: after standing facing the sensor, the person turns this
/// far to their left (an eighth of a turn: the side of the chest, waist and hips comes into
/// view while the front still shows; see `docs/measure.md` for the turns tried).
pub const TURN_DEG: f32 = 45.0;

impl Stance {
    /// The same stance turned `degrees` further about the vertical.
    pub fn turned(&self, degrees: f32) -> Self {
        Self {
            yaw_deg: self.yaw_deg + degrees,
            ..*self
        }
    }
}

/// Per bone, the rotation from rest of the calibration pose: each upper arm lifted sideways
/// (about the model's forward axis) by its angle.
pub fn calibration_pose(model: &BodyModel, rest: &RestPose, stance: &Stance) -> Vec<Quat> {
    let mut local = vec![Quat::IDENTITY; model.bones.len()];
    for (bone, degrees) in [
        ("upperarm_l", stance.arm_left_deg),
        ("upperarm_r", -stance.arm_right_deg),
    ] {
        let Some(b) = model.bone_index(bone) else {
            continue;
        };
        let globals = forward_kinematics(&model.bones, rest, &local, Vec3::ZERO);
        let g = globals[b].rotation;
        let q = Quat::from_axis_angle(Vec3::Z, degrees.to_radians());
        local[b] = (local[b] * (g.inverse() * q * g)).normalize();
    }
    local
}

/// A filmed calibration and its truth.
#[derive(Clone, Debug)]
pub struct Recording {
    pub frames: Vec<CalibrationFrame>,
    /// The pose filmed (per bone, from rest) and where the body stood (mean over frames).
    pub locals: Vec<Quat>,
    pub placement: Placement,
    /// The body filmed, at rest: what its true measurements are taken on.
    pub body: PosedBody,
    pub stance: Stance,
}

/// A garment as the person wears it in the calibration pose: its surface with the body's
/// pelvis at the origin, turned as a body facing the sensor is ([`MODEL_TO_SENSOR`]); see
/// [`super::dressed::worn`].
#[derive(Clone, Debug)]
pub struct Worn {
    pub positions: Vec<Vec3>,
    pub triangles: Vec<[u32; 3]>,
}

/// The body filmed: a shape of the model, and perhaps its rest mesh with detail no shape
/// has ([`super::detail`]).
#[derive(Clone, Copy, Debug)]
pub struct Filmed<'a> {
    pub shape: &'a Shape,
    /// The rest mesh (whole mesh) to film instead of the shape's own.
    pub detailed: Option<&'a [Vec3]>,
}

impl<'a> From<&'a Shape> for Filmed<'a> {
    fn from(shape: &'a Shape) -> Self {
        Self {
            shape,
            detailed: None,
        }
    }
}

/// Films `body` in `stance` for `frames` frames (30 Hz) with the sensor's
/// `noise` (the published model: [`NoiseSettings::default`]), seeded by `seed`; wearing
/// `worn` if given (the garment moves with the body).
pub fn record<'a>(
    model: &BodyModel,
    body: impl Into<Filmed<'a>>,
    stance: &Stance,
    frames: usize,
    noise: NoiseSettings,
    seed: u64,
    worn: Option<&Worn>,
) -> Result<Recording, MeasureError> {
    let filmed = body.into();
    let weights = filmed.shape.target_weights(model)?;
    let positions = match filmed.detailed {
        Some(p) if p.len() == model.positions.len() => p.to_vec(),
        Some(p) => {
            return Err(MeasureError::MeshSize {
                got: p.len(),
                expected: model.positions.len(),
            });
        }
        None => model.apply_targets(&weights),
    };
    let locals = calibration_pose(model, &model.rest_pose(&positions), stance);
    let posing = Posing::new(model, locals.clone());
    let turn = Quat::from_rotation_y(stance.yaw_deg.to_radians()) * MODEL_TO_SENSOR;
    let floor_y = -stance.sensor_height_m;
    // The pelvis where the soles touch the floor.
    let probe = Placement {
        rotation: turn,
        pelvis: Vec3::ZERO,
    };
    let at_origin = posing.body_of(weights, positions, &probe);
    let sole = at_origin
        .vertices
        .iter()
        .map(|v| v.y)
        .fold(f32::INFINITY, f32::min);
    // A tall person steps back until the camera sees them whole (as the kiosk asks them
    // to): 5 cm of margin above the head and below the soles.
    let top = at_origin
        .vertices
        .iter()
        .map(|v| v.y)
        .fold(f32::NEG_INFINITY, f32::max);
    let cam = DepthCamera::default();
    let (up, down) = (cam.cy / cam.fy, (HEIGHT as f32 - cam.cy) / cam.fy);
    let height = top - sole;
    let needed =
        ((height - stance.sensor_height_m + 0.05) / up).max((stance.sensor_height_m + 0.05) / down);
    let mut stance = *stance;
    stance.distance_m = stance.distance_m.max(needed);
    let stance = &stance;
    let placement = Placement {
        rotation: turn,
        pelvis: Vec3::new(stance.offset_m, floor_y - sole, stance.distance_m),
    };
    let mut scene = Scene::room(floor_y, stance.distance_m + 1.2);
    let mut camera = SyntheticCamera::new(DepthCamera::default(), noise, seed);
    let mut out = Vec::with_capacity(frames);
    let mut body = None;
    for k in 0..frames {
        let t = k as f32 / 30.0;
        // A standing person sways by a few millimetres (~0.3 Hz) and breathes.
        let sway = Vec3::new(0.004 * (t * 1.9).sin(), 0.0, 0.003 * (t * 1.3 + 0.7).sin());
        let now = Placement {
            pelvis: placement.pelvis + sway,
            ..placement
        };
        let posed = posing.repose(&at_origin, &now);
        let joints = posing.kinect_joints(&posed, &now);
        // The body's mesh is added once; each frame moves its vertices.
        if scene.meshes.len() == scene.still {
            scene.meshes.push(SceneMesh {
                positions: Vec::new(),
                triangles: model.triangles.clone(),
                label: Label::Body,
                closed: true,
            });
        }
        if let Some(mesh) = scene.meshes.get_mut(scene.still) {
            mesh.positions.clone_from(&posed.vertices);
        }
        if let Some(worn) = worn {
            let yaw = Quat::from_rotation_y(stance.yaw_deg.to_radians());
            let positions = worn
                .positions
                .iter()
                .map(|p| now.pelvis + yaw * *p)
                .collect();
            let mesh = SceneMesh {
                positions,
                triangles: worn.triangles.clone(),
                label: Label::Garment,
                closed: false,
            };
            match scene.meshes.get_mut(scene.still + 1) {
                Some(m) => *m = mesh,
                None => scene.meshes.push(mesh),
            }
        }
        let filmed = camera.render(&scene, f64::from(t));
        let mask: Vec<bool> = filmed
            .labels
            .iter()
            .map(|&l| l == Label::Body as u8 || l == Label::Garment as u8)
            .collect();
        out.push(CalibrationFrame {
            depth: filmed.frame,
            mask: mask.into(),
            joints,
            floor: Some(Plane {
                normal: Vec3::Y,
                d: -floor_y,
            }),
        });
        body.get_or_insert(posed);
    }
    let body = body.ok_or(MeasureError::TooFewFrames { got: 0, need: 1 })?;
    Ok(Recording {
        frames: out,
        locals,
        placement,
        body,
        stance: *stance,
    })
}
