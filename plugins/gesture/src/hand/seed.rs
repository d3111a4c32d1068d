//! Seed 000's hand-state method (App. C), the baseline: a window about the hand joint sized
//! by the head-neck distance, the hand's pixels in it (the depth near the hand joint's: the
//! seed's user map with the body behind the hand cut off), two 3x3 dilations and one
//! erosion, the outer contour, its convex hull, and the depth of the deepest convexity
//! defect (the gaps between spread fingers) over the window's side as the score: an open
//! hand scores high, a fist low. The threshold is learnt ([`super::classify::train`]).

use fitroom_depth::{DepthFrame, HEIGHT, WIDTH};

use super::geometry::{Binary, convexity_defects};
use super::region::HandJoints;

/// The window's side over the head-neck distance; the depth band kept about the hand
/// joint's depth, metres.
pub const WINDOW_PER_HEAD_NECK: f32 = 1.0;
pub const DEPTH_BAND_M: f32 = 0.08;

/// The seed's score of the hand at `joints` in `frame` (deepest defect over the window's
/// side), or `None` if the hand is out of view or nothing is seen in its window.
pub fn seed_score(frame: &DepthFrame, joints: &HandJoints) -> Option<f32> {
    let hand = joints.hand;
    if !hand.is_finite() {
        return None;
    }
    let centre = frame.camera.project(hand)?;
    let head_neck = if joints.head_neck_m.is_finite() && joints.head_neck_m > 0.05 {
        joints.head_neck_m
    } else {
        super::region::REFERENCE_HEAD_NECK_M
    };
    let side = (WINDOW_PER_HEAD_NECK * head_neck * frame.camera.fx / hand.z.max(0.3))
        .round()
        .max(8.0) as i64;
    let (u0, v0) = (
        centre.x.round() as i64 - side / 2,
        centre.y.round() as i64 - side / 2,
    );
    let mut img = Binary::new(side as usize, side as usize);
    let (near, far) = (
        ((hand.z - DEPTH_BAND_M) * 1000.0) as i64,
        ((hand.z + DEPTH_BAND_M) * 1000.0) as i64,
    );
    for y in 0..side {
        for x in 0..side {
            let (u, v) = (u0 + x, v0 + y);
            if u < 0 || v < 0 || u >= WIDTH as i64 || v >= HEIGHT as i64 {
                continue;
            }
            let d = i64::from(frame.depth_mm[v as usize * WIDTH + u as usize]);
            if d > 0 && (near..=far).contains(&d) {
                img.on[(y * side + x) as usize] = true;
            }
        }
    }
    if img.count() < 4 {
        return None;
    }
    let smooth = img.dilated().dilated().eroded();
    let contour = smooth.outer_contour((side / 2, side / 2));
    let deepest = convexity_defects(&contour).first().copied().unwrap_or(0.0);
    Some(deepest / side as f32)
}
