//! A parser and forward kinematics for Biovision Hierarchy (BVH) motion-capture files.
//!
//! BVH is the de-facto exchange format of the CMU motion-capture database: a `HIERARCHY` of
//! joints (each with an `OFFSET` from its parent, a list of `CHANNELS` and optionally an
//! `End Site`) followed by a `MOTION` block with one line of channel values per frame. The
//! parser is hand-written so that every error names the file and the 1-based line and says what
//! it found and what it expected; it never panics, whatever the input.
//!
//! Tolerated variations seen in real files: LF, CRLF or mixed line endings, tabs or spaces
//! anywhere whitespace is allowed (`Frames:\t344`), trailing whitespace, blank lines in the
//! motion block. The parser is otherwise strict: the motion block must hold exactly `Frames:`
//! lines, each with exactly one finite number per declared channel.
//!
//! Units: the file's own. Offsets and position channels are in the skeleton's length unit
//! (centimetres for the cgspeed CMU conversion, about 0.056 m for the MotionBuilder-style
//! export), rotation channels in degrees, `Frame Time` in seconds. Converting to metres is the
//! job of [`crate::bvh_skeleton`], which derives the scale from the leg length.
//!
//! Forward kinematics follows the BVH convention: a joint's local transform is
//! `translate(offset + position channels) * R`, with `R = R_c1 * R_c2 * R_c3` for the rotation
//! channels in the order they are listed (intrinsic rotations: `Zrotation Xrotation Yrotation`
//! gives `Rz * Rx * Ry`); the global transform is `parent_global * local`. Position channels
//! are added to the offset for any joint that has them (in the CMU files only the root does, with
//! a zero offset).

use std::path::Path;

use glam::{Quat, Vec3};

/// One channel of a joint: a translation along or a rotation about a parent-frame axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Channel {
    Xposition,
    Yposition,
    Zposition,
    Xrotation,
    Yrotation,
    Zrotation,
}

impl Channel {
    /// The channel named as in a `CHANNELS` line (`"Zrotation"`), case-sensitive.
    pub fn parse(name: &str) -> Option<Channel> {
        Some(match name {
            "Xposition" => Channel::Xposition,
            "Yposition" => Channel::Yposition,
            "Zposition" => Channel::Zposition,
            "Xrotation" => Channel::Xrotation,
            "Yrotation" => Channel::Yrotation,
            "Zrotation" => Channel::Zrotation,
            _ => return None,
        })
    }

    /// The name as written in a BVH file.
    pub fn name(self) -> &'static str {
        match self {
            Channel::Xposition => "Xposition",
            Channel::Yposition => "Yposition",
            Channel::Zposition => "Zposition",
            Channel::Xrotation => "Xrotation",
            Channel::Yrotation => "Yrotation",
            Channel::Zrotation => "Zrotation",
        }
    }

    pub fn is_rotation(self) -> bool {
        matches!(
            self,
            Channel::Xrotation | Channel::Yrotation | Channel::Zrotation
        )
    }

    /// The unit axis of this channel.
    pub fn axis(self) -> Vec3 {
        match self {
            Channel::Xposition | Channel::Xrotation => Vec3::X,
            Channel::Yposition | Channel::Yrotation => Vec3::Y,
            Channel::Zposition | Channel::Zrotation => Vec3::Z,
        }
    }
}

/// One joint of the hierarchy.
#[derive(Clone, Debug, PartialEq)]
pub struct BvhJoint {
    /// The name after `ROOT` / `JOINT` (all words up to the end of the line).
    pub name: String,
    /// Index of the parent joint in [`BvhClip::joints`]; parents always come before children.
    /// `None` for the root (index 0).
    pub parent: Option<usize>,
    /// Translation from the parent joint in the parent's frame, file units.
    pub offset: Vec3,
    /// Channels in the order listed, which is the order of their values on a motion line.
    pub channels: Vec<Channel>,
    /// Index of this joint's first channel value within a motion line.
    pub first_channel: usize,
    /// The `End Site` offset in this joint's frame, file units, if the joint has one.
    pub end_site: Option<Vec3>,
    /// 1-based line of the `ROOT` / `JOINT` keyword.
    pub line: usize,
}

