//! Where the kiosk's frames come from (`--sensor`, or `sensor` in the kiosk configuration),
//! and the depth stream's systems:
//!
//! - `bvh:FILE`: a recorded clip replayed as a skeleton stream; no depth.
//! - `synthetic`: the clip drives the avatar, and the synthetic Kinect v1 sees the avatar
//!   and its garment in a room; the clip's skeleton is passed on, labelled ground truth,
//!   until the tracker exists.
//! - `performer` or `performer:FILE`: the clip (FILE: a `.bvh` clip, or a `.ron` gesture
//!   script in which the person turns, swipes and grips) drives a performer the synthetic
//!   Kinect v1 films in a room ([`crate::performer`]); the tracker finds the skeleton in that
//!   depth and drives the avatar: the whole chain of a camera kiosk, without a camera.
//! - `fakenect:DIR`: a fakenect recording played in pure Rust at its pace, looping; its
//!   ground-truth skeleton drives the avatar when the recording has one.
//! - `kinect`: a Kinect v1 through libfreenect (`LD_LIBRARY_PATH` naming Debian's fakenect
//!   folder replays a recording through the same library); depth only until the tracker
//!   exists.
//!
//! A depth source that fails (a vanished device, an unreadable frame) never stops the app:
//! the last good frame stays in [`DepthFeed`] and its error is shown.

use std::path::PathBuf;
use std::str::FromStr;

use anyhow::{Context, Result, bail};
use bevy::prelude::*;
use fitroom_body::plugin::{AvatarBody, SensorPlacement};
use fitroom_depth::DepthCamera;
use fitroom_depth::player::Player;
use fitroom_depth::plugin::DepthFeed;
use fitroom_depth::synthetic::{NoiseSettings, Scene, SyntheticCamera};
use fitroom_depth::truth::{FrameTruth, read_truth};
use fitroom_freenect::{KinectOptions, KinectSource, SourceStatus};
use fitroom_sensor::plugin::SensorFeed;

use crate::depth_scene;
use crate::performer::Performer;

/// A sensor, as `--sensor` and the kiosk configuration name it.
#[derive(Clone, Debug, PartialEq)]
pub enum SensorSpec {
    Bvh(PathBuf),
    Synthetic,
    /// The clip or gesture script the performer plays (`None`: the configuration's clip).
    Performer(Option<PathBuf>),
    Fakenect(PathBuf),
    Kinect,
}

/// The forms a sensor is given in, for error messages.
pub const SENSOR_FORMS: &str = "`bvh:FILE` (a recorded clip), `synthetic` (the synthetic Kinect v1 seeing the avatar), `performer` or `performer:FILE` (the synthetic Kinect v1 filming a performer playing the clip, or FILE: a clip or a gesture script, the tracker driving the avatar), `fakenect:DIR` (a depth recording) or `kinect` (a Kinect v1 through libfreenect)";

impl FromStr for SensorSpec {
    type Err = anyhow::Error;

    fn from_str(s: &str) -> Result<Self> {
        let s = s.trim();
        let non_empty = |rest: &str, what: &str| {
            if rest.is_empty() {
                bail!("\"{s}\" names no {what}; sensors are {SENSOR_FORMS}")
            }
            Ok(PathBuf::from(rest))
        };
        Ok(match s {
            "synthetic" => Self::Synthetic,
            "performer" => Self::Performer(None),
            "kinect" => Self::Kinect,
            _ if s.starts_with("bvh:") => Self::Bvh(non_empty(&s[4..], "clip")?),
            _ if s.starts_with("performer:") => {
                Self::Performer(Some(non_empty(&s[10..], "clip or gesture script")?))
            }
            _ if s.starts_with("fakenect:") => Self::Fakenect(non_empty(&s[9..], "folder")?),
            _ => bail!("\"{s}\" is not a sensor; sensors are {SENSOR_FORMS}"),
        })
    }
}

impl SensorSpec {
    /// A `bvh:` or `performer:` sensor playing `clip` (the path the app resolved); other
    /// sensors as they are.
    pub fn with_clip(self, clip: &std::path::Path) -> Self {
        match self {
            Self::Bvh(_) => Self::Bvh(clip.to_owned()),
            Self::Performer(Some(_)) => Self::Performer(Some(clip.to_owned())),
            other => other,
        }
    }

    /// The name shown on screen.
    pub fn name(&self) -> String {
        match self {
            Self::Bvh(path) => format!("bvh:{}", path.display()),
            Self::Synthetic => "synthetic".into(),
            Self::Performer(None) => "performer".into(),
            Self::Performer(Some(path)) => format!("performer:{}", path.display()),
            Self::Fakenect(dir) => format!("fakenect:{}", dir.display()),
            Self::Kinect => "kinect".into(),
        }
    }
}

