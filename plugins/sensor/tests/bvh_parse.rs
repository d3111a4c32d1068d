//! The BVH parser on the real CMU clips: what it reads, how it fails, and its forward
//! kinematics against a hand-written chain.

mod common;

use fitroom_sensor::bvh::{BvhClip, BvhError};
use fitroom_sensor::{BvhSkeletonKind, BvhSource, BvhSourceOptions, inspect};
use glam::{DMat4, DVec3, Vec3};

/// Replaces line `line` (1-based) of `text`, keeping the file's line terminator.
fn replace_line(text: &str, line: usize, f: impl Fn(&str) -> String) -> String {
    text.split_inclusive('\n')
        .enumerate()
        .map(|(i, l)| {
            if i + 1 != line {
                return l.to_string();
            }
            let body = l.trim_end_matches(['\r', '\n']);
            format!("{}{}", f(body), &l[body.len()..])
        })
        .collect()
}

/// The first `n` lines of `text`, terminators included.
fn first_lines(text: &str, n: usize) -> String {
    text.split_inclusive('\n').take(n).collect()
}

/// Asserts that `result` failed at `file:line` and returns the message.
fn assert_fails_at(
    result: Result<BvhClip, BvhError>,
    file: &str,
    line: usize,
) -> (BvhError, String) {
    let error = match result {
        Ok(_) => panic!("{file}: expected an error at line {line}, but the text parsed"),
        Err(e) => e,
    };
    let message = error.to_string();
    assert!(
        message.starts_with(&format!("{file}:{line}: ")),
        "expected the message to start with '{file}:{line}: ', got: {message}"
    );
    assert_eq!(error.file(), file);
    assert_eq!(error.line(), Some(line), "{message}");
    (error, message)
}

#[test]
fn every_indexed_clip_parses_with_the_index_frame_count_and_skeleton() {
    for entry in common::index() {
        let clip = BvhClip::load(entry.path())
            .unwrap_or_else(|e| panic!("{} does not parse: {e}", entry.file));
        assert_eq!(clip.frame_count(), entry.frames, "{}", entry.file);
        assert_eq!(clip.frames().count(), entry.frames, "{}", entry.file);
        assert!(
            (clip.frame_time_s() - entry.frame_time).abs() < 1e-9,
            "{}: frame time {} vs INDEX {}",
            entry.file,
            clip.frame_time_s(),
            entry.frame_time
        );
        assert!(
            (clip.fps() - 120.0).abs() < 0.01,
            "{}: {} fps",
            entry.file,
            clip.fps()
        );

        let expected = if entry.is_motionbuilder() {
            BvhSkeletonKind::MotionBuilder
        } else {
            BvhSkeletonKind::CgspeedDaz
        };
        assert_eq!(
            BvhSkeletonKind::detect(&clip),
            Some(expected),
            "{}",
            entry.file
        );
        let (joints, channels) = match expected {
            BvhSkeletonKind::CgspeedDaz => (43, 132),
            BvhSkeletonKind::MotionBuilder => (31, 96),
        };
        assert_eq!(clip.joints().len(), joints, "{}", entry.file);
        assert_eq!(expected.expected_joint_count(), joints);
        assert_eq!(clip.channel_count(), channels, "{}", entry.file);
        assert_eq!(
            clip.joints()
                .iter()
                .map(|j| j.channels.len())
                .sum::<usize>(),
            channels
        );

        let info = inspect(entry.path()).expect("inspect reads what load reads");
        assert_eq!(info.frames, entry.frames);
        assert_eq!(info.joints, joints);
        assert_eq!(info.channels, channels);
        assert_eq!(info.skeleton, expected.name());
        assert_eq!(info.tpose_frame, expected == BvhSkeletonKind::CgspeedDaz);
        assert_eq!(
            info.first_played_frame,
            if info.tpose_frame { 8 } else { 0 }
        );
        assert!((info.duration_s - entry.frames as f64 * entry.frame_time).abs() < 1e-9);
        let json = serde_json::to_value(&info).expect("BvhInfo serialises");
        assert_eq!(json["frames"], entry.frames);
        assert_eq!(json["skeleton"], expected.name());
    }
}

