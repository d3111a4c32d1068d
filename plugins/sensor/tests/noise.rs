//! The Kinect v1 noise model on the real CMU clips: determinism, depth-dependent noise level,
//! temporal correlation, self-occlusion, dropped and duplicated frames, latency, bone-length
//! noise, the orientation contract and finiteness. Run with `--nocapture` to see the measured
//! figures.

mod common;

use KinectJoint::*;
use fitroom_sensor::noise::{
    BodyVolumes, KinectNoiseModel, NoisyFrame, NoisySource, corrupt_stream, occluded_joints,
};
use fitroom_sensor::{BvhSource, BvhSourceOptions, KinectJoint, SensorFrame, SensorSource};
use glam::{Quat, Vec3};

const FPS: f64 = 30.0;

fn load_at(file: &str, start_distance_m: f32) -> BvhSource {
    let options = BvhSourceOptions {
        start_distance_m,
        ..BvhSourceOptions::default()
    };
    BvhSource::load(common::clip_path(file), options).unwrap_or_else(|e| panic!("{file}: {e}"))
}

/// `n` consecutive 30 Hz frames of the looping clip (`frame_at(k / 30)`).
fn clean_frames(source: &BvhSource, n: usize) -> Vec<SensorFrame> {
    (0..n).map(|k| source.frame_at(k as f64 / FPS)).collect()
}

/// Frames covering `loops` loops of the clip.
fn clean_loops(source: &BvhSource, loops: f64) -> Vec<SensorFrame> {
    let n = (source.clip_duration_s() * loops * FPS).ceil() as usize;
    clean_frames(source, n.max(2))
}

/// Every bit of a noisy stream, for exact comparisons.
fn bits(frames: &[NoisyFrame]) -> Vec<u64> {
    let mut out = Vec::new();
    for f in frames {
        out.extend([
            f.frame.timestamp_s.to_bits(),
            f.frame.sequence,
            f.clean_index as u64,
            f.arrival_index as u64,
            u64::from(f.duplicate),
        ]);
        for j in &f.frame.joints {
            out.extend(j.position.to_array().map(|v| u64::from(v.to_bits())));
            out.extend(j.orientation.to_array().map(|v| u64::from(v.to_bits())));
            out.push(u64::from(j.confidence.to_bits()));
        }
    }
    out
}

fn error(noisy: &NoisyFrame, clean: &[SensorFrame], joint: KinectJoint) -> Vec3 {
    noisy.frame.joint(joint).position - clean[noisy.clean_index].joint(joint).position
}

fn is_extremity(joint: KinectJoint) -> bool {
    matches!(
        joint,
        WristLeft
            | HandLeft
            | WristRight
            | HandRight
            | AnkleLeft
            | FootLeft
            | AnkleRight
            | FootRight
    )
}

fn std(values: &[f32]) -> f32 {
    let n = values.len() as f64;
    let mean = values.iter().map(|&v| f64::from(v)).sum::<f64>() / n;
    let var = values
        .iter()
        .map(|&v| (f64::from(v) - mean).powi(2))
        .sum::<f64>()
        / n;
    var.sqrt() as f32
}

