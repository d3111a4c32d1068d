//! Bad sensor frames in the running app: NaN positions, all joints at the origin, a timestamp
//! that goes backwards. None reaches the avatar; each is counted.

mod common;

use fitroom::{Mode, headless};
use fitroom_body::plugin::AvatarJoint;
use fitroom_motion::plugin::AvatarMotion;
use fitroom_sensor::{
    SensorFrame, SensorSource, SourceError, bvh_source::BvhSource, plugin::ActiveSensor,
};

/// Replays a clip and spoils three of its frames.
struct SpoiledSource {
    inner: BvhSource,
    emitted: usize,
}

impl SensorSource for SpoiledSource {
    fn name(&self) -> &str {
        "spoiled"
    }
    fn fps(&self) -> f32 {
        self.inner.fps()
    }
    fn advance(&mut self, dt_s: f64) -> Result<Vec<SensorFrame>, SourceError> {
        let mut frames = self.inner.advance(dt_s)?;
        for frame in &mut frames {
            self.emitted += 1;
            match self.emitted {
                20 => frame.joints[6].position.x = f32::NAN,
                30 => frame
                    .joints
                    .iter_mut()
                    .for_each(|j| j.position = glam::Vec3::ZERO),
                40 => frame.timestamp_s -= 1.0,
                _ => {}
            }
        }
        Ok(frames)
    }
}

#[test]
fn bad_frames_never_reach_the_avatar() {
    let options = common::clip_options(Mode::Headless { render: false });
    let mut app = headless::headless_app(&options).expect("app builds");
    let inner = BvhSource::load(&options.motion, Default::default()).expect("clip");
    app.insert_resource(ActiveSensor(Box::new(SpoiledSource { inner, emitted: 0 })));
    for _ in 0..120 {
        app.update();
        let world = app.world_mut();
        let mut joints = world.query::<(&AvatarJoint, &bevy::prelude::GlobalTransform)>();
        for (joint, transform) in joints.iter(world) {
            assert!(
                transform.translation().is_finite(),
                "joint {} is not finite",
                joint.0
            );
        }
    }
    let motion = app.world().resource::<AvatarMotion>();
    let rejected = motion.pipeline.gate.stats().rejected_total();
    assert_eq!(
        rejected,
        3,
        "rejections by reason: {:?}",
        motion.pipeline.gate.stats()
    );
    assert!(
        motion.frames_applied >= 55,
        "good frames applied: {}",
        motion.frames_applied
    );
}
