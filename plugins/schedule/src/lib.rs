//! The order of one fitroom frame, said once.
//!
//! Every plugin of the app puts its systems in its own `SystemSet`, and places that set in one
//! of the stages below with a single `configure_sets` call. [`SchedulePlugin`] chains the stages
//! in the order data flows through a kiosk frame (docs/ARCHITECTURE.md):
//!
//! ```text
//! PostUpdate:  Sensor -> Track -> Motion -> Pose -> [transform propagation]
//!              -> Measure -> Cloth -> Gesture -> Ui
//! ```
//!
//! The stages run in `PostUpdate` because the cloth needs the avatar's propagated joint
//! transforms ([`FitroomSystems::Cloth`] after Bevy's `TransformSystems::Propagate`), and the
//! pose must be written before propagation ([`FitroomSystems::Pose`]), all in one frame. `Update`
//! stays free for input and editing (keys, the body panel), which then take effect in the same
//! frame's pipeline.

#![forbid(unsafe_code)]

use bevy::{prelude::*, transform::TransformSystems};

/// The stages of a fitroom frame, in order (see the crate documentation).
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum FitroomSystems {
    /// Poll the depth camera or recording: new frames into the sensor feed.
    Sensor,
    /// Depth to a skeleton: segmentation and the tracker (sources with a skeleton skip it).
    Track,
    /// Skeleton frames to an avatar pose: gate, filter, retargeting, limits, foot skate.
    Motion,
    /// The body's shape and the pose written to the avatar's joint transforms; the camera
    /// follows. Ends before transform propagation.
    Pose,
    /// Body measurement from depth (during calibration); after transform propagation.
    Measure,
    /// Garments loaded and stepped on the avatar's propagated joint transforms.
    Cloth,
    /// Hand states, cursor and swipes into kiosk actions.
    Gesture,
    /// The kiosk flow and what the screen shows.
    Ui,
}

impl FitroomSystems {
    /// Every stage, in the order they run.
    pub const ALL: [FitroomSystems; 8] = [
        FitroomSystems::Sensor,
        FitroomSystems::Track,
        FitroomSystems::Motion,
        FitroomSystems::Pose,
        FitroomSystems::Measure,
        FitroomSystems::Cloth,
        FitroomSystems::Gesture,
        FitroomSystems::Ui,
    ];

    /// A short lowercase name (reports, logs).
    pub fn name(self) -> &'static str {
        match self {
            FitroomSystems::Sensor => "sensor",
            FitroomSystems::Track => "track",
            FitroomSystems::Motion => "motion",
            FitroomSystems::Pose => "pose",
            FitroomSystems::Measure => "measure",
            FitroomSystems::Cloth => "cloth",
            FitroomSystems::Gesture => "gesture",
            FitroomSystems::Ui => "ui",
        }
    }
}

/// Chains the [`FitroomSystems`] stages in `PostUpdate` around transform propagation. Every
/// fitroom plugin adds it (once) so that each plugin also works alone in a test app.
pub struct SchedulePlugin;

impl Plugin for SchedulePlugin {
    fn build(&self, app: &mut App) {
        use FitroomSystems::*;
        app.configure_sets(
            PostUpdate,
            (
                (Sensor, Track, Motion, Pose)
                    .chain()
                    .before(TransformSystems::Propagate),
                (Measure, Cloth, Gesture, Ui)
                    .chain()
                    .after(TransformSystems::Propagate),
            )
                .chain(),
        );
    }
}

/// Adds [`SchedulePlugin`] unless the app has it (call from every fitroom plugin's `build`).
pub fn ensure(app: &mut App) {
    if !app.is_plugin_added::<SchedulePlugin>() {
        app.add_plugins(SchedulePlugin);
    }
}