#[test]
fn same_seed_same_stream_and_different_seeds_differ() {
    let source = load_at("07_01.bvh", 2.5);
    let clean = clean_loops(&source, 2.0);
    let model = KinectNoiseModel::default();
    let a = corrupt_stream(&clean, &model, 42);
    let b = corrupt_stream(&clean, &model, 42);
    let c = corrupt_stream(&clean, &model, 43);
    assert!(a.len() > clean.len() * 9 / 10);
    assert_eq!(bits(&a), bits(&b), "same seed, same input: bit-identical");
    let differing = a
        .iter()
        .zip(&c)
        .filter(|(x, y)| x.frame.joints != y.frame.joints)
        .count();
    assert!(
        differing > a.len() * 9 / 10,
        "other seed: only {differing} of {} frames differ",
        a.len()
    );

    // The source form gives the same stream as the function form, however it is advanced.
    let steps: [f64; 4] = [1.0 / 30.0, 0.05, 0.0, 1.0 / 90.0];
    let mut wrapped = NoisySource::new(load_at("07_01.bvh", 2.5), &model, 42);
    let mut plain = load_at("07_01.bvh", 2.5);
    assert_eq!(wrapped.name(), "noisy:bvh:07_01");
    assert_eq!(wrapped.fps(), 30.0);
    let (mut noisy, mut inner) = (Vec::new(), Vec::new());
    let mut clock = 0.0;
    for dt in steps.iter().cycle() {
        noisy.extend(wrapped.advance_detailed(*dt).expect("never fails"));
        inner.extend(plain.advance(*dt).expect("never fails"));
        clock += dt;
        if clock > 12.0 {
            break;
        }
    }
    assert!(noisy.len() > 300);
    assert_eq!(bits(&noisy), bits(&corrupt_stream(&inner, &model, 42)));
    let mut again = NoisySource::new(load_at("07_01.bvh", 2.5), &model, 42);
    let frames = again.advance(9.0).expect("never fails");
    assert_eq!(
        frames,
        noisy
            .iter()
            .take(frames.len())
            .map(|f| f.frame.clone())
            .collect::<Vec<_>>()
    );
}