/// A point of the skeleton: a joint or the end site of a joint.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum BvhPoint {
    Joint(usize),
    /// The `End Site` of the joint with this index.
    EndSite(usize),
}

/// Why a BVH file could not be read. Every variant names the file; all but `Io` and
/// `InvalidOptions` name the 1-based line, and the message says what was expected.
#[derive(Debug, thiserror::Error)]
pub enum BvhError {
    #[error("{file}: cannot read the file: {source}")]
    Io {
        file: String,
        #[source]
        source: std::io::Error,
    },
    /// A keyword or structure other than the one the format requires at this point.
    #[error("{file}:{line}: found {found}; expected {expected}")]
    Syntax {
        file: String,
        line: usize,
        found: String,
        expected: String,
    },
    /// A token that should be a number is not one (or is not finite).
    #[error("{file}:{line}: '{value}' is not a valid number; expected {expected}")]
    NotANumber {
        file: String,
        line: usize,
        value: String,
        expected: String,
    },
    /// A motion line with a different number of values than the hierarchy has channels.
    #[error(
        "{file}:{line}: frame index {frame} has {found} values; expected {expected} (one per channel declared in HIERARCHY)"
    )]
    ChannelCount {
        file: String,
        line: usize,
        /// 0-based frame index.
        frame: usize,
        found: usize,
        expected: usize,
    },
    /// The motion block ends before the number of frames given by `Frames:`.
    #[error(
        "{file}:{line}: motion data ends after {found} frame lines; expected {declared} frame lines as declared by 'Frames: {declared}' (truncated file?)"
    )]
    Truncated {
        file: String,
        /// The line where the next frame was expected.
        line: usize,
        found: usize,
        declared: usize,
    },
    /// More frame lines than `Frames:` declares.
    #[error(
        "{file}:{line}: extra frame line; expected only {declared} frame lines as declared by 'Frames: {declared}'"
    )]
    ExtraFrames {
        file: String,
        line: usize,
        declared: usize,
    },
    /// `Frames: 0`.
    #[error("{file}:{line}: 'Frames: 0' declares an empty clip; expected at least one frame")]
    NoFrames { file: String, line: usize },
    /// A well-formed file whose skeleton cannot be mapped onto the Kinect joints (an unknown
    /// root name, a missing joint, a degenerate leg).
    #[error("{file}:{line}: {message}")]
    Skeleton {
        file: String,
        line: usize,
        message: String,
    },
    /// Options given to a BVH source that cannot work (non-positive frame rate...).
    #[error("{file}: invalid BVH source options: {message}")]
    InvalidOptions { file: String, message: String },
}

impl BvhError {
    /// The file name or path the error is about.
    pub fn file(&self) -> &str {
        match self {
            BvhError::Io { file, .. }
            | BvhError::Syntax { file, .. }
            | BvhError::NotANumber { file, .. }
            | BvhError::ChannelCount { file, .. }
            | BvhError::Truncated { file, .. }
            | BvhError::ExtraFrames { file, .. }
            | BvhError::NoFrames { file, .. }
            | BvhError::Skeleton { file, .. }
            | BvhError::InvalidOptions { file, .. } => file,
        }
    }

    /// The 1-based line the error is about, if it is about one.
    pub fn line(&self) -> Option<usize> {
        match self {
            BvhError::Io { .. } | BvhError::InvalidOptions { .. } => None,
            BvhError::Syntax { line, .. }
            | BvhError::NotANumber { line, .. }
            | BvhError::ChannelCount { line, .. }
            | BvhError::Truncated { line, .. }
            | BvhError::ExtraFrames { line, .. }
            | BvhError::NoFrames { line, .. }
            | BvhError::Skeleton { line, .. } => Some(*line),
        }
    }
}

