//! Limbs the fit lost, found again. Followed from the last frame, a fit is a local search: a
//! leg that crossed over its neighbour as they passed in a walk stays crossed, an arm that
//! went behind the body or folded into the chest stays there while the data points of the
//! real arm are left unexplained. Such a limb is suspected (legs whose knees or ankles lie in
//! the other's order than the hips; a limb with almost no data points on it; every limb when
//! much of the person is left unexplained; an arm folded up on itself) and a second
//! hypothesis is fitted: the limb (both legs, for crossed legs) back at rest and pulled to
//! the geodesic extrema of its hand or foot, as a start is, and for an arm also with the
//! forearm bent forward, and, with a body-part forest ([`crate::bodyparts`]), pulled to the
//! forest's joint proposals; an arm held before the body ([`super::front`]) is tried with
//! its hand pulled to what stands out there; legs whose ankles are off the feet seen near the
//! floor ([`super::feet`]) are tried with the ankles pulled to them. A hypothesis is kept when it explains the frame
//! better.

use std::f32::consts::FRAC_PI_2;

use fitroom_depth::DepthFrame;
use fitroom_sensor::KinectJoint;
use glam::{Quat, Vec3};

use super::{Tracker, score};
use crate::extrema::{Part, geodesic_extrema};
use crate::fit::{FitStats, Observation};
use crate::model::{JointKind, Pose};
use crate::segment::Segmentation;

/// A limb and the rig bones that move it, shoulder or hip first.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Limb {
    ArmLeft,
    ArmRight,
    LegLeft,
    LegRight,
}

impl Limb {
    const ALL: [Self; 4] = [Self::ArmLeft, Self::ArmRight, Self::LegLeft, Self::LegRight];

    /// The Kinect joints whose bones' drivers move the limb: upper arm or thigh, forearm or
    /// shin, hand or foot.
    pub(super) fn joints(self) -> [KinectJoint; 3] {
        use KinectJoint::*;
        match self {
            Self::ArmLeft => [ElbowLeft, WristLeft, HandLeft],
            Self::ArmRight => [ElbowRight, WristRight, HandRight],
            Self::LegLeft => [KneeLeft, AnkleLeft, FootLeft],
            Self::LegRight => [KneeRight, AnkleRight, FootRight],
        }
    }

    /// Its end, as the extrema name it.
    fn end(self) -> Part {
        match self {
            Self::ArmLeft => Part::HandLeft,
            Self::ArmRight => Part::HandRight,
            Self::LegLeft => Part::FootLeft,
            Self::LegRight => Part::FootRight,
        }
    }

    /// An arm's shoulder (`None` for a leg).
    pub(super) fn shoulder(self) -> Option<KinectJoint> {
        match self {
            Self::ArmLeft => Some(KinectJoint::ShoulderLeft),
            Self::ArmRight => Some(KinectJoint::ShoulderRight),
            _ => None,
        }
    }

    fn end_joint(self) -> KinectJoint {
        match self {
            Self::ArmLeft => KinectJoint::HandLeft,
            Self::ArmRight => KinectJoint::HandRight,
            Self::LegLeft => KinectJoint::FootLeft,
            Self::LegRight => KinectJoint::FootRight,
        }
    }
}

/// How a suspected limb is tried again.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Hypothesis {
    /// At rest, pulled to the geodesic extremum of its end.
    Extremum,
    /// An arm at rest with its forearm bent forward a right angle.
    Bent,
    /// At rest, pulled to the body-part forest's proposals for its joints.
    Proposed,
    /// An arm with its forearm bent forward and its hand pulled to a point before the body.
    Held(Vec3),
    /// Legs at rest, their ankles pulled to the feet seen near the floor ([`super::feet`]),
    /// the left's and the right's.
    Feet([Vec3; 2]),
    /// An arm at rest, pulled nowhere (tried for an arm folded up on itself, with
    /// [`super::TrackerSettings::recover_folded_at_rest`]).
    Rest,
}

