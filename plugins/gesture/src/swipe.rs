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
    /// wave), with where the stroke ended (sideways, shoulder widths).
    pending: Option<(Swipe, f32)>,
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
        let (centre, right, forward, width) = body_frame(frame)?;
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
                && let Some(direction) = stroke(&track.samples, &s)
            {
                found = Some(Swipe {
                    direction,
                    hand: side,
                    time_s: t,
                });
            }
        }
        // A pending stroke becomes a swipe unless its hand swings back (a wave).
        let mut confirmed = None;
        if let Some((swipe, end_x)) = self.pending {
            let back = self.hands[swipe.hand.index()]
                .samples
                .back()
                .map_or(0.0, |h| {
                    let moved = h.1.x - end_x;
                    match swipe.direction {
                        SwipeDirection::Right => -moved,
                        SwipeDirection::Left => moved,
                    }
                });
            if back >= s.wave_back {
                self.pending = None;
            } else if (t - swipe.time_s) as f32 >= s.confirm_s {
                self.pending = None;
                confirmed = Some(swipe);
            }
        }
        if let Some(swipe) = found {
            let since_last = self
                .last
                .map(|last| ((t - last.time_s) as f32, last.direction));
            let refused = since_last.is_some_and(|(since, direction)| {
                since < s.refractory_s || (since < s.return_s && swipe.direction != direction)
            });
            if !refused && self.pending.is_none() {
                let end_x = self.hands[swipe.hand.index()]
                    .samples
                    .back()
                    .map_or(0.0, |h| h.1.x);
                self.pending = Some((swipe, end_x));
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
/// speed past the thresholds, every sample's height within the slope's band.
fn stroke(samples: &VecDeque<(f64, Vec2, bool)>, s: &SwipeSettings) -> Option<SwipeDirection> {
    let &(t1, p1, ok1) = samples.back()?;
    if !ok1 {
        return None;
    }
    let (mut low, mut high) = (p1.y, p1.y);
    for &(t0, p0, ok0) in samples.iter().rev().skip(1) {
        let dt = (t1 - t0) as f32;
        if dt > s.max_duration_s || !ok0 {
            break;
        }
        low = low.min(p0.y);
        high = high.max(p0.y);
        let travel = p1 - p0;
        if travel.x.abs() >= s.min_travel
            && travel.x.abs() / dt >= s.min_speed
            && high - low <= s.max_slope * travel.x.abs()
        {
            return Some(if travel.x > 0.0 {
                SwipeDirection::Right
            } else {
                SwipeDirection::Left
            });
        }
    }
    None
}