#[test]
fn skeleton_names_are_stable() {
    assert_eq!(BvhSkeletonKind::CgspeedDaz.name(), "cgspeed-daz");
    assert_eq!(BvhSkeletonKind::MotionBuilder.name(), "motionbuilder");
}

#[test]
fn line_endings_and_header_whitespace_do_not_change_the_parse() {
    // 07_01: LF with a tab after "Frames:".
    let lf = common::clip_text("07_01.bvh");
    assert!(!lf.contains('\r'));
    let reference = BvhClip::from_str(&lf, "x.bvh").expect("07_01 parses");

    let crlf = lf.replace('\n', "\r\n");
    assert_eq!(
        BvhClip::from_str(&crlf, "x.bvh").expect("CRLF parses"),
        reference
    );

    // CRLF on the header lines (1-275) only, as in 10_03.
    let header_crlf: String = lf
        .split_inclusive('\n')
        .enumerate()
        .map(|(i, l)| {
            if i < 275 {
                l.replace('\n', "\r\n")
            } else {
                l.to_string()
            }
        })
        .collect();
    assert_eq!(
        BvhClip::from_str(&header_crlf, "x.bvh").expect("CRLF header parses"),
        reference
    );

    let spaces = replace_line(&lf, 274, |l| l.replace('\t', "   "));
    let spaces = replace_line(&spaces, 275, |l| l.replace('\t', " "));
    assert_eq!(
        BvhClip::from_str(&spaces, "x.bvh").expect("spaces parse"),
        reference
    );

    let blank_lines = replace_line(&lf, 300, |l| format!("\n  \n{l}"));
    assert_eq!(
        BvhClip::from_str(&blank_lines, "x.bvh").expect("blank lines"),
        reference
    );

    // 16_11: CRLF everywhere, space after "Frames:"; as LF it is the same clip.
    let mb = common::clip_text("16_11.bvh");
    assert!(mb.contains("\r\n"));
    assert_eq!(
        BvhClip::from_str(&mb, "y.bvh").expect("16_11 parses"),
        BvhClip::from_str(&mb.replace("\r\n", "\n"), "y.bvh").expect("16_11 as LF parses")
    );

    // 10_03: mixed; CRLF on most header lines (LF on lines 1-6), LF in the motion data.
    let mixed = common::clip_text("10_03.bvh");
    let lines: Vec<&str> = mixed.split_inclusive('\n').collect();
    assert!(lines[..275].iter().filter(|l| l.ends_with("\r\n")).count() > 250);
    assert!(lines[275..].iter().all(|l| !l.contains('\r')));
    assert_eq!(
        BvhClip::from_str(&mixed, "z.bvh").expect("10_03 parses"),
        BvhClip::from_str(&mixed.replace("\r\n", "\n"), "z.bvh").expect("10_03 as LF parses")
    );
}

#[test]
fn a_truncated_motion_block_names_the_line_where_frames_are_missing() {
    let text = common::clip_text("07_01.bvh");
    // Header: lines 1-275; frame k on line 276 + k; keep 100 frames.
    let truncated = first_lines(&text, 375);
    let (error, message) =
        assert_fails_at(BvhClip::from_str(&truncated, "07_01.bvh"), "07_01.bvh", 376);
    assert!(
        matches!(
            error,
            BvhError::Truncated {
                found: 100,
                declared: 317,
                ..
            }
        ),
        "{error:?}"
    );
    assert!(message.contains("317"), "{message}");

    // The same for a CRLF file (16_11: header lines 1-187, frame k on line 188 + k).
    let text = common::clip_text("16_11.bvh");
    let truncated = first_lines(&text, 187 + 10);
    let (error, _) = assert_fails_at(BvhClip::from_str(&truncated, "16_11.bvh"), "16_11.bvh", 198);
    assert!(
        matches!(
            error,
            BvhError::Truncated {
                found: 10,
                declared: 534,
                ..
            }
        ),
        "{error:?}"
    );

    // Cut inside the motion header.
    let truncated = first_lines(&text, 186);
    let (_, message) =
        assert_fails_at(BvhClip::from_str(&truncated, "16_11.bvh"), "16_11.bvh", 187);
    assert!(message.contains("Frame Time"), "{message}");
}

