//! Synthetic hands: the MakeHuman body with one hand raised towards the mirror, its fingers
//! opened or curled into a fist, filmed by the synthetic Kinect v1 (its published noise) at a
//! chosen distance, turned and tilted; with the truth (the hand's state, the 20 joints).
//!
//! The body's rig has three bones per finger (`index_01_l` ... `pinky_03_r`, `thumb_*`): a
//! fist is each finger bent at its three joints towards the palm (about 85°, 100° and 65°
//! for a tight fist) and the thumb folded over the fingers; an open hand is the fingers
//! straight and spread (Kinect v1 resolves the gaps only up to about 1.5 m).

use fitroom_body::{BodyModel, MODEL_TO_SENSOR, RestPose, Shape, ShapeError, forward_kinematics};
use fitroom_depth::DepthCamera;
use fitroom_depth::synthetic::{
    Label, NoiseSettings, Scene, SceneMesh, SyntheticCamera, next_unit,
};
use fitroom_sensor::KinectJoint;
use fitroom_tracker::kinect::rig_joints;
use glam::{Quat, Vec3};

use crate::{HandSide, HandState};

/// How a synthetic hand is shown (drawn per sample from a seed by [`HandPose::drawn`]).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct HandPose {
    pub side: HandSide,
    pub state: HandState,
    /// From the sensor to the hand, metres.
    pub distance_m: f32,
    /// The hand turned about the forearm from palm-to-the-mirror, degrees.
    pub turn_deg: f32,
    /// The wrist bent forwards (+) or back (-), degrees.
    pub tilt_deg: f32,
    /// The upper arm lifted forwards from hanging, and the forearm leaned forwards from
    /// upright, degrees.
    pub arm_raise_deg: f32,
    pub forearm_lean_deg: f32,
    /// How far the fingers curl, 0 (straight) to 1 (a tight fist); and the spread of an
    /// open hand's fingers (1: the natural spread).
    pub curl: f32,
    pub spread: f32,
    /// How far above the sensor's axis the hand is seen, degrees (the sensor's height
    /// follows: a hand raised at 1 m must be seen by a sensor mounted high enough).
    pub elevation_deg: f32,
    /// The body turned about the vertical (degrees) and standing aside (metres).
    pub yaw_deg: f32,
    pub offset_m: f32,
    /// The body's shape: MakeHuman's gender, height and weight sliders.
    pub gender: f32,
    pub height: f32,
    pub weight: f32,
}

impl HandPose {
    /// A pose drawn from `seed` with the hand `distance_m` from the sensor: either hand,
    /// open or closed (half each), turned up to ±40° and tilted up to ±25°, the arm raised
    /// 25-60° and the forearm leaning 0-45° forwards, a loose (0.85) to tight fist or an open
    /// hand curled up to 0.12, seen up to 12° above or below the sensor's axis, the body turned up to ±15° and up to
    /// 25 cm aside, any gender, height and weight.
    pub fn drawn(seed: u64, distance_m: f32) -> Self {
        let mut state = fitroom_depth::synthetic::splitmix64(seed ^ 0x4a4e_d5ee_d000_0001);
        let mut u = || next_unit(&mut state);
        let side = if u() < 0.5 {
            HandSide::Left
        } else {
            HandSide::Right
        };
        let open = u() < 0.5;
        Self {
            side,
            state: if open {
                HandState::Open
            } else {
                HandState::Closed
            },
            distance_m,
            turn_deg: (u() - 0.5) * 80.0,
            tilt_deg: (u() - 0.5) * 50.0,
            arm_raise_deg: 25.0 + 35.0 * u(),
            forearm_lean_deg: 45.0 * u(),
            curl: if open { 0.12 * u() } else { 0.85 + 0.15 * u() },
            spread: 0.6 + 0.8 * u(),
            elevation_deg: (u() - 0.5) * 24.0,
            yaw_deg: (u() - 0.5) * 30.0,
            offset_m: (u() - 0.5) * 0.5,
            gender: u(),
            height: 0.2 + 0.6 * u(),
            weight: 0.2 + 0.6 * u(),
        }
    }

    /// The body's shape.
    pub fn shape(&self) -> Shape {
        Shape {
            gender: self.gender,
            height: self.height,
            weight: self.weight,
            ..Shape::default()
        }
    }
}

