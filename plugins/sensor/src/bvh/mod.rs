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
//!
//! The parser is in `parser`, the error type ([`BvhError`]) in `error`; the clip, its
//! hierarchy and the forward kinematics are here.

mod error;
mod parser;

use std::path::Path;

use glam::{Quat, Vec3};

pub use error::BvhError;

use parser::Parser;

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
    /// Reads and parses a BVH file, plain or gzip-compressed (`walk.bvh.gz`). Errors name the
    /// path as given.
    pub fn load(path: impl AsRef<Path>) -> Result<BvhClip, BvhError> {
        let path = path.as_ref();
        let file = path.display().to_string();
        let bytes = read_maybe_gzip(path).map_err(|source| BvhError::Io {
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
/// The bytes of a file, decompressed when it is gzip-compressed (it starts with gzip's magic
/// bytes, whatever its name).
fn read_maybe_gzip(path: &Path) -> std::io::Result<Vec<u8>> {
    use std::io::Read;
    let bytes = std::fs::read(path)?;
    if !bytes.starts_with(&[0x1f, 0x8b]) {
        return Ok(bytes);
    }
    let mut text = Vec::with_capacity(bytes.len() * 4);
    flate2::read::GzDecoder::new(bytes.as_slice()).read_to_end(&mut text)?;
    Ok(text)
}