#[test]
fn a_motion_line_with_a_missing_value_is_a_channel_count_error() {
    let text = common::clip_text("07_01.bvh");
    let edited = replace_line(&text, 300, |l| {
        let words: Vec<&str> = l.split_whitespace().collect();
        words[..words.len() - 1].join(" ")
    });
    let (error, message) =
        assert_fails_at(BvhClip::from_str(&edited, "07_01.bvh"), "07_01.bvh", 300);
    assert!(
        matches!(
            error,
            BvhError::ChannelCount {
                frame: 24,
                found: 131,
                expected: 132,
                ..
            }
        ),
        "{error:?}"
    );
    assert!(
        message.contains("131") && message.contains("132"),
        "{message}"
    );

    // An extra value in a CRLF-only file (141_16).
    let text = common::clip_text("141_16.bvh");
    let edited = replace_line(&text, 250, |l| format!("{l} 1.0"));
    let (error, _) = assert_fails_at(BvhClip::from_str(&edited, "141_16.bvh"), "141_16.bvh", 250);
    assert!(
        matches!(
            error,
            BvhError::ChannelCount {
                found: 97,
                expected: 96,
                ..
            }
        ),
        "{error:?}"
    );
}

#[test]
fn a_non_numeric_value_is_reported_with_its_text() {
    let text = common::clip_text("07_01.bvh");
    let edited = replace_line(&text, 400, |l| {
        let mut words: Vec<&str> = l.split_whitespace().collect();
        words[9] = "abc";
        words.join(" ")
    });
    let (error, message) =
        assert_fails_at(BvhClip::from_str(&edited, "07_01.bvh"), "07_01.bvh", 400);
    assert!(matches!(error, BvhError::NotANumber { .. }), "{error:?}");
    assert!(
        message.contains("'abc'") && message.contains("channel 10"),
        "{message}"
    );

    // In the CRLF-header-only file 10_03, on a body (LF) line.
    let text = common::clip_text("10_03.bvh");
    let edited = replace_line(&text, 280, |l| l.replacen(' ', " nan ", 1));
    let edited = replace_line(&edited, 280, |l| {
        let mut words: Vec<&str> = l.split_whitespace().collect();
        words.pop();
        words.join(" ")
    });
    let (_, message) = assert_fails_at(BvhClip::from_str(&edited, "10_03.bvh"), "10_03.bvh", 280);
    assert!(message.contains("'nan'"), "{message}");

    // A non-numeric OFFSET in the hierarchy.
    let text = common::clip_text("16_11.bvh");
    let edited = replace_line(&text, 12, |l| l.replace("-1.794630", "-1.79x"));
    let (_, message) = assert_fails_at(BvhClip::from_str(&edited, "16_11.bvh"), "16_11.bvh", 12);
    assert!(
        message.contains("'-1.79x'") && message.contains("OFFSET"),
        "{message}"
    );
}