/// A filmed synthetic hand.
#[derive(Clone, Debug)]
pub struct HandShot {
    pub pose: HandPose,
    pub frame: fitroom_depth::DepthFrame,
    /// The 20 Kinect joints (sensor space, metres; the tracker's rig bones): exact.
    pub joints: [Vec3; KinectJoint::COUNT],
    /// What each pixel sees (the synthetic camera's labels, before noise).
    pub labels: std::sync::Arc<[u8]>,
}

/// Films synthetic hands (one body model, one camera; each shot a new seed's noise).
pub struct HandStudio<'a> {
    model: &'a BodyModel,
    camera: DepthCamera,
    noise: NoiseSettings,
}

impl<'a> HandStudio<'a> {
    pub fn new(model: &'a BodyModel, noise: NoiseSettings) -> Self {
        Self {
            model,
            camera: DepthCamera::default(),
            noise,
        }
    }

    /// Films `pose` with the sensor's noise drawn from `seed`.
    pub fn film(&self, pose: &HandPose, seed: u64) -> Result<HandShot, ShapeError> {
        let m = self.model;
        let weights = pose.shape().target_weights(m)?;
        let positions = m.apply_targets(&weights);
        let rest = m.rest_pose(&positions);
        let locals = hand_pose_locals(m, &rest, pose);
        let globals = forward_kinematics(&m.bones, &rest, &locals, Vec3::ZERO);
        let n = (m.body_vertex_count as usize).min(positions.len());
        let skinned = m.skin_positions(&positions[..n], &rest, &globals);
        let head = |name: &str| {
            m.bone_index(name)
                .and_then(|b| globals.get(b))
                .map_or(Vec3::ZERO, |g| g.translation)
        };
        let turn = Quat::from_rotation_y(pose.yaw_deg.to_radians()) * MODEL_TO_SENSOR;
        let hand_bone = match pose.side {
            HandSide::Left => "middle_01_l",
            HandSide::Right => "middle_01_r",
        };
        let hand = turn * head(hand_bone);
        let sole = skinned
            .iter()
            .map(|p| (turn * *p).y)
            .fold(f32::INFINITY, f32::min);
        // The hand at its distance and elevation, the body `offset_m` aside; the floor under
        // the soles.
        let hand_y = pose.distance_m * pose.elevation_deg.to_radians().tan();
        let shift = Vec3::new(
            pose.offset_m - hand.x * 0.5,
            hand_y - hand.y,
            pose.distance_m - hand.z,
        );
        let sensor_height = -(sole + shift.y);
        let to_sensor = |p: Vec3| turn * p + shift;
        let vertices: Vec<Vec3> = skinned.iter().map(|&p| to_sensor(p)).collect();
        let joints = rig_joints(m, &globals).map(to_sensor);
        let mut scene = Scene::room(-sensor_height, pose.distance_m + 1.8);
        scene.meshes.push(SceneMesh {
            positions: vertices,
            triangles: m.triangles.clone(),
            label: Label::Body,
            closed: true,
        });
        let mut camera = SyntheticCamera::new(self.camera, self.noise, seed);
        let filmed = camera.render(&scene, 0.0);
        Ok(HandShot {
            pose: *pose,
            frame: filmed.frame,
            joints,
            labels: filmed.labels,
        })
    }
}

/// Per bone, the rotation from rest that raises `pose`'s hand towards the mirror with its
/// fingers as `pose` says (model space: the body faces +Z, +X its left, +Y up).
pub fn hand_pose_locals(model: &BodyModel, rest: &RestPose, pose: &HandPose) -> Vec<Quat> {
    let mut locals = vec![Quat::IDENTITY; model.bones.len()];
    let outward = pose.side.outward();
    let raise = pose.arm_raise_deg.to_radians();
    let lean = pose.forearm_lean_deg.to_radians();
    let spread_out = 12f32.to_radians();
    let upper_dir = Vec3::new(
        outward * spread_out.sin(),
        -raise.cos() * spread_out.cos(),
        raise.sin() * spread_out.cos(),
    );
    // The forearm upright, leaning forwards, a little inwards (the hand before the chest).
    let forearm_dir = Vec3::new(-outward * 0.15, lean.cos(), lean.sin()).normalize();
    let arm = ArmPose {
        upper_dir,
        forearm_dir,
        // The palm to the mirror (+Z), turned by `turn_deg`.
        palm: Quat::from_axis_angle(forearm_dir, outward * pose.turn_deg.to_radians()) * Vec3::Z,
        tilt_deg: pose.tilt_deg,
        curl: pose.curl,
        spread: pose.spread,
    };
    pose_arm(model, rest, &mut locals, pose.side, &arm);
    locals
}