/// A parsed BVH clip: the hierarchy and every frame's channel values.
///
/// Invariants (kept by the parser, relied on by the accessors): `joints[0]` is the root, every
/// parent index is smaller than its child's, the channels of all joints tile `0..channel_count`,
/// there is at least one frame and every frame has exactly `channel_count` finite values.
#[derive(Clone, Debug, PartialEq)]
pub struct BvhClip {
    file_name: String,
    joints: Vec<BvhJoint>,
    channel_count: usize,
    frame_time_s: f64,
    frame_count: usize,
    /// Frame-major channel values: frame `k` is `values[k * channel_count..(k + 1) * channel_count]`.
    values: Vec<f32>,
}

/// Global (world) pose of every joint of a clip for one set of channel values, file units.
#[derive(Clone, Debug, PartialEq)]
pub struct BvhPose {
    /// Global joint positions, indexed like [`BvhClip::joints`].
    pub positions: Vec<Vec3>,
    /// Global joint rotations (the joint frame in BVH world space).
    pub rotations: Vec<Quat>,
    /// Global end-site positions (`None` for joints without an end site).
    pub end_sites: Vec<Option<Vec3>>,
}

impl BvhPose {
    /// Position of a skeleton point, `None` if the point does not exist in this pose.
    pub fn point(&self, point: BvhPoint) -> Option<Vec3> {
        match point {
            BvhPoint::Joint(j) => self.positions.get(j).copied(),
            BvhPoint::EndSite(j) => self.end_sites.get(j).copied().flatten(),
        }
    }
}

impl BvhClip {
    /// Reads and parses a BVH file. Errors name the path as given.
    pub fn load(path: impl AsRef<Path>) -> Result<BvhClip, BvhError> {
        let path = path.as_ref();
        let file = path.display().to_string();
        let bytes = std::fs::read(path).map_err(|source| BvhError::Io {
            file: file.clone(),
            source,
        })?;
        BvhClip::from_str(&String::from_utf8_lossy(&bytes), &file)
    }

    /// Parses BVH text; `file_name` is only used in error messages and [`BvhClip::file_name`].
    pub fn from_str(text: &str, file_name: &str) -> Result<BvhClip, BvhError> {
        Parser::new(text, file_name).parse()
    }

    /// The file name or path given when parsing.
    pub fn file_name(&self) -> &str {
        &self.file_name
    }

    /// The joints in file order; `joints()[0]` is the root.
    pub fn joints(&self) -> &[BvhJoint] {
        &self.joints
    }

    /// The root joint.
    pub fn root(&self) -> &BvhJoint {
        self.joints
            .first()
            .expect("invariant: the parser never builds a clip without a root joint")
    }

    /// Index of the first joint with this exact name.
    pub fn joint_index(&self, name: &str) -> Option<usize> {
        self.joints.iter().position(|j| j.name == name)
    }

    /// Number of values on each motion line.
    pub fn channel_count(&self) -> usize {
        self.channel_count
    }

    /// Number of frames (the `Frames:` header; always at least 1).
    pub fn frame_count(&self) -> usize {
        self.frame_count
    }

    /// Seconds between frames (`Frame Time:`; always positive).
    pub fn frame_time_s(&self) -> f64 {
        self.frame_time_s
    }

    /// Frames per second, `1 / frame_time_s`.
    pub fn fps(&self) -> f64 {
        1.0 / self.frame_time_s
    }

    /// `frame_count * frame_time_s`, seconds.
    pub fn duration_s(&self) -> f64 {
        self.frame_count as f64 * self.frame_time_s
    }

    /// The channel values of frame `index` (file units, degrees), `None` past the end.
    pub fn frame(&self, index: usize) -> Option<&[f32]> {
        let start = index.checked_mul(self.channel_count)?;
        let end = start.checked_add(self.channel_count)?;
        if index >= self.frame_count {
            return None;
        }
        self.values.get(start..end)
    }

    /// Iterates over all frames' channel values.
    pub fn frames(&self) -> impl Iterator<Item = &[f32]> {
        (0..self.frame_count).filter_map(|k| self.frame(k))
    }

