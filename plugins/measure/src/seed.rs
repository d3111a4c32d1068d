//! The seed's method (seed 000 ch. 6), the baseline: per frame, the user's depth map filled and
//! smoothed (Algorithm 6), collision-sphere radii at the joints (Algorithm 7), lengths read off
//! the map and the skeleton and combined through the body's proportions (Table 6.2, Eqs.
//! 6.6-6.7), then the parameters averaged over the frames (Algorithm 9); and the garment scale
//! of Algorithm 8 with Table 6.3's primary proportions.
//!
//! The thesis leaves several choices open (its extraction: `docs/measure.md`); ours:
//! - Algorithm 6: the user's pixels without a reading (holes) are filled like the others with
//!   the user's mean depth; the Gaussian is 5×5, σ = 1 px.
//! - A length in the image is converted to metres at the user's mean depth (pinhole,
//!   `pixels × z / f`); the thesis gives no formula.
//! - Body height from the map: the user's topmost to lowest pixel. Head height: twice the
//!   top of the head to the neck (the narrowest row of the user's pixels between the head
//!   and shoulder-centre joints). Hip height: the hip-centre joint
//!   above the lowest pixel. Elbow-fingertip: the fingertip where the user's
//!   pixels end, on along the forearm from the hand joint, at its smoothed depth; the lengths
//!   in space. Height = the mean of the map's value, 7 heads and 7/4 hip heights
//!   (Eq. 6.7; the fingertip rows of Table 6.2 are not averaged in: a relaxed
//!   hand's fingers curl and the estimates came out 25-30 % short).
//! - Shoulder width from the map: along the shoulder joints' row, from each shoulder joint out
//!   to the end of the user's pixels. Head width: the widest row of the head (above the neck). Shoulder width = the mean of the map's value and 3 head widths.
//! - Algorithm 7: the scans stop at the first pixel where the smoothed surface is at or
//!   behind the joint's depth, or where the user's pixels end; the radius is the smallest of
//!   the five values (the pseudo-code's reading), all in metres.

use fitroom_depth::DepthCamera;
use fitroom_depth::camera::{HEIGHT, PIXELS, WIDTH};
use fitroom_sensor::KinectJoint;
use glam::Vec2;
use serde::Serialize;

use crate::MeasureError;
use crate::view::{CalibrationFrame, MIN_FRAMES};

/// What the seed's method measures, averaged over the frames (metres).
#[derive(Clone, Debug, Default, Serialize)]
pub struct SeedMeasurement {
    /// Body height: the mean of the map's value and the proportions' estimates.
    pub height_m: f32,
    /// Body height read off the map alone.
    pub height_map_m: f32,
    pub shoulder_width_m: f32,
    pub shoulder_width_map_m: f32,
    pub head_height_m: f32,
    pub head_width_m: f32,
    pub hip_height_m: f32,
    /// Shoulder centre to hip centre (Table 6.3's primary height of short sleeves).
    pub torso_height_m: f32,
    /// The user's pixels along the hip joints' row.
    pub hip_width_m: f32,
    pub elbow_fingertip_m: f32,
    /// Collision-sphere radius per Kinect joint ([`KinectJoint::ALL`] order).
    pub sphere_radii_m: Vec<f32>,
    pub frames: usize,
}

/// The user's depth map after Algorithm 6 and what the measurements need of the frame.
struct Smoothed<'a> {
    depth_mm: Vec<f32>,
    mask: &'a [bool],
    mean_mm: f32,
    camera: DepthCamera,
}

