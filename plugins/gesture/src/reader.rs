//! Everything the hands say, frame by frame (Bevy-free: the plugin, the CLI and the tests
//! run the same reader): both hands' states from depth, swipes, and the hand cursor with its
//! grip clicks.

use fitroom_depth::DepthFrame;
use fitroom_sensor::SensorFrame;

use crate::HandSide;
use crate::HandState;
use crate::cursor::{Click, Cursor, CursorTracker};
use crate::hand::classify::{HandLook, HandModel, look};
use crate::hand::region::HandJoints;
use crate::hand::state::HandFilter;
use crate::swipe::{Swipe, SwipeDetector};

/// What one skeleton frame gave.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GestureStep {
    pub swipe: Option<Swipe>,
    pub cursor: Option<Cursor>,
    pub click: Option<Click>,
}

/// The detectors of one person.
#[derive(Clone, Debug, Default)]
pub struct GestureReader {
    pub model: Option<HandModel>,
    pub filters: [HandFilter; 2],
    pub swipes: SwipeDetector,
    pub cursor: CursorTracker,
    /// [left, right] after the hysteresis, and the last look's probability of open.
    pub hands: [HandState; 2],
    pub p_open: [f32; 2],
}

impl GestureReader {
    /// A reader with the embedded hand model (`None` with the model's error: hands are
    /// then unknown, swipes still work).
    pub fn new(model: Option<HandModel>) -> Self {
        Self {
            model,
            ..Self::default()
        }
    }

    /// Reads both hands in `depth` at the joints of `skeleton` (the skeleton frame that came
    /// with it); `None`: no depth at all (a skeleton-only sensor), the hands are unseen.
    pub fn read_hands(&mut self, skeleton: &SensorFrame, depth: Option<&DepthFrame>) {
        for (i, side) in [HandSide::Left, HandSide::Right].into_iter().enumerate() {
            let seen = match (depth, &self.model) {
                (Some(depth), Some(model)) => {
                    look(depth, &HandJoints::of_frame(skeleton, side), model)
                }
                _ => HandLook::UNSEEN,
            };
            self.hands[i] = self.filters[i].update(&seen);
            self.p_open[i] = self.filters[i].p_open;
        }
    }

    /// Swipes and the cursor on one skeleton frame, with the hands' last states.
    pub fn step(&mut self, skeleton: &SensorFrame) -> GestureStep {
        let swipe = self.swipes.update(skeleton);
        let (cursor, click) = self.cursor.update(skeleton, self.hands);
        GestureStep {
            swipe,
            cursor,
            click,
        }
    }
}
