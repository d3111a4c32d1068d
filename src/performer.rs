//! The person the synthetic camera films when the kiosk runs its whole chain without a camera
//! (`--sensor performer`, the embedded default): the MakeHuman body driven by a clip through
//! the same motion pipeline the avatar uses, or performing a gesture script
//! (`performer:motions/gestures.ron`: turning, swiping, gripping, its fingers curled and
//! opened; `fitroom_gesture::script`), skinned on the CPU in sensor space. The avatar on
//! screen is not driven by the clip: the tracker finds the performer in the camera's depth and
//! its skeleton drives the avatar, as a person before a Kinect would.

use fitroom_body::plugin::AvatarBody;
use fitroom_body::skin_with_matrices;
use fitroom_depth::synthetic::{Label, SceneMesh};
use fitroom_gesture::script::{SCRIPT_FPS, ScriptedPerson};
use fitroom_motion::MotionPipeline;
use fitroom_motion::retarget::AvatarPose;
use fitroom_sensor::{SensorSource, SourceError};
use glam::{Affine3A, Vec3};

/// What the synthetic camera films.
pub enum Performer {
    Clip(Box<ClipPerformer>),
    /// A gesture script, looping; `frame`: the one shown (`None` before the first).
    Script {
        person: Box<ScriptedPerson>,
        clock_s: f64,
        frame: Option<usize>,
    },
}

impl Performer {
    pub fn clip(source: Box<dyn SensorSource>, pipeline: MotionPipeline, body: AvatarBody) -> Self {
        Self::Clip(Box::new(ClipPerformer {
            source,
            pipeline,
            body,
            pose: None,
        }))
    }

    pub fn script(person: ScriptedPerson) -> Self {
        Self::Script {
            person: Box::new(person),
            clock_s: 0.0,
            frame: None,
        }
    }

    /// Plays `dt` seconds; whether a new pose came (frames come at 30 Hz, the app's faster).
    pub fn advance(&mut self, dt: f64) -> Result<bool, SourceError> {
        match self {
            Self::Clip(clip) => clip.advance(dt),
            Self::Script {
                person,
                clock_s,
                frame,
            } => {
                let count = person.frames().len().max(1);
                let k = (*clock_s * SCRIPT_FPS).floor() as usize % count;
                *clock_s += dt;
                let moved = *frame != Some(k);
                *frame = Some(k);
                Ok(moved)
            }
        }
    }

    /// The performer's skin in sensor space, as the camera's scene mesh (`None` before the
    /// first pose).
    pub fn mesh(&self) -> Option<SceneMesh> {
        match self {
            Self::Clip(clip) => clip.mesh(),
            Self::Script { person, frame, .. } => frame.map(|k| person.mesh(k)),
        }
    }
}

/// A clip, its pipeline and the body it poses.
pub struct ClipPerformer {
    source: Box<dyn SensorSource>,
    pipeline: MotionPipeline,
    body: AvatarBody,
    pose: Option<AvatarPose>,
}

impl ClipPerformer {
    fn advance(&mut self, dt: f64) -> Result<bool, SourceError> {
        let mut moved = false;
        for frame in self.source.advance(dt)? {
            if let Some(step) = self.pipeline.push(&frame) {
                self.pose = Some(step.pose);
                moved = true;
            }
        }
        Ok(moved)
    }

    fn mesh(&self) -> Option<SceneMesh> {
        let pose = self.pose.as_ref()?;
        let rest = &self.body.rest;
        // Rest model space to sensor space, bone by bone: the posed bone frame after the
        // rest one's inverse (as the avatar's skinning does with its joint entities).
        let matrices: Vec<Affine3A> = (0..self.body.model.bones.len())
            .map(|i| {
                match (
                    pose.rotations.get(i),
                    pose.heads.get(i),
                    rest.rotations.get(i),
                    rest.heads.get(i),
                ) {
                    (Some(&r), Some(&h), Some(&rr), Some(&rh)) => {
                        Affine3A::from_rotation_translation(r, h)
                            * Affine3A::from_rotation_translation(rr, rh).inverse()
                    }
                    _ => Affine3A::IDENTITY,
                }
            })
            .collect();
        let n = (self.body.model.body_vertex_count as usize).min(self.body.positions.len());
        let positions: Vec<Vec3> = skin_with_matrices(
            &self.body.positions[..n],
            &self.body.model.skin_joints,
            &self.body.model.skin_weights,
            &matrices,
        );
        Some(SceneMesh {
            positions,
            triangles: self.body.model.triangles.clone(),
            label: Label::Body,
            closed: true,
        })
    }
}