    /// The local transform of `joint` for a motion line: translation (offset plus position
    /// channels) and rotation (rotation channels composed in the listed order). Missing values
    /// count as zero.
    pub fn local_transform(&self, joint: &BvhJoint, values: &[f32]) -> (Vec3, Quat) {
        let mut translation = joint.offset;
        let mut rotation = Quat::IDENTITY;
        for (i, channel) in joint.channels.iter().enumerate() {
            let value = values.get(joint.first_channel + i).copied().unwrap_or(0.0);
            if channel.is_rotation() {
                rotation *= Quat::from_axis_angle(channel.axis(), value.to_radians());
            } else {
                translation += channel.axis() * value;
            }
        }
        (translation, rotation.normalize())
    }

    /// Forward kinematics for arbitrary channel values (missing values count as zero).
    pub fn pose_from_values(&self, values: &[f32]) -> BvhPose {
        let n = self.joints.len();
        let mut positions = Vec::with_capacity(n);
        let mut rotations: Vec<Quat> = Vec::with_capacity(n);
        let mut end_sites = Vec::with_capacity(n);
        for joint in &self.joints {
            let (translation, local) = self.local_transform(joint, values);
            let parent = joint
                .parent
                .and_then(|p| Some((*positions.get(p)?, *rotations.get(p)?)));
            let (position, rotation) = match parent {
                Some((parent_position, parent_rotation)) => (
                    parent_position + parent_rotation * translation,
                    (parent_rotation * local).normalize(),
                ),
                None => (translation, local),
            };
            positions.push(position);
            rotations.push(rotation);
            end_sites.push(joint.end_site.map(|e| position + rotation * e));
        }
        BvhPose {
            positions,
            rotations,
            end_sites,
        }
    }

    /// Forward kinematics of frame `index`, `None` past the end.
    pub fn pose(&self, index: usize) -> Option<BvhPose> {
        self.frame(index)
            .map(|values| self.pose_from_values(values))
    }

    /// The rest pose: every channel zero (offsets only).
    pub fn rest_pose(&self) -> BvhPose {
        self.pose_from_values(&[])
    }
}

/// A whitespace-separated word of the hierarchy with its 1-based line.
#[derive(Clone, Copy, Debug)]
struct Token<'a> {
    text: &'a str,
    line: usize,
}

struct Parser<'a> {
    file: &'a str,
    /// Lines without their `\n` / `\r\n` terminators; `lines[i]` is line `i + 1`.
    lines: Vec<&'a str>,
    /// Hierarchy tokens up to and including `MOTION`.
    tokens: Vec<Token<'a>>,
    pos: usize,
}