/// How a recording is played: its pace (1 = as recorded) and whether it loops.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Replay {
    pub speed: f64,
    pub looping: bool,
}

impl Default for Replay {
    fn default() -> Self {
        Self {
            speed: 1.0,
            looping: true,
        }
    }
}

/// The depth source of the running app.
#[derive(Resource)]
pub enum ActiveDepth {
    /// Renders the avatar after each new skeleton frame.
    Synthetic {
        camera: Box<SyntheticCamera>,
        /// The room (its first `room_meshes` meshes, which do not move), then the avatar's
        /// meshes of the last frame, replaced each frame (the room is not copied).
        scene: Scene,
        room_meshes: usize,
        rendered: u64,
    },
    /// Renders the performer after each new pose of its clip.
    Performer {
        camera: Box<SyntheticCamera>,
        /// The room, then the performer (replaced each frame).
        scene: Scene,
        room_meshes: usize,
        performer: Box<Performer>,
    },
    /// A recording, with its ground truth when it has one.
    Recording(Box<Player>, Option<Vec<FrameTruth>>),
    Kinect(Box<KinectSource>),
}

impl ActiveDepth {
    /// The synthetic camera filming `performer` in the room (with `extras`).
    pub fn performer(
        placement: &SensorPlacement,
        seed: u64,
        scene: (&AvatarBody, depth_scene::Extras),
        performer: Performer,
    ) -> Self {
        let room = depth_scene::room_with(placement, scene.0, scene.1);
        Self::Performer {
            camera: Box::new(SyntheticCamera::new(
                DepthCamera::default(),
                NoiseSettings::default(),
                seed,
            )),
            room_meshes: room.meshes.len(),
            scene: room,
            performer: Box::new(performer),
        }
    }

    /// The depth source of `spec` (`None` for a source without depth).
    pub fn open(
        spec: &SensorSpec,
        placement: &SensorPlacement,
        seed: u64,
        replay: Replay,
        scene: (&AvatarBody, depth_scene::Extras),
    ) -> Result<Option<Self>> {
        let camera = DepthCamera::default();
        Ok(match spec {
            // The performer needs the clip and its pipeline: [`Self::performer`].
            SensorSpec::Bvh(_) | SensorSpec::Performer(_) => None,
            SensorSpec::Synthetic => {
                let room = depth_scene::room_with(placement, scene.0, scene.1);
                Some(Self::Synthetic {
                    camera: Box::new(SyntheticCamera::new(camera, NoiseSettings::default(), seed)),
                    room_meshes: room.meshes.len(),
                    scene: room,
                    rendered: 0,
                })
            }
            SensorSpec::Fakenect(dir) => {
                let mut player = Player::open(dir, camera)
                    .with_context(|| format!("cannot play the recording '{}'", dir.display()))?;
                player.speed = replay.speed;
                player.looping = replay.looping;
                let truth = read_truth(dir).with_context(|| {
                    format!("cannot read the ground truth of '{}'", dir.display())
                })?;
                Some(Self::Recording(Box::new(player), truth))
            }
            SensorSpec::Kinect => Some(Self::Kinect(Box::new(
                KinectSource::open(KinectOptions {
                    camera,
                    ..KinectOptions::default()
                })
                .context("cannot use a Kinect")?,
            ))),
        })
    }
}

/// Systems of the depth stream.
#[derive(SystemSet, Debug, Clone, PartialEq, Eq, Hash)]
pub enum DepthSystems {
    /// Reads a recording or a Kinect (in the `Sensor` stage).
    Poll,
}

/// Adds the depth stream: [`DepthFeed`], and the system of the active depth source.
pub struct DepthPlugin {
    pub source_name: String,
}

impl Plugin for DepthPlugin {
    fn build(&self, app: &mut App) {
        app.insert_resource(DepthFeed {
            source_name: self.source_name.clone(),
            ..default()
        })
        .configure_sets(
            PostUpdate,
            DepthSystems::Poll.in_set(fitroom_schedule::FitroomSystems::Sensor),
        )
        .add_systems(PostUpdate, poll_depth.in_set(DepthSystems::Poll))
        // After everything has moved: the avatar's joints propagated, the garment stepped.
        .add_systems(Last, render_synthetic_depth.before(crate::timing::FrameEnd));
    }
}

