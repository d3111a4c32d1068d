//! The hand's pixels in a depth frame, found from the skeleton's hand, wrist and elbow
//! joints; and what they measure (metric area, widths along the hand, depth spread,
//! solidity): the features both classifiers read.
//!
//! The region: from the valid pixel nearest (in 3D) to the hand joint, the surface is grown
//! over neighbours whose depth steps by less than a few of the sensor's raw steps, within a
//! cylinder along the hand's axis; then cut across the hand's axis (elbow -> hand) at one hand's
//! length back from its farthest point (the fingertips of an open hand, the knuckles of a
//! fist). Everything is in metres, so the same hand measures the same at 1 m and at 3 m.

use fitroom_depth::{DepthCamera, DepthFrame, HEIGHT, WIDTH};
use glam::{Vec2, Vec3};

/// The joints and body size the region is found from (sensor space, metres).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HandJoints {
    pub hand: Vec3,
    pub wrist: Vec3,
    pub elbow: Vec3,
    /// From the Kinect head joint to the shoulder centre: the body's size (seed 000 App. C
    /// sizes the hand's window by the head-neck distance).
    pub head_neck_m: f32,
}

impl HandJoints {
    /// The joints of `side`'s hand in a skeleton frame (a joint not tracked is NaN: the
    /// hand is then unknown).
    pub fn of_frame(frame: &fitroom_sensor::SensorFrame, side: crate::HandSide) -> Self {
        use fitroom_sensor::KinectJoint;
        let [h, w, e] = side.arm_joints();
        let at = |j: KinectJoint| {
            let s = frame.joint(j);
            if s.confidence > 0.0 {
                s.position
            } else {
                Vec3::NAN
            }
        };
        Self {
            hand: at(h),
            wrist: at(w),
            elbow: at(e),
            head_neck_m: at(KinectJoint::Head).distance(at(KinectJoint::ShoulderCenter)),
        }
    }

    /// The hand's length (wrist to fingertip) expected for this body: 0.18 m for a head-neck
    /// distance of 0.20 m (MakeHuman's default body; the Kinect head joint is the head's
    /// centre, the shoulder centre the neck's base), in proportion.
    pub fn hand_length_m(&self) -> f32 {
        let s = if self.head_neck_m.is_finite() && self.head_neck_m > 0.05 {
            self.head_neck_m
        } else {
            REFERENCE_HEAD_NECK_M
        };
        HAND_LENGTH_M * (s / REFERENCE_HEAD_NECK_M).clamp(0.6, 1.6)
    }

    fn finite(&self) -> bool {
        self.hand.is_finite() && self.wrist.is_finite() && self.elbow.is_finite()
    }
}

/// The default body's hand length and head-neck distance, metres.
pub const HAND_LENGTH_M: f32 = 0.18;
pub const REFERENCE_HEAD_NECK_M: f32 = 0.20;

/// A hand's pixels.
#[derive(Clone, Debug, Default)]
pub struct HandRegion {
    /// Pixel coordinates and sensor-space points of the hand's surface.
    pub pixels: Vec<(u16, u16)>,
    pub points: Vec<Vec3>,
    /// The hand's axis (unit, sensor space) and its farthest point along it.
    pub axis: Vec3,
    pub tip: Vec3,
    /// Whether the grown surface reached the cylinder's side within the cut (the hand lies
    /// on something: the body, the face) and is not a hand alone.
    pub touching: bool,
}

/// The features of a hand region, metric.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct HandFeatures {
    /// Pixels in the region.
    pub pixels: u32,
    /// The surface seen, square metres (each pixel's footprint at its depth).
    pub area_m2: f32,
    /// From the tip back to the region's end along the axis, metres.
    pub length_m: f32,
    /// Widths across the axis in bands of [`BAND_M`] from the tip, metres.
    pub widths_m: [f32; BANDS],
    /// Root-mean-square distance of the region from its best plane, metres.
    pub depth_spread_m: f32,
    /// Pixels over the pixel hull's area (gaps between fingers lower it).
    pub solidity: f32,
    /// Mean distance from the axis, metres.
    pub mean_offset_m: f32,
}

/// Bands across the hand for [`HandFeatures::widths_m`].
pub const BANDS: usize = 6;
pub const BAND_M: f32 = 0.03;

/// Sensor points of the pixels within `radius_px` of `centre`, with their pixel.
fn unproject(frame: &DepthFrame, u: usize, v: usize) -> Option<Vec3> {
    let d = *frame.depth_mm.get(v * WIDTH + u)?;
    (d > 0).then(|| {
        frame
            .camera
            .unproject(u as f32, v as f32, f32::from(d) * 1e-3)
    })
}

