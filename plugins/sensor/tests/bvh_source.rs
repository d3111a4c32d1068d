//! The BVH sensor source on the real CMU clips: resampling, looping, placement in front of the
//! sensor, metre scale and the bone-orientation contract of `JointSample::orientation`.

mod common;

use KinectJoint::*;
use fitroom_sensor::bvh::BvhClip;
use fitroom_sensor::bvh_source::MAX_FRAMES_PER_ADVANCE;
use fitroom_sensor::frame::bone_reference_frame;
use fitroom_sensor::{
    BvhSkeletonKind, BvhSource, BvhSourceOptions, KinectJoint, SensorFrame, SensorSource,
};
use glam::{Quat, Vec3};

/// Every indexed clip as a source with the default options.
fn all_sources() -> Vec<(String, BvhSource)> {
    common::index()
        .into_iter()
        .map(|entry| {
            let source = BvhSource::load(entry.path(), BvhSourceOptions::default())
                .unwrap_or_else(|e| panic!("{}: {e}", entry.file));
            (entry.file, source)
        })
        .collect()
}

fn load(file: &str) -> BvhSource {
    BvhSource::load(common::clip_path(file), BvhSourceOptions::default())
        .unwrap_or_else(|e| panic!("{file}: {e}"))
}

fn pos(frame: &SensorFrame, joint: KinectJoint) -> Vec3 {
    frame.joint(joint).position
}

/// Times from 0 to the end of one loop, `step` apart.
fn times(source: &BvhSource, step: f64) -> Vec<f64> {
    let end = source.clip_duration_s();
    (0..)
        .map(|k| k as f64 * step)
        .take_while(|t| *t < end)
        .collect()
}

/// |cos(angle / 2)| between two rotations: 1 when they are the same rotation.
fn same_rotation(a: Quat, b: Quat) -> f32 {
    a.normalize().dot(b.normalize()).abs()
}

#[test]
fn name_rates_and_the_skipped_tpose() {
    let source = load("07_01.bvh");
    assert_eq!(source.name(), "bvh:07_01");
    assert_eq!(source.fps(), 30.0);
    assert!((source.clip_fps() - 120.0).abs() < 0.01);
    assert_eq!(source.skeleton_kind(), BvhSkeletonKind::CgspeedDaz);
    assert_eq!(source.first_played_frame(), 8);
    assert_eq!(source.played_frame_count(), 317 - 8);
    assert!((source.clip_duration_s() - 308.0 * 0.00833333).abs() < 1e-9);

    // Frame 0 of the file is the T-pose (hands level with the shoulders) and is not played:
    // the first played frame of this walk has the hands well below the shoulders.
    let clip = source.clip();
    let pose = clip.pose(0).expect("frame 0");
    let (hand, shoulder) = (
        clip.joint_index("lHand").expect("lHand"),
        clip.joint_index("lShldr").expect("lShldr"),
    );
    assert!((pose.positions[hand].y - pose.positions[shoulder].y).abs() < 2.0);
    let first = source.frame_at(0.0);
    assert!(pos(&first, WristLeft).y < pos(&first, ShoulderLeft).y - 0.2);
    assert!(pos(&first, WristRight).y < pos(&first, ShoulderRight).y - 0.2);

    let mb = load("16_11.bvh");
    assert_eq!(mb.skeleton_kind(), BvhSkeletonKind::MotionBuilder);
    assert_eq!(mb.first_played_frame(), 0);
    assert_eq!(mb.played_frame_count(), 534);
    for (file, source) in all_sources() {
        let daz = source.skeleton_kind() == BvhSkeletonKind::CgspeedDaz;
        assert_eq!(
            source.first_played_frame(),
            if daz { 8 } else { 0 },
            "{file}"
        );
    }
}

/// Largest frame-to-frame change of any rotation channel of `joint` over `frames`, degrees.
fn largest_step(clip: &BvhClip, joint: &str, frames: std::ops::Range<usize>) -> f32 {
    let joint = &clip.joints()[clip.joint_index(joint).expect("joint exists")];
    let range = joint.first_channel..joint.first_channel + joint.channels.len();
    frames
        .map(|k| {
            let a = &clip.frame(k).expect("frame")[range.clone()];
            let b = &clip.frame(k + 1).expect("frame")[range.clone()];
            a.iter()
                .zip(b)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f32::max)
        })
        .fold(0.0, f32::max)
}

