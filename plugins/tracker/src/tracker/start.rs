//! Starting from nothing, and which way the person faces. A start places the body standing
//! under the person, sized by their height, pulls it to the geodesic extrema and fits it to
//! the depth alone, twice: facing the sensor and with its back to it (the person may have
//! turned while no one was tracked: a dancer's spin); a person's first start also tries the
//! arms hanging, not pulled to the hands' ends. Which way round is kept leans to the
//! way the person last faced, since a trunk seen from the front or the back differs in the
//! depth by little more than the sensor's steps at 3 m; a followed fit carries on the turn the
//! body was making ([`carry_turn`]), and one with its back to the sensor is checked now and
//! then against a start facing it ([`Tracker::check_turn`]).

use fitroom_depth::DepthFrame;
use fitroom_sensor::KinectJoint;
use glam::{Quat, Vec3};

use super::{HEIGHT, SIZE_LIMITS, Tracker, score};
use crate::extrema::{Part, geodesic_extrema};
use crate::fit::FitStats;
use crate::kinect::facing_degrees;
use crate::model::Pose;
use crate::segment::Segmentation;

impl Tracker {
    /// Starts from nothing: the body standing under the person, sized by their height,
    /// pulled to the geodesic extrema, then fitted to the depth alone; facing the way
    /// `prior_away` says unless the other way explains the frame better by
    /// [`super::TrackerSettings::turn_margin`]. `first`: no pose to follow (a person's first
    /// frame), not a restart.
    pub(super) fn start(
        &mut self,
        frame: &DepthFrame,
        person: &Segmentation,
        prior_away: bool,
        first: bool,
    ) -> (Pose, FitStats) {
        self.starts += 1;
        self.followed = 0;
        let StartFrom {
            spot,
            scale,
            targets,
            hand_on_top,
        } = self.start_from(frame, person);
        // Facing the sensor, and facing away (the extrema's left and right swapped): a
        // person who turned their back while no one was tracked is found so as well.
        let (pose, fit) = self.start_facing(frame, person, spot, scale, &targets, prior_away);
        let support = self.fitter.support.clone();
        let (other, other_fit) =
            self.start_facing(frame, person, spot, scale, &targets, !prior_away);
        let (away, pose, fit, support) =
            if score(&other_fit) > score(&fit) + self.settings.turn_margin {
                let support = self.fitter.support.clone();
                (!prior_away, other, other_fit, support)
            } else {
                (prior_away, pose, fit, support)
            };
        // A person's first start, the same way round with the arms hanging, not pulled to
        // the hands' ends: a hand resting beside the hip is no end, and the end taken for it
        // (an elbow, a hip) pulls the arm into the trunk and the trunk askew with it. Not in
        // a restart, which comes mid-motion (a dancer's hands on the floor are ends), nor
        // with a hand on top (arms raised: the arms hanging took the hands for the head).
        if self.settings.start_arms_hanging && first && !hand_on_top {
            let hands = [
                KinectJoint::HandLeft.index(),
                KinectJoint::HandRight.index(),
            ];
            let no_hands: Vec<(usize, Vec3, f32)> = targets
                .iter()
                .copied()
                .filter(|t| !hands.contains(&t.0))
                .collect();
            if no_hands.len() < targets.len() {
                let (hanging, hanging_fit) =
                    self.start_facing(frame, person, spot, scale, &no_hands, away);
                if score(&hanging_fit) > score(&fit) {
                    return (hanging, hanging_fit);
                }
            }
        }
        // The kept fit's evidence per capsule (the joints' confidences) is its own.
        self.fitter.support = support;
        (pose, fit)
    }

    /// Where a start places the body, at what size, and the extrema it pulls it to.
    fn start_from(&mut self, frame: &DepthFrame, person: &Segmentation) -> StartFrom {
        let floor = person.floor;
        let ends = geodesic_extrema(frame, person);
        // A hand is the top of what is seen: raised.
        let hand_on_top = ends.iter().any(|e| {
            matches!(e.part, Part::HandLeft | Part::HandRight)
                && floor.height(e.position) > person.top_m - 0.1
        });
        // The head's end, if it is one: above the person's middle (within 25 cm across) and
        // within `below` of their top (a broad shoulder can pass for it).
        let head_end = |below: f32| {
            ends.iter().find(|e| {
                e.part == Part::Head
                    && floor.height(e.position) > person.top_m - below
                    && (e.position.x - person.centroid.x).abs() < 0.25
            })
        };
        // The start pulls to it only near the top, as before sizing looked farther down.
        let head = head_end(0.3).map(|e| e.position);
        // The person's height: the top of what is seen, unless that is a raised hand; then
        // the top of the head's surface around its end, which may lie an arm's reach under
        // the hands (not the top of a column above the head's end, which takes in a hand
        // raised close beside it: a small woman on CMU 13_10 was sized from her hand so, 11 %
        // too tall).
        let whole = usize::from(person.bbox[3]) + 1 < HEIGHT && usize::from(person.bbox[1]) > 0;
        let top = match (hand_on_top, head_end(0.7)) {
            (false, _) => Some(person.top_m),
            (true, Some(e)) => Some(floor.height(e.top)),
            (true, None) => None,
        };
        // Beneath the centroid of what is seen, half a body's depth behind it.
        let spot = |scale: f32| {
            let centre = person.centroid + person.centroid.normalize_or_zero() * 0.08 * scale;
            centre - floor.normal * floor.height(centre)
        };
        let scale = match (self.settings.scale.or(self.scale), top) {
            (Some(s), _) => s,
            (None, Some(top)) if whole => {
                // The top seen is the outline's, under the crown.
                let seen = self
                    .body
                    .rest_seen_top(spot(top / self.body.height_m), floor.normal);
                let s = (top / seen).clamp(SIZE_LIMITS.0, SIZE_LIMITS.1);
                self.scale = Some(s);
                s
            }
            // Not measurable yet (cut off, or arms up and no head found): the body's own
            // size until the person is seen whole.
            _ => 1.0,
        };
        let targets: Vec<(usize, Vec3, f32)> = ends
            .iter()
            .filter_map(|e| {
                let joint = match e.part {
                    Part::Head if head.is_some() => KinectJoint::Head,
                    Part::Head => return None,
                    Part::HandLeft => KinectJoint::HandLeft,
                    Part::HandRight => KinectJoint::HandRight,
                    Part::FootLeft => KinectJoint::FootLeft,
                    Part::FootRight => KinectJoint::FootRight,
                    Part::Other => return None,
                };
                Some((joint.index(), e.joint, 1.0))
            })
            .collect();
        StartFrom {
            spot: spot(scale),
            scale,
            targets,
            hand_on_top,
        }
    }

