//! Swipes: a hand sweeping sideways across the body, quickly and far enough, judged in the
//! body's own frame and size (seed 000 App. C: "a listener activated when the 3D velocity of
//! the hand exceeds a threshold", made invariant to the person's size and place).
//!
//! Each frame the hand's position is taken relative to the shoulder centre, along the
//! shoulders' line (the person's right) and the vertical, over the shoulder width. A swipe
//! is a stroke within [`SwipeSettings::max_duration_s`] whose sideways travel passes
//! [`SwipeSettings::min_travel`] shoulder widths at a mean speed above
//! [`SwipeSettings::min_speed`], level, with the hand raised in front of the body (not an
//! arm swinging at the hip) and the body standing still (a walking, jumping or turning
//! person's hands are not swiping). After a swipe the hand's way back (the opposite direction) is ignored for
//! [`SwipeSettings::return_s`], and any swipe for [`SwipeSettings::refractory_s`].

use std::collections::VecDeque;

use fitroom_sensor::{KinectJoint, SensorFrame};
use glam::{Vec2, Vec3};

use crate::HandSide;

/// Which way the hand swept, in the person's own terms (on the mirror, the same way on the
/// screen).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub enum SwipeDirection {
    /// Towards the person's left.
    Left,
    /// Towards the person's right.
    Right,
}

/// A detected swipe.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Swipe {
    pub direction: SwipeDirection,
    pub hand: HandSide,
    /// The frame's time, seconds.
    pub time_s: f64,
}

/// Thresholds (lengths in shoulder widths, times in seconds).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SwipeSettings {
    pub min_travel: f32,
    /// Mean sideways speed over the stroke, shoulder widths per second.
    pub min_speed: f32,
    pub max_duration_s: f32,
    /// The stroke's vertical range (every sample's, not only its ends: a hand raised across
    /// the body is not level) over its sideways travel.
    pub max_slope: f32,
    /// The hand's height band relative to the shoulder centre (negative: below).
    pub min_height: f32,
    pub max_height: f32,
    /// How far in front of the shoulders the hand must be, shoulder widths.
    pub min_reach: f32,
    /// The hip centre's speed (in any direction: walking, jumping) above which the body is
    /// on the move, shoulder widths per second, and the shoulders' turning rate above which
    /// it is turning (a pirouette), degrees per second; both over [`Self::walk_window_s`].
    pub max_body_speed: f32,
    pub max_turn_deg_s: f32,
    pub walk_window_s: f32,
    pub refractory_s: f32,
    pub return_s: f32,
    /// A stroke is a swipe once the hand has not swung back `wave_back` shoulder widths
    /// within this time (a wave swings to and fro; a swipe ends and the hand drops or rests).
    pub confirm_s: f32,
    pub wave_back: f32,
    /// Faster than a hand moves (shoulder widths per second; a quick swipe peaks near 14):
    /// a stroke whose hand jumps this fast before it is confirmed is the tracker losing the
    /// hand, not the hand.
    pub max_hand_speed: f32,
}

impl Default for SwipeSettings {
    fn default() -> Self {
        Self {
            min_travel: 1.0,
            min_speed: 2.2,
            max_duration_s: 0.8,
            max_slope: 0.6,
            min_height: -1.6,
            max_height: 0.6,
            min_reach: 0.3,
            max_body_speed: 1.0,
            max_turn_deg_s: 90.0,
            walk_window_s: 0.5,
            refractory_s: 0.5,
            return_s: 1.2,
            confirm_s: 0.3,
            wave_back: 0.5,
            max_hand_speed: 25.0,
        }
    }
}

/// One hand's recent positions in the body frame.
#[derive(Clone, Debug, Default)]
struct Track {
    /// (time, sideways and up over shoulder width, usable: raised and in front).
    samples: VecDeque<(f64, Vec2, bool)>,
}

/// The swipe detector of both hands.
#[derive(Clone, Debug, Default)]
pub struct SwipeDetector {
    pub settings: SwipeSettings,
    hands: [Track; 2],
    /// The hip centre and the shoulders' direction (the person's right), over time.
    hips: VecDeque<(f64, Vec3, Vec3)>,
    last: Option<Swipe>,
    /// A stroke waiting [`SwipeSettings::confirm_s`] for the hand not to swing back (a
    /// wave) nor to carry on downwards (an arm dropping out to the side), nor to jump (the
    /// tracker losing the hand).
    pending: Option<Pending>,
}

/// A stroke found, followed until it is confirmed (positions in shoulder widths).
#[derive(Clone, Copy, Debug)]
struct Pending {
    swipe: Swipe,
    /// Where the stroke began and ended, sideways.
    start_x: f32,
    end_x: f32,
    /// The farthest the hand has gone in the stroke's direction since, sideways, and the
    /// vertical range of the movement up to there.
    farthest_x: f32,
    low: f32,
    high: f32,
    /// The vertical range since the farthest point (it joins the movement's if the hand goes
    /// farther still).
    since_low: f32,
    since_high: f32,
    /// The hand's last position and time, and its fastest move since, shoulder widths/s.
    last: (f64, Vec2),
    fastest: f32,
}