#[test]
fn the_model_serialises_validates_and_can_be_switched_off() {
    let model = KinectNoiseModel::default();
    assert_eq!(model.validate(), Ok(()));
    let json = serde_json::to_string_pretty(&model).expect("serialises");
    let back: KinectNoiseModel = serde_json::from_str(&json).expect("deserialises");
    assert_eq!(back, model);
    let partial: KinectNoiseModel =
        serde_json::from_str(r#"{"latency_s": 0.2, "body": {"head_radius_m": 0.12}}"#)
            .expect("partial model");
    assert_eq!(partial.latency_s, 0.2);
    assert_eq!(partial.body.head_radius_m, 0.12);
    assert_eq!(
        partial.body.trunk_radius_m,
        BodyVolumes::default().trunk_radius_m
    );
    assert_eq!(partial.drop_probability, model.drop_probability);

    // Calibration: 1.5 cm at 3 m, quadratic growth, lateral half of axial.
    assert!((model.axial_sigma_m(3.0) - 0.015).abs() < 2e-4);
    assert!((model.lateral_sigma_m(3.0) - 0.0075).abs() < 1e-4);
    assert!(model.axial_sigma_m(3.5) > 3.0 * model.axial_sigma_m(2.0));

    let bad = KinectNoiseModel {
        inferred_confidence: 0.7,
        ..model.clone()
    };
    assert_eq!(
        bad.validate().map_err(|e| e.name),
        Err("inferred_confidence")
    );
    assert_eq!(bad.sanitized().inferred_confidence, 0.5);
    let nan = KinectNoiseModel {
        drop_probability: f32::NAN,
        latency_s: -1.0,
        ..model.clone()
    };
    assert!(nan.validate().is_err());
    assert_eq!(nan.sanitized().drop_probability, model.drop_probability);
    assert_eq!(nan.sanitized().latency_s, 0.0);

    // Everything off: the positions and confidences come through unchanged, one frame per
    // input frame, no latency.
    let source = load_at("05_06.bvh", 2.5);
    let clean = clean_frames(&source, 200);
    let out = corrupt_stream(&clean, &KinectNoiseModel::noiseless(), 1);
    assert_eq!(out.len(), clean.len());
    for (k, (noisy, clean)) in out.iter().zip(&clean).enumerate() {
        assert_eq!((noisy.clean_index, noisy.arrival_index), (k, k));
        assert!(!noisy.duplicate);
        assert_eq!(noisy.frame.timestamp_s, clean.timestamp_s);
        assert_eq!(noisy.frame.sequence, k as u64);
        for (a, b) in noisy.frame.joints.iter().zip(&clean.joints) {
            assert_eq!(a.position, b.position);
            assert_eq!(a.confidence, b.confidence);
            assert!(a.orientation.dot(b.orientation).abs() > 1.0 - 1e-5);
        }
    }
}

/// Axial (line-of-sight) and lateral errors of tracked non-extremity joints, with the model's
/// axial sigma at each sample's depth.
struct DepthSamples {
    axial: Vec<f32>,
    lateral: Vec<f32>,
    expected_axial: Vec<f32>,
    depth: Vec<f32>,
}

fn depth_samples(file: &str, distance: f32, model: &KinectNoiseModel, seed: u64) -> DepthSamples {
    let source = load_at(file, distance);
    let clean = clean_loops(&source, 3.0);
    let noisy = corrupt_stream(&clean, model, seed);
    let mut out = DepthSamples {
        axial: Vec::new(),
        lateral: Vec::new(),
        expected_axial: Vec::new(),
        depth: Vec::new(),
    };
    for frame in noisy.iter().filter(|f| !f.duplicate) {
        for joint in KinectJoint::ALL {
            if is_extremity(joint) || frame.frame.joint(joint).confidence < 1.0 {
                continue;
            }
            let truth = clean[frame.clean_index].joint(joint).position;
            let e = error(frame, &clean, joint);
            let a = truth.normalize();
            let e1 = Vec3::Y.cross(a).normalize();
            out.axial.push(e.dot(a));
            out.lateral.push(e.dot(e1));
            out.expected_axial.push(model.axial_sigma_m(truth.z));
            out.depth.push(truth.z);
        }
    }
    out
}

#[test]
fn position_noise_is_about_1_5_cm_at_3_m_and_grows_with_depth() {
    let model = KinectNoiseModel::default();
    let mut measured = Vec::new();
    for file in ["14_19.bvh", "141_16.bvh"] {
        for distance in [2.0f32, 3.0, 3.5] {
            let s = depth_samples(file, distance, &model, 7);
            let near: Vec<usize> = (0..s.depth.len())
                .filter(|&i| (s.depth[i] - distance).abs() < 0.3)
                .collect();
            assert!(
                near.len() > 1000,
                "{file} at {distance} m: {} samples",
                near.len()
            );
            let pick = |v: &[f32]| near.iter().map(|&i| v[i]).collect::<Vec<f32>>();
            let axial = std(&pick(&s.axial));
            let lateral = std(&pick(&s.lateral));
            let expected = pick(&s.expected_axial).iter().sum::<f32>() / near.len() as f32;
            let normalised: Vec<f32> = near
                .iter()
                .map(|&i| s.axial[i] / s.expected_axial[i])
                .collect();
            let z_ratio = std(&normalised);
            println!(
                "{file} at {distance} m: axial std {:.2} cm (model {:.2} cm), lateral std {:.2} cm, \
                 axial/model {z_ratio:.3}, {} samples",
                axial * 100.0,
                expected * 100.0,
                lateral * 100.0,
                near.len()
            );
            assert!(
                (0.85..1.15).contains(&z_ratio),
                "{file} at {distance} m: axial noise / model = {z_ratio}"
            );
            assert!(
                lateral < axial,
                "{file}: lateral {lateral} >= axial {axial}"
            );
            measured.push((file, distance, axial));
        }
    }
    for (file, distance, axial) in &measured {
        if *distance == 3.0 {
            assert!(
                (0.011..0.019).contains(axial),
                "{file}: axial noise at 3 m is {axial} m, not 1.5 +- 0.4 cm"
            );
        }
    }
    for file in ["14_19.bvh", "141_16.bvh"] {
        let at = |d: f32| {
            measured
                .iter()
                .find(|(f, distance, _)| *f == file && *distance == d)
                .map(|m| m.2)
                .expect("measured")
        };
        assert!(
            at(2.0) < at(3.0) && at(3.0) < at(3.5),
            "{file}: {measured:?}"
        );
        assert!(at(3.5) > 2.0 * at(2.0), "{file}: {measured:?}");
    }

    // Per joint at 3 m (all joints, tracked samples, 3D RMS and per axis).
    let source = load_at("14_19.bvh", 3.0);
    let clean = clean_loops(&source, 3.0);
    let noisy = corrupt_stream(&clean, &model, 11);
    for joint in KinectJoint::ALL {
        let errors: Vec<Vec3> = noisy
            .iter()
            .filter(|f| !f.duplicate && f.frame.joint(joint).confidence == 1.0)
            .map(|f| error(f, &clean, joint))
            .collect();
        let per_axis = |k: usize| std(&errors.iter().map(|e| e[k]).collect::<Vec<_>>());
        let (x, y, z) = (per_axis(0), per_axis(1), per_axis(2));
        println!(
            "  {:<15} std x {:.2} y {:.2} z {:.2} cm, 3D rms {:.2} cm ({} samples)",
            joint.name(),
            x * 100.0,
            y * 100.0,
            z * 100.0,
            (x * x + y * y + z * z).sqrt() * 100.0,
            errors.len()
        );
    }
}

/// Lag-1 autocorrelation of the error of every tracked joint and axis over pairs of
/// consecutive fresh frames.
fn lag1_autocorrelation(noisy: &[NoisyFrame], clean: &[SensorFrame]) -> f32 {
    let (mut num, mut den) = (0.0f64, 0.0f64);
    for joint in KinectJoint::ALL {
        for axis in 0..3 {
            let series: Vec<(usize, f32)> = noisy
                .iter()
                .filter(|f| !f.duplicate && f.frame.joint(joint).confidence == 1.0)
                .map(|f| (f.clean_index, error(f, clean, joint)[axis]))
                .collect();
            let mean = series.iter().map(|s| f64::from(s.1)).sum::<f64>() / series.len() as f64;
            for pair in series.windows(2) {
                if pair[1].0 == pair[0].0 + 1 {
                    num += (f64::from(pair[0].1) - mean) * (f64::from(pair[1].1) - mean);
                    den += (f64::from(pair[0].1) - mean).powi(2);
                }
            }
        }
    }
    (num / den) as f32
}

#[test]
fn noise_is_temporally_correlated() {
    let source = load_at("14_19.bvh", 3.0);
    let clean = clean_loops(&source, 2.0);
    let model = KinectNoiseModel::default();
    let r1 = lag1_autocorrelation(&corrupt_stream(&clean, &model, 5), &clean);
    println!("lag-1 autocorrelation of the joint error at 30 Hz: {r1:.3} (model 0.68)");
    assert!((0.5..0.95).contains(&r1), "lag-1 autocorrelation {r1}");
    let white = KinectNoiseModel {
        white_noise_fraction: 1.0,
        bone_length_sigma: 0.0,
        hand_spike_rate_hz: 0.0,
        ..model
    };
    let r1_white = lag1_autocorrelation(&corrupt_stream(&clean, &white, 5), &clean);
    println!("  with white noise only: {r1_white:.3}");
    assert!(
        r1_white.abs() < 0.1,
        "white noise autocorrelation {r1_white}"
    );
}

/// Turns a pose by `angle` about the vertical through its hip centre (keeping the
/// orientations' consistency irrelevant: only positions are used).
fn turned(frame: &SensorFrame, angle: f32) -> [Vec3; KinectJoint::COUNT] {
    let hip = frame.joint(HipCenter).position;
    let q = Quat::from_rotation_y(angle);
    frame.joints.map(|j| hip + q * (j.position - hip))
}

#[test]
fn a_sideways_body_hides_its_far_side() {
    let source = load_at("07_01.bvh", 2.5);
    let frame = source.frame_at(0.0);
    let usable = [true; KinectJoint::COUNT];
    let body = BodyVolumes::default();
    let facing = occluded_joints(&turned(&frame, 0.0), &usable, &body, 0.05, 0.03);
    let hidden: Vec<&str> = KinectJoint::ALL
        .iter()
        .filter(|j| facing[j.index()])
        .map(|j| j.name())
        .collect();
    assert!(hidden.is_empty(), "facing the sensor, hidden: {hidden:?}");
    // Sensor -X is the performer's left. Turned by +90 deg about +Y the left side (at -X)
    // goes to +Z, away from the sensor.
    let pose = turned(&frame, std::f32::consts::FRAC_PI_2);
    assert!(pose[ShoulderLeft.index()].z > pose[ShoulderRight.index()].z + 0.2);
    let side = occluded_joints(&pose, &usable, &body, 0.05, 0.03);
    let hidden: Vec<&str> = KinectJoint::ALL
        .iter()
        .filter(|j| side[j.index()])
        .map(|j| j.name())
        .collect();
    println!("turned sideways (left side away), hidden: {hidden:?}");
    assert!(side[ShoulderLeft.index()], "{hidden:?}");
    assert!(side[HipLeft.index()], "{hidden:?}");
    for near in [ShoulderRight, ElbowRight, HipRight, KneeRight, Head] {
        assert!(!side[near.index()], "{}: {hidden:?}", near.name());
    }
}

#[test]
fn occluded_joints_are_inferred_with_low_confidence_and_larger_error() {
    let model = KinectNoiseModel::default();
    let usable = [true; KinectJoint::COUNT];
    let mut shares = Vec::new();
    let (mut tracked_error, mut tracked_n) = (0.0f64, 0usize);
    let (mut inferred_error, mut inferred_n) = (0.0f64, 0usize);
    for entry in common::index() {
        let source = load_at(&entry.file, 2.5);
        let clean = clean_loops(&source, 2.0);

        // The geometric test on the clean frames whose hip centre is in view.
        let (mut occluded, mut outside, mut in_view_total) = (0usize, 0usize, 0usize);
        let mut per_joint = [0usize; KinectJoint::COUNT];
        for frame in &clean {
            if !model.in_view(frame.joint(HipCenter).position) {
                continue;
            }
            let positions = frame.joints.map(|j| j.position);
            let hidden = occluded_joints(
                &positions,
                &usable,
                &model.body,
                model.occlusion_margin_m,
                model.occlusion_inset_m,
            );
            for joint in KinectJoint::ALL {
                in_view_total += 1;
                if hidden[joint.index()] {
                    occluded += 1;
                    per_joint[joint.index()] += 1;
                } else if !model.in_view(positions[joint.index()]) {
                    outside += 1;
                }
            }
        }

        let noisy = corrupt_stream(&clean, &model, 3);
        let (mut inferred, mut not_tracked, mut total) = (0usize, 0usize, 0usize);
        for frame in noisy.iter().filter(|f| !f.duplicate) {
            let truth = &clean[frame.clean_index];
            if !model.in_view(truth.joint(HipCenter).position) {
                assert!(
                    frame.frame.joint(HipCenter).confidence <= 0.5,
                    "{}: hip out of view but tracked",
                    entry.file
                );
            }
            for joint in KinectJoint::ALL {
                let c = frame.frame.joint(joint).confidence;
                let e = f64::from(error(frame, &clean, joint).length());
                total += 1;
                if c == 1.0 {
                    tracked_error += e;
                    tracked_n += 1;
                } else {
                    assert!(c == 0.5 || c == 0.0, "{}: confidence {c}", entry.file);
                    if c == 0.5 {
                        inferred += 1;
                        inferred_error += e;
                        inferred_n += 1;
                    } else {
                        not_tracked += 1;
                    }
                }
            }
        }
        let percent = |n: usize, of: usize| 100.0 * n as f64 / of.max(1) as f64;
        let occluded_share = percent(occluded, in_view_total);
        println!(
            "{:<10} occluded {:5.2} %, out of view {:5.2} % (frames with the hip in view); \
             stream: inferred {:5.2} %, not tracked {:5.2} % ({})",
            entry.file,
            occluded_share,
            percent(outside, in_view_total),
            percent(inferred, total),
            percent(not_tracked, total),
            entry.description.split(" [").next().unwrap_or("")
        );
        let list: Vec<String> = KinectJoint::ALL
            .iter()
            .filter(|j| per_joint[j.index()] > 0)
            .map(|j| format!("{} {}", j.name(), per_joint[j.index()]))
            .collect();
        println!("    occluded frames per joint: {}", list.join(", "));
        shares.push((entry.file, occluded_share));
    }
    let share_of = |file: &str| {
        shares
            .iter()
            .find(|s| s.0 == file)
            .map(|s| s.1)
            .expect("clip listed")
    };
    // The pirouettes turn the far side away; the wave faces the sensor throughout.
    assert!(share_of("05_06.bvh") > 1.0, "{shares:?}");
    assert!(share_of("141_16.bvh") < 0.5, "{shares:?}");
    let tracked_mean = tracked_error / tracked_n as f64;
    let inferred_mean = inferred_error / inferred_n as f64;
    println!(
        "mean error: tracked {:.2} cm, inferred {:.2} cm",
        tracked_mean * 100.0,
        inferred_mean * 100.0
    );
    assert!(inferred_mean > 1.5 * tracked_mean);

    // Occlusion alone (view limits off): the share of inferred joints and their error.
    let occlusion_only = KinectNoiseModel {
        view_limits_enabled: false,
        ..model
    };
    let (mut tracked, mut inferred) = ((0.0f64, 0usize), (0.0f64, 0usize));
    for file in ["05_06.bvh", "14_19.bvh", "10_03.bvh", "07_01.bvh"] {
        let source = load_at(file, 2.5);
        let clean = clean_loops(&source, 2.0);
        let noisy = corrupt_stream(&clean, &occlusion_only, 3);
        let (mut hidden, mut total) = (0usize, 0usize);
        for frame in noisy.iter().filter(|f| !f.duplicate) {
            if frame.frame.joint(HipCenter).position.z < 1.0 {
                continue; // the walk passes the sensor: the occlusion geometry means nothing
            }
            for joint in KinectJoint::ALL {
                let e = f64::from(error(frame, &clean, joint).length());
                total += 1;
                let slot = if frame.frame.joint(joint).confidence < 1.0 {
                    hidden += 1;
                    &mut inferred
                } else {
                    &mut tracked
                };
                slot.0 += e;
                slot.1 += 1;
            }
        }
        println!(
            "{file}: occlusion only, hip at z >= 1 m: {:.2} % of the joints inferred or not tracked",
            100.0 * hidden as f64 / total as f64
        );
    }
    let (t, i) = (tracked.0 / tracked.1 as f64, inferred.0 / inferred.1 as f64);
    println!(
        "occlusion only: mean error tracked {:.2} cm, inferred/not tracked {:.2} cm",
        t * 100.0,
        i * 100.0
    );
    assert!(i > 1.5 * t);
}

#[test]
fn drop_and_duplicate_rates_match_the_parameters() {
    let source = load_at("07_01.bvh", 2.5);
    let clean = clean_frames(&source, 30_000);
    for (drop, dup) in [(0.05f32, 0.03f32), (0.01, 0.01)] {
        let model = KinectNoiseModel {
            drop_probability: drop,
            duplicate_probability: dup,
            ..KinectNoiseModel::default()
        };
        let noisy = corrupt_stream(&clean, &model, 9);
        let slots = (clean.len() - 3) as f64;
        let drop_rate = 1.0 - noisy.len() as f64 / slots;
        let dup_rate = noisy.iter().filter(|f| f.duplicate).count() as f64 / slots;
        println!(
            "drop {drop} -> {drop_rate:.4}, duplicate {dup} -> {dup_rate:.4} over {slots} slots"
        );
        assert!((drop_rate - f64::from(drop)).abs() < 0.006);
        assert!((dup_rate - f64::from(dup)).abs() < 0.006);
        // Timestamps increase, sequence numbers are consecutive, duplicates repeat joints.
        for pair in noisy.windows(2) {
            assert!(pair[1].frame.timestamp_s > pair[0].frame.timestamp_s);
            assert_eq!(pair[1].frame.sequence, pair[0].frame.sequence + 1);
            if pair[1].duplicate {
                assert_eq!(pair[1].frame.joints, pair[0].frame.joints);
                assert_eq!(pair[1].clean_index, pair[0].clean_index);
            }
        }
    }
}

/// The lag (frames) that best lines the noisy hip centre up with the clean one: the argmin of
/// the mean squared difference between noisy at arrival `a` and clean at `a - lag` (the
/// least-squares form of the cross-correlation).
fn best_lag(noisy: &[NoisyFrame], clean: &[SensorFrame]) -> usize {
    (0..=12usize)
        .map(|lag| {
            let (mut sum, mut n) = (0.0f64, 0usize);
            for f in noisy
                .iter()
                .filter(|f| !f.duplicate && f.arrival_index >= lag)
            {
                let truth = clean[f.arrival_index - lag].joint(HipCenter).position;
                sum += f64::from(f.frame.joint(HipCenter).position.distance_squared(truth));
                n += 1;
            }
            (lag, sum / n as f64)
        })
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(lag, _)| lag)
        .expect("lags")
}

