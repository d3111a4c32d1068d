//! Hands from depth and the gestures made with them: whether a hand is open or closed
//! ([`hand`]: seed 000's App. C method and ours), synthetic hands to train and test them on
//! ([`synth`]).
#![forbid(unsafe_code)]

pub mod cursor;
pub mod eval;
pub mod hand;
pub mod swipe;
pub mod synth;

#[cfg(feature = "plugin")]
pub mod plugin;

/// Which hand.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub enum HandSide {
    Left,
    Right,
}

impl HandSide {
    /// This side's hand, wrist and elbow Kinect joints.
    pub fn arm_joints(self) -> [fitroom_sensor::KinectJoint; 3] {
        use fitroom_sensor::KinectJoint::*;
        match self {
            HandSide::Left => [HandLeft, WristLeft, ElbowLeft],
            HandSide::Right => [HandRight, WristRight, ElbowRight],
        }
    }
}

/// What a hand is doing.
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize,
)]
pub enum HandState {
    Open,
    Closed,
    /// Not seen well enough to say (out of view, against the body, too far).
    #[default]
    Unknown,
}
