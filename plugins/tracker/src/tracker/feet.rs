//! Legs found again by their feet. A skirt hides the thighs and knees, and its points are
//! left out of the fit ([`crate::skirt`]); a leg the fit lost there (both legs drawn onto one
//! foot, a leg folded back behind the skirt) has only the few points of the shin and foot
//! below the hem to bring it back, too few to count as a limb left unexplained. Near the
//! floor the two feet are seen apart: each is where its leg's ankle is.

use fitroom_sensor::KinectJoint;
use glam::Vec3;

use super::Tracker;
use super::recover::Limb;
use crate::segment::Segmentation;

/// The person's points this high over the floor are the ankles' (the lower shin and the top
/// of the foot), metres.
const ANKLE_BAND_M: (f32, f32) = (0.06, 0.16);
/// The ankle joint lies this far behind the surface seen, metres (the shin is 8-10 cm thick).
const BEHIND_M: f32 = 0.04;
/// The feet are two when the widest gap across between those points is this wide, metres.
const GAP_M: f32 = 0.05;
/// Each foot must have this many points.
const MIN_POINTS: usize = 4;
/// How far sideways from the hips' middle a foot may be, metres.
const SIDEWAYS_M: f32 = 0.6;
/// A foot farther from its hip than the leg's length and this is not the leg's, metres.
const REACH_SLACK_M: f32 = 0.05;
/// With a hand this low over the floor, no foot is judged (a cartwheel, a hand on the
/// floor), metres.
const HAND_LOW_M: f32 = 0.3;
/// A fitted ankle this far from its foot's is suspected lost, metres.
const MISSED_M: f32 = 0.12;

/// The feet seen and the legs whose fitted ankles are not at them.
pub(super) struct FeetMissed {
    /// Where the feet put the ankles, left and right.
    pub ankles: [Vec3; 2],
    pub legs: Vec<Limb>,
}

impl Tracker {
    /// Where the feet put the ankles, `[left, right]`, about the hips of the fit posed in
    /// `self.posed`: the person's points in [`ANKLE_BAND_M`] (below a skirt's hem, if there
    /// is one), parted across the hips at their widest gap, each foot's mean [`BEHIND_M`]
    /// deeper; `None` unless two feet are seen apart.
    fn feet(&self, person: &Segmentation, joints: &[Vec3]) -> Option<[Vec3; 2]> {
        let floor = person.floor;
        let (hip_l, hip_r) = (
            joints[KinectJoint::HipLeft.index()],
            joints[KinectJoint::HipRight.index()],
        );
        let centre = (hip_l + hip_r) * 0.5;
        let side = hip_l - hip_r;
        let side = (side - floor.normal * side.dot(floor.normal)).normalize_or_zero();
        let mut across: Vec<(f32, Vec3)> = self
            .points
            .iter()
            .filter(|&&p| {
                let h = floor.height(p);
                h >= ANKLE_BAND_M.0
                    && h <= ANKLE_BAND_M.1
                    && self.skirt.as_ref().is_none_or(|s| s.up.dot(p) < s.hem)
            })
            .map(|&p| ((p - centre).dot(side), p))
            .filter(|(side, _)| side.abs() <= SIDEWAYS_M)
            .collect();
        across.sort_by(|a, b| a.0.total_cmp(&b.0));
        // The widest gap across parts the right foot (the lower side) from the left.
        let (split, gap) = across
            .windows(2)
            .enumerate()
            .map(|(i, w)| (i + 1, w[1].0 - w[0].0))
            .max_by(|a, b| a.1.total_cmp(&b.1))?;
        if gap < GAP_M || split < MIN_POINTS || across.len() - split < MIN_POINTS {
            return None;
        }
        let ankle = |points: &[(f32, Vec3)]| {
            let mean = points.iter().map(|(_, p)| *p).sum::<Vec3>() / points.len() as f32;
            mean + mean.normalize_or_zero() * BEHIND_M
        };
        Some([ankle(&across[split..]), ankle(&across[..split])])
    }

    /// The feet ([`Self::feet`]) if a fitted ankle (`self.posed`'s) is [`MISSED_M`] or more
    /// from its foot's, each foot within its leg's reach of its hip and no hand down there.
    pub(super) fn feet_missed(&self, person: &Segmentation) -> Option<FeetMissed> {
        let joints = self.body.kinect_joints(&self.posed);
        let at = |j: KinectJoint| joints[j.index()];
        if [KinectJoint::HandLeft, KinectJoint::HandRight]
            .iter()
            .any(|&h| person.floor.height(at(h)) < HAND_LOW_M)
        {
            return None;
        }
        let ankles = self.feet(person, &joints)?;
        let mut legs = Vec::new();
        for (limb, hip, foot) in [
            (Limb::LegLeft, KinectJoint::HipLeft, ankles[0]),
            (Limb::LegRight, KinectJoint::HipRight, ankles[1]),
        ] {
            let [knee, ankle, _] = limb.joints();
            let reach = at(hip).distance(at(knee)) + at(knee).distance(at(ankle));
            if at(hip).distance(foot) > reach + REACH_SLACK_M {
                return None;
            }
            if at(ankle).distance(foot) > MISSED_M {
                legs.push(limb);
            }
        }
        (!legs.is_empty()).then_some(FeetMissed { ankles, legs })
    }
}