#[test]
fn latency_shows_in_the_cross_correlation_with_the_clean_stream() {
    for file in ["07_01.bvh", "16_11.bvh", "09_01.bvh"] {
        let source = load_at(file, 3.0);
        let clean = clean_loops(&source, 3.0);
        for latency_s in [0.0f32, 0.1, 0.2] {
            let model = KinectNoiseModel {
                latency_s,
                ..KinectNoiseModel::default()
            };
            let noisy = corrupt_stream(&clean, &model, 21);
            let expected = (f64::from(latency_s) * FPS).round() as usize;
            assert!(
                noisy
                    .iter()
                    .all(|f| f.duplicate || f.arrival_index - f.clean_index == expected)
            );
            assert_eq!(noisy[0].arrival_index, expected);
            let lag = best_lag(&noisy, &clean);
            println!("{file}: latency {latency_s} s -> best lag {lag} frames");
            assert!(lag.abs_diff(expected) <= 1, "{file}: {lag} vs {expected}");
        }
    }
}

#[test]
fn bone_lengths_vary_by_a_few_per_cent() {
    let model = KinectNoiseModel::default();
    for file in ["14_19.bvh", "07_01.bvh"] {
        let source = load_at(file, 2.5);
        let clean = clean_loops(&source, 3.0);
        let noisy = corrupt_stream(&clean, &model, 13);
        let truth = clean[0]
            .joint(WristLeft)
            .position
            .distance(clean[0].joint(ElbowLeft).position);
        for (bone, parent) in [
            (WristLeft, ElbowLeft),
            (KneeRight, HipRight),
            (Spine, HipCenter),
        ] {
            let lengths: Vec<f32> = noisy
                .iter()
                .filter(|f| {
                    !f.duplicate
                        && f.frame.joint(bone).confidence == 1.0
                        && f.frame.joint(parent).confidence == 1.0
                })
                .map(|f| {
                    f.frame
                        .joint(bone)
                        .position
                        .distance(f.frame.joint(parent).position)
                })
                .collect();
            let mean = lengths.iter().sum::<f32>() / lengths.len() as f32;
            let relative = std(&lengths) / mean;
            let clean_len = clean[0]
                .joint(bone)
                .position
                .distance(clean[0].joint(parent).position);
            println!(
                "{file} {}-{}: clean {:.1} cm, noisy mean {:.1} cm, std {:.2} % of the mean",
                parent.name(),
                bone.name(),
                clean_len * 100.0,
                mean * 100.0,
                relative * 100.0
            );
            assert!(relative > 0.005, "{file} {}: {relative}", bone.name());
            if bone == WristLeft {
                assert!(relative < 0.06, "{file} forearm: {relative}");
                assert!(
                    (mean / truth - 1.0).abs() < 0.03,
                    "{file}: {mean} vs {truth}"
                );
            }
        }
    }
}

