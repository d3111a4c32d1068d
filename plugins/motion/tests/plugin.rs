//! The motion plugin alone in an app, in the style of Bevy's `tests/how_to_test_systems.rs`:
//! sensor frames in the feed, the pose on the avatar's joint transforms.

mod common;

use bevy::prelude::*;
use fitroom_body::plugin::AvatarJoint;
use fitroom_motion::{
    AvatarPipeline, MotionPipeline,
    filter::FilterKind,
    plugin::{AvatarMotion, MotionPlugin},
};
use fitroom_sensor::plugin::SensorFeed;

#[test]
fn each_frame_of_the_feed_poses_the_joints() {
    let skeleton = common::skeleton();
    let frames = common::clean_frames("07_01.bvh");
    let pipeline = MotionPipeline::new(
        AvatarPipeline::new(&skeleton, -0.8).expect("a pipeline for the avatar"),
        FilterKind::default().build(),
    );
    let mut app = App::new();
    app.add_plugins((MinimalPlugins, MotionPlugin))
        .insert_resource(AvatarMotion::new(pipeline));
    let joints: Vec<Entity> = (0..skeleton.bones.len())
        .map(|i| {
            app.world_mut()
                .spawn((AvatarJoint(i), Transform::default()))
                .id()
        })
        .collect();

    for frame in frames.iter().take(30) {
        app.world_mut().resource_mut::<SensorFeed>().new_frames = vec![frame.clone()];
        app.update();
    }

    let motion = app.world().resource::<AvatarMotion>();
    assert_eq!(motion.frames_applied, 30);
    let root = skeleton
        .bones
        .iter()
        .position(|b| b.parent.is_none())
        .expect("the skeleton has a root");
    let root_joint = app.world().get::<Transform>(joints[root]).expect("joint");
    assert!(
        root_joint.translation.distance(motion.pose.heads[root]) < 1e-6,
        "the root joint stands where the pose puts the root"
    );
    assert!(
        root_joint
            .rotation
            .abs_diff_eq(motion.pose.rotations[root], 1e-6)
    );
    // Every other joint carries its bone's local rotation of the pose.
    for (i, &e) in joints.iter().enumerate() {
        let t = app.world().get::<Transform>(e).expect("joint");
        if skeleton.bones[i].parent.is_some() {
            assert!(
                t.rotation.abs_diff_eq(motion.pose.local_rotations[i], 1e-6),
                "bone {i}"
            );
        }
    }
}

#[test]
fn a_rejected_frame_leaves_the_pose_alone() {
    let skeleton = common::skeleton();
    let frames = common::clean_frames("07_01.bvh");
    let pipeline = MotionPipeline::new(
        AvatarPipeline::new(&skeleton, -0.8).expect("pipeline"),
        FilterKind::default().build(),
    );
    let mut app = App::new();
    app.add_plugins((MinimalPlugins, MotionPlugin))
        .insert_resource(AvatarMotion::new(pipeline));
    app.world_mut().resource_mut::<SensorFeed>().new_frames = vec![frames[0].clone()];
    app.update();
    let before = app.world().resource::<AvatarMotion>().pose.heads.clone();
    // The same frame again (a duplicate: same timestamp) and a frame with a NaN joint.
    let mut broken = frames[1].clone();
    broken.joints[3].position.x = f32::NAN;
    app.world_mut().resource_mut::<SensorFeed>().new_frames = vec![frames[0].clone(), broken];
    app.update();
    let motion = app.world().resource::<AvatarMotion>();
    assert_eq!(motion.frames_applied, 1);
    assert_eq!(motion.pipeline.gate.stats().rejected_total(), 2);
    assert_eq!(motion.pose.heads, before);
}

/// The designer's T-pose: upper arms horizontal and sideways, every bone keeps its length and
/// its rotation relative to its parent (below the shoulder), the rest of the body stays.
#[test]
fn the_t_pose_raises_the_arms_and_keeps_the_bones() {
    use fitroom_motion::still_pose::{a_pose, t_pose};
    let skeleton = common::skeleton();
    let (a, t) = (a_pose(&skeleton), t_pose(&skeleton));
    for arm in ["upperarm_l", "upperarm_r", "lowerarm_l", "lowerarm_r"] {
        let i = skeleton.index_of(arm).expect("arm");
        let along = t.rotations[i] * Vec3::Y;
        assert!(
            along.y.abs() < 1e-4 && along.z.abs() < 1e-4,
            "{arm}: {along}"
        );
        let rest_along = a.rotations[i] * Vec3::Y;
        assert!(
            rest_along.y < -0.2,
            "{arm} points down at rest: {rest_along}"
        );
    }
    let hand = skeleton.index_of("hand_l").expect("hand");
    let shoulder = skeleton.index_of("upperarm_l").expect("arm");
    assert!(
        (t.heads[hand].y - t.heads[shoulder].y).abs() < 0.01,
        "the hand at shoulder height"
    );
    for (i, bone) in skeleton.bones.iter().enumerate() {
        if let Some(p) = bone.parent {
            let rest = a.heads[i].distance(a.heads[p]);
            let raised = t.heads[i].distance(t.heads[p]);
            assert!(
                (rest - raised).abs() < 1e-4,
                "{}: {rest} -> {raised}",
                bone.name
            );
            let local = t.rotations[p].inverse() * t.rotations[i];
            assert!(
                local.abs_diff_eq(t.local_rotations[i], 1e-4),
                "{}",
                bone.name
            );
        }
    }
    let pelvis = skeleton.index_of("pelvis").expect("pelvis");
    assert_eq!(t.heads[pelvis], a.heads[pelvis]);
}

/// Editing [`FilterSettings`] (as the inspector or a configuration would) replaces the filter
/// the avatar runs: the Kalman filter lags a walking person; no filter passes the frames on.
#[test]
fn a_changed_filter_setting_replaces_the_running_filter() {
    use fitroom_motion::plugin::FilterSettings;
    let skeleton = common::skeleton();
    let frames = common::clean_frames("07_01.bvh");
    let pipeline = MotionPipeline::new(
        AvatarPipeline::new(&skeleton, -0.8).expect("pipeline"),
        FilterSettings::default().filter.build(),
    );
    let mut app = App::new();
    app.add_plugins((MinimalPlugins, MotionPlugin))
        .insert_resource(AvatarMotion::new(pipeline));
    let largest_lag = |app: &App| {
        let motion = app.world().resource::<AvatarMotion>();
        let (raw, filtered) = (
            motion.last_raw.as_ref().expect("a frame"),
            motion.last_filtered.as_ref().expect("a frame"),
        );
        raw.joints
            .iter()
            .zip(&filtered.joints)
            .map(|(r, f)| r.position.distance(f.position))
            .fold(0.0f32, f32::max)
    };
    for frame in &frames[..40] {
        app.world_mut().resource_mut::<SensorFeed>().new_frames = vec![frame.clone()];
        app.update();
    }
    assert!(largest_lag(&app) > 1e-3, "the Kalman filter smooths");

    app.world_mut().resource_mut::<FilterSettings>().filter = FilterKind::None;
    for frame in &frames[40..45] {
        app.world_mut().resource_mut::<SensorFeed>().new_frames = vec![frame.clone()];
        app.update();
        assert_eq!(largest_lag(&app), 0.0, "no filter: the frame as measured");
    }
}