#[test]
fn zero_frames_and_frame_count_mismatches_are_errors() {
    let text = common::clip_text("07_01.bvh");
    let edited = replace_line(&text, 274, |_| "Frames:\t0".to_string());
    let (error, message) =
        assert_fails_at(BvhClip::from_str(&edited, "07_01.bvh"), "07_01.bvh", 274);
    assert!(matches!(error, BvhError::NoFrames { .. }), "{error:?}");
    assert!(message.contains("at least one frame"), "{message}");

    let header_only = first_lines(&edited, 275);
    assert_fails_at(
        BvhClip::from_str(&header_only, "07_01.bvh"),
        "07_01.bvh",
        274,
    );

    // One frame fewer declared than present: the last line is extra.
    let edited = replace_line(&text, 274, |_| "Frames:\t316".to_string());
    let (error, _) = assert_fails_at(
        BvhClip::from_str(&edited, "07_01.bvh"),
        "07_01.bvh",
        276 + 316,
    );
    assert!(
        matches!(error, BvhError::ExtraFrames { declared: 316, .. }),
        "{error:?}"
    );

    let edited = replace_line(&text, 274, |_| "Frames: many".to_string());
    let (error, _) = assert_fails_at(BvhClip::from_str(&edited, "07_01.bvh"), "07_01.bvh", 274);
    assert!(matches!(error, BvhError::NotANumber { .. }), "{error:?}");
}

#[test]
fn a_wrong_or_missing_root_is_reported_at_its_line() {
    let text = common::clip_text("07_01.bvh");

    // Not a BVH file at all.
    let (_, message) = assert_fails_at(
        BvhClip::from_str(&format!("hello\n{text}"), "07_01.bvh"),
        "07_01.bvh",
        1,
    );
    assert!(message.contains("HIERARCHY"), "{message}");
    assert_fails_at(BvhClip::from_str("", "empty.bvh"), "empty.bvh", 1);

    // HIERARCHY without ROOT.
    let edited = replace_line(&text, 2, |_| "JOINT hip".to_string());
    let (_, message) = assert_fails_at(BvhClip::from_str(&edited, "07_01.bvh"), "07_01.bvh", 2);
    assert!(message.contains("ROOT"), "{message}");

    // A root the Kinect mapping does not know: parses, but cannot be replayed.
    let edited = replace_line(&text, 2, |_| "ROOT Pelvis".to_string());
    let clip = BvhClip::from_str(&edited, "07_01.bvh").expect("a renamed root still parses");
    assert_eq!(BvhSkeletonKind::detect(&clip), None);
    let error = BvhSource::from_clip(clip, BvhSourceOptions::default())
        .expect_err("an unknown root cannot be mapped");
    let message = error.to_string();
    assert!(message.starts_with("07_01.bvh:2: "), "{message}");
    assert!(
        message.contains("'Pelvis'") && message.contains("'hip'") && message.contains("'Hips'"),
        "{message}"
    );

    // The same in a CRLF file.
    let text = common::clip_text("05_06.bvh");
    let edited = replace_line(&text, 2, |_| "ROOT Pelvis".to_string());
    let clip = BvhClip::from_str(&edited, "05_06.bvh").expect("a renamed root still parses");
    let message = BvhSource::from_clip(clip, BvhSourceOptions::default())
        .expect_err("an unknown root cannot be mapped")
        .to_string();
    assert!(message.starts_with("05_06.bvh:2: "), "{message}");

    // A mapped joint that is missing.
    let text = common::clip_text("16_11.bvh");
    let edited = text.replace("JOINT LeftForeArm", "JOINT LeftLowerArm");
    let clip = BvhClip::from_str(&edited, "16_11.bvh").expect("a renamed joint still parses");
    let message = BvhSource::from_clip(clip, BvhSourceOptions::default())
        .expect_err("a missing mapped joint")
        .to_string();
    assert!(
        message.starts_with("16_11.bvh:2: ") && message.contains("'LeftForeArm'"),
        "{message}"
    );
}

#[test]
fn hierarchy_structure_errors_name_their_line() {
    let text = common::clip_text("07_01.bvh");
    // An unknown channel name on line 9 (abdomen's CHANNELS).
    let edited = replace_line(&text, 9, |l| l.replace("Xrotation", "Wrotation"));
    let (_, message) = assert_fails_at(BvhClip::from_str(&edited, "07_01.bvh"), "07_01.bvh", 9);
    assert!(message.contains("'Wrotation'"), "{message}");

    // A missing closing brace: MOTION is found where '}' was expected.
    let edited = replace_line(&text, 272, |_| String::new());
    let (_, message) = assert_fails_at(BvhClip::from_str(&edited, "07_01.bvh"), "07_01.bvh", 273);
    assert!(
        message.contains("'MOTION'") && message.contains("'}'"),
        "{message}"
    );

    // A stray word in a joint block.
    let edited = replace_line(&text, 8, |l| format!("{l} banana"));
    let (_, message) = assert_fails_at(BvhClip::from_str(&edited, "07_01.bvh"), "07_01.bvh", 8);
    assert!(message.contains("'banana'"), "{message}");
}