impl Smoothed<'_> {
    fn user(&self, u: i32, v: i32) -> bool {
        (0..WIDTH as i32).contains(&u)
            && (0..HEIGHT as i32).contains(&v)
            && self.mask[v as usize * WIDTH + u as usize]
    }

    /// Metres per pixel at the user's mean depth.
    fn metres(&self, pixels: f32) -> f32 {
        pixels * self.mean_mm / 1000.0 / self.camera.fy
    }

    /// Pixels from `from` along `dir` (a unit step in the image) to the last user pixel.
    fn run(&self, from: Vec2, dir: Vec2) -> f32 {
        let mut t = 0.0;
        loop {
            let p = from + dir * (t + 1.0);
            if !self.user(p.x.round() as i32, p.y.round() as i32) || t > 640.0 {
                return t;
            }
            t += 1.0;
        }
    }
}

/// Algorithm 6: non-user pixels (and holes) at the user's mean depth, then a Gaussian at
/// the user's pixels.
fn smooth<'a>(frame: &'a CalibrationFrame) -> Option<Smoothed<'a>> {
    let depth = &frame.depth.depth_mm;
    let mask = &frame.mask[..];
    let (mut sum, mut n) = (0.0f64, 0usize);
    for i in 0..PIXELS {
        if mask[i] && depth[i] > 0 {
            sum += f64::from(depth[i]);
            n += 1;
        }
    }
    if n == 0 {
        return None;
    }
    let mean = (sum / n as f64) as f32;
    let filled: Vec<f32> = (0..PIXELS)
        .map(|i| {
            if mask[i] && depth[i] > 0 {
                f32::from(depth[i])
            } else {
                mean
            }
        })
        .collect();
    let kernel: Vec<f32> = (-2..=2)
        .map(|k: i32| (-(k * k) as f32 / 2.0).exp())
        .collect();
    let total: f32 = kernel.iter().sum::<f32>().powi(2);
    let mut out = filled.clone();
    for v in 2..HEIGHT - 2 {
        for u in 2..WIDTH - 2 {
            let i = v * WIDTH + u;
            if !mask[i] {
                continue;
            }
            let mut s = 0.0;
            for (a, ka) in kernel.iter().enumerate() {
                for (b, kb) in kernel.iter().enumerate() {
                    s += ka * kb * filled[(v + a - 2) * WIDTH + u + b - 2];
                }
            }
            out[i] = s / total;
        }
    }
    Some(Smoothed {
        depth_mm: out,
        mask,
        mean_mm: mean,
        camera: frame.depth.camera,
    })
}