#[test]
fn the_tpose_blend_in_is_skipped_and_what_is_played_is_smooth() {
    for (file, source) in all_sources() {
        let clip = source.clip();
        let first = source.first_played_frame();
        let shoulders: &[&str] = if first > 0 {
            // The blend from the T-pose: the shoulders swing more than 15 deg per frame.
            for shoulder in ["lShldr", "rShldr"] {
                assert!(
                    largest_step(clip, shoulder, 0..4) > 15.0,
                    "{file} {shoulder}"
                );
            }
            &["lShldr", "rShldr"]
        } else {
            &["LeftArm", "RightArm"]
        };
        // From the first played frame on, the arms move like a person's.
        for shoulder in shoulders {
            let step = largest_step(clip, shoulder, first..first + 20);
            assert!(step < 10.0, "{file} {shoulder}: {step} deg per frame");
        }
    }
}

#[test]
fn resampled_frames_match_the_clip_interpolated_at_their_time() {
    for file in ["07_01.bvh", "16_11.bvh", "05_06.bvh", "13_10.bvh"] {
        let source = load(file);
        let clip = source.clip();
        let mapping = source.mapping();
        let placement = source.placement();
        let first = source.first_played_frame() as f64;
        let in_sensor = |pose: &fitroom_sensor::BvhPose, joint: KinectJoint| {
            placement.to_sensor(pose.point(mapping.point(joint)).expect("mapped point"))
        };
        let mut checked = 0;
        for t in times(&source, 0.0777) {
            let u = first + t / clip.frame_time_s();
            assert!((source.clip_frame_at(t) - u).abs() < 1e-6, "{file} t={t}");
            let i = u.floor() as usize;
            let f = (u - i as f64) as f32;
            let a = clip.pose(i).expect("frame i");
            let b = clip.pose(i + 1).expect("frame i + 1");
            let frame = source.frame_at(t);
            assert_eq!(frame.timestamp_s, t);
            for joint in KinectJoint::ALL {
                let expected = in_sensor(&a, joint).lerp(in_sensor(&b, joint), f);
                let actual = pos(&frame, joint);
                assert!(
                    actual.distance(expected) < 1e-4,
                    "{file} t={t} {}: {actual} vs {expected}",
                    joint.name()
                );
                assert_eq!(frame.joint(joint).confidence, 1.0);
            }
            // The loop repeats the same motion.
            for loops in [1.0, 3.0] {
                let again = source.frame_at(t + loops * source.clip_duration_s());
                for joint in KinectJoint::ALL {
                    assert!(
                        pos(&again, joint).distance(pos(&frame, joint)) < 1e-3,
                        "{file} t={t}"
                    );
                }
            }
            checked += 1;
        }
        assert!(checked > 20, "{file}: only {checked} times checked");

        // The 30 Hz stream lands on every 4th clip frame (up to the rounding of Frame Time).
        for k in [0usize, 1, 2, 17, 60] {
            let frame = source.frame_at(k as f64 / 30.0);
            let pose = clip
                .pose(source.first_played_frame() + 4 * k)
                .expect("clip frame");
            for joint in KinectJoint::ALL {
                assert!(
                    pos(&frame, joint).distance(in_sensor(&pose, joint)) < 2e-3,
                    "{file} k={k}"
                );
            }
        }
    }
}

/// Advances `source` by `total` seconds in uneven steps and returns the emitted frames.
fn advance_by(source: &mut BvhSource, total: f64) -> Vec<SensorFrame> {
    let steps: [f64; 5] = [1.0 / 60.0, 1.0 / 144.0, 0.05, 0.0, 0.033];
    let mut frames = Vec::new();
    let mut clock = 0.0;
    for dt in steps.iter().cycle() {
        let dt = dt.min(total - clock);
        frames.extend(source.advance(dt).expect("a BVH source never fails"));
        clock += dt;
        if clock >= total {
            break;
        }
    }
    frames
}