impl<'a> Parser<'a> {
    fn new(text: &'a str, file: &'a str) -> Self {
        let lines: Vec<&str> = text
            .split('\n')
            .map(|l| l.strip_suffix('\r').unwrap_or(l))
            .collect();
        let mut tokens = Vec::new();
        'lines: for (i, line) in lines.iter().enumerate() {
            for word in line.split_whitespace() {
                tokens.push(Token {
                    text: word,
                    line: i + 1,
                });
                if word == "MOTION" {
                    break 'lines;
                }
            }
        }
        Parser {
            file,
            lines,
            tokens,
            pos: 0,
        }
    }

    /// The line reported for "end of file": the last line of the text.
    fn eof_line(&self) -> usize {
        self.lines.len().max(1)
    }

    fn syntax(&self, line: usize, found: impl Into<String>, expected: &str) -> BvhError {
        BvhError::Syntax {
            file: self.file.to_string(),
            line,
            found: found.into(),
            expected: expected.to_string(),
        }
    }

    fn next(&mut self, expected: &str) -> Result<Token<'a>, BvhError> {
        match self.tokens.get(self.pos) {
            Some(token) => {
                self.pos += 1;
                Ok(*token)
            }
            None => Err(self.syntax(self.eof_line(), "the end of the file", expected)),
        }
    }

    fn expect(&mut self, keyword: &str, expected: &str) -> Result<Token<'a>, BvhError> {
        let token = self.next(expected)?;
        if token.text == keyword {
            Ok(token)
        } else {
            Err(self.syntax(token.line, format!("'{}'", token.text), expected))
        }
    }

    /// The words after a `ROOT` / `JOINT` keyword on its line, up to an optional `{`.
    fn name(&mut self, keyword: Token<'a>) -> Result<String, BvhError> {
        let mut words = Vec::new();
        while let Some(token) = self.tokens.get(self.pos) {
            if token.line != keyword.line || token.text == "{" {
                break;
            }
            words.push(token.text);
            self.pos += 1;
        }
        if words.is_empty() {
            return Err(self.syntax(
                keyword.line,
                format!("'{}' without a name", keyword.text),
                &format!("'{} <name>' on one line", keyword.text),
            ));
        }
        Ok(words.join(" "))
    }

    fn number(&mut self, expected: &str) -> Result<f32, BvhError> {
        let token = self.next(expected)?;
        parse_finite(token.text).ok_or_else(|| BvhError::NotANumber {
            file: self.file.to_string(),
            line: token.line,
            value: token.text.to_string(),
            expected: expected.to_string(),
        })
    }

    fn vec3(&mut self, what: &str) -> Result<Vec3, BvhError> {
        let x = self.number(&format!("the x of {what}"))?;
        let y = self.number(&format!("the y of {what}"))?;
        let z = self.number(&format!("the z of {what}"))?;
        Ok(Vec3::new(x, y, z))
    }

    fn parse(mut self) -> Result<BvhClip, BvhError> {
        let (joints, channel_count, motion_line) = self.hierarchy()?;
        let (frame_time_s, frame_count, values) = self.motion(motion_line, channel_count)?;
        Ok(BvhClip {
            file_name: self.file.to_string(),
            joints,
            channel_count,
            frame_time_s,
            frame_count,
            values,
        })
    }

    /// Parses `HIERARCHY ... MOTION`; returns the joints, the channel count and the line of
    /// `MOTION`. Iterative, so deep nesting cannot overflow the stack.
    fn hierarchy(&mut self) -> Result<(Vec<BvhJoint>, usize, usize), BvhError> {
        self.expect("HIERARCHY", "'HIERARCHY' at the start of the file")?;
        let root = self.expect("ROOT", "'ROOT <name>' after 'HIERARCHY'")?;
        let name = self.name(root)?;
        self.expect("{", "'{' after the ROOT name")?;
        let mut joints = vec![new_joint(name, None, root.line)];
        let mut has_offset = vec![false];
        let mut stack = vec![0usize];
        let mut channel_count = 0usize;
        const BODY: &str = "'OFFSET', 'CHANNELS', 'JOINT', 'End Site' or '}' in a joint block";

        while let Some(&current) = stack.last() {
            let token = self.next(BODY)?;
            match token.text {
                "OFFSET" => {
                    if has_offset.get(current).copied().unwrap_or(true) {
                        return Err(self.syntax(
                            token.line,
                            "a second 'OFFSET' in one joint",
                            "one 'OFFSET x y z' per joint",
                        ));
                    }
                    let offset = self.vec3("OFFSET x y z")?;
                    if let (Some(joint), Some(flag)) =
                        (joints.get_mut(current), has_offset.get_mut(current))
                    {
                        joint.offset = offset;
                        *flag = true;
                    }
                }
                "CHANNELS" => {
                    let count_token = self.next("the channel count after 'CHANNELS'")?;
                    let count: usize =
                        count_token.text.parse().map_err(|_| BvhError::NotANumber {
                            file: self.file.to_string(),
                            line: count_token.line,
                            value: count_token.text.to_string(),
                            expected: "a whole channel count after 'CHANNELS'".to_string(),
                        })?;
                    if joints.get(current).is_some_and(|j| !j.channels.is_empty()) {
                        return Err(self.syntax(
                            token.line,
                            "a second 'CHANNELS' in one joint",
                            "one 'CHANNELS n ...' per joint",
                        ));
                    }
                    let mut channels = Vec::new();
                    for _ in 0..count {
                        let expected = "a channel name (Xposition, Yposition, Zposition, Xrotation, Yrotation or Zrotation)";
                        let channel_token = self.next(expected)?;
                        if channel_token.line != token.line {
                            return Err(self.syntax(
                                channel_token.line,
                                format!(
                                    "the end of the 'CHANNELS {count}' line after {} names",
                                    channels.len()
                                ),
                                &format!("{count} channel names on the CHANNELS line"),
                            ));
                        }
                        let channel = Channel::parse(channel_token.text).ok_or_else(|| {
                            self.syntax(
                                channel_token.line,
                                format!("'{}'", channel_token.text),
                                expected,
                            )
                        })?;
                        channels.push(channel);
                    }
                    if let Some(joint) = joints.get_mut(current) {
                        joint.first_channel = channel_count;
                        joint.channels = channels;
                    }
                    channel_count = channel_count.saturating_add(count);
                }
                "JOINT" => {
                    let name = self.name(token)?;
                    self.expect("{", "'{' after the JOINT name")?;
                    joints.push(new_joint(name, Some(current), token.line));
                    has_offset.push(false);
                    stack.push(joints.len() - 1);
                }
                "End" => {
                    self.expect("Site", "'Site' after 'End'")?;
                    self.expect("{", "'{' after 'End Site'")?;
                    self.expect("OFFSET", "'OFFSET x y z' in the End Site block")?;
                    let offset = self.vec3("the End Site OFFSET")?;
                    self.expect("}", "'}' closing the End Site block")?;
                    if let Some(joint) = joints.get_mut(current) {
                        if joint.end_site.is_some() {
                            return Err(self.syntax(
                                token.line,
                                "a second 'End Site' in one joint",
                                "at most one End Site per joint",
                            ));
                        }
                        joint.end_site = Some(offset);
                    }
                }
                "}" => {
                    if !has_offset.get(current).copied().unwrap_or(false) {
                        let name = joints.get(current).map_or("", |j| j.name.as_str());
                        return Err(self.syntax(
                            token.line,
                            format!("the end of joint '{name}' without an OFFSET"),
                            "'OFFSET x y z' in every joint",
                        ));
                    }
                    stack.pop();
                }
                other => {
                    let found = if other == "ROOT" {
                        "'ROOT' inside a joint block".to_string()
                    } else {
                        format!("'{other}'")
                    };
                    return Err(self.syntax(token.line, found, BODY));
                }
            }
        }

        let motion = self.expect(
            "MOTION",
            "'MOTION' after the root joint's closing '}' (one skeleton per file)",
        )?;
        if channel_count == 0 {
            return Err(self.syntax(
                motion.line,
                "a hierarchy without channels",
                "at least one 'CHANNELS' line",
            ));
        }
        let trailing = self
            .lines
            .get(motion.line - 1)
            .and_then(|l| l.split_whitespace().skip_while(|w| *w != "MOTION").nth(1));
        if let Some(word) = trailing {
            return Err(self.syntax(
                motion.line,
                format!("'{word}' after 'MOTION'"),
                "'MOTION' alone on its line",
            ));
        }
        Ok((joints, channel_count, motion.line))
    }

    /// The next non-blank line after line `after` (1-based), as (line number, text).
    fn next_line(&self, after: usize) -> Option<(usize, &'a str)> {
        self.lines
            .iter()
            .enumerate()
            .skip(after)
            .find(|(_, l)| !l.trim().is_empty())
            .map(|(i, l)| (i + 1, *l))
    }

    /// Parses `Frames:`, `Frame Time:` and the frame lines after the `MOTION` line.
    fn motion(
        &self,
        motion_line: usize,
        channel_count: usize,
    ) -> Result<(f64, usize, Vec<f32>), BvhError> {
        // "Frames:" line.
        let (frames_line, text) = self.next_line(motion_line).ok_or_else(|| {
            self.syntax(
                self.eof_line(),
                "the end of the file",
                "'Frames: <count>' after 'MOTION'",
            )
        })?;
        let normalized = normalize_spaces(text);
        let Some(count_text) = normalized.strip_prefix("Frames:") else {
            return Err(self.syntax(
                frames_line,
                format!("'{}'", clip_text(text)),
                "'Frames: <count>' after 'MOTION'",
            ));
        };
        let count_text = count_text.trim();
        let declared: usize = count_text.parse().map_err(|_| BvhError::NotANumber {
            file: self.file.to_string(),
            line: frames_line,
            value: count_text.to_string(),
            expected: "a whole number of frames after 'Frames:'".to_string(),
        })?;
        if declared == 0 {
            return Err(BvhError::NoFrames {
                file: self.file.to_string(),
                line: frames_line,
            });
        }

        // "Frame Time:" line.
        let (time_line, text) = self.next_line(frames_line).ok_or_else(|| {
            self.syntax(
                self.eof_line(),
                "the end of the file",
                "'Frame Time: <seconds>' after 'Frames:'",
            )
        })?;
        let normalized = normalize_spaces(text);
        let Some(time_text) = normalized.strip_prefix("Frame Time:") else {
            return Err(self.syntax(
                time_line,
                format!("'{}'", clip_text(text)),
                "'Frame Time: <seconds>' after 'Frames:'",
            ));
        };
        let time_text = time_text.trim();
        let frame_time_s = time_text
            .parse::<f64>()
            .ok()
            .filter(|t| t.is_finite() && *t > 0.0)
            .ok_or_else(|| {
                self.syntax(
                    time_line,
                    format!("'Frame Time: {time_text}'"),
                    "a positive number of seconds after 'Frame Time:'",
                )
            })?;

        // Frame lines.
        let remaining = self.lines.len().saturating_sub(time_line);
        let mut values = Vec::with_capacity(declared.min(remaining).saturating_mul(channel_count));
        let mut read = 0usize;
        let mut last_line = time_line;
        for (i, line) in self.lines.iter().enumerate().skip(time_line) {
            if line.trim().is_empty() {
                continue;
            }
            let line_no = i + 1;
            if read == declared {
                return Err(BvhError::ExtraFrames {
                    file: self.file.to_string(),
                    line: line_no,
                    declared,
                });
            }
            let found = line.split_whitespace().count();
            if found != channel_count {
                return Err(BvhError::ChannelCount {
                    file: self.file.to_string(),
                    line: line_no,
                    frame: read,
                    found,
                    expected: channel_count,
                });
            }
            for (column, word) in line.split_whitespace().enumerate() {
                let value = parse_finite(word).ok_or_else(|| BvhError::NotANumber {
                    file: self.file.to_string(),
                    line: line_no,
                    value: word.to_string(),
                    expected: format!("a number for channel {} of frame index {read}", column + 1),
                })?;
                values.push(value);
            }
            read += 1;
            last_line = line_no;
        }
        if read < declared {
            return Err(BvhError::Truncated {
                file: self.file.to_string(),
                line: last_line + 1,
                found: read,
                declared,
            });
        }
        Ok((frame_time_s, declared, values))
    }
}

fn new_joint(name: String, parent: Option<usize>, line: usize) -> BvhJoint {
    BvhJoint {
        name,
        parent,
        offset: Vec3::ZERO,
        channels: Vec::new(),
        first_channel: 0,
        end_site: None,
        line,
    }
}

fn parse_finite(text: &str) -> Option<f32> {
    text.parse::<f32>().ok().filter(|v| v.is_finite())
}

/// Collapses runs of whitespace to single spaces (so `Frame\tTime:` matches `Frame Time:`).
fn normalize_spaces(text: &str) -> String {
    text.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// A line shortened for an error message.
fn clip_text(text: &str) -> String {
    let trimmed = text.trim();
    match trimmed.char_indices().nth(60) {
        Some((i, _)) => format!("{}...", &trimmed[..i]),
        None => trimmed.to_string(),
    }
}