/// The hand's region in `frame`, or `None` if no surface is seen near the hand joint.
pub fn hand_region(frame: &DepthFrame, joints: &HandJoints) -> Option<HandRegion> {
    if !joints.finite() {
        return None;
    }
    let cam: DepthCamera = frame.camera;
    let hand = joints.hand;
    let length = joints.hand_length_m();
    let centre = cam.project(hand)?;
    // The window searched: a hand's length and more about the hand joint (its knuckles).
    let sphere = 1.3 * length;
    // The hand's axis: from the elbow through the hand.
    let axis = (hand - joints.elbow)
        .try_normalize()
        .or_else(|| (hand - joints.wrist).try_normalize())?;
    // The surface grows inside a cylinder along the axis through the seed (the surface
    // point nearest the hand joint): a hand's half-width and a bit around it, from a hand's
    // length behind (the wrist and some forearm) to most of one ahead (the fingertips), so
    // a hand held beside the face or the chest does not grow into them.
    let inside = |anchor: Vec3, q: Vec3| {
        let d = q - anchor;
        let along = d.dot(axis);
        (-1.2 * length..=0.9 * length).contains(&along)
            && (d - axis * along).length_squared() < (0.55 * length).powi(2)
    };
    let px_per_m = cam.fx / hand.z.max(0.3);
    let half = (sphere * px_per_m).ceil() as i64 + 1;
    let (cu, cv) = (centre.x.round() as i64, centre.y.round() as i64);
    let (u0, v0) = ((cu - half).max(0), (cv - half).max(0));
    let (u1, v1) = (
        (cu + half).min(WIDTH as i64 - 1),
        (cv + half).min(HEIGHT as i64 - 1),
    );
    if u0 > u1 || v0 > v1 {
        return None;
    }
    let (w, h) = ((u1 - u0 + 1) as usize, (v1 - v0 + 1) as usize);
    // The seed: the surface point nearest the hand joint, within a third of a hand's length
    // of it on the image. A lone pixel (a reading strayed off an edge) grows no region: then
    // the next nearest, a few times.
    let seed_r = (0.35 * length * px_per_m).ceil() as i64;
    let mut candidates = Vec::new();
    for v in (cv - seed_r).max(v0)..=(cv + seed_r).min(v1) {
        for u in (cu - seed_r).max(u0)..=(cu + seed_r).min(u1) {
            if let Some(p) = unproject(frame, u as usize, v as usize) {
                let d = p.distance(hand);
                if d <= 0.8 * length {
                    candidates.push((d, u as usize, v as usize));
                }
            }
        }
    }
    candidates.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut seen = vec![false; w * h];
    let local = |u: usize, v: usize| (v - v0 as usize) * w + (u - u0 as usize);
    let (mut pixels, mut points, mut at_edge) = (Vec::new(), Vec::new(), Vec::new());
    for &(_, su, sv) in candidates.iter() {
        if seen[local(su, sv)] {
            continue;
        }
        let Some(anchor) = unproject(frame, su, sv) else {
            continue;
        };
        pixels.clear();
        points.clear();
        at_edge.clear();
        // Grow over depth-continuous neighbours (8-connected) inside the cylinder.
        let mut stack = vec![(su, sv)];
        seen[local(su, sv)] = true;
        while let Some((u, v)) = stack.pop() {
            let Some(p) = unproject(frame, u, v) else {
                continue;
            };
            pixels.push((u as u16, v as u16));
            points.push(p);
            // A step of a few raw values is the same surface: 3 cm, or 2.5 raw steps far
            // away.
            let step = (2.5 * fitroom_depth::camera::raw_step_m(p.z)).max(0.03);
            for (du, dv) in NEIGHBOURS {
                let (nu, nv) = (u as i64 + du, v as i64 + dv);
                if nu < u0 || nu > u1 || nv < v0 || nv > v1 {
                    continue;
                }
                let (nu, nv) = (nu as usize, nv as usize);
                let k = local(nu, nv);
                if seen[k] {
                    continue;
                }
                let Some(q) = unproject(frame, nu, nv) else {
                    continue;
                };
                if (q.z - p.z).abs() > step {
                    continue;
                }
                seen[k] = true;
                if !inside(anchor, q) {
                    at_edge.push(q);
                    continue;
                }
                stack.push((nu, nv));
            }
        }
        if points.len() >= MIN_GROWN {
            break;
        }
    }
    if points.len() < MIN_GROWN {
        return None;
    }
    // The tip is the region's farthest point along the axis (robustly: the 98th
    // percentile, so one noisy pixel does not move it).
    let mut along: Vec<f32> = points.iter().map(|p| (*p - hand).dot(axis)).collect();
    along.sort_by(f32::total_cmp);
    let tip_along = along[((along.len() - 1) as f32 * 0.98) as usize];
    let tip = hand + axis * tip_along;
    let keep = |p: &Vec3| (*p - tip).dot(axis) >= -length;
    let touching = at_edge.iter().any(keep);
    let (pixels, points): (Vec<_>, Vec<_>) = pixels
        .into_iter()
        .zip(points)
        .filter(|(_, p)| keep(p))
        .unzip();
    Some(HandRegion {
        pixels,
        points,
        axis,
        tip,
        touching,
    })
}