#[test]
fn advance_emits_30_frames_per_second_of_clip() {
    for (file, mut source) in all_sources() {
        let duration = source.clip_duration_s();
        let frames = advance_by(&mut source, duration);
        let expected = duration * 30.0;
        assert!(
            (frames.len() as f64 - expected).abs() <= 1.0,
            "{file}: {} frames over {duration} s",
            frames.len()
        );
        assert_eq!(
            frames.len() as f64,
            (duration * 30.0 + 1e-6).floor() + 1.0,
            "{file}"
        );
    }
}

#[test]
fn timestamps_and_sequences_keep_increasing_across_loops() {
    let mut source = load("07_01.bvh");
    let duration = source.clip_duration_s();
    let frames = advance_by(&mut source, 2.5 * duration);
    assert!(frames.len() as f64 >= 2.5 * duration * 30.0 - 1.0);
    for (i, frame) in frames.iter().enumerate() {
        assert_eq!(frame.sequence, i as u64);
        assert!((frame.timestamp_s - i as f64 / 30.0).abs() < 1e-9);
        if i > 0 {
            assert!(frame.timestamp_s > frames[i - 1].timestamp_s);
        }
        // Each streamed frame is the frame at its time.
        let direct = source.frame_at(frame.timestamp_s);
        assert_eq!(frame.joints, direct.joints);
    }
    // At the loop boundary the walker jumps back to the start.
    let boundary = frames
        .iter()
        .position(|f| f.timestamp_s >= duration)
        .expect("the stream passes the loop boundary");
    let before = pos(&frames[boundary - 1], HipCenter);
    let after = pos(&frames[boundary], HipCenter);
    assert!(
        before.distance(after) > 1.0,
        "walked {before} -> restarted at {after}"
    );
    let start = pos(
        &source.frame_at(frames[boundary].timestamp_s - duration),
        HipCenter,
    );
    assert!(after.distance(start) < 1e-3);
}

#[test]
fn advance_ignores_bad_steps_and_caps_long_stalls() {
    let mut source = load("16_11.bvh");
    assert_eq!(
        source.advance(0.0).expect("ok").len(),
        1,
        "the frame at t = 0"
    );
    assert!(source.advance(0.0).expect("ok").is_empty());
    assert!(source.advance(-1.0).expect("ok").is_empty());
    assert!(source.advance(f64::NAN).expect("ok").is_empty());
    assert!(source.advance(f64::INFINITY).expect("ok").is_empty());
    assert!(
        source.advance(0.01).expect("ok").is_empty(),
        "next frame due at 1/30 s"
    );
    assert_eq!(source.advance(0.03).expect("ok").len(), 1);

    let frames = source.advance(1.0e6).expect("ok");
    assert_eq!(frames.len(), MAX_FRAMES_PER_ADVANCE);
    assert_eq!(frames[0].sequence, 2, "sequence stays consecutive");
    let last = frames.last().expect("frames");
    assert!((last.timestamp_s - source.clock_s()).abs() <= 1.0 / 30.0 + 1e-6);
    for pair in frames.windows(2) {
        assert!(pair[1].timestamp_s > pair[0].timestamp_s);
        assert_eq!(pair[1].sequence, pair[0].sequence + 1);
    }
    let next = source.advance(1.0 / 30.0).expect("ok");
    assert_eq!(next.len(), 1);
    assert_eq!(next[0].sequence, 2 + MAX_FRAMES_PER_ADVANCE as u64);
    assert!(next[0].timestamp_s > last.timestamp_s);

    let bad = BvhSourceOptions {
        fps: 0.0,
        ..BvhSourceOptions::default()
    };
    let clip = source.clip().clone();
    assert!(BvhSource::from_clip(clip, bad).is_err());
}