#[test]
fn hand_spikes_hit_hands_and_wrists_only() {
    let model = KinectNoiseModel {
        hand_spike_rate_hz: 0.3,
        hand_spike_sigma_m: 0.05,
        ..KinectNoiseModel::noiseless()
    };
    let source = load_at("141_16.bvh", 2.5);
    let clean = clean_frames(&source, 9000);
    let noisy = corrupt_stream(&clean, &model, 17);
    let mut spiked = 0usize;
    for f in &noisy {
        let hand = error(f, &clean, HandLeft);
        let wrist = error(f, &clean, WristLeft);
        if hand.length() > 0.0 {
            spiked += 1;
            assert!((wrist - hand * 0.5).length() < 1e-4);
        } else {
            assert_eq!(wrist, Vec3::ZERO);
        }
        for joint in [ElbowLeft, Head, KneeRight, HipCenter] {
            assert_eq!(error(f, &clean, joint), Vec3::ZERO);
        }
    }
    let share = spiked as f64 / noisy.len() as f64;
    println!("left hand spiked in {:.2} % of the frames", share * 100.0);
    // 0.3 spikes/s lasting 1-6 frames (mean ~3.5) at 30 Hz: about 3.4 % of the frames.
    assert!((0.015..0.06).contains(&share), "{share}");
}

