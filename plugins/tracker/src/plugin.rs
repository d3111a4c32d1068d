//! Bevy adapter: the tracker on each new depth frame of [`DepthFeed`], in the app's `Track`
//! stage. Out come the person's pixels ([`UserMap`]) and their skeleton
//! ([`TrackedSkeleton`]); where depth is the only sensor ([`SkeletonFromDepth`]), each
//! skeleton also joins the [`SensorFeed`] as a Kinect v1 frame, so the motion pipeline
//! (gate, filter, retarget, limits, foot skate) runs on it as on a BVH clip's.
//!
//! The tracker fits the unshaped body of [`AvatarBody`]'s model (the person is not the
//! avatar's shape: it sizes the body to them and estimates their build as it tracks, with
//! [`TrackerBuildFit`]'s fitter if another plugin gives one); it is made when that body first
//! exists.

use bevy::prelude::*;
use fitroom_body::plugin::AvatarBody;
use fitroom_depth::plugin::DepthFeed;
use fitroom_schedule::FitroomSystems;
use fitroom_sensor::SensorFrame;
use fitroom_sensor::plugin::SensorFeed;

use crate::segment::Segmentation;
use crate::shape::BuildFit;
use crate::tracker::{Tracked, Tracker, TrackerSettings};

/// Systems of the tracker plugin.
#[derive(SystemSet, Debug, Clone, PartialEq, Eq, Hash)]
pub enum TrackerSystems {
    Track,
}

/// The person in the newest depth frame.
#[derive(Resource, Default)]
pub struct UserMap {
    /// `None`: nobody in view (or no depth yet).
    pub person: Option<std::sync::Arc<Segmentation>>,
    /// The depth frame (its count in [`DepthFeed`]) this map is of.
    pub frame: u64,
    /// Time to segment and track that frame, milliseconds.
    pub track_ms: f64,
}

/// The skeleton in the newest depth frame.
#[derive(Resource, Default)]
pub struct TrackedSkeleton {
    /// `None`: nobody tracked.
    pub latest: Option<Tracked>,
    /// Fits (re)started from the extrema since the app started.
    pub starts: usize,
    /// Why there is no tracker (its body could not be made), if so.
    pub error: Option<String>,
}

/// The fitter of the person's build the tracker uses instead of its own search (the
/// measurement plugin gives its body fit), read when the tracker is made.
#[derive(Resource, Clone)]
pub struct TrackerBuildFit(pub std::sync::Arc<dyn BuildFit>);

/// Present when depth is the only sensor (a recording, a Kinect): the tracker's skeletons
/// feed the motion pipeline.
#[derive(Resource)]
pub struct SkeletonFromDepth;

/// The tracker, made once the avatar's body exists.
#[derive(Resource, Default)]
struct ActiveTracker {
    tracker: Option<Tracker>,
    sequence: u64,
    /// Added to the depth frames' times so the skeleton's never run backwards (a looping
    /// recording starts its clock again), and the last time given.
    time_offset_s: f64,
    last_time_s: Option<f64>,
}

pub struct TrackerPlugin;

impl Plugin for TrackerPlugin {
    fn build(&self, app: &mut App) {
        fitroom_schedule::ensure(app);
        app.init_resource::<UserMap>()
            .init_resource::<TrackedSkeleton>()
            .init_resource::<ActiveTracker>()
            .configure_sets(
                PostUpdate,
                TrackerSystems::Track.in_set(FitroomSystems::Track),
            )
            .add_systems(
                PostUpdate,
                (make_tracker, track).chain().in_set(TrackerSystems::Track),
            );
    }
}

/// Makes the tracker once the avatar's body exists (and depth comes in).
fn make_tracker(
    depth: Option<Res<DepthFeed>>,
    body: Option<Res<AvatarBody>>,
    build_fit: Option<Res<TrackerBuildFit>>,
    mut active: ResMut<ActiveTracker>,
    mut skeleton: ResMut<TrackedSkeleton>,
) {
    if active.tracker.is_some() || skeleton.error.is_some() || depth.is_none() {
        return;
    }
    let Some(body) = body else { return };
    // The person's build is estimated on a thread of its own: a frame does not wait.
    let mut settings = TrackerSettings::default();
    settings.shape.background = true;
    match Tracker::estimating(body.model.clone(), settings) {
        Ok(tracker) => {
            active.tracker = Some(match build_fit {
                Some(fit) => tracker.with_build_fit(fit.0.clone()),
                None => tracker,
            })
        }
        Err(e) => {
            warn!("no skeleton tracker: {e}");
            skeleton.error = Some(e.to_string());
        }
    }
}

fn track(
    depth: Option<Res<DepthFeed>>,
    from_depth: Option<Res<SkeletonFromDepth>>,
    mut active: ResMut<ActiveTracker>,
    mut map: ResMut<UserMap>,
    mut skeleton: ResMut<TrackedSkeleton>,
    mut sensor: ResMut<SensorFeed>,
) {
    let Some(depth) = depth else { return };
    if depth.frames_received == map.frame {
        return;
    }
    let Some(frame) = &depth.latest else { return };
    let Some(tracker) = active.tracker.as_mut() else {
        return;
    };
    let start = std::time::Instant::now();
    let tracked = tracker.track(frame);
    map.track_ms = start.elapsed().as_secs_f64() * 1e3;
    map.frame = depth.frames_received;
    map.person = tracked.as_ref().map(|t| t.person.clone());
    skeleton.starts = tracker.starts;
    if from_depth.is_some() {
        let mut time_s = frame.time_s + active.time_offset_s;
        if let Some(last) = active.last_time_s
            && time_s <= last
        {
            active.time_offset_s = last + 1.0 / 30.0 - frame.time_s;
            time_s = last + 1.0 / 30.0;
        }
        active.last_time_s = Some(time_s);
        // Nobody tracked: a frame with every joint not tracked, so the kiosk sees the gap.
        let sequence = active.sequence;
        let out = match &tracked {
            Some(t) => t.sensor_frame(time_s, sequence),
            None => SensorFrame::nobody(time_s, sequence),
        };
        active.sequence += 1;
        sensor.frames_received += 1;
        sensor.latest = Some(out.clone());
        sensor.new_frames.push(out);
    }
    skeleton.latest = tracked;
}
