//! The hand cursor: the raised hand's position in an interaction box fixed to the body
//! (beside the shoulder of that hand, sized by the shoulder width, so a short and a tall
//! person reach the screen's corners alike), smoothed (the One Euro filter's idea: smooth
//! when still, quick when moving), mirrored like the mirror (the person's right is the
//! screen's right); a grip presses, opening releases. A grip presses only a hand that was
//! seen open and held still for a moment since it was raised, and is still now: a hand read
//! closed while it rises or drops past the body (where its region is the arm's), or a waving
//! hand read closed when seen edge-on, clicks nothing.

use fitroom_motion::filter::one_euro::smoothing_factor;
use fitroom_sensor::{KinectJoint, SensorFrame};
use glam::{Vec2, Vec3};

use crate::swipe::body_frame;
use crate::{HandSide, HandState};

/// The box and the smoothing.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CursorSettings {
    /// The box's centre from the shoulder centre: sideways towards the hand's side, and up,
    /// in shoulder widths; its half width and half height.
    pub centre_out: f32,
    pub centre_up: f32,
    pub half_width: f32,
    pub half_height: f32,
    /// A hand this far in front of the shoulders (shoulder widths) drives the cursor.
    pub min_reach: f32,
    /// Cutoff at rest and its growth with speed (screen widths per second), Hz.
    pub min_cutoff_hz: f32,
    pub beta: f32,
    /// A hand moving slower than this (box widths per second, over [`Self::still_window_s`])
    /// is still.
    pub max_still_speed: f32,
    pub still_window_s: f32,
    /// How long the hand must be seen open and still before a grip may press, seconds.
    pub arm_s: f32,
}

impl Default for CursorSettings {
    fn default() -> Self {
        Self {
            centre_out: 0.5,
            centre_up: -0.4,
            half_width: 0.9,
            half_height: 0.7,
            min_reach: 0.5,
            min_cutoff_hz: 1.5,
            beta: 4.0,
            max_still_speed: 0.8,
            still_window_s: 0.25,
            arm_s: 0.3,
        }
    }
}

/// The cursor this frame.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Cursor {
    pub hand: HandSide,
    /// On the screen, 0..1 each way from the top left.
    pub position: Vec2,
    /// The hand is closed (a grip presses).
    pub pressed: bool,
}

/// A press or a release.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum Click {
    Press,
    Release,
}

/// Follows the raised hand.
#[derive(Clone, Debug, Default)]
pub struct CursorTracker {
    pub settings: CursorSettings,
    smoothed: Option<(HandSide, Vec2, f64)>,
    /// The raw positions of the last [`CursorSettings::still_window_s`].
    recent: std::collections::VecDeque<(f64, Vec2)>,
    /// Since when the hand has been seen open and still (without a break).
    open_since: Option<f64>,
    /// The hand was seen open and still for `arm_s` since it was raised (a grip may press).
    armed: bool,
    pressed: bool,
}

impl CursorTracker {
    pub fn new(settings: CursorSettings) -> Self {
        Self {
            settings,
            ..Self::default()
        }
    }