/// The fewest pixels a grown region may have.
const MIN_GROWN: usize = 6;

const NEIGHBOURS: [(i64, i64); 8] = [
    (-1, -1),
    (0, -1),
    (1, -1),
    (-1, 0),
    (1, 0),
    (-1, 1),
    (0, 1),
    (1, 1),
];

impl HandRegion {
    /// The region's features, measured with `camera`'s intrinsics.
    pub fn features(&self, camera: &DepthCamera) -> HandFeatures {
        let n = self.points.len();
        if n == 0 {
            return HandFeatures::default();
        }
        let area_m2 = self
            .points
            .iter()
            .map(|p| (p.z / camera.fx) * (p.z / camera.fy))
            .sum();
        // Across: perpendicular to the axis and to the line of sight.
        let centroid = self.points.iter().copied().sum::<Vec3>() / n as f32;
        let view = centroid.normalize_or_zero();
        let across = self
            .axis
            .cross(view)
            .try_normalize()
            .unwrap_or_else(|| self.axis.any_orthonormal_vector());
        // Per band, the points across the axis (2D: across, and towards the camera); the
        // band's width is their widest extent over directions in that plane, so a hand
        // turned away from the camera keeps its width (its visible surface spans the width
        // across and in depth).
        let mut bands: [Vec<glam::Vec2>; BANDS] = Default::default();
        let mut length = 0.0f32;
        let mut offset = 0.0;
        for p in &self.points {
            let d = *p - self.tip;
            let back = -d.dot(self.axis);
            length = length.max(back);
            let flat = d - self.axis * d.dot(self.axis);
            offset += flat.length();
            let band = (back.max(0.0) / BAND_M) as usize;
            if band < BANDS {
                bands[band].push(glam::Vec2::new(flat.dot(across), flat.dot(view)));
            }
        }
        let mut widths_m = [0.0; BANDS];
        for (w, pts) in widths_m.iter_mut().zip(&bands) {
            *w = widest_extent(pts);
        }
        // Depth about the best plane (a flat hand is a plane; a fist is round).
        let spread = plane_residual(&self.points, centroid);
        let pixels: Vec<Vec2> = self
            .pixels
            .iter()
            .map(|&(u, v)| Vec2::new(f32::from(u), f32::from(v)))
            .collect();
        let hull = super::geometry::convex_hull(&pixels);
        // Each pixel is a unit square: the hull of the centres misses half a pixel all
        // round, which the perimeter's half adds back.
        let hull_area =
            super::geometry::polygon_area(&hull) + 0.5 * super::geometry::perimeter(&hull) + 1.0;
        HandFeatures {
            pixels: n as u32,
            area_m2,
            length_m: length,
            widths_m,
            depth_spread_m: spread,
            solidity: (n as f32 / hull_area).min(1.0),
            mean_offset_m: offset / n as f32,
        }
    }
}

/// The widest extent of `points` over 16 directions, robust to one stray point: the 2nd
/// smallest and 2nd largest projections.
fn widest_extent(points: &[glam::Vec2]) -> f32 {
    if points.len() < 3 {
        return 0.0;
    }
    let mut best = 0.0f32;
    for k in 0..16 {
        let a = std::f32::consts::PI * k as f32 / 16.0;
        let dir = glam::Vec2::new(a.cos(), a.sin());
        let (mut lo, mut lo2, mut hi, mut hi2) = (
            f32::INFINITY,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NEG_INFINITY,
        );
        for p in points {
            let x = p.dot(dir);
            if x < lo {
                lo2 = lo;
                lo = x;
            } else if x < lo2 {
                lo2 = x;
            }
            if x > hi {
                hi2 = hi;
                hi = x;
            } else if x > hi2 {
                hi2 = x;
            }
        }
        best = best.max(hi2 - lo2);
    }
    best
}

/// The root-mean-square distance of `points` from their least-squares plane (the smallest
/// eigenvalue of their covariance, by inverse iteration on the 3x3 matrix).
fn plane_residual(points: &[Vec3], centroid: Vec3) -> f32 {
    let n = points.len().max(1) as f32;
    let mut c = glam::Mat3::ZERO;
    for p in points {
        let d = *p - centroid;
        c += glam::Mat3::from_cols(d * d.x, d * d.y, d * d.z);
    }
    let c = c * (1.0 / n);
    // Shift by a hair so the inverse exists; iterate towards the smallest eigenvector.
    let shifted = c + glam::Mat3::IDENTITY * 1e-9;
    if shifted.determinant().abs() < 1e-30 {
        return 0.0;
    }
    let inv = shifted.inverse();
    let mut v = Vec3::new(0.3, 0.5, 0.8).normalize();
    for _ in 0..20 {
        v = (inv * v).normalize_or_zero();
        if v == Vec3::ZERO {
            return 0.0;
        }
    }
    v.dot(c * v).max(0.0).sqrt()
}
