//! The calibration frames and what both methods read of them: the person standing still for
//! about a second (30 frames), each frame's depth, person mask and skeleton; averaged over
//! the frames per pixel, which takes the sensor's axial noise down by about √30 and dithers
//! its 11-bit steps (a single Kinect v1 reading at 2.5 m is ±10 mm noisy and 19 mm coarse).

use std::sync::Arc;

use fitroom_depth::{DepthCamera, DepthFrame};
use fitroom_sensor::KinectJoint;
use fitroom_tracker::Plane;
use glam::Vec3;

use crate::MeasureError;
use fitroom_depth::camera::{HEIGHT, PIXELS, WIDTH};

/// One frame of the calibration: depth, the person's pixels and their skeleton.
#[derive(Clone, Debug)]
pub struct CalibrationFrame {
    pub depth: DepthFrame,
    /// Per pixel (row-major, 640×480), whether it sees the person.
    pub mask: Arc<[bool]>,
    /// The 20 Kinect joints, sensor space, metres ([`KinectJoint::ALL`] order).
    pub joints: [Vec3; KinectJoint::COUNT],
    /// The floor the person stands on, sensor space, if known.
    pub floor: Option<Plane>,
}

/// The person seen over the calibration frames, averaged per pixel.
#[derive(Clone, Debug)]
pub struct AveragedView {
    pub camera: DepthCamera,
    /// Mean depth of the pixel's readings while it saw the person, metres (0: not the
    /// person's).
    pub depth_m: Vec<f32>,
    /// How many frames the pixel read the person in.
    pub readings: Vec<u16>,
    /// Whether the pixel is the person's: seen as the person in at least a third of the
    /// frames (the mask without its frame-to-frame flicker at the edges). A third, as for a
    /// surface point ([`Self::points`]): the sensor's lateral error makes a pixel at the
    /// person's edge read the wall in many frames, and a tracker's mask, made of readings,
    /// leaves it out then; at half, a one-pixel rim was lost around the person and every
    /// girth came out 0.1-0.2 cm small through the tracker (the renderer's mask, which
    /// knows the surface, kept it).
    pub mask: Vec<bool>,
    /// The last frame's depth everywhere (0: no reading), metres: where the scene is, to
    /// tell free space (the person is not there) from a surface the person's pixels left
    /// out (the soles, cut with the floor).
    pub scene_m: Vec<f32>,
    /// The frames' mean skeleton.
    pub joints: [Vec3; KinectJoint::COUNT],
    /// The floor, as the last frame that knew it saw it.
    pub floor: Option<Plane>,
    pub frames: usize,
}

/// A reading farther than this from its pixel's median is another surface's, mm.
const OUTLIER_MM: f64 = 40.0;

/// Frames a calibration needs at least (one second at 30 Hz in the kiosk; fewer are
/// accepted down to this, with more noise).
pub const MIN_FRAMES: usize = 5;

impl AveragedView {
    /// The per-pixel average of `frames` (all of one camera), at least [`MIN_FRAMES`].
    pub fn new(frames: &[CalibrationFrame]) -> Result<Self, MeasureError> {
        if frames.len() < MIN_FRAMES {
            return Err(MeasureError::TooFewFrames {
                got: frames.len(),
                need: MIN_FRAMES,
            });
        }
        Self::average(frames)
    }

    /// One frame as a view, its noise as it is (the tracker's snapshots of a moving person,
    /// [`crate::build`]).
    pub fn single(frame: &CalibrationFrame) -> Result<Self, MeasureError> {
        Self::average(std::slice::from_ref(frame))
    }