#[test]
fn noisy_orientations_follow_the_noisy_bones() {
    let model = KinectNoiseModel::default();
    for file in ["05_06.bvh", "13_10.bvh", "07_01.bvh"] {
        let source = load_at(file, 2.5);
        let clean = clean_loops(&source, 1.0);
        let noisy = corrupt_stream(&clean, &model, 19);
        let mut worst = 0.0f32;
        let mut twist = Vec::new();
        for f in &noisy {
            for joint in KinectJoint::ALL {
                let Some(parent) = joint.parent() else {
                    continue;
                };
                let bone = f.frame.joint(joint).position - f.frame.joint(parent).position;
                if bone.length() < 1e-3 {
                    continue;
                }
                let y = f.frame.joint(joint).orientation * Vec3::Y;
                let angle = y.normalize().angle_between(bone.normalize());
                worst = worst.max(angle);
                // The rotation between the clean and the noisy frame, measured about the bone.
                let clean_q = clean[f.clean_index].joint(joint).orientation;
                let rel = f.frame.joint(joint).orientation * clean_q.inverse();
                twist.push(rel.to_scaled_axis().dot(bone.normalize()));
            }
        }
        println!(
            "{file}: worst angle between orientation*Y and the noisy bone {worst:.2e} rad, \
             twist-axis component std {:.2} deg",
            std(&twist).to_degrees()
        );
        assert!(worst < 1e-3, "{file}: {worst}");
    }
}

