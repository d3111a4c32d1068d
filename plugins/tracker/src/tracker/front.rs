//! Something held in front of the body: a forearm or a hand before the belly or the chest.
//! The fit followed from the last frame loses such an arm (its points are nearer the trunk's
//! skin than the arm's last place, and the trunk takes them), and nothing else in the frame
//! says so: the arm left hanging at the side still has the person's edge under it, and the
//! points it should explain are close enough to the trunk not to count as unexplained.
//! What does say so is the depth itself: a forearm before the body stands out of the surface
//! around it, deeper on both sides of it, where a loose shirt's front runs on smoothly.

use fitroom_depth::{DepthFrame, HEIGHT, WIDTH};
use fitroom_sensor::KinectJoint;
use glam::Vec3;

use super::Tracker;
use super::recover::Limb;
use crate::fit::capsule_distance;
use crate::segment::Segmentation;

/// How far `p` lies outside a posed capsule `(a, b, radius at a, radius at b)`, metres.
fn outside_capsule(p: Vec3, (a, b, ra, rb): (Vec3, Vec3, f32, f32)) -> f32 {
    capsule_distance(p, a, b, ra, rb).0
}

/// How far to each side of a point the surface behind it is looked for, metres (a forearm is
/// 6-8 cm across, a hand 9).
const SIDE_M: f32 = 0.07;
/// How much deeper the surface must be on both sides, metres (about two of the sensor's
/// depth steps at 3 m).
const DEEPER_M: f32 = 0.05;

/// Points standing out of the body farther than this from all of it are unexplained, metres.
const NEAR_M: f32 = 0.04;
/// This many unexplained points standing out of the body suspect an arm held there.
const MIN_STANDING_OUT: usize = 8;
/// An arm whose capsules come this near the middle of those points is taken to hold them.
const HELD_M: f32 = 0.1;
/// Points standing out of the body count from this far up the trunk (hips 0, shoulders 1).
const ABOVE_HIPS: f32 = 0.2;
/// Points standing out this near the body's middle may be either arm's, metres.
const MIDDLE_M: f32 = 0.05;
/// The points standing out within this of their middle are the held forearm and hand, metres.
const CLUSTER_M: f32 = 0.15;

/// The mean depth of the person's readings in the 3x3 pixels around `(x, y)`, metres.
fn patch_depth(frame: &DepthFrame, mask: &[bool], x: i32, y: i32) -> Option<f32> {
    let (mut sum, mut n) = (0u32, 0u32);
    for dy in -1..=1 {
        for dx in -1..=1 {
            let (u, v) = (x + dx, y + dy);
            if u < 0 || v < 0 || u >= WIDTH as i32 || v >= HEIGHT as i32 {
                continue;
            }
            let k = v as usize * WIDTH + u as usize;
            let mm = frame.depth_mm[k];
            if mask[k] && mm > 0 {
                sum += u32::from(mm);
                n += 1;
            }
        }
    }
    (n > 0).then(|| sum as f32 / n as f32 / 1000.0)
}

/// The points that stand in front of the person's own surface on both sides, across or along
/// the image: the person's readings [`SIDE_M`] away to the left and right, or above and
/// below, both [`DEEPER_M`] deeper. (At the person's edge one side is not the person: no.)
fn standing_out(frame: &DepthFrame, mask: &[bool], points: &[Vec3], out: &mut Vec<Vec3>) {
    out.clear();
    let camera = frame.camera;
    for &p in points {
        let Some(px) = camera.project(p) else {
            continue;
        };
        let (x, y) = (px.x.round() as i32, px.y.round() as i32);
        let Some(z) = patch_depth(frame, mask, x, y) else {
            continue;
        };
        let side = (SIDE_M * camera.fx / p.z).round() as i32;
        let deeper = |dx: i32, dy: i32| {
            patch_depth(frame, mask, x + dx, y + dy).is_some_and(|behind| behind > z + DEEPER_M)
        };
        if (deeper(-side, 0) && deeper(side, 0)) || (deeper(0, -side) && deeper(0, side)) {
            out.push(p);
        }
    }
}

impl Tracker {
    /// The arms that may be held before the body, each with where its hand would be: with
    /// points standing out of the body's surface ([`standing_out`]) that no part of the body
    /// (posed in `self.posed`) is near, the arm on their side not near them either, its hand
    /// at the point of them farthest from its shoulder.
    pub(super) fn before_the_body(
        &mut self,
        frame: &DepthFrame,
        person: &Segmentation,
    ) -> Vec<(Limb, Vec3)> {
        let mut out = std::mem::take(&mut self.standing_out);
        standing_out(frame, &person.mask, &self.points, &mut out);
        let held = self.held_at(&mut out);
        self.standing_out = out;
        held
    }