/// One frame's parameters.
fn measure_frame(frame: &CalibrationFrame) -> Option<SeedMeasurement> {
    let s = smooth(frame)?;
    let cam = s.camera;
    let px = |j: KinectJoint| cam.project(frame.joints[j.index()]);
    let (head, neck) = (px(KinectJoint::Head)?, px(KinectJoint::ShoulderCenter)?);
    let (hip, hip_l, hip_r) = (
        px(KinectJoint::HipCenter)?,
        px(KinectJoint::HipLeft)?,
        px(KinectJoint::HipRight)?,
    );
    let (sh_l, sh_r) = (
        px(KinectJoint::ShoulderLeft)?,
        px(KinectJoint::ShoulderRight)?,
    );
    // The user's rows.
    let rows: Vec<usize> = (0..HEIGHT)
        .filter(|&v| s.mask[v * WIDTH..(v + 1) * WIDTH].iter().any(|&m| m))
        .collect();
    let (top, bottom) = (*rows.first()? as f32, *rows.last()? as f32);
    // The head: from the topmost user pixel of the head joint's column down to the
    // neck, the narrowest row of the user's pixels between the head joint and the shoulder
    // centre.
    let head_top = (0..=head.y.round().max(0.0) as i32)
        .find(|&v| s.user(head.x.round() as i32, v))
        .map_or(top, |v| v as f32);
    let row_width = |at: Vec2| s.run(at, Vec2::X) + s.run(at, -Vec2::X) + 1.0;
    let (head_row, neck_row) = (head.y.round() as i32, neck.y.round() as i32);
    let column = |v: i32| {
        Vec2::new(
            head.x
                + (neck.x - head.x) * (v - head_row) as f32 / (neck_row - head_row).max(1) as f32,
            v as f32,
        )
    };
    let neck_at = (head_row..=neck_row.max(head_row))
        .min_by(|&a, &b| row_width(column(a)).total_cmp(&row_width(column(b))))
        .map_or(neck.y, |v| v as f32);
    let head_width = s.metres(
        (head_top.round() as i32..=neck_at.round() as i32)
            .map(|v| row_width(column(v)))
            .fold(0.0, f32::max),
    );
    let height_map = s.metres(bottom - top + 1.0);
    let head_height = s.metres(neck_at - head_top);
    let floor_y = cam.unproject(hip.x, bottom, s.mean_mm / 1000.0).y;
    let hip_height = frame.joints[KinectJoint::HipCenter.index()].y - floor_y;
    // Fingertips: on along the forearm from the hand until the user's pixels end; both
    // arms, averaged.
    let mut elbow_tips = Vec::new();
    for (e_joint, h_joint) in [
        (KinectJoint::ElbowLeft, KinectJoint::HandLeft),
        (KinectJoint::ElbowRight, KinectJoint::HandRight),
    ] {
        let (Some(e), Some(h)) = (px(e_joint), px(h_joint)) else {
            continue;
        };
        let dir = (h - e).normalize_or_zero();
        if dir == Vec2::ZERO {
            continue;
        }
        // The fingertip where the user's pixels end, at its smoothed depth; the lengths in
        // space (a forearm turned towards the camera is shorter in the image).
        let tip = h + dir * s.run(h, dir);
        let (tu, tv) = (tip.x.round() as i32, tip.y.round() as i32);
        if !s.user(tu, tv) {
            continue;
        }
        let tip = cam.unproject(
            tip.x,
            tip.y,
            s.depth_mm[tv as usize * WIDTH + tu as usize] / 1000.0,
        );
        elbow_tips.push(tip.distance(frame.joints[e_joint.index()]));
    }
    let mean = |v: &[f32]| (!v.is_empty()).then(|| v.iter().sum::<f32>() / v.len() as f32);
    let elbow_tip = mean(&elbow_tips);
    // The fingertip estimates (7/2 elbow-fingertips, 7 wrist-fingertips) are left out of
    // the mean: a relaxed hand's fingers curl, and the lengths came out 25-30 % short,
    // taking 20 cm off the height. The elbow-fingertip is kept for Algorithm 8.
    let height = mean(&[height_map, 7.0 * head_height, 7.0 / 4.0 * hip_height])?;
    let (left, right) = if sh_l.x > sh_r.x {
        (sh_l, sh_r)
    } else {
        (sh_r, sh_l)
    };
    let shoulder_map = s.metres(left.x - right.x + s.run(left, Vec2::X) + s.run(right, -Vec2::X));
    let shoulder = (shoulder_map + 3.0 * head_width) / 2.0;
    let hip_row = Vec2::new((hip_l.x + hip_r.x) / 2.0, (hip_l.y + hip_r.y) / 2.0);
    let hip_width = s.metres(row_width(hip_row));
    let torso = frame.joints[KinectJoint::ShoulderCenter.index()]
        .distance(frame.joints[KinectJoint::HipCenter.index()]);
    let radii = KinectJoint::ALL
        .iter()
        .map(|&j| sphere_radius(&s, frame.joints[j.index()]))
        .collect();
    Some(SeedMeasurement {
        height_m: height,
        height_map_m: height_map,
        shoulder_width_m: shoulder,
        shoulder_width_map_m: shoulder_map,
        head_height_m: head_height,
        head_width_m: head_width,
        hip_height_m: hip_height,
        torso_height_m: torso,
        hip_width_m: hip_width,
        elbow_fingertip_m: elbow_tip.unwrap_or(0.0),
        sphere_radii_m: radii,
        frames: 1,
    })
}