#[test]
fn the_performer_starts_in_front_of_the_sensor_facing_it() {
    for (file, source) in all_sources() {
        let first = source.frame_at(0.0);
        let hip = pos(&first, HipCenter);
        assert!(
            hip.x.abs() < 1e-4 && (hip.z - 2.5).abs() < 1e-4,
            "{file}: hip at {hip}"
        );

        // Facing the sensor (-Z), the performer's left is at sensor -X.
        assert!(
            pos(&first, ShoulderLeft).x < pos(&first, ShoulderRight).x - 0.1,
            "{file}"
        );
        assert!(
            pos(&first, HipLeft).x < pos(&first, HipRight).x - 0.1,
            "{file}"
        );

        // Independent of how left and right were told apart: the toes point at the sensor.
        let mut toe_ahead = [0.0f32; 2];
        let early = times(&source, 1.0 / 30.0);
        for &t in early.iter().take(15) {
            let frame = source.frame_at(t);
            toe_ahead[0] += (pos(&frame, FootLeft) - pos(&frame, AnkleLeft)).z;
            toe_ahead[1] += (pos(&frame, FootRight) - pos(&frame, AnkleRight)).z;
        }
        // (Summed over both feet: in a run one foot may point down for a while.)
        assert!(
            toe_ahead[0] + toe_ahead[1] < -0.6,
            "{file}: toes {toe_ahead:?}"
        );

        // The pelvis orientation agrees: identity means facing -Z with the left at -X.
        let pelvis = first.joint(HipCenter).orientation;
        assert!(
            (pelvis * Vec3::NEG_Z).z < -0.8,
            "{file}: pelvis faces {}",
            pelvis * Vec3::NEG_Z
        );
        let hips_left = (pos(&first, HipLeft) - pos(&first, HipRight)).normalize();
        assert!((pelvis * Vec3::NEG_X).dot(hips_left) > 0.8, "{file}");

        // Upright.
        let heights: Vec<f32> = [HipCenter, Spine, ShoulderCenter, Head]
            .iter()
            .map(|&j| pos(&first, j).y)
            .collect();
        assert!(
            heights.windows(2).all(|w| w[0] < w[1]),
            "{file}: {heights:?}"
        );
        assert!(
            hip.y > -0.8 + 0.6 && hip.y < -0.8 + 1.1,
            "{file}: hip height {}",
            hip.y
        );
    }
}

#[test]
fn placement_options_move_the_performer() {
    let options = BvhSourceOptions {
        sensor_height_m: 1.2,
        start_distance_m: 3.0,
        ..BvhSourceOptions::default()
    };
    let source = BvhSource::load(common::clip_path("02_01.bvh"), options).expect("loads");
    let reference = load("02_01.bvh");
    for t in [0.0, 0.5, 1.7] {
        for joint in KinectJoint::ALL {
            let moved = pos(&source.frame_at(t), joint);
            let expected = pos(&reference.frame_at(t), joint) + Vec3::new(0.0, -0.4, 0.5);
            assert!(moved.distance(expected) < 1e-4);
        }
    }
}