    fn average(frames: &[CalibrationFrame]) -> Result<Self, MeasureError> {
        let first = frames.first().ok_or(MeasureError::TooFewFrames {
            got: 0,
            need: MIN_FRAMES,
        })?;
        let n = frames.len();
        let mut masked = vec![0u16; PIXELS];
        let mut joints = [Vec3::ZERO; KinectJoint::COUNT];
        for (k, f) in frames.iter().enumerate() {
            if f.depth.depth_mm.len() != PIXELS || f.mask.len() != PIXELS {
                return Err(MeasureError::BadFrame {
                    frame: k,
                    why: format!(
                        "{} depth pixels and {} mask pixels, expected {PIXELS} ({WIDTH}x{HEIGHT})",
                        f.depth.depth_mm.len(),
                        f.mask.len()
                    ),
                });
            }
            if f.joints.iter().any(|j| !j.is_finite()) {
                return Err(MeasureError::BadFrame {
                    frame: k,
                    why: "a joint is not a finite position".into(),
                });
            }
            for (j, p) in joints.iter_mut().zip(&f.joints) {
                *j += *p;
            }
            for (m, &is) in masked.iter_mut().zip(f.mask.iter()) {
                *m += u16::from(is);
            }
        }
        let third = a_third(n);
        let mask: Vec<bool> = masked.iter().map(|&m| m >= third).collect();
        // Each pixel's readings while it saw the person; their robust mean: the readings
        // within OUTLIER_MM of their median. (The sensor's lateral error makes a pixel at
        // the person's edge read the wall behind in some frames; a plain mean would pull
        // the edge back by centimetres and the girths in by millimetres.)
        let mut depth_m = vec![0.0f32; PIXELS];
        let mut readings = vec![0u16; PIXELS];
        let mut values: Vec<u16> = Vec::with_capacity(n);
        for i in 0..PIXELS {
            if !mask[i] {
                continue;
            }
            values.clear();
            values.extend(
                frames
                    .iter()
                    .filter(|f| f.mask[i] && f.depth.depth_mm[i] > 0)
                    .map(|f| f.depth.depth_mm[i]),
            );
            if values.is_empty() {
                continue;
            }
            values.sort_unstable();
            let median = f64::from(values[values.len() / 2]);
            let (mut sum, mut count) = (0.0f64, 0u16);
            for &v in &values {
                if (f64::from(v) - median).abs() <= OUTLIER_MM {
                    sum += f64::from(v);
                    count += 1;
                }
            }
            readings[i] = count;
            depth_m[i] = (sum / f64::from(count.max(1)) / 1000.0) as f32;
        }
        for j in &mut joints {
            *j /= n as f32;
        }
        let last = frames.last().unwrap_or(first);
        let scene_m = last
            .depth
            .depth_mm
            .iter()
            .map(|&mm| f32::from(mm) / 1000.0)
            .collect();
        Ok(Self {
            camera: first.depth.camera,
            scene_m,
            depth_m,
            readings,
            mask,
            joints,
            floor: frames.iter().rev().find_map(|f| f.floor),
            frames: n,
        })
    }

    /// The person's averaged surface points, every `step`-th pixel along both axes, with at
    /// least a third of the frames read there (fewer readings: an edge that flickered).
    pub fn points(&self, step: usize) -> Vec<Vec3> {
        self.points_and_pixels(step).0
    }

    /// [`Self::points`] and the pixel each is seen at.
    pub fn points_and_pixels(&self, step: usize) -> (Vec<Vec3>, Vec<(f32, f32)>) {
        let step = step.max(1);
        let need = a_third(self.frames);
        let (mut points, mut pixels) = (Vec::new(), Vec::new());
        for v in (0..HEIGHT).step_by(step) {
            for u in (0..WIDTH).step_by(step) {
                let i = v * WIDTH + u;
                if self.mask[i] && self.readings[i] >= need && self.depth_m[i] > 0.0 {
                    let (u, v) = (u as f32, v as f32);
                    points.push(self.camera.unproject(u, v, self.depth_m[i]));
                    pixels.push((u, v));
                }
            }
        }
        (points, pixels)
    }

    pub fn joint(&self, j: KinectJoint) -> Vec3 {
        self.joints[j.index()]
    }
}

/// A third of `frames` (at least one): the frames a pixel must see the person in to be
/// theirs, and read them in to be a surface point.
fn a_third(frames: usize) -> u16 {
    u16::try_from((frames / 3).max(1)).unwrap_or(u16::MAX)
}
