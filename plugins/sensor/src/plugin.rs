//! Bevy adapter: polls the active [`SensorSource`] in the app's `Sensor` stage
//! ([`fitroom_schedule::FitroomSystems`]) and publishes the frames that became due. A source error never stops the app: the last good frame stays, the error is
//! kept for the kiosk to show.

use bevy::prelude::*;
use fitroom_schedule::FitroomSystems;

use crate::{SensorFrame, SensorSource};

/// Systems of the sensor plugin, in order.
#[derive(SystemSet, Debug, Clone, PartialEq, Eq, Hash)]
pub enum SensorSystems {
    Poll,
}

/// The source the kiosk reads from.
#[derive(Resource)]
pub struct ActiveSensor(pub Box<dyn SensorSource>);

/// What the sensor delivered.
#[derive(Resource, Default, Debug)]
pub struct SensorFeed {
    /// Frames that arrived during this update, oldest first.
    pub new_frames: Vec<SensorFrame>,
    /// The most recent frame (kept when the source stalls or fails).
    pub latest: Option<SensorFrame>,
    pub frames_received: u64,
    /// The last error reported by the source, cleared when frames flow again.
    pub error: Option<String>,
    /// Name of the active source.
    pub source_name: String,
}

pub struct SensorPlugin;

impl Plugin for SensorPlugin {
    fn build(&self, app: &mut App) {
        fitroom_schedule::ensure(app);
        app.init_resource::<SensorFeed>()
            .configure_sets(
                PostUpdate,
                SensorSystems::Poll.in_set(FitroomSystems::Sensor),
            )
            .add_systems(PostUpdate, poll_sensor.in_set(SensorSystems::Poll));
    }
}

fn poll_sensor(
    time: Res<Time>,
    sensor: Option<ResMut<ActiveSensor>>,
    mut feed: ResMut<SensorFeed>,
) {
    feed.new_frames.clear();
    let Some(mut sensor) = sensor else {
        return;
    };
    if feed.source_name.is_empty() {
        feed.source_name = sensor.0.name().to_string();
    }
    match sensor.0.advance(time.delta_secs_f64()) {
        Ok(frames) => {
            if !frames.is_empty() {
                feed.error = None;
            }
            feed.frames_received += frames.len() as u64;
            if let Some(last) = frames.last() {
                feed.latest = Some(last.clone());
            }
            feed.new_frames = frames;
        }
        Err(error) => {
            if feed.error.is_none() {
                warn!("{error}");
            }
            feed.error = Some(error.to_string());
        }
    }
}