    /// [`Self::before_the_body`] from the points standing out (`out`, filtered in place).
    fn held_at(&self, out: &mut Vec<Vec3>) -> Vec<(Limb, Vec3)> {
        let joints = self.body.kinect_joints(&self.posed);
        // Above the hips along the trunk: a loose shirt's hem before the crotch stands out
        // of the legs around it too.
        let hips = joints[KinectJoint::HipCenter.index()];
        let trunk = joints[KinectJoint::ShoulderCenter.index()] - hips;
        out.retain(|&p| (p - hips).dot(trunk) > ABOVE_HIPS * trunk.length_squared());
        // Left unexplained: no capsule of the body near them (a thigh's front, a breast
        // stand out of the surface around them as well, and are where the body is).
        out.retain(|&p| {
            self.posed
                .capsules
                .iter()
                .all(|&c| outside_capsule(p, c) > NEAR_M)
        });
        if out.len() < MIN_STANDING_OUT {
            return Vec::new();
        }
        let centre = out.iter().copied().sum::<Vec3>() / out.len() as f32;
        // How near an arm's capsules come to `p`.
        let near = |limb: Limb, p: Vec3| {
            let upper = self.body.drivers[limb.joints()[0].index()];
            self.body
                .capsules
                .iter()
                .zip(&self.posed.capsules)
                .filter(|(c, _)| {
                    self.body.chains[c.bone]
                        .iter()
                        .any(|&j| self.body.joints[j].bone == upper)
                })
                .map(|(_, &c)| outside_capsule(p, c))
                .fold(f32::INFINITY, f32::min)
        };
        // Whose they are: the arm on their side of the body, either near its middle.
        let across = (joints[KinectJoint::ShoulderLeft.index()]
            - joints[KinectJoint::ShoulderRight.index()])
        .normalize_or_zero();
        let lateral = (centre - hips).dot(across);
        [Limb::ArmLeft, Limb::ArmRight]
            .into_iter()
            .filter(|&arm| match arm {
                Limb::ArmLeft => lateral > -MIDDLE_M,
                _ => lateral < MIDDLE_M,
            })
            .filter(|&arm| near(arm, centre) > HELD_M)
            .filter_map(|arm| {
                let shoulder = joints[arm.shoulder()?.index()];
                let hand = out
                    .iter()
                    .copied()
                    .filter(|p| p.distance(centre) < CLUSTER_M)
                    .max_by(|a, b| a.distance(shoulder).total_cmp(&b.distance(shoulder)))?;
                Some((arm, hand))
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use fitroom_depth::DepthCamera;
    use std::sync::Arc;

    /// A body 3 m away seen as a plane, with a forearm (a horizontal cylinder 7 cm across,
    /// its back 2 cm off the plane) at x < 0 and a shirt's front (a bulge 8 cm high and 60 cm
    /// across) at x > 0: depth by ray casting, every pixel the person's.
    fn scene() -> (DepthFrame, Vec<bool>) {
        let camera = DepthCamera::default();
        let plane = 3.0f32;
        let (radius, axis_z) = (0.035f32, 3.0 - 0.02 - 0.035);
        let mut depth = vec![0u16; WIDTH * HEIGHT];
        for v in 0..HEIGHT {
            for u in 0..WIDTH {
                let ray = camera.unproject(u as f32, v as f32, 1.0);
                let mut z = plane;
                // The bulge: a smooth cap, deepest 8 cm before the plane, 30 cm in radius.
                let p = ray * plane;
                if p.x > 0.1 {
                    let r2 = ((p.x - 0.5).powi(2) + p.y.powi(2)) / 0.09;
                    if r2 < 1.0 {
                        z = plane - 0.08 * (1.0 - r2);
                    }
                }
                // The forearm along x from -0.5 to -0.1 m at height 0: the ray (x, y, 1) t
                // meets the cylinder (y t)² + (t - axis_z)² = radius².
                if p.x > -0.5 && p.x < -0.1 {
                    let (a, b, c) = (
                        ray.y * ray.y + 1.0,
                        -2.0 * axis_z,
                        axis_z * axis_z - radius * radius,
                    );
                    let disc = b * b - 4.0 * a * c;
                    if disc >= 0.0 {
                        z = z.min((-b - disc.sqrt()) / (2.0 * a));
                    }
                }
                depth[v * WIDTH + u] = (z * 1000.0).round() as u16;
            }
        }
        let frame = DepthFrame {
            depth_mm: Arc::from(depth),
            raw: None,
            rgb: None,
            time_s: 0.0,
            timestamp: 0,
            camera,
        };
        (frame, vec![true; WIDTH * HEIGHT])
    }

    #[test]
    fn a_forearm_stands_out_of_the_body_and_a_shirt_front_does_not() {
        let (frame, mask) = scene();
        let at = |x: f32, y: f32| {
            let px = frame
                .camera
                .project(Vec3::new(x, y, 3.0))
                .expect("in front");
            let k = px.y.round() as usize * WIDTH + px.x.round() as usize;
            let z = f32::from(frame.depth_mm[k]) / 1000.0;
            frame.camera.unproject(px.x.round(), px.y.round(), z)
        };
        let forearm = [at(-0.4, 0.0), at(-0.3, 0.0), at(-0.2, 0.005)];
        let shirt = [at(0.5, 0.0), at(0.4, 0.1), at(0.6, -0.1)];
        let plane = [at(0.0, 0.2), at(-0.3, 0.3)];
        let mut out = Vec::new();
        let points: Vec<Vec3> = forearm
            .iter()
            .chain(&shirt)
            .chain(&plane)
            .copied()
            .collect();
        standing_out(&frame, &mask, &points, &mut out);
        assert_eq!(out, forearm.to_vec(), "standing out: {out:?}");
    }
}
