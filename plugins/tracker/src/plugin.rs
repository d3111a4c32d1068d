//! Bevy adapter: the person's pixels in each new depth frame ([`UserMap`]), found in the
//! app's `Track` stage from [`DepthFeed`]. A frame without a person clears the map; the
//! segmenter keeps its floor and its last person between frames.

use bevy::prelude::*;
use fitroom_depth::plugin::DepthFeed;
use fitroom_schedule::FitroomSystems;

use crate::segment::{SegmentSettings, Segmentation, Segmenter};

/// Systems of the tracker plugin.
#[derive(SystemSet, Debug, Clone, PartialEq, Eq, Hash)]
pub enum TrackerSystems {
    Segment,
}

/// The person in the newest depth frame.
#[derive(Resource, Default)]
pub struct UserMap {
    /// `None`: nobody in view (or no depth yet).
    pub person: Option<Segmentation>,
    /// The depth frame (its count in [`DepthFeed`]) this map is of.
    pub frame: u64,
    /// Time to segment that frame, milliseconds.
    pub segment_ms: f64,
}

/// The segmenter, kept between frames.
#[derive(Resource)]
struct ActiveSegmenter(Segmenter);

pub struct TrackerPlugin;

impl Plugin for TrackerPlugin {
    fn build(&self, app: &mut App) {
        fitroom_schedule::ensure(app);
        app.init_resource::<UserMap>()
            .insert_resource(ActiveSegmenter(Segmenter::new(SegmentSettings::default())))
            .configure_sets(
                PostUpdate,
                TrackerSystems::Segment.in_set(FitroomSystems::Track),
            )
            .add_systems(PostUpdate, segment.in_set(TrackerSystems::Segment));
    }
}

fn segment(
    feed: Option<Res<DepthFeed>>,
    mut segmenter: ResMut<ActiveSegmenter>,
    mut map: ResMut<UserMap>,
) {
    let Some(feed) = feed else { return };
    if feed.frames_received == map.frame {
        return;
    }
    let Some(frame) = &feed.latest else { return };
    let start = std::time::Instant::now();
    map.person = segmenter.0.segment(frame);
    map.frame = feed.frames_received;
    map.segment_ms = start.elapsed().as_secs_f64() * 1e3;
}