/// The treadmill keeps the hip centre on the spot in x and z over a whole walk (the clip
/// without it walks more than a metre), and changes nothing else: heights, every joint's
/// position relative to the hip centre, and the orientations are those of the plain replay.
#[test]
fn the_treadmill_keeps_the_hip_on_the_spot_and_the_pose_unchanged() {
    // A cgspeed walk and a MotionBuilder-style walk that veers left.
    for file in ["07_01.bvh", "16_11.bvh"] {
        let plain = load(file);
        let options = BvhSourceOptions {
            treadmill: true,
            ..BvhSourceOptions::default()
        };
        let treadmill = BvhSource::load(common::clip_path(file), options)
            .unwrap_or_else(|e| panic!("{file}: {e}"));
        let start = pos(&plain.frame_at(0.0), HipCenter);
        let spot = Vec3::new(0.0, 0.0, BvhSourceOptions::default().start_distance_m);
        assert!(
            Vec3::new(start.x, 0.0, start.z).distance(spot) < 1e-4,
            "{file}: starts at {start}"
        );
        let mut travel = 0.0f32;
        // Off the clip's frame times (interpolated frames) and past the end of the loop.
        let end = plain.clip_duration_s() * 1.5;
        let steps = (end / 0.0237).ceil() as usize;
        for k in 0..steps {
            let t = k as f64 * 0.0237;
            let (a, b) = (plain.frame_at(t), treadmill.frame_at(t));
            let (hip_a, hip_b) = (pos(&a, HipCenter), pos(&b, HipCenter));
            travel = travel.max(Vec3::new(hip_a.x - start.x, 0.0, hip_a.z - start.z).length());
            assert!(
                (hip_b.x - spot.x).abs() < 1e-4 && (hip_b.z - spot.z).abs() < 1e-4,
                "{file} t={t}: treadmill hip centre at {hip_b}"
            );
            assert!((hip_b.y - hip_a.y).abs() < 1e-5, "{file} t={t}: hip height");
            for joint in KinectJoint::ALL {
                let relative_a = pos(&a, joint) - hip_a;
                let relative_b = pos(&b, joint) - hip_b;
                assert!(
                    relative_a.distance(relative_b) < 1e-4,
                    "{file} t={t} {joint:?}: {relative_a} vs {relative_b}"
                );
                let (qa, qb) = (a.joint(joint).orientation, b.joint(joint).orientation);
                assert!(
                    same_rotation(qa, qb) > 1.0 - 1e-6,
                    "{file} t={t} {joint:?}: orientation {qa} vs {qb}"
                );
                assert_eq!(a.joint(joint).confidence, b.joint(joint).confidence);
            }
        }
        assert!(
            travel > 1.0,
            "{file}: the plain replay travels only {travel} m"
        );
    }
    assert!(!BvhSourceOptions::default().treadmill);
}

fn lowest_foot(frame: &SensorFrame) -> f32 {
    [AnkleLeft, AnkleRight, FootLeft, FootRight]
        .iter()
        .map(|&j| pos(frame, j).y)
        .fold(f32::INFINITY, f32::min)
}

#[test]
fn the_feet_are_on_the_floor() {
    for (file, source) in all_sources() {
        let first_second = times(&source, 1.0 / 30.0)
            .into_iter()
            .take(30)
            .map(|t| lowest_foot(&source.frame_at(t)))
            .fold(f32::INFINITY, f32::min);
        assert!(
            (first_second + 0.8).abs() < 0.05,
            "{file}: lowest foot {first_second}"
        );

        // The floor is the lowest foot point of the clip: nothing below, something on it.
        let ft = source.clip().frame_time_s();
        let whole = (0..source.played_frame_count())
            .map(|k| lowest_foot(&source.frame_at(k as f64 * ft)))
            .fold(f32::INFINITY, f32::min);
        assert!(
            (-0.8 - 1e-4..-0.8 + 1e-3).contains(&whole),
            "{file}: lowest foot {whole}"
        );
    }
}

#[test]
fn legs_are_scaled_to_the_reference_length() {
    for (file, source) in all_sources() {
        for t in [0.0, 0.4, 1.1] {
            let frame = source.frame_at(t);
            let leg = |hip, knee, ankle| {
                pos(&frame, hip).distance(pos(&frame, knee))
                    + pos(&frame, knee).distance(pos(&frame, ankle))
            };
            let left = leg(HipLeft, KneeLeft, AnkleLeft);
            let right = leg(HipRight, KneeRight, AnkleRight);
            assert!((left - 0.82).abs() < 0.02, "{file}: left leg {left} m");
            assert!((right - 0.82).abs() < 0.02, "{file}: right leg {right} m");
            assert!(((left + right) / 2.0 - 0.82).abs() < 0.002, "{file}");
        }
    }
}

#[test]
fn orientations_point_along_their_bones() {
    for (file, source) in all_sources() {
        for t in times(&source, 0.05).into_iter().map(|t| t + 0.013) {
            let frame = source.frame_at(t);
            let pelvis = frame.joint(HipCenter).orientation;
            assert!((pelvis.length() - 1.0).abs() < 1e-4, "{file}");
            for joint in KinectJoint::ALL {
                let Some(parent) = joint.parent() else {
                    continue;
                };
                let orientation = frame.joint(joint).orientation;
                assert!((orientation.length() - 1.0).abs() < 1e-4, "{file}");
                let bone = (pos(&frame, joint) - pos(&frame, parent)).normalize();
                let y = orientation * Vec3::Y;
                assert!(
                    y.cross(bone).length() < 1e-3 && y.dot(bone) > 0.0,
                    "{file} t={t} {}: +Y {y} vs bone {bone}",
                    joint.name()
                );
            }
        }
    }
}