/// How one arm is posed (model space: the body faces +Z, +X its left, +Y up).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ArmPose {
    /// The upper arm's and the forearm's directions (unit).
    pub upper_dir: Vec3,
    pub forearm_dir: Vec3,
    /// Where the palm should face (its part across the forearm is what counts).
    pub palm: Vec3,
    /// The wrist bent forwards (+) or back (-), degrees.
    pub tilt_deg: f32,
    /// Finger curl (0 straight, 1 a tight fist) and an open hand's spread (1 natural).
    pub curl: f32,
    pub spread: f32,
}

/// Poses `side`'s arm, hand and fingers as `arm` says, on top of `locals` (per-bone rotations
/// from rest; the other bones' are kept).
pub fn pose_arm(
    model: &BodyModel,
    rest: &RestPose,
    locals: &mut [Quat],
    side: HandSide,
    arm: &ArmPose,
) {
    let sfx = side.suffix();
    let bone = |name: &str| model.bone_index(&format!("{name}{sfx}"));
    let globals = |locals: &[Quat]| forward_kinematics(&model.bones, rest, locals, Vec3::ZERO);
    // Turns bone `b` by the global rotation `q` (about its head).
    let turn = |locals: &mut [Quat], b: usize, q: Quat| {
        let g = globals(locals)[b].rotation;
        locals[b] = (locals[b] * (g.inverse() * q * g)).normalize();
    };
    let (Some(upper), Some(lower), Some(twist), Some(hand)) = (
        bone("upperarm"),
        bone("lowerarm"),
        bone("lowerarm_twist"),
        bone("hand"),
    ) else {
        return;
    };
    let forearm_dir = arm.forearm_dir;
    let aim = |locals: &mut [Quat], b: usize, end: usize, want: Vec3| {
        let g = globals(locals);
        let now = (g[end].translation - g[b].translation).normalize_or_zero();
        if now != Vec3::ZERO {
            turn(locals, b, Quat::from_rotation_arc(now, want));
        }
    };
    aim(locals, upper, lower, arm.upper_dir);
    aim(locals, lower, hand, forearm_dir);
    // Twist the forearm (half at the elbow, half at the wrist's end) until the palm faces
    // `arm.palm`.
    if let Some((palm, _, _)) = hand_frame(model, &globals(locals), sfx) {
        let flat = |v: Vec3| (v - forearm_dir * v.dot(forearm_dir)).normalize_or_zero();
        let (a, b) = (flat(palm), flat(arm.palm));
        let angle = a.cross(b).dot(forearm_dir).atan2(a.dot(b));
        turn(
            locals,
            lower,
            Quat::from_axis_angle(forearm_dir, angle * 0.5),
        );
        turn(
            locals,
            twist,
            Quat::from_axis_angle(forearm_dir, angle * 0.5),
        );
    }
    // The hand straight on the forearm (the rig's rest hand is bent a little aside), then
    // bent at the wrist about its radial axis (positive: the fingers towards the palm).
    if let Some(knuckle) = bone("middle_01") {
        aim(locals, hand, knuckle, forearm_dir);
    }
    let Some((palm, along, _)) = hand_frame(model, &globals(locals), sfx) else {
        return;
    };
    let hinge = along.cross(palm).normalize_or_zero();
    turn(
        locals,
        hand,
        Quat::from_axis_angle(hinge, arm.tilt_deg.to_radians()),
    );
    let Some((palm, along, radial)) = hand_frame(model, &globals(locals), sfx) else {
        return;
    };
    let hinge = along.cross(palm).normalize_or_zero();
    // Abduction: the fingers fan out about the palm's normal, towards the radial side for
    // the index, away from it for the ring and little fingers.
    let fan = along.cross(radial).normalize_or_zero();
    let c = arm.curl;
    for (finger, fan_deg) in [
        ("index", 9.0),
        ("middle", 0.0),
        ("ring", -7.0),
        ("pinky", -14.0),
    ] {
        let bent = [85.0 * c, 100.0 * c, 65.0 * c];
        for (k, deg) in bent.iter().enumerate() {
            let Some(b) = bone(&format!("{finger}_0{}", k + 1)) else {
                continue;
            };
            if k == 0 {
                let fan_angle = f32::to_radians(fan_deg * arm.spread * (1.0 - c));
                turn(locals, b, Quat::from_axis_angle(fan, fan_angle));
            }
            turn(
                locals,
                b,
                Quat::from_axis_angle(hinge, f32::to_radians(*deg)),
            );
        }
    }
    // The thumb: an open hand's spread away from the fingers (turned about the palm's
    // normal); a fist's laid across the curled fingers (aimed at the index and middle
    // fingers' middle joints, just in front of them), as far as the curl goes.
    let (Some(t1), Some(t2), Some(t3)) = (bone("thumb_01"), bone("thumb_02"), bone("thumb_03"))
    else {
        return;
    };
    if c < 0.5 {
        turn(
            locals,
            t1,
            Quat::from_axis_angle(fan, f32::to_radians(12.0 * arm.spread)),
        );
    } else {
        let g = globals(locals);
        let (Some(i2), Some(m2)) = (bone("index_02"), bone("middle_02")) else {
            return;
        };
        let front = palm * 0.018;
        let targets = [
            (t1, t2, g[i2].translation + front),
            (t2, t3, g[m2].translation + front),
        ];
        for (b, end, target) in targets {
            let g = globals(locals);
            let want = (target - g[b].translation).normalize_or_zero();
            let now = (g[end].translation - g[b].translation).normalize_or_zero();
            if want != Vec3::ZERO && now != Vec3::ZERO {
                let full = Quat::from_rotation_arc(now, want);
                turn(locals, b, Quat::IDENTITY.slerp(full, c));
            }
        }
    }
}