/// A limb with fewer data points on its upper and lower bones than this is suspected lost.
const MIN_LIMB_SUPPORT: u32 = 6;
/// Above this share of the person's points far from the body, every limb is suspected.
const MAX_OUTLIERS: f32 = 0.03;
/// Legs are crossed when a knee or an ankle lies this far on the other leg's side, metres.
const CROSSED_M: f32 = 0.02;
/// An arm whose forearm is turned more than this from its upper arm is suspected (the fit
/// folds a forearm it lost up into the upper arm and the chest).
const FOLDED_RAD: f32 = 100.0 * std::f32::consts::PI / 180.0;
/// A hypothesis replaces the followed fit when its score is better by this much.
const BETTER_BY: f32 = 0.01;

impl Tracker {
    /// The limbs suspected lost in the fit of `pose` (the fitter's support is that fit's),
    /// each with whether it is an arm folded up on itself.
    fn suspects(&mut self, pose: &Pose, fit: &FitStats) -> Vec<(Vec<Limb>, bool)> {
        self.body.pose_into(pose, &mut self.posed);
        let joints = self.body.kinect_joints(&self.posed);
        let at = |j: KinectJoint| joints[j.index()];
        let mut out = Vec::new();
        // Crossed legs: the knees' or ankles' left-right order against the hips'.
        let across = at(KinectJoint::HipLeft) - at(KinectJoint::HipRight);
        let side = |l: KinectJoint, r: KinectJoint| (at(l) - at(r)).dot(across.normalize_or_zero());
        if side(KinectJoint::KneeLeft, KinectJoint::KneeRight) < -CROSSED_M
            || side(KinectJoint::AnkleLeft, KinectJoint::AnkleRight) < -CROSSED_M
        {
            out.push((vec![Limb::LegLeft, Limb::LegRight], false));
        }
        let support = self.bone_support();
        // An arm folded up on itself: a forearm the fit lost (its points taken by the trunk,
        // a T-shirt's front standing off the body) ends up there.
        let folded = |limb: Limb| {
            let [elbow, wrist, _] = limb.joints();
            let Some(shoulder) = limb.shoulder() else {
                return false;
            };
            let upper = at(elbow) - at(shoulder);
            let fore = at(wrist) - at(elbow);
            upper.angle_between(fore) > FOLDED_RAD
        };
        for limb in Limb::ALL {
            let seen: u32 = limb.joints()[..2]
                .iter()
                .map(|j| support[self.body.drivers[j.index()]])
                .sum();
            // A part of the person left unexplained: any limb may be the one missing there.
            let unexplained = fit.outliers > MAX_OUTLIERS;
            let folded = folded(limb);
            if (seen < MIN_LIMB_SUPPORT || unexplained || folded)
                && !out.iter().any(|(s, _)| s.contains(&limb))
            {
                out.push((vec![limb], folded));
            }
        }
        out
    }

