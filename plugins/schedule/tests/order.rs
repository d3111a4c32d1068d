//! The schedule plugin alone in an app: systems placed in the stages run in the stages' order,
//! with Bevy's transform propagation between `Pose` and `Measure`.

use bevy::{prelude::*, transform::TransformSystems};
use fitroom_schedule::{FitroomSystems, SchedulePlugin};

#[derive(Resource, Default)]
struct Ran(Vec<&'static str>);

fn record(name: &'static str) -> impl FnMut(ResMut<Ran>) {
    move |mut ran| ran.0.push(name)
}

#[test]
fn stages_run_in_order_around_transform_propagation() {
    let mut app = App::new();
    app.add_plugins((MinimalPlugins, TransformPlugin, SchedulePlugin))
        .init_resource::<Ran>();
    // Added in reverse so that insertion order cannot explain the result.
    for stage in FitroomSystems::ALL.into_iter().rev() {
        app.add_systems(PostUpdate, record(stage.name()).in_set(stage));
    }
    app.add_systems(
        PostUpdate,
        record("propagate").in_set(TransformSystems::Propagate),
    );
    app.update();
    let ran = &app.world().resource::<Ran>().0;
    assert_eq!(
        ran,
        &[
            "sensor",
            "track",
            "motion",
            "pose",
            "propagate",
            "measure",
            "cloth",
            "gesture",
            "ui"
        ]
    );
}
