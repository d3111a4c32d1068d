//! Hands from depth and the gestures made with them: whether a hand is open or closed
//! ([`hand`]: seed 000's App. C method and ours), synthetic hands to train and test them on
//! ([`synth`]), scripted people making gestures ([`script`]), and the reader of all of it
//! frame by frame ([`reader`]).
#![forbid(unsafe_code)]

pub mod cursor;
pub mod eval;
pub mod hand;
pub mod reader;
pub mod script;
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
    /// The rig's bone-name suffix of this side.
    pub fn suffix(self) -> &'static str {
        match self {
            HandSide::Left => "_l",
            HandSide::Right => "_r",
        }
    }

    /// This side's index in the `[left, right]` arrays.
    pub fn index(self) -> usize {
        match self {
            HandSide::Left => 0,
            HandSide::Right => 1,
        }
    }

    /// +1 for the right hand, -1 for the left: the hand's side along the person's right.
    pub fn rightward(self) -> f32 {
        -self.outward()
    }

    /// +1 for the left arm (the body's +X side in model space), -1 for the right.
    pub fn outward(self) -> f32 {
        match self {
            HandSide::Left => 1.0,
            HandSide::Right => -1.0,
        }
    }

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
