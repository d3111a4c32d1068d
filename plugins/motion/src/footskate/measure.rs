//! Measuring foot skating (the figure seed 000 §4.5's correction is judged by): the share of
//! frame pairs in which a foot on the floor slides, and the floor the avatar actually stands
//! on.

use glam::Vec3;

use crate::retarget::{AvatarPose, AvatarSkeleton};

use super::leg::{Leg, horizontal};
use super::{Foot, FootSkateError};

/// Which height decides whether a foot is "below `height_m`" in [`SkateCriteria`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FootHeight {
    /// The whole sole (heel *and* ball) is below the threshold: the foot is down. Swing-phase
    /// frames with a low toe but a raised heel do not count.
    WholeFoot,
    /// Its lowest point (heel *or* ball) is below the threshold. Also counts the swing foot
    /// whose toe passes the floor at a few centimetres (normal toe clearance is 1-2 cm), so it
    /// is far from zero even for clean walking.
    LowestPoint,
}

/// The foot-skating measure: in a pair of consecutive frames a foot is *on the floor* when its
/// height (see [`FootHeight`]; heel = the sole point below the ankle, ball = the ball joint
/// minus its rest height, both rigid with the foot) is below `height_m` in both frames, and it
/// *skates* when its lowest sole point (the lower one in the later frame) moves more than
/// `slide_m` horizontally between them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SkateCriteria {
    pub height_m: f32,
    pub slide_m: f32,
    pub foot_height: FootHeight,
}

impl Default for SkateCriteria {
    /// 5 cm and 2.5 cm per frame (at 30 Hz: 0.75 m/s), whole foot.
    fn default() -> Self {
        Self {
            height_m: 0.05,
            slide_m: 0.025,
            foot_height: FootHeight::WholeFoot,
        }
    }
}

/// The result of [`foot_skating`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SkateReport {
    /// Consecutive frame pairs examined.
    pub pairs: usize,
    /// Pairs in which at least one foot skates.
    pub skating_pairs: usize,
    /// Pairs in which each foot (left, right) skates.
    pub per_foot: [usize; 2],
    /// Pairs in which each foot is on the floor.
    pub on_floor: [usize; 2],
    /// Largest slide of a foot on the floor, metres.
    pub max_slide_m: f32,
}

impl SkateReport {
    /// Share of frame pairs with a skating foot.
    pub fn ratio(&self) -> f32 {
        if self.pairs == 0 {
            0.0
        } else {
            self.skating_pairs as f32 / self.pairs as f32
        }
    }
}

/// Measures foot skating over a sequence of poses of `skeleton` (see [`SkateCriteria`]).
pub fn foot_skating(
    skeleton: &AvatarSkeleton,
    poses: &[AvatarPose],
    floor_y: f32,
    criteria: SkateCriteria,
) -> Result<SkateReport, FootSkateError> {
    let legs = [
        Leg::new(skeleton, Foot::Left)?,
        Leg::new(skeleton, Foot::Right)?,
    ];
    let n = skeleton.bones.len();
    let points = |leg: &Leg, pose: &AvatarPose| -> Option<[(Vec3, f32); 2]> {
        if pose.heads.len() < n || pose.rotations.len() < n {
            return None;
        }
        Some(leg.sole(pose.heads[leg.foot], pose.rotations[leg.foot], floor_y))
    };
    let mut report = SkateReport::default();
    for pair in poses.windows(2) {
        report.pairs += 1;
        let mut skates = false;
        for (k, leg) in legs.iter().enumerate() {
            let (Some(a), Some(b)) = (points(leg, &pair[0]), points(leg, &pair[1])) else {
                continue;
            };
            let low = |p: &[(Vec3, f32); 2]| match criteria.foot_height {
                FootHeight::WholeFoot => p[0].1.max(p[1].1) < criteria.height_m,
                FootHeight::LowestPoint => p[0].1.min(p[1].1) < criteria.height_m,
            };
            if !(low(&a) && low(&b)) {
                continue;
            }
            report.on_floor[k] += 1;
            let j = if b[0].1 <= b[1].1 { 0 } else { 1 };
            let slide = horizontal(b[j].0 - a[j].0).length();
            if slide.is_finite() {
                report.max_slide_m = report.max_slide_m.max(slide);
            }
            if slide > criteria.slide_m || !slide.is_finite() {
                report.per_foot[k] += 1;
                skates = true;
            }
        }
        if skates {
            report.skating_pairs += 1;
        }
    }
    Ok(report)
}

/// The height (sensor y) of the floor the avatar actually stands on in `poses`: the 5th
/// percentile over the frames of the lowest foot point (heel = ankle or ball, each minus its
/// rest height above the floor). The retargeter's root height is only as good as its leg-ratio
/// scaling: on the CMU clips the avatar's feet end up several centimetres below or above the
/// sensor floor, which would make a fixed-floor skating measure meaningless. `None` without
/// usable poses.
pub fn estimate_floor(
    skeleton: &AvatarSkeleton,
    poses: &[AvatarPose],
) -> Result<Option<f32>, FootSkateError> {
    let legs = [
        Leg::new(skeleton, Foot::Left)?,
        Leg::new(skeleton, Foot::Right)?,
    ];
    let n = skeleton.bones.len();
    let mut lows: Vec<f32> = poses
        .iter()
        .filter(|p| p.heads.len() >= n && p.rotations.len() >= n)
        .map(|p| {
            legs.iter()
                .map(|leg| {
                    let [(_, heel), (_, ball)] =
                        leg.sole(p.heads[leg.foot], p.rotations[leg.foot], 0.0);
                    heel.min(ball)
                })
                .fold(f32::INFINITY, f32::min)
        })
        .filter(|y| y.is_finite())
        .collect();
    if lows.is_empty() {
        return Ok(None);
    }
    lows.sort_by(f32::total_cmp);
    Ok(Some(lows[(lows.len() - 1) / 20]))
}