    /// Takes one frame and both hands' states ([left, right]); returns the cursor (`None`:
    /// no hand raised) and a click if the driving hand closed or opened.
    pub fn update(
        &mut self,
        frame: &SensorFrame,
        states: [HandState; 2],
    ) -> (Option<Cursor>, Option<Click>) {
        let s = self.settings;
        let Some((centre, right, forward, width)) = body_frame(frame) else {
            return (None, self.release());
        };
        // The driving hand: the raised one reaching furthest forward.
        let mut best: Option<(HandSide, Vec3, f32)> = None;
        for (side, joint) in [
            (HandSide::Left, KinectJoint::HandLeft),
            (HandSide::Right, KinectJoint::HandRight),
        ] {
            let sample = frame.joint(joint);
            if sample.confidence <= 0.0 || !sample.position.is_finite() {
                continue;
            }
            let reach = (sample.position - centre).dot(forward) / width;
            if reach >= s.min_reach && best.is_none_or(|b| reach > b.2) {
                best = Some((side, sample.position, reach));
            }
        }
        let box_of = |side: HandSide, hand: Vec3| {
            let out = side.rightward();
            let d = (hand - centre) / width;
            Vec2::new(
                (d.dot(right) - out * s.centre_out) / s.half_width,
                (d.y - s.centre_up) / s.half_height,
            )
        };
        // A hand below the box is not raised (an arm swinging forwards in a walk).
        let Some((side, hand, _)) = best.filter(|b| box_of(b.0, b.1).y >= -1.0) else {
            self.smoothed = None;
            self.recent.clear();
            self.armed = false;
            self.open_since = None;
            return (None, self.release());
        };
        let Vec2 { x, y } = box_of(side, hand);
        let raw = Vec2::new(0.5 + 0.5 * x, 0.5 - 0.5 * y).clamp(Vec2::ZERO, Vec2::ONE);
        let t = frame.timestamp_s;
        let position = match self.smoothed {
            Some((hand_was, last, t0)) if hand_was == side && t > t0 => {
                let dt = (t - t0) as f32;
                let speed = (raw - last).length() / dt;
                let cutoff = s.min_cutoff_hz + s.beta * speed;
                let a = smoothing_factor(f64::from(cutoff), f64::from(dt)) as f32;
                last + (raw - last) * a
            }
            _ => raw,
        };
        if self.smoothed.is_some_and(|(was, _, _)| was != side) {
            self.recent.clear();
            self.armed = false;
            self.open_since = None;
        }
        self.smoothed = Some((side, position, t));
        // Still: the raw position moved little over the window.
        while self
            .recent
            .front()
            .is_some_and(|&(t0, _)| t - t0 > f64::from(s.still_window_s) || t0 > t)
        {
            self.recent.pop_front();
        }
        let still = self.recent.front().is_some_and(|&(t0, p0)| {
            t - t0 >= f64::from(s.still_window_s) * 0.5
                && (raw - p0).length() <= s.max_still_speed * (t - t0) as f32
        });
        self.recent.push_back((t, raw));
        let closed = states[side.index()] == HandState::Closed;
        let opened = states[side.index()] == HandState::Open;
        if opened && still {
            let since = *self.open_since.get_or_insert(t);
            if t - since >= f64::from(s.arm_s) {
                self.armed = true;
            }
        } else {
            self.open_since = None;
        }
        let click = if closed && !self.pressed && self.armed && still {
            self.pressed = true;
            self.armed = false;
            Some(Click::Press)
        } else if opened && self.pressed {
            self.pressed = false;
            Some(Click::Release)
        } else {
            None
        };
        (
            Some(Cursor {
                hand: side,
                position,
                pressed: self.pressed,
            }),
            click,
        )
    }

    /// Whether a grip would press now (the hand was seen open and still since it was raised).
    pub fn armed(&self) -> bool {
        self.armed
    }