/// The posed hand's palm normal (out of the palm), its direction from the wrist to the
/// middle finger's base, and its radial direction (little finger to index), model space.
fn hand_frame(
    model: &BodyModel,
    globals: &[fitroom_body::RigidTransform],
    sfx: &str,
) -> Option<(Vec3, Vec3, Vec3)> {
    let at = |name: &str| {
        model
            .bone_index(&format!("{name}{sfx}"))
            .and_then(|b| globals.get(b))
            .map(|g| g.translation)
    };
    let (hand, index, middle, pinky) = (
        at("hand")?,
        at("index_01")?,
        at("middle_01")?,
        at("pinky_01")?,
    );
    let along = (middle - hand).try_normalize()?;
    let radial = (index - pinky).try_normalize()?;
    let radial = (radial - along * radial.dot(along)).try_normalize()?;
    // As the motion crate's joint limits read it: along x radial on the left hand, radial x
    // along on the right.
    let palm = if sfx == "_l" {
        along.cross(radial)
    } else {
        radial.cross(along)
    };
    Some((palm.try_normalize()?, along, radial))
}

/// The 20 Kinect joints (sensor space) of `shape` standing in the rig's rest pose, turned
/// `yaw_deg` from facing the sensor, its pelvis at `pelvis`.
pub fn standing_joints(
    model: &BodyModel,
    shape: &Shape,
    pelvis: Vec3,
    yaw_deg: f32,
) -> Result<[Vec3; KinectJoint::COUNT], ShapeError> {
    let weights = shape.target_weights(model)?;
    let positions = model.apply_targets(&weights);
    let rest = model.rest_pose(&positions);
    let globals = forward_kinematics(&model.bones, &rest, &[], Vec3::ZERO);
    let turn = Quat::from_rotation_y(yaw_deg.to_radians()) * MODEL_TO_SENSOR;
    let joints = rig_joints(model, &globals);
    let root = joints[KinectJoint::HipCenter.index()];
    Ok(joints.map(|p| pelvis + turn * (p - root)))
}