/// Algorithm 7 at one joint: the surface in front of it and the four scans, the smallest.
fn sphere_radius(s: &Smoothed, joint: glam::Vec3) -> f32 {
    let Some(p) = s.camera.project(joint) else {
        return 0.0;
    };
    let (u, v) = (p.x.round() as i32, p.y.round() as i32);
    if !s.user(u, v) {
        return 0.0;
    }
    let joint_mm = joint.z * 1000.0;
    let at = |u: i32, v: i32| s.depth_mm[v as usize * WIDTH + u as usize];
    let r_z = ((joint_mm - at(u, v)) / 1000.0).max(0.0);
    let scan = |du: i32, dv: i32| -> f32 {
        let (mut x, mut y, mut k) = (u, v, 0);
        loop {
            x += du;
            y += dv;
            k += 1;
            if !s.user(x, y) || at(x, y) >= joint_mm {
                return k as f32 * joint.z / s.camera.fx;
            }
        }
    };
    [r_z, scan(-1, 0), scan(1, 0), scan(0, -1), scan(0, 1)]
        .into_iter()
        .fold(f32::INFINITY, f32::min)
}

/// Algorithm 9: the parameters of every frame averaged.
pub fn measure(frames: &[CalibrationFrame]) -> Result<SeedMeasurement, MeasureError> {
    if frames.len() < MIN_FRAMES {
        return Err(MeasureError::TooFewFrames {
            got: frames.len(),
            need: MIN_FRAMES,
        });
    }
    let each: Vec<SeedMeasurement> = frames.iter().filter_map(measure_frame).collect();
    if each.len() < MIN_FRAMES {
        return Err(MeasureError::TooFewPoints {
            points: each.len(),
            need: MIN_FRAMES,
        });
    }
    let n = each.len() as f32;
    let avg = |f: fn(&SeedMeasurement) -> f32| each.iter().map(f).sum::<f32>() / n;
    let radii = (0..KinectJoint::COUNT)
        .map(|j| each.iter().map(|m| m.sphere_radii_m[j]).sum::<f32>() / n)
        .collect();
    Ok(SeedMeasurement {
        height_m: avg(|m| m.height_m),
        height_map_m: avg(|m| m.height_map_m),
        shoulder_width_m: avg(|m| m.shoulder_width_m),
        shoulder_width_map_m: avg(|m| m.shoulder_width_map_m),
        head_height_m: avg(|m| m.head_height_m),
        head_width_m: avg(|m| m.head_width_m),
        hip_height_m: avg(|m| m.hip_height_m),
        torso_height_m: avg(|m| m.torso_height_m),
        hip_width_m: avg(|m| m.hip_width_m),
        elbow_fingertip_m: avg(|m| m.elbow_fingertip_m),
        sphere_radii_m: radii,
        frames: each.len(),
    })
}

/// Table 6.3: the garment types and their primary proportions.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum GarmentKind {
    Trousers,
    LongSleeves,
    ShortSleeves,
}

/// Algorithm 8: the garment's scale `(x_s, y_s)` for a garment `width_m` wide and `height_m`
/// high, from the primary proportions of its kind (Table 6.3) and the estimates of them from
/// the others (Table 6.2), equally weighted (Eq. 6.7).
pub fn garment_scale(
    kind: GarmentKind,
    m: &SeedMeasurement,
    width_m: f32,
    height_m: f32,
) -> (f32, f32) {
    let (width, height) = match kind {
        GarmentKind::Trousers => (m.hip_width_m, m.hip_height_m),
        // Elbow-fingertip is 2 heads, the shoulders 3 head widths: the two primary widths
        // as one shoulder width.
        GarmentKind::LongSleeves => (
            (m.shoulder_width_m + 1.5 * m.elbow_fingertip_m) / 2.0,
            m.height_m,
        ),
        GarmentKind::ShortSleeves => (m.shoulder_width_m, m.torso_height_m),
    };
    (width / width_m.max(1e-6), height / height_m.max(1e-6))
}
