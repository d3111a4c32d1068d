//! The gesture plugin: each new skeleton frame (from the tracker or a skeleton source) and
//! the newest depth frame give both hands' states, the cursor and swipes; they come out as
//! [`GestureEvent`] messages (for the kiosk's actions) and the [`Gestures`] resource (for the
//! feedback on screen). Without depth the hands are unknown and swipes still work.

use bevy::prelude::*;
use fitroom_depth::plugin::DepthFeed;
use fitroom_schedule::FitroomSystems;
use fitroom_sensor::plugin::SensorFeed;

use crate::HandState;
use crate::cursor::{Click, Cursor};
use crate::hand::classify::HandModel;
use crate::reader::GestureReader;
use crate::swipe::{Swipe, SwipeDirection};

/// A gesture the kiosk may act on.
#[derive(Message, Clone, Copy, Debug, PartialEq, Eq)]
pub enum GestureEvent {
    Swipe(SwipeDirection),
    /// The cursor's hand closed (a grip) / opened again.
    Press,
    Release,
}

/// What the hands are doing now (for feedback on screen).
#[derive(Resource, Debug, Default, Clone)]
pub struct Gestures {
    /// [left, right].
    pub hands: [HandState; 2],
    pub p_open: [f32; 2],
    pub cursor: Option<Cursor>,
    pub last_swipe: Option<Swipe>,
    /// Why hands are not read (the model file), if so.
    pub error: Option<String>,
}

/// The detectors, and the depth frame last read.
#[derive(Resource)]
struct GestureState {
    reader: GestureReader,
    depth_frame: u64,
}

#[derive(SystemSet, Debug, Clone, PartialEq, Eq, Hash)]
pub struct GestureSystems;

pub struct GesturePlugin;

impl Plugin for GesturePlugin {
    fn build(&self, app: &mut App) {
        fitroom_schedule::ensure(app);
        let (model, error) = match HandModel::embedded() {
            Ok(m) => (Some(m), None),
            Err(e) => (None, Some(e.to_string())),
        };
        app.add_message::<GestureEvent>()
            .insert_resource(Gestures { error, ..default() })
            .insert_resource(GestureState {
                reader: GestureReader::new(model),
                depth_frame: 0,
            })
            .configure_sets(PostUpdate, GestureSystems.in_set(FitroomSystems::Gesture))
            .add_systems(PostUpdate, read_gestures.in_set(GestureSystems));
    }
}

fn read_gestures(
    feed: Res<SensorFeed>,
    depth: Option<Res<DepthFeed>>,
    mut state: ResMut<GestureState>,
    mut gestures: ResMut<Gestures>,
    mut events: MessageWriter<GestureEvent>,
) {
    let state = &mut *state;
    // The newest depth frame, once: the hands are read on the skeleton frame that came
    // with it (the last new one).
    let depth_frame = depth
        .as_ref()
        .filter(|d| d.frames_received != state.depth_frame)
        .and_then(|d| d.latest.clone().map(|f| (d.frames_received, f)));
    let reader = &mut state.reader;
    let last = feed.new_frames.len().saturating_sub(1);
    for (k, frame) in feed.new_frames.iter().enumerate() {
        if k == last {
            match (&depth_frame, &depth) {
                (Some((_, d)), _) => reader.read_hands(frame, Some(d)),
                (None, None) => reader.read_hands(frame, None),
                // Depth exists but no new frame came: the hands keep their states.
                (None, Some(_)) => {}
            }
            gestures.hands = reader.hands;
            gestures.p_open = reader.p_open;
        }
        let step = reader.step(frame);
        if let Some(swipe) = step.swipe {
            gestures.last_swipe = Some(swipe);
            events.write(GestureEvent::Swipe(swipe.direction));
        }
        gestures.cursor = step.cursor;
        match step.click {
            Some(Click::Press) => {
                events.write(GestureEvent::Press);
            }
            Some(Click::Release) => {
                events.write(GestureEvent::Release);
            }
            None => {}
        }
    }
    if let Some((n, _)) = depth_frame {
        state.depth_frame = n;
    }
}