#[test]
fn no_nan_on_any_clip_even_with_harsh_parameters() {
    let harsh = KinectNoiseModel {
        axial_sigma_c2_per_m: 0.01,
        hand_spike_rate_hz: 3.0,
        hand_spike_sigma_m: 0.3,
        bone_length_sigma: 0.2,
        twist_sigma_deg: 40.0,
        drop_probability: 0.2,
        duplicate_probability: 0.2,
        not_tracked_after_s: 0.1,
        inferred_body_pull: 1.0,
        body: BodyVolumes {
            trunk_radius_m: 0.3,
            ..BodyVolumes::default()
        },
        ..KinectNoiseModel::default()
    };
    for entry in common::index() {
        let source = load_at(&entry.file, 2.5);
        let clean = clean_loops(&source, 2.0);
        for (name, model) in [
            ("default", KinectNoiseModel::default()),
            ("harsh", harsh.clone()),
        ] {
            let noisy = corrupt_stream(&clean, &model, 23);
            assert!(!noisy.is_empty());
            for f in &noisy {
                assert!(f.frame.timestamp_s.is_finite());
                for (k, j) in f.frame.joints.iter().enumerate() {
                    assert!(
                        j.position.is_finite() && j.orientation.is_finite(),
                        "{} {name}: joint {k} at {}",
                        entry.file,
                        f.frame.timestamp_s
                    );
                    assert!((j.orientation.length() - 1.0).abs() < 1e-3);
                    assert!([0.0, 0.5, 1.0].contains(&j.confidence));
                }
            }
        }
    }
    // Non-finite input joints come out finite and not tracked.
    let source = load_at("07_01.bvh", 2.5);
    let mut clean = clean_frames(&source, 60);
    for frame in clean.iter_mut().skip(20).take(5) {
        frame.joints[ElbowLeft.index()].position = Vec3::NAN;
        frame.joints[HandRight.index()].orientation = Quat::from_xyzw(f32::NAN, 0.0, 0.0, 1.0);
    }
    let noisy = corrupt_stream(&clean, &KinectNoiseModel::default(), 1);
    for f in &noisy {
        for j in &f.frame.joints {
            assert!(j.position.is_finite() && j.orientation.is_finite());
        }
        if (20..25).contains(&f.clean_index) {
            assert_eq!(f.frame.joint(ElbowLeft).confidence, 0.0);
        }
    }
}
