//! The sensor plugin alone in an app, in the style of Bevy's `tests/how_to_test_systems.rs`:
//! add the plugin, step exact time, read the `World`.

mod common;

use std::time::Duration;

use bevy::{prelude::*, time::TimeUpdateStrategy};
use fitroom_sensor::{
    BvhSource, SensorFrame, SensorSource, SourceError,
    plugin::{ActiveSensor, SensorFeed, SensorPlugin},
};

fn app_with(source: Box<dyn SensorSource>) -> App {
    let mut app = App::new();
    app.add_plugins((MinimalPlugins, SensorPlugin))
        .insert_resource(TimeUpdateStrategy::ManualDuration(Duration::from_millis(
            100,
        )))
        .insert_resource(ActiveSensor(source));
    app
}

#[test]
fn frames_that_became_due_are_published_in_order() {
    let source = BvhSource::load(common::clip_path("07_01.bvh"), Default::default())
        .expect("the clip loads");
    let mut app = app_with(Box::new(source));
    let mut last_timestamp = f64::NEG_INFINITY;
    let mut seen = 0;
    for _ in 0..20 {
        app.update();
        let feed = app.world().resource::<SensorFeed>();
        for frame in &feed.new_frames {
            assert!(
                frame.timestamp_s > last_timestamp,
                "frames arrive oldest first"
            );
            last_timestamp = frame.timestamp_s;
        }
        seen += feed.new_frames.len() as u64;
        assert_eq!(feed.frames_received, seen);
    }
    let feed = app.world().resource::<SensorFeed>();
    // About 1.9-2.0 s of clock (the first update may carry no time) at 30 Hz.
    assert!(
        (55..=61).contains(&feed.frames_received),
        "{}",
        feed.frames_received
    );
    assert_eq!(feed.source_name, "bvh:07_01");
    assert!(feed.error.is_none());
    assert!(feed.latest.is_some());
}

/// A source that delivers two frames and then reports that it is gone.
struct Vanishing {
    delivered: u64,
}

impl SensorSource for Vanishing {
    fn name(&self) -> &str {
        "vanishing"
    }
    fn fps(&self) -> f32 {
        30.0
    }
    fn advance(&mut self, _dt_s: f64) -> Result<Vec<SensorFrame>, SourceError> {
        if self.delivered >= 2 {
            return Err(SourceError::Disconnected {
                source_name: "vanishing".into(),
                reason: "unplugged".into(),
            });
        }
        self.delivered += 1;
        Ok(vec![SensorFrame {
            timestamp_s: self.delivered as f64 / 30.0,
            sequence: self.delivered,
            joints: Default::default(),
        }])
    }
}

#[test]
fn a_source_that_vanishes_keeps_the_last_frame_and_says_why() {
    let mut app = app_with(Box::new(Vanishing { delivered: 0 }));
    for _ in 0..5 {
        app.update();
    }
    let feed = app.world().resource::<SensorFeed>();
    assert_eq!(feed.frames_received, 2);
    assert!(feed.new_frames.is_empty());
    assert_eq!(feed.latest.as_ref().map(|f| f.sequence), Some(2));
    let error = feed
        .error
        .as_deref()
        .expect("the error is kept for the kiosk");
    assert!(
        error.contains("vanishing") && error.contains("unplugged"),
        "{error}"
    );
}