/// Deterministic pseudo-random numbers (xorshift).
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
}

/// Every result of parsing damaged text is Ok or an Err naming the file and a line that exists.
fn check_no_panic(text: &str, file: &str) {
    match BvhClip::from_str(text, file) {
        Ok(clip) => {
            // Whatever parses must also replay without panicking.
            if let Ok(source) = BvhSource::from_clip(clip, BvhSourceOptions::default()) {
                let _ = source.frame_at(0.37);
            }
        }
        Err(error) => {
            let message = error.to_string();
            assert!(message.starts_with(file), "{message}");
            let lines = text.split('\n').count();
            let line = error.line().expect("parse errors carry a line");
            assert!(
                line >= 1 && line <= lines + 1,
                "line {line} of {lines}: {message}"
            );
        }
    }
}

#[test]
fn damaged_files_never_panic() {
    for file in ["07_01.bvh", "16_11.bvh"] {
        let text = common::clip_text(file);
        let header_end = text.find("MOTION").expect("has MOTION") + 40;
        // Every byte offset in the hierarchy and the motion header, then every 997th.
        let last_line_start = text.trim_end().rfind('\n').expect("several lines");
        let offsets = (0..header_end).chain((header_end..last_line_start).step_by(997));
        let mut parsed = 0;
        for cut in offsets {
            if text.is_char_boundary(cut) {
                let result = BvhClip::from_str(&text[..cut], file);
                parsed += usize::from(result.is_ok());
                check_no_panic(&text[..cut], file);
            }
        }
        assert_eq!(parsed, 0, "{file}: a truncated file never parses");
        check_no_panic(&text, file);

        // Random byte damage in the hierarchy.
        let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
        let replacements = [b'{', b'}', b'\n', b' ', b'x', b'-', b'9', b'.'];
        for _ in 0..400 {
            let mut bytes = text.as_bytes().to_vec();
            for _ in 0..3 {
                let at = (rng.next() % header_end as u64) as usize;
                bytes[at] = replacements[(rng.next() % replacements.len() as u64) as usize];
            }
            check_no_panic(&String::from_utf8_lossy(&bytes), file);
        }
    }
}

/// Rotation matrix for a BVH channel list, composed in the listed order.
fn euler(order: &str, values: &[f64]) -> DMat4 {
    order
        .chars()
        .zip(values)
        .fold(DMat4::IDENTITY, |m, (axis, deg)| {
            let r = deg.to_radians();
            m * match axis {
                'X' => DMat4::from_rotation_x(r),
                'Y' => DMat4::from_rotation_y(r),
                _ => DMat4::from_rotation_z(r),
            }
        })
}

/// The values of frame `k` read straight from the file text.
fn raw_frame(text: &str, first_frame_line: usize, k: usize) -> Vec<f64> {
    text.lines()
        .nth(first_frame_line - 1 + k)
        .expect("frame line exists")
        .split_whitespace()
        .map(|w| w.parse().expect("numeric"))
        .collect()
}

/// Walks a chain of (offset, first channel, rotation order) from the root and returns the
/// global matrix of the last joint.
fn chain(values: &[f64], root_order: &str, joints: &[([f64; 3], usize, &str)]) -> DMat4 {
    let root = DMat4::from_translation(DVec3::new(values[0], values[1], values[2]))
        * euler(root_order, &values[3..6]);
    joints.iter().fold(root, |m, (offset, channel, order)| {
        m * DMat4::from_translation(DVec3::from_array(*offset))
            * euler(order, &values[*channel..*channel + 3])
    })
}