    fn release(&mut self) -> Option<Click> {
        std::mem::take(&mut self.pressed).then_some(Click::Release)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use fitroom_sensor::JointSample;
    use glam::Quat;

    /// A person 2 m away facing the sensor, the right hand at `hand` (body frame: right,
    /// up, forward from the shoulder centre, metres).
    fn frame(t: f64, hand: Vec3) -> SensorFrame {
        let mut f = SensorFrame {
            timestamp_s: t,
            sequence: 0,
            joints: [JointSample {
                position: Vec3::new(0.0, 0.0, 2.0),
                orientation: Quat::IDENTITY,
                confidence: 1.0,
            }; KinectJoint::COUNT],
        };
        let centre = Vec3::new(0.0, 0.5, 2.0);
        // Facing the sensor, the person's right is the sensor's +X, forward is -Z.
        f.joints[KinectJoint::ShoulderCenter.index()].position = centre;
        f.joints[KinectJoint::ShoulderLeft.index()].position = centre - Vec3::X * 0.18;
        f.joints[KinectJoint::ShoulderRight.index()].position = centre + Vec3::X * 0.18;
        f.joints[KinectJoint::HandLeft.index()].position = centre + Vec3::new(-0.2, -0.7, 0.0);
        f.joints[KinectJoint::HandRight.index()].position =
            centre + Vec3::new(hand.x, hand.y, -hand.z);
        f
    }

    #[test]
    fn the_raised_hand_moves_the_cursor_like_a_mirror_and_grips_click() {
        let mut c = CursorTracker::default();
        let open = [HandState::Unknown, HandState::Open];
        let closed = [HandState::Unknown, HandState::Closed];
        // Hands down: no cursor.
        assert!(
            c.update(&frame(0.0, Vec3::new(0.2, -0.7, 0.0)), open)
                .0
                .is_none()
        );
        // Raised, to the person's right: the screen's right half.
        let (cursor, click) = c.update(&frame(0.1, Vec3::new(0.4, -0.1, 0.4)), open);
        let cursor = cursor.expect("raised");
        assert_eq!(cursor.hand, HandSide::Right);
        assert!(cursor.position.x > 0.6, "{cursor:?}");
        assert!(click.is_none());
        // Moved to the left and up, held there: the cursor follows, left of where it was.
        let mut p = cursor.position;
        for k in 0..30 {
            let (cur, _) = c.update(
                &frame(0.2 + k as f64 / 30.0, Vec3::new(-0.1, 0.05, 0.4)),
                open,
            );
            p = cur.expect("raised").position;
        }
        assert!(
            p.x < cursor.position.x - 0.2 && p.y < cursor.position.y,
            "{p}"
        );
        // Grip, then open: a press then a release.
        let t = 1.2;
        assert_eq!(
            c.update(&frame(t, Vec3::new(-0.1, 0.05, 0.4)), closed).1,
            Some(Click::Press)
        );
        assert_eq!(
            c.update(&frame(t + 0.03, Vec3::new(-0.1, 0.05, 0.4)), closed)
                .1,
            None
        );
        assert_eq!(
            c.update(&frame(t + 0.06, Vec3::new(-0.1, 0.05, 0.4)), open)
                .1,
            Some(Click::Release)
        );
        // A hand read closed as it rises (no open, still hand seen yet) does not press.
        let mut c2 = CursorTracker::default();
        for k in 0..10 {
            let y = -0.6 + 0.07 * k as f32;
            let (_, click) = c2.update(&frame(k as f64 / 30.0, Vec3::new(0.3, y, 0.4)), closed);
            assert_eq!(click, None, "frame {k}");
        }
        // Held still and open, then closed: a press.
        let mut pressed = false;
        for k in 10..40 {
            let states = if k < 30 { open } else { closed };
            let (_, click) = c2.update(&frame(k as f64 / 30.0, Vec3::new(0.3, 0.0, 0.4)), states);
            pressed |= click == Some(Click::Press);
        }
        assert!(pressed);
        // Right after a release a grip does not press: the hand must be seen open a moment.
        assert_eq!(
            c.update(&frame(t + 0.1, Vec3::new(-0.1, 0.05, 0.4)), closed)
                .1,
            None
        );
        // Open and still for 0.4 s, then a grip: pressed; then the hand drops: released.
        for k in 0..12 {
            c.update(
                &frame(t + 0.13 + k as f64 / 30.0, Vec3::new(-0.1, 0.05, 0.4)),
                open,
            );
        }
        assert_eq!(
            c.update(&frame(t + 0.55, Vec3::new(-0.1, 0.05, 0.4)), closed)
                .1,
            Some(Click::Press)
        );
        let (cur, click) = c.update(&frame(t + 0.58, Vec3::new(0.2, -0.7, 0.0)), closed);
        assert!(cur.is_none());
        assert_eq!(click, Some(Click::Release));
    }
}