/// A clip of the file's hierarchy with every channel zero: the rest pose.
fn rest_clip(file: &str, header_lines: usize) -> BvhClip {
    let text = common::clip_text(file);
    let hierarchy: String = text.split_inclusive('\n').take(header_lines - 3).collect();
    let parsed = BvhClip::from_str(&text, file).expect("parses");
    let zeros = vec!["0"; parsed.channel_count()].join(" ");
    let rest =
        format!("{hierarchy}MOTION\nFrames: 3\nFrame Time: 0.008333\n{zeros}\n{zeros}\n{zeros}\n");
    BvhClip::from_str(&rest, file).expect("rest clip parses")
}

#[test]
fn the_rest_pose_facing_the_sensor_gives_the_reference_orientations() {
    // The cgspeed rest pose is left-right symmetric, so it faces exactly +Z; the MotionBuilder
    // one has its shoulders 0.6 deg off, which the facing from hips and shoulders follows.
    for (file, header_lines, max_angle) in [("07_01.bvh", 275, 0.1f32), ("16_11.bvh", 187, 1.0f32)]
    {
        let source =
            BvhSource::from_clip(rest_clip(file, header_lines), BvhSourceOptions::default())
                .expect("rest clip maps");
        let frame = source.frame_at(0.0);
        let angle = |a: Quat, b: Quat| a.angle_between(b).to_degrees();
        // The rest pose faces +Z in BVH space: turned by half a turn to face the sensor.
        let half_turn = Quat::from_rotation_y(std::f32::consts::PI);
        assert!(
            angle(source.placement().yaw, half_turn) < max_angle,
            "{file}"
        );
        let pelvis = frame.joint(HipCenter).orientation;
        assert!(
            angle(pelvis, Quat::IDENTITY) < max_angle,
            "{file}: pelvis {pelvis}"
        );
        assert!(
            pos(&frame, HandLeft).x < -0.5 && pos(&frame, HandRight).x > 0.5,
            "{file}: T-pose arms"
        );
        for joint in KinectJoint::ALL {
            let Some(parent) = joint.parent() else {
                continue;
            };
            let bone = pos(&frame, joint) - pos(&frame, parent);
            let reference = bone_reference_frame(bone);
            let orientation = frame.joint(joint).orientation;
            assert!(
                angle(orientation, reference) < max_angle,
                "{file} {}: {orientation} vs reference {reference}",
                joint.name()
            );
        }
    }
}

#[test]
fn bone_twist_follows_the_driving_bvh_joint() {
    let c = Quat::from_rotation_y(std::f32::consts::PI);
    for file in ["07_01.bvh", "141_16.bvh"] {
        let source = load(file);
        let clip = source.clip();
        let mapping = source.mapping();
        let yaw = source.placement().yaw;
        let rest = clip.rest_pose();
        let ft = clip.frame_time_s();
        // Wrist and knee end single BVH bones (forearm, thigh), so the emitted frame is exactly
        // R * G_D * C^-1 * bone_reference_frame(C * rest direction) at the clip's own frames.
        for joint in [WristLeft, WristRight, KneeLeft, KneeRight, ElbowLeft] {
            let parent = joint.parent().expect("not the root");
            let rest_dir = rest.point(mapping.point(joint)).expect("point")
                - rest.point(mapping.point(parent)).expect("point");
            let reference = bone_reference_frame(c * rest_dir.normalize());
            for n in [0usize, 37, 101, 250] {
                let pose = clip.pose(source.first_played_frame() + n).expect("frame");
                let driver = pose.rotations[mapping.driver(joint)];
                let expected = yaw * driver * c.inverse() * reference;
                let actual = source.frame_at(n as f64 * ft).joint(joint).orientation;
                assert!(
                    same_rotation(actual, expected) > 1.0 - 1e-4,
                    "{file} {} frame {n}: {actual} vs {expected}",
                    joint.name()
                );
            }
        }
    }
}
