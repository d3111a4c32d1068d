//! The self-occlusion test of the Kinect v1 noise model: a joint is hidden when the line of
//! sight from the sensor to it passes through one of the body's capsules
//! ([`super::BodyVolumes`]); see effect 5 in the [module docs](super). Seed 000, the 2013
//! Kinect fitting-room thesis, names self-occlusion (worst in lateral views) as the main cause
//! of the unnatural movements its motion filters must handle.

use glam::Vec3;

use crate::frame::KinectJoint;

use super::BodyVolumes;

/// Joints never reported as occluded (they are inside the trunk).
const TRUNK_JOINTS: [KinectJoint; 3] = [
    KinectJoint::HipCenter,
    KinectJoint::Spine,
    KinectJoint::ShoulderCenter,
];

/// The point of segment `[a, b]` nearest to `p`.
pub(super) fn closest_on_segment(p: Vec3, a: Vec3, b: Vec3) -> Vec3 {
    let ab = b - a;
    let len2 = ab.length_squared();
    if len2 <= f32::EPSILON {
        return a;
    }
    a + ab * ((p - a).dot(ab) / len2).clamp(0.0, 1.0)
}

/// Distance between segments `[p1, q1]` and `[p2, q2]` (Ericson, *Real-Time Collision
/// Detection*, 5.1.9).
fn segment_distance(p1: Vec3, q1: Vec3, p2: Vec3, q2: Vec3) -> f32 {
    let (d1, d2, r) = (q1 - p1, q2 - p2, p1 - p2);
    let (a, e, f) = (d1.dot(d1), d2.dot(d2), d2.dot(r));
    const EPS: f32 = 1e-12;
    let (s, t) = if a <= EPS && e <= EPS {
        (0.0, 0.0)
    } else if a <= EPS {
        (0.0, (f / e).clamp(0.0, 1.0))
    } else {
        let c = d1.dot(r);
        if e <= EPS {
            ((-c / a).clamp(0.0, 1.0), 0.0)
        } else {
            let b = d1.dot(d2);
            let denom = a * e - b * b;
            let mut s = if denom > 1e-9 * a * e {
                ((b * f - c * e) / denom).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let mut t = (b * s + f) / e;
            if t < 0.0 {
                t = 0.0;
                s = (-c / a).clamp(0.0, 1.0);
            } else if t > 1.0 {
                t = 1.0;
                s = ((b - c) / a).clamp(0.0, 1.0);
            }
            (s, t)
        }
    };
    ((p1 + d1 * s) - (p2 + d2 * t)).length()
}

/// The body capsules `(start, end, radius)` of the occlusion test.
fn body_capsules(body: &BodyVolumes) -> [(KinectJoint, KinectJoint, f32); 12] {
    use KinectJoint::*;
    [
        (HipCenter, ShoulderCenter, body.trunk_radius_m),
        (ShoulderLeft, HipLeft, body.trunk_side_radius_m),
        (ShoulderRight, HipRight, body.trunk_side_radius_m),
        (Head, Head, body.head_radius_m),
        (ShoulderLeft, ElbowLeft, body.upper_arm_radius_m),
        (ShoulderRight, ElbowRight, body.upper_arm_radius_m),
        (ElbowLeft, WristLeft, body.forearm_radius_m),
        (ElbowRight, WristRight, body.forearm_radius_m),
        (HipLeft, KneeLeft, body.thigh_radius_m),
        (HipRight, KneeRight, body.thigh_radius_m),
        (KneeLeft, AnkleLeft, body.shank_radius_m),
        (KneeRight, AnkleRight, body.shank_radius_m),
    ]
}

/// Which joints of a pose are hidden from the sensor (at the origin) by a body capsule; see
/// the module docs. Public so that evaluators and visualisations can show the same test.
pub fn occluded_joints(
    positions: &[Vec3; KinectJoint::COUNT],
    usable: &[bool; KinectJoint::COUNT],
    body: &BodyVolumes,
    margin_m: f32,
    inset_m: f32,
) -> [bool; KinectJoint::COUNT] {
    let capsules = body_capsules(body);
    let mut out = [false; KinectJoint::COUNT];
    for joint in KinectJoint::ALL {
        let j = joint.index();
        if TRUNK_JOINTS.contains(&joint) || !usable[j] {
            continue;
        }
        let p = positions[j];
        let range = p.length();
        if range <= margin_m + 1e-3 {
            continue;
        }
        let sight_end = p * (1.0 - margin_m / range);
        out[j] = capsules.iter().any(|&(a, b, radius)| {
            if a == joint || b == joint || !usable[a.index()] || !usable[b.index()] {
                return false;
            }
            let (pa, pb) = (positions[a.index()], positions[b.index()]);
            closest_on_segment(p, pa, pb).distance(p) > radius
                && segment_distance(Vec3::ZERO, sight_end, pa, pb) < radius - inset_m
        });
    }
    out
}