fn assert_close(actual: Vec3, expected: DVec3, tolerance: f64, what: &str) {
    let d = (actual.as_dvec3() - expected).length();
    assert!(d < tolerance, "{what}: {actual:?} vs {expected:?} ({d})");
}

#[test]
fn forward_kinematics_matches_a_hand_written_chain() {
    // cgspeed 07_01: hip (ZYX) -> abdomen -> chest -> lCollar -> lShldr -> lForeArm -> lHand
    // (all ZXY), offsets copied from the file; frame k is on line 276 + k.
    let text = common::clip_text("07_01.bvh");
    let clip = BvhClip::from_str(&text, "07_01.bvh").expect("parses");
    let chain_daz: [([f64; 3], usize, &str); 6] = [
        ([0.0, 20.6881, -0.73152], 6, "ZXY"),
        ([0.0, 11.7043, -0.48768], 9, "ZXY"),
        ([2.68224, 19.2634, -4.8768], 66, "ZXY"),
        ([8.77824, -1.95073, 1.46304], 69, "ZXY"),
        ([28.1742, -1.7115, 0.48768], 72, "ZXY"),
        ([22.5879, 0.773209, 7.07136], 75, "ZXY"),
    ];
    let hand = clip.joint_index("lHand").expect("lHand");
    for k in [1, 150, 316] {
        let values = raw_frame(&text, 276, k);
        let expected = chain(&values, "ZYX", &chain_daz);
        let pose = clip.pose(k).expect("frame exists");
        assert_close(
            pose.positions[hand],
            expected.w_axis.truncate(),
            1e-3,
            "lHand position",
        );
        let x = pose.rotations[hand] * Vec3::X;
        assert_close(x, expected.x_axis.truncate(), 1e-5, "lHand x axis");
        let y = pose.rotations[hand] * Vec3::Y;
        assert_close(y, expected.y_axis.truncate(), 1e-5, "lHand y axis");
        // The end site of lMid2 hangs off the same hand.
        let mid_tip = pose.end_sites[clip.joint_index("lMid2").expect("lMid2")];
        assert!(mid_tip.is_some());
    }

    // MotionBuilder 16_11 (CRLF): Hips -> LHipJoint -> LeftUpLeg -> LeftLeg -> LeftFoot ->
    // LeftToeBase, all ZYX; frame k is on line 188 + k.
    let text = common::clip_text("16_11.bvh");
    let clip = BvhClip::from_str(&text, "16_11.bvh").expect("parses");
    let chain_mb: [([f64; 3], usize, &str); 5] = [
        ([0.0, 0.0, 0.0], 6, "ZYX"),
        ([1.36306, -1.79463, 0.83929], 9, "ZYX"),
        ([2.44811, -6.72613, 0.0], 12, "ZYX"),
        ([2.5622, -7.03959, 0.0], 15, "ZYX"),
        ([0.15764, -0.43311, 2.32255], 18, "ZYX"),
    ];
    let toe = clip.joint_index("LeftToeBase").expect("LeftToeBase");
    for k in [0, 200, 533] {
        let values = raw_frame(&text, 188, k);
        let expected = chain(&values, "ZYX", &chain_mb);
        let pose = clip.pose(k).expect("frame exists");
        assert_close(
            pose.positions[toe],
            expected.w_axis.truncate(),
            1e-4,
            "LeftToeBase position",
        );
        let z = pose.rotations[toe] * Vec3::Z;
        assert_close(z, expected.z_axis.truncate(), 1e-5, "LeftToeBase z axis");
    }

    // The rest pose is the offsets added up.
    let rest = clip.rest_pose();
    let sum = DVec3::new(
        1.36306 + 2.44811 + 2.5622 + 0.15764,
        -1.79463 - 6.72613 - 7.03959 - 0.43311,
        0.83929 + 2.32255,
    );
    assert_close(rest.positions[toe], sum, 1e-4, "rest LeftToeBase");
}
