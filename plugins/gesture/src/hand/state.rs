//! A hand's state over frames: the per-frame probability smoothed, with hysteresis (it
//! takes a clear look to change the state, so a grip does not flicker), unknown after a few
//! frames without a look.

use crate::HandState;

use super::classify::HandLook;

/// Hysteresis settings.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Hysteresis {
    /// The smoothed probability must pass these to turn open / closed.
    pub open_above: f32,
    pub closed_below: f32,
    /// Each frame's weight in the smoothed probability.
    pub blend: f32,
    /// Frames without a look before the state is unknown.
    pub unseen_frames: u32,
}

impl Default for Hysteresis {
    fn default() -> Self {
        Self {
            open_above: 0.65,
            closed_below: 0.35,
            blend: 0.6,
            unseen_frames: 4,
        }
    }
}

/// One hand's state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HandFilter {
    pub settings: Hysteresis,
    pub state: HandState,
    pub p_open: f32,
    unseen: u32,
    /// No look since the start or since the hand was lost: the next look is taken whole.
    fresh: bool,
}

impl HandFilter {
    pub fn new(settings: Hysteresis) -> Self {
        Self {
            settings,
            state: HandState::Unknown,
            p_open: 0.5,
            unseen: 0,
            fresh: true,
        }
    }

    /// Takes one frame's look; returns the state.
    pub fn update(&mut self, look: &HandLook) -> HandState {
        let s = self.settings;
        if look.state == HandState::Unknown {
            self.unseen += 1;
            if self.unseen >= s.unseen_frames {
                self.state = HandState::Unknown;
                self.p_open = 0.5;
                self.fresh = true;
            }
            return self.state;
        }
        self.unseen = 0;
        self.p_open = if std::mem::take(&mut self.fresh) {
            look.p_open
        } else {
            self.p_open + s.blend * (look.p_open - self.p_open)
        };
        if self.p_open > s.open_above {
            self.state = HandState::Open;
        } else if self.p_open < s.closed_below {
            self.state = HandState::Closed;
        }
        self.state
    }
}

impl Default for HandFilter {
    fn default() -> Self {
        Self::new(Hysteresis::default())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn look(p: f32) -> HandLook {
        HandLook {
            state: if p >= 0.5 {
                HandState::Open
            } else {
                HandState::Closed
            },
            p_open: p,
            features: None,
        }
    }

    #[test]
    fn one_doubtful_frame_does_not_flip_the_state() {
        let mut f = HandFilter::default();
        for _ in 0..3 {
            f.update(&look(0.9));
        }
        assert_eq!(f.state, HandState::Open);
        // One frame that says closed, then open again: still open.
        assert_eq!(f.update(&look(0.3)), HandState::Open);
        assert_eq!(f.update(&look(0.9)), HandState::Open);
        // A clear grip turns it within two frames.
        f.update(&look(0.05));
        assert_eq!(f.update(&look(0.05)), HandState::Closed);
        // Lost for a while: unknown.
        for _ in 0..4 {
            f.update(&HandLook::UNSEEN);
        }
        assert_eq!(f.state, HandState::Unknown);
    }
}