impl Pending {
    /// The stroke's direction as a sign along the sideways axis.
    fn sign(&self) -> f32 {
        match self.swipe.direction {
            SwipeDirection::Right => 1.0,
            SwipeDirection::Left => -1.0,
        }
    }

    /// Follows the stroke's hand at `p` at time `t`.
    fn follow(&mut self, t: f64, p: Vec2) {
        let dt = (t - self.last.0) as f32;
        if dt > 0.0 {
            self.fastest = self.fastest.max(p.distance(self.last.1) / dt);
        }
        self.last = (t, p);
        self.since_low = self.since_low.min(p.y);
        self.since_high = self.since_high.max(p.y);
        if (p.x - self.farthest_x) * self.sign() > 0.0 {
            self.farthest_x = p.x;
            self.low = self.low.min(self.since_low);
            self.high = self.high.max(self.since_high);
            self.since_low = p.y;
            self.since_high = p.y;
        }
    }

    /// The hand swung back this far from the stroke's end (a wave), shoulder widths.
    fn back(&self, p: Vec2) -> f32 {
        (self.end_x - p.x) * self.sign()
    }

    /// The whole movement in the stroke's direction, from its start to the farthest point,
    /// is steeper than `max_slope` (the stroke was a level stretch of a diagonal sweep).
    fn diagonal(&self, max_slope: f32) -> bool {
        self.high - self.low > max_slope * (self.farthest_x - self.start_x).abs()
    }
}

/// The person's frame: the shoulder centre, their right (unit, horizontal), up, forward
/// (towards the sensor), and the shoulder width; `None` if the joints are missing.
pub fn body_frame(frame: &SensorFrame) -> Option<(Vec3, Vec3, Vec3, f32)> {
    let at = |j: KinectJoint| {
        let s = frame.joint(j);
        (s.confidence > 0.0 && s.position.is_finite()).then_some(s.position)
    };
    let (l, r) = (
        at(KinectJoint::ShoulderLeft)?,
        at(KinectJoint::ShoulderRight)?,
    );
    let centre = at(KinectJoint::ShoulderCenter).unwrap_or((l + r) * 0.5);
    let across = r - l;
    let width = across.length();
    if !(0.15..=0.8).contains(&width) {
        return None;
    }
    let right = Vec3::new(across.x, 0.0, across.z).try_normalize()?;
    // Facing the sensor: forward is towards it (-Z); right x up points backwards.
    let forward = Vec3::Y.cross(right);
    Some((centre, right, forward, width))
}

impl SwipeDetector {
    pub fn new(settings: SwipeSettings) -> Self {
        Self {
            settings,
            ..Self::default()
        }
    }

    /// Forgets every hand and the last swipe (a new person).
    pub fn reset(&mut self) {
        *self = Self::new(self.settings);
    }