    /// A body followed with its back to the sensor, checked: a start facing the sensor is
    /// fitted to the frame and kept if it explains it better by [`TURN_CHECK_MARGIN`]. A
    /// person at a mirror faces it; a followed fit turned the wrong way round explains the
    /// depth almost as well as the right one (a trunk's front and back differ by little
    /// more than the sensor's steps at 3 m), so without this it is followed for as long as
    /// the person stays. Returns whether the start was kept.
    pub(super) fn check_turn(
        &mut self,
        frame: &DepthFrame,
        person: &Segmentation,
        pose: &mut Pose,
        fit: &mut FitStats,
    ) -> bool {
        let start = self.start_from(frame, person);
        let support = self.fitter.support.clone();
        let (facing, facing_fit) = self.start_facing(
            frame,
            person,
            start.spot,
            start.scale,
            &start.targets,
            false,
        );
        if facing.is_finite() && score(&facing_fit) > score(fit) + TURN_CHECK_MARGIN {
            (*pose, *fit) = (facing, facing_fit);
            true
        } else {
            self.fitter.support = support;
            false
        }
    }

    /// The body standing at `spot`, facing the sensor or `away` from it, pulled to `targets`
    /// (named as for a body facing the sensor), then fitted to the depth alone.
    fn start_facing(
        &mut self,
        frame: &DepthFrame,
        person: &Segmentation,
        spot: Vec3,
        scale: f32,
        targets: &[(usize, Vec3, f32)],
        away: bool,
    ) -> (Pose, FitStats) {
        let mut pose = self.body.standing_on(spot, person.floor.normal, scale);
        let mut targets = targets.to_vec();
        if away {
            let turn = Quat::from_axis_angle(person.floor.normal, std::f32::consts::PI);
            pose.rotation = (turn * pose.rotation).normalize();
            pose.translation = spot + turn * (pose.translation - spot);
            for t in &mut targets {
                t.0 = KinectJoint::ALL
                    .get(t.0)
                    .map_or(t.0, |j| j.mirror().index());
            }
        }
        let n = self.settings.start_iterations;
        self.fit(frame, person, &mut pose, &targets, n);
        let fit = self.fit(frame, person, &mut pose, &[], n / 3);
        (pose, fit)
    }

    /// Whether the body in `pose` has its back to the sensor.
    pub(super) fn faces_away(&mut self, pose: &Pose) -> bool {
        self.body.pose_into(pose, &mut self.posed);
        facing_degrees(&self.body.kinect_joints(&self.posed)).abs() > 90.0
    }
}

/// What [`Tracker::start_from`] finds.
struct StartFrom {
    /// Under the person's centroid, on the floor.
    spot: Vec3,
    scale: f32,
    /// The extrema as targets, named as for a body facing the sensor.
    targets: Vec<(usize, Vec3, f32)>,
    /// A hand is the top of what is seen.
    hand_on_top: bool,
}

/// A start facing the sensor replaces a followed fit with its back to it when it explains
/// the frame better by this ([`score`]).
const TURN_CHECK_MARGIN: f32 = 0.01;

/// A turn smaller than this between two frames (degrees) is the fit's jitter as often as the
/// person's turn, and is not carried on.
const MIN_TURN_CARRIED: f32 = 3.0;

/// `pose` turned on about the vertical as its root turned since `before` (the root's rotation
/// a frame earlier; `share` of that turn): a
/// dancer spinning keeps spinning, and a turn of the nearly round trunk about its own axis is
/// what depth alone shows least. Only the turn about `up`: the rest of the root's motion is
/// the fit's own jitter as often as the person's.
pub(super) fn carry_turn(pose: &mut Pose, before: Quat, up: Vec3, share: f32) {
    if share <= 0.0 {
        return;
    }
    let delta = (pose.rotation * before.inverse()).normalize();
    // The twist of `delta` about `up` (swing-twist decomposition).
    let (axis, w) = (Vec3::new(delta.x, delta.y, delta.z), delta.w);
    let along = up * axis.dot(up);
    // The shorter way round (`q` and `-q` are the same turn).
    let twist = Quat::from_xyzw(along.x, along.y, along.z, w) * w.signum();
    if twist.length_squared() < 1e-8 {
        return;
    }
    let twist = twist.normalize();
    if twist.angle_between(Quat::IDENTITY) < MIN_TURN_CARRIED.to_radians() {
        return;
    }
    let twist = Quat::IDENTITY.slerp(twist, share);
    let turned = (twist * pose.rotation).normalize();
    if turned.is_finite() {
        pose.rotation = turned;
    }
}
