//! Whether a hand is open or closed, from depth and the skeleton's hand, wrist and elbow:
//! seed 000's method ([`seed`]) and ours ([`classify`]: metric features of the hand's
//! region, [`region`], read by a logistic model trained on synthetic hands), and the
//! per-hand state with hysteresis the kiosk reads ([`state`]).

pub mod classify;
pub mod geometry;
pub mod region;
pub mod seed;
pub mod state;