    /// Takes one skeleton frame; returns a swipe confirmed here: its stroke ended
    /// [`SwipeSettings::confirm_s`] ago and the hand did not swing back.
    pub fn update(&mut self, frame: &SensorFrame) -> Option<Swipe> {
        let s = self.settings;
        let t = frame.timestamp_s;
        let Some((centre, right, forward, width)) = body_frame(frame) else {
            // The person lost mid-gesture (the tracker's frame without a skeleton): a stroke
            // waiting to be confirmed is not (when the tracker finds them again, their hands
            // are wherever it puts them first). A frame that never came (a Kinect drops
            // some) is no evidence either way.
            self.pending = None;
            return None;
        };
        let keep = f64::from(s.max_duration_s.max(s.walk_window_s)) + 0.1;
        let hip = frame.joint(KinectJoint::HipCenter).position;
        if hip.is_finite() {
            self.hips.push_back((t, hip, right));
        }
        while self.hips.front().is_some_and(|h| h.0 < t - keep) {
            self.hips.pop_front();
        }
        let moving = self.body_moving(t, width);
        let mut found = None;
        for (k, side) in [HandSide::Left, HandSide::Right].into_iter().enumerate() {
            let joint = match side {
                HandSide::Left => KinectJoint::HandLeft,
                HandSide::Right => KinectJoint::HandRight,
            };
            let sample = frame.joint(joint);
            let track = &mut self.hands[k];
            while track.samples.front().is_some_and(|h| h.0 < t - keep) {
                track.samples.pop_front();
            }
            if sample.confidence <= 0.0 || !sample.position.is_finite() {
                continue;
            }
            let d = sample.position - centre;
            let p = Vec2::new(d.dot(right), d.y) / width;
            let reach = d.dot(forward) / width;
            // A hand the tracker only infers (it does not see it: before the body, out of
            // view) makes no stroke: its jumps are the tracker's, not the hand's.
            let usable = !moving
                && sample.confidence >= 1.0
                && (s.min_height..=s.max_height).contains(&p.y)
                && reach >= s.min_reach;
            track.samples.push_back((t, p, usable));
            if found.is_none()
                && let Some((direction, start, low, high)) = stroke(&track.samples, &s)
            {
                let swipe = Swipe {
                    direction,
                    hand: side,
                    time_s: t,
                };
                found = Some(Pending {
                    swipe,
                    start_x: start,
                    end_x: p.x,
                    farthest_x: p.x,
                    low,
                    high,
                    since_low: p.y,
                    since_high: p.y,
                    last: (t, p),
                    fastest: 0.0,
                });
            }
        }
        // A pending stroke becomes a swipe unless its hand swings back (a wave), the movement
        // it was part of carries on steeply (an arm dropping out to the side), or the hand
        // jumps (the tracker lost it; a frame without the person, above, drops it too).
        let mut confirmed = None;
        if let Some(mut pending) = self.pending {
            let latest = self.hands[pending.swipe.hand.index()]
                .samples
                .back()
                .filter(|h| h.0 > pending.last.0);
            if let Some(&(at, p, _)) = latest {
                pending.follow(at, p);
            }
            self.pending = Some(pending);
            let back = latest.map_or(0.0, |h| pending.back(h.1));
            if back >= s.wave_back
                || pending.diagonal(s.max_slope)
                || pending.fastest > s.max_hand_speed
            {
                self.pending = None;
            } else if (t - pending.swipe.time_s) as f32 >= s.confirm_s {
                self.pending = None;
                confirmed = Some(pending.swipe);
            }
        }
        if let Some(stroke) = found {
            let swipe = stroke.swipe;
            let since_last = self
                .last
                .map(|last| ((t - last.time_s) as f32, last.direction));
            let refused = since_last.is_some_and(|(since, direction)| {
                since < s.refractory_s || (since < s.return_s && swipe.direction != direction)
            });
            if !refused && self.pending.is_none() {
                self.pending = Some(stroke);
                self.last = Some(swipe);
                // The stroke is used up: the next swipe needs a stroke of its own.
                for track in &mut self.hands {
                    track.samples.retain(|h| h.0 >= t);
                }
            }
        }
        confirmed
    }

    /// Whether the body is on the move over the walk window: its hip centre faster than a
    /// standing person's, or its shoulders turning.
    fn body_moving(&self, t: f64, width: f32) -> bool {
        let s = self.settings;
        let Some(&(t1, p1, r1)) = self.hips.back() else {
            return false;
        };
        let Some(&(t0, p0, r0)) = self
            .hips
            .iter()
            .find(|h| h.0 >= t - f64::from(s.walk_window_s))
        else {
            return false;
        };
        let dt = (t1 - t0) as f32;
        if dt < 0.1 {
            return false;
        }
        let turned = r0.dot(r1).clamp(-1.0, 1.0).acos().to_degrees();
        (p1 - p0).length() / dt / width > s.max_body_speed || turned / dt > s.max_turn_deg_s
    }
}

/// A swipe direction if the samples (oldest first) end with a qualifying stroke: from some
/// sample within the duration to the last, every sample usable, sideways travel and mean
/// speed past the thresholds, every sample's height within the slope's band, no jump faster
/// than a hand moves between samples. With it, where
/// the stroke began sideways and its vertical range (low, high).
fn stroke(
    samples: &VecDeque<(f64, Vec2, bool)>,
    s: &SwipeSettings,
) -> Option<(SwipeDirection, f32, f32, f32)> {
    let &(t1, p1, ok1) = samples.back()?;
    if !ok1 {
        return None;
    }
    let (mut low, mut high) = (p1.y, p1.y);
    let mut later = (t1, p1);
    for &(t0, p0, ok0) in samples.iter().rev().skip(1) {
        let dt = (t1 - t0) as f32;
        // A jump faster than a hand moves is the tracker's: no stroke spans it.
        let step_s = (later.0 - t0) as f32;
        let jumped = step_s > 0.0 && later.1.distance(p0) / step_s > s.max_hand_speed;
        if dt > s.max_duration_s || !ok0 || jumped {
            break;
        }
        later = (t0, p0);
        low = low.min(p0.y);
        high = high.max(p0.y);
        let travel = p1 - p0;
        if travel.x.abs() >= s.min_travel
            && travel.x.abs() / dt >= s.min_speed
            && high - low <= s.max_slope * travel.x.abs()
        {
            let direction = if travel.x > 0.0 {
                SwipeDirection::Right
            } else {
                SwipeDirection::Left
            };
            return Some((direction, p0.x, low, high));
        }
    }
    None
}