/// Reads a recording or a Kinect.
fn poll_depth(
    time: Res<Time>,
    depth: Option<ResMut<ActiveDepth>>,
    mut feed: ResMut<DepthFeed>,
    mut warned: Local<Option<String>>,
) {
    let Some(mut depth) = depth else { return };
    let mut report = |feed: &mut DepthFeed, error: String| {
        // Logged once until another error comes (a looping recording meets the same one
        // every pass); the screen shows it while it lasts.
        if warned.as_deref() != Some(error.as_str()) {
            warn!("depth: {error}");
            *warned = Some(error.clone());
        }
        feed.error = Some(error);
    };
    match depth.as_mut() {
        ActiveDepth::Synthetic { .. } => {}
        ActiveDepth::Performer {
            camera,
            scene,
            room_meshes,
            performer,
        } => match performer.advance(time.delta_secs_f64()) {
            Ok(true) => {
                if let Some(mesh) = performer.mesh() {
                    scene.meshes.truncate(*room_meshes);
                    scene.meshes.push(mesh);
                    let frame = camera.render(scene, time.elapsed_secs_f64());
                    feed.labels = Some(frame.labels.clone());
                    feed.publish(frame.frame, None);
                }
            }
            Ok(false) => {}
            Err(error) => report(&mut feed, format!("the performer's clip: {error}")),
        },
        ActiveDepth::Recording(player, truth) => match player.advance(time.delta_secs_f64()) {
            Ok(delivered) => {
                if let Some((index, frame)) = delivered.frame {
                    let truth = truth.as_ref().and_then(|t| t.get(index)).cloned();
                    feed.publish(frame, truth);
                } else if player.finished() && feed.error.is_none() {
                    report(&mut feed, "the recording has played out".into());
                }
            }
            Err(error) => report(&mut feed, error.to_string()),
        },
        ActiveDepth::Kinect(kinect) => {
            if let Some(frame) = kinect.try_latest() {
                feed.publish(frame, None);
            }
            match kinect.status() {
                SourceStatus::Disconnected { reason } => {
                    report(&mut feed, format!("Kinect disconnected: {reason}"));
                }
                SourceStatus::Ended => report(&mut feed, "the Kinect stream ended".into()),
                SourceStatus::Connecting | SourceStatus::Streaming => {}
            }
        }
    }
}

/// The synthetic camera sees the avatar once per skeleton frame the sensor delivered.
fn render_synthetic_depth(world: &mut World) {
    let delivered = world
        .get_resource::<SensorFeed>()
        .map_or(0, |f| f.frames_received);
    let Some(mut active) = world.remove_resource::<ActiveDepth>() else {
        return;
    };
    if let ActiveDepth::Synthetic {
        camera,
        scene,
        room_meshes,
        rendered,
    } = &mut active
        && delivered > *rendered
    {
        *rendered = delivered;
        if let Some(meshes) = depth_scene::avatar_meshes(world) {
            let joints = depth_scene::avatar_kinect_joints(world);
            scene.meshes.truncate(*room_meshes);
            scene.meshes.extend(meshes);
            let time_s = world
                .get_resource::<Time>()
                .map_or(0.0, |t| t.elapsed_secs_f64());
            let index = world
                .get_resource::<DepthFeed>()
                .map_or(0, |f| f.frames_received as usize);
            let frame = camera.render(scene, time_s);
            let truth = joints.map(|j| depth_scene::frame_truth(index, &frame, &j));
            if let Some(mut feed) = world.get_resource_mut::<DepthFeed>() {
                feed.labels = Some(frame.labels.clone());
                feed.publish(frame.frame, truth);
            }
        }
    }
    world.insert_resource(active);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sensors_parse_and_bad_ones_are_explained() {
        assert_eq!(
            "bvh:motions/walk.bvh".parse::<SensorSpec>().expect("valid"),
            SensorSpec::Bvh("motions/walk.bvh".into())
        );
        assert_eq!(
            "fakenect:/tmp/rec".parse::<SensorSpec>().expect("valid"),
            SensorSpec::Fakenect("/tmp/rec".into())
        );
        assert_eq!(
            "kinect".parse::<SensorSpec>().expect("valid"),
            SensorSpec::Kinect
        );
        assert_eq!(
            " synthetic ".parse::<SensorSpec>().expect("valid"),
            SensorSpec::Synthetic
        );
        assert_eq!(
            "performer".parse::<SensorSpec>().expect("valid"),
            SensorSpec::Performer(None)
        );
        assert_eq!(
            "performer:motions/gestures.ron"
                .parse::<SensorSpec>()
                .expect("valid"),
            SensorSpec::Performer(Some("motions/gestures.ron".into()))
        );
        for bad in ["fakenect:", "bvh:", "performer:", "kinekt", ""] {
            let message = bad.parse::<SensorSpec>().expect_err(bad).to_string();
            assert!(message.contains("fakenect:DIR"), "{message}");
        }
    }
}
