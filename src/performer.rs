//! The person the synthetic camera films when the kiosk runs its whole chain without a camera
//! (`--sensor performer`, the embedded default): the MakeHuman body driven by the clip through
//! the same motion pipeline the avatar uses, skinned on the CPU in sensor space. The avatar on
//! screen is not driven by the clip: the tracker finds the performer in the camera's depth and
//! its skeleton drives the avatar, as a person before a Kinect would.

use fitroom_body::plugin::AvatarBody;
use fitroom_body::skin_with_matrices;
use fitroom_depth::synthetic::{Label, SceneMesh};
use fitroom_motion::MotionPipeline;
use fitroom_motion::retarget::AvatarPose;
use fitroom_sensor::{SensorSource, SourceError};
use glam::{Affine3A, Vec3};

/// The clip, its pipeline and the body it poses.
pub struct Performer {
    source: Box<dyn SensorSource>,
    pipeline: MotionPipeline,
    body: AvatarBody,
    pose: Option<AvatarPose>,
}

impl Performer {
    pub fn new(source: Box<dyn SensorSource>, pipeline: MotionPipeline, body: AvatarBody) -> Self {
        Self {
            source,
            pipeline,
            body,
            pose: None,
        }
    }

    /// Plays `dt` seconds of the clip; whether a new pose came (the clip's frames come at 30
    /// Hz, the app's faster).
    pub fn advance(&mut self, dt: f64) -> Result<bool, SourceError> {
        let mut moved = false;
        for frame in self.source.advance(dt)? {
            if let Some(step) = self.pipeline.push(&frame) {
                self.pose = Some(step.pose);
                moved = true;
            }
        }
        Ok(moved)
    }

    /// The performer's skin in sensor space, as the camera's scene mesh (`None` before the
    /// first pose).
    pub fn mesh(&self) -> Option<SceneMesh> {
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
