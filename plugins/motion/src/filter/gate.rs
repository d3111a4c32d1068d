//! Bad-frame rejection before filtering.
//!
//! A Kinect stream occasionally delivers frames no filter should see: non-finite numbers, a
//! skeleton collapsed onto the origin (the SDK reports untracked skeletons as zeros) or onto a
//! single point, a frame without its hip centre, a joint at exactly `(0, 0, 0)` (the SDK's
//! "invalid joint", see `JointPositionIsValid` in the SDK sample, [`super::holt`]), or a
//! timestamp that does not move forward. [`FrameGate::check`] classifies each frame; a rejected
//! frame leaves the gate's last good frame in place ([`FrameGate::last_good`]), which the caller
//! shows instead ([`FrameGate::pass`] does both), and is counted by reason in [`GateStats`].

use fitroom_sensor::{KinectJoint, SensorFrame};
use glam::Vec3;
use serde::{Deserialize, Serialize};

/// Why a frame was rejected, in the order the checks run (the first failing check names it).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum RejectReason {
    /// A position, orientation, confidence or the timestamp is NaN or infinite.
    NonFinite,
    /// Every joint is at the origin (an empty skeleton).
    AllAtOrigin,
    /// Every joint is at one and the same point (a collapsed skeleton).
    AllIdentical,
    /// The hip centre is not tracked (confidence 0): there is no body to place.
    MissingHip,
    /// Some joint is exactly at the origin (the SDK's invalid joint).
    ZeroJoint,
    /// The timestamp is earlier than the last accepted frame's.
    TimestampBackwards,
    /// The timestamp equals the last accepted frame's.
    TimestampRepeated,
}

impl RejectReason {
    pub const ALL: [RejectReason; 7] = [
        RejectReason::NonFinite,
        RejectReason::AllAtOrigin,
        RejectReason::AllIdentical,
        RejectReason::MissingHip,
        RejectReason::ZeroJoint,
        RejectReason::TimestampBackwards,
        RejectReason::TimestampRepeated,
    ];

    fn slot(self) -> usize {
        self as usize
    }

    pub fn name(self) -> &'static str {
        match self {
            RejectReason::NonFinite => "non_finite",
            RejectReason::AllAtOrigin => "all_at_origin",
            RejectReason::AllIdentical => "all_identical",
            RejectReason::MissingHip => "missing_hip",
            RejectReason::ZeroJoint => "zero_joint",
            RejectReason::TimestampBackwards => "timestamp_backwards",
            RejectReason::TimestampRepeated => "timestamp_repeated",
        }
    }
}

/// The gate's verdict on one frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GateDecision {
    /// Good frame: it is now the gate's last good frame.
    Accept,
    /// Bad frame: hold the last good frame ([`FrameGate::last_good`]).
    Reject(RejectReason),
}

impl GateDecision {
    pub fn is_accept(self) -> bool {
        self == GateDecision::Accept
    }
}

/// Counts of accepted and rejected frames.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct GateStats {
    pub accepted: u64,
    /// Indexed like [`RejectReason::ALL`].
    rejected: [u64; 7],
}

impl GateStats {
    /// Frames rejected for `reason`.
    pub fn rejected(&self, reason: RejectReason) -> u64 {
        self.rejected[reason.slot()]
    }

    /// Frames rejected for any reason.
    pub fn rejected_total(&self) -> u64 {
        self.rejected.iter().sum()
    }

    /// `(reason, count)` for every reason.
    pub fn by_reason(&self) -> impl Iterator<Item = (RejectReason, u64)> + '_ {
        RejectReason::ALL.into_iter().map(|r| (r, self.rejected(r)))
    }
}

/// Rejects bad frames and remembers the last good one. See the module docs.
#[derive(Clone, Debug, Default)]
pub struct FrameGate {
    last_good: Option<SensorFrame>,
    stats: GateStats,
}

impl FrameGate {
    pub fn new() -> Self {
        Self::default()
    }

    /// Forgets the last good frame (a new stream: its timestamps may start over); the counts
    /// are kept.
    pub fn reset(&mut self) {
        self.last_good = None;
    }

    pub fn stats(&self) -> &GateStats {
        &self.stats
    }

    /// The last accepted frame.
    pub fn last_good(&self) -> Option<&SensorFrame> {
        self.last_good.as_ref()
    }

    /// What is wrong with `frame`, without counting or remembering anything.
    pub fn classify(&self, frame: &SensorFrame) -> Option<RejectReason> {
        let joints = &frame.joints;
        let finite = frame.timestamp_s.is_finite()
            && joints.iter().all(|j| {
                j.position.is_finite() && j.orientation.is_finite() && j.confidence.is_finite()
            });
        if !finite {
            return Some(RejectReason::NonFinite);
        }
        if joints.iter().all(|j| j.position == Vec3::ZERO) {
            return Some(RejectReason::AllAtOrigin);
        }
        let first = joints[0].position;
        if joints.iter().all(|j| j.position == first) {
            return Some(RejectReason::AllIdentical);
        }
        if frame.joint(KinectJoint::HipCenter).confidence <= 0.0 {
            return Some(RejectReason::MissingHip);
        }
        if joints.iter().any(|j| j.position == Vec3::ZERO) {
            return Some(RejectReason::ZeroJoint);
        }
        if let Some(last) = &self.last_good {
            if frame.timestamp_s < last.timestamp_s {
                return Some(RejectReason::TimestampBackwards);
            }
            if frame.timestamp_s == last.timestamp_s {
                return Some(RejectReason::TimestampRepeated);
            }
        }
        None
    }

    /// Checks a frame: an accepted frame becomes the last good frame; a rejected one is counted
    /// and leaves the last good frame as it was.
    pub fn check(&mut self, frame: &SensorFrame) -> GateDecision {
        match self.classify(frame) {
            None => {
                self.stats.accepted += 1;
                self.last_good = Some(frame.clone());
                GateDecision::Accept
            }
            Some(reason) => {
                self.stats.rejected[reason.slot()] += 1;
                GateDecision::Reject(reason)
            }
        }
    }

    /// [`FrameGate::check`], then the frame to show: `frame` if accepted, else the last good
    /// frame (`None` before any good frame). Feed a filter only accepted frames: after a
    /// rejection keep showing the filter's previous output (the held frame's timestamp would
    /// repeat).
    pub fn pass(&mut self, frame: &SensorFrame) -> Option<&SensorFrame> {
        self.check(frame);
        self.last_good.as_ref()
    }
}