    /// Tries the suspected limbs of the followed fit (`pose`, `fit`) at rest, pulled to their
    /// extrema; returns the better pose and its fit.
    pub(super) fn recover(
        &mut self,
        frame: &DepthFrame,
        person: &Segmentation,
        pose: Pose,
        fit: FitStats,
    ) -> (Pose, FitStats) {
        let suspects = self.suspects(&pose, &fit);
        // (`suspects` posed the body as `pose`.)
        let feet = if self.settings.recover_by_feet {
            self.feet_missed(person)
        } else {
            None
        };
        let held = self.before_the_body(frame, person);
        if suspects.is_empty() && held.is_empty() && feet.is_none() {
            return (pose, fit);
        }
        let ends = geodesic_extrema(frame, person);
        self.propose(frame, person);
        let (mut best, mut best_fit) = (pose, fit);
        // Each suspect at rest, pulled to its extrema; an arm also with its forearm bent
        // forward a right angle (a hand in front of the belly shows no extremum); with a
        // body-part forest, a single limb also pulled to the forest's proposals.
        let mut tries: Vec<(Vec<Limb>, Hypothesis)> = Vec::new();
        let proposed = |limb: Limb| {
            limb.joints()
                .iter()
                .any(|j| self.proposals.iter().any(|p| p.joint == j.index()))
        };
        for (limbs, folded) in suspects {
            if let [limb] = limbs[..] {
                if limb.shoulder().is_some() {
                    tries.push((vec![limb], Hypothesis::Bent));
                    if self.settings.recover_folded_at_rest && folded {
                        tries.push((vec![limb], Hypothesis::Rest));
                    }
                }
                if proposed(limb) {
                    tries.push((vec![limb], Hypothesis::Proposed));
                }
            }
            tries.push((limbs, Hypothesis::Extremum));
        }
        // The legs whose ankles are off their feet, and if that is one, both.
        if let Some(f) = feet {
            let one = f.legs.len() == 1;
            tries.push((f.legs, Hypothesis::Feet(f.ankles)));
            if one {
                tries.push((
                    vec![Limb::LegLeft, Limb::LegRight],
                    Hypothesis::Feet(f.ankles),
                ));
            }
        }
        // Then an arm held before the body, pulled there; the two arms are alternatives to
        // each other (a hand before the belly may be either's): each is tried from the same
        // pose, the better kept.
        tries.extend(
            held.iter()
                .map(|&(arm, hand)| (vec![arm], Hypothesis::Held(hand))),
        );
        let mut held_base: Option<(Pose, f32)> = None;
        for (limbs, how) in tries {
            if matches!(how, Hypothesis::Held(_)) && held_base.is_none() {
                held_base = Some((best.clone(), score(&best_fit)));
            }
            let mut candidate = match &held_base {
                Some((base, _)) => base.clone(),
                None => best.clone(),
            };
            let mut targets = Vec::new();
            for &limb in &limbs {
                for j in limb.joints() {
                    candidate.local[self.body.drivers[j.index()]] = Quat::IDENTITY;
                }
                if how == Hypothesis::Proposed {
                    for j in limb.joints() {
                        if let Some(p) = self.proposals.iter().find(|p| p.joint == j.index()) {
                            targets.push((j.index(), p.position, 1.0));
                        }
                    }
                } else if matches!(how, Hypothesis::Bent | Hypothesis::Held(_)) {
                    if let Hypothesis::Held(hand) = how {
                        targets.push((limb.end_joint().index(), hand, 1.0));
                    }
                    let forearm = self.body.drivers[limb.joints()[1].index()];
                    if let Some(JointKind::Hinge { axis, .. }) = self
                        .body
                        .joints
                        .iter()
                        .find(|j| j.bone == forearm)
                        .map(|j| j.kind)
                    {
                        candidate.local[forearm] = Quat::from_axis_angle(axis, FRAC_PI_2);
                    }
                } else if let Hypothesis::Feet([left, right]) = how {
                    match limb {
                        Limb::LegLeft => targets.push((KinectJoint::AnkleLeft.index(), left, 1.0)),
                        Limb::LegRight => {
                            targets.push((KinectJoint::AnkleRight.index(), right, 1.0))
                        }
                        _ => {}
                    }
                } else if how == Hypothesis::Rest {
                    // At rest, pulled nowhere: the fit alone places it.
                } else if let Some(e) = ends.iter().find(|e| e.part == limb.end()) {
                    targets.push((limb.end_joint().index(), e.joint, 1.0));
                }
            }
            let mut fitter = std::mem::take(&mut self.recovery);
            let obs = Observation {
                frame,
                mask: &person.mask,
                silhouette: &self.silhouette,
                points: &self.points,
                targets: &targets,
                skirt: self.skirt.as_ref(),
            };
            let n = self.settings.iterations;
            fitter.fit(&self.body, &mut candidate, &obs, &self.settings.fit, n);
            let obs = Observation {
                targets: &[],
                ..obs
            };
            let candidate_fit = fitter.fit(&self.body, &mut candidate, &obs, &self.settings.fit, n);
            let s = score(&candidate_fit);
            let better = match held_base {
                Some((_, base)) => s > base + BETTER_BY && s > score(&best_fit),
                None => s > score(&best_fit) + BETTER_BY,
            };
            if candidate.is_finite() && better {
                // The kept fit's support is the hypothesis's: swap the fitters.
                std::mem::swap(&mut self.fitter, &mut fitter);
                (best, best_fit) = (candidate, candidate_fit);
                self.recoveries += 1;
            }
            self.recovery = fitter;
        }
        (best, best_fit)
    }
}
