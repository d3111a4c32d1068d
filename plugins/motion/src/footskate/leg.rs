//! The leg and foot model of the foot-skate corrector (seed 000 §4.5): the leg bones and
//! their fixed geometry, the sole's heel and ball points and the rolling contact between
//! them, and the per-foot state (ground estimate, lock, fading correction).

use glam::{Quat, Vec3};

use crate::retarget::AvatarSkeleton;

use super::{Foot, FootSkateError};

/// The leg bones and their fixed geometry.
#[derive(Clone, Debug)]
pub(super) struct Leg {
    pub(super) thigh: usize,
    pub(super) calf: usize,
    pub(super) foot: usize,
    pub(super) upper_len: f32,
    pub(super) lower_len: f32,
    /// Ball (toe base) in the foot frame.
    pub(super) ball_local: Vec3,
    /// Heel contact point in the foot frame: on the rest floor, straight below the ankle.
    pub(super) heel_local: Vec3,
    /// Rest height of the ball above the rest floor (the heel point's is 0).
    pub(super) ball_clearance: f32,
    /// The knee's forward direction in the thigh frame (the IK pole for a straight leg).
    pub(super) knee_front_local: Vec3,
}

/// A held foot position.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Lock {
    /// The contact point's horizontal position, world (sensor) space (`y` unused: the contact
    /// point keeps the input's height).
    pub(super) point: Vec3,
    /// Where the contact point is on the sole: 0 heel (ankle), 1 ball.
    pub(super) pivot: f32,
}

/// The fading correction of a released leg: the horizontal offset of its ankle from the input
/// at the release (where the lock held it), of which the share `remaining` is still applied.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Correction {
    pub(super) offset: Vec3,
    /// The held foot's orientation relative to the input's at the release.
    pub(super) foot: Quat,
    pub(super) remaining: f32,
}

#[derive(Clone, Debug, PartialEq)]
pub(super) struct FootState {
    pub(super) ground: f32,
    pub(super) height_var: f32,
    pub(super) speed_sq: f32,
    pub(super) lock: Option<Lock>,
    pub(super) correction: Option<Correction>,
    pub(super) relock_wait_s: f32,
    pub(super) prev_contact: Option<Vec3>,
    /// Last output's sole points (heel, ball), world, with their heights above the floor.
    pub(super) prev_output_sole: Option<[(Vec3, f32); 2]>,
    /// Smoothed contact position on the sole (0 heel .. 1 ball).
    pub(super) pivot: Option<f32>,
    /// Smoothed orientation of a held foot.
    pub(super) foot_rotation: Option<Quat>,
}

impl FootState {
    pub(super) fn new() -> Self {
        Self {
            ground: 0.0,
            height_var: 0.01 * 0.01,
            speed_sq: 0.1 * 0.1,
            lock: None,
            correction: None,
            relock_wait_s: 0.0,
            prev_contact: None,
            prev_output_sole: None,
            pivot: None,
            foot_rotation: None,
        }
    }
}

pub(super) fn smoothstep(e0: f32, e1: f32, x: f32) -> f32 {
    if e1 <= e0 {
        return if x >= e1 { 1.0 } else { 0.0 };
    }
    let t = ((x - e0) / (e1 - e0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

pub(super) fn horizontal(v: Vec3) -> Vec3 {
    Vec3::new(v.x, 0.0, v.z)
}

impl Leg {
    /// Where the ankle is with the hip at `hip` and the thigh and shin turned by `rot[0]` and
    /// `rot[1]` (bones along +Y).
    pub(super) fn ankle(&self, hip: Vec3, rot: &[Quat; 3]) -> Vec3 {
        hip + rot[0] * Vec3::Y * self.upper_len + rot[1] * Vec3::Y * self.lower_len
    }

    pub(super) fn new(skeleton: &AvatarSkeleton, foot: Foot) -> Result<Self, FootSkateError> {
        let find = |base: &str| {
            let name = format!("{base}{}", foot.suffix());
            skeleton
                .index_of(&name)
                .ok_or(FootSkateError::MissingBone(name))
        };
        let (thigh, calf, foot_bone, ball) =
            (find("thigh")?, find("calf")?, find("foot")?, find("ball")?);
        let bones = &skeleton.bones;
        let along_y = |child: usize| -> Result<f32, FootSkateError> {
            let t = bones[child].local_translation;
            let len = t.length();
            if len > 1e-4 && Vec3::new(t.x, 0.0, t.z).length() <= 1e-3 * len.max(1.0) && t.y > 0.0 {
                Ok(len)
            } else {
                Err(FootSkateError::NotAChain(bones[child].name.clone()))
            }
        };
        let upper_len = along_y(calf)?;
        let lower_len = along_y(foot_bone)?;
        if bones[calf].parent != Some(thigh)
            || bones[foot_bone].parent != Some(calf)
            || bones[ball].parent != Some(foot_bone)
        {
            return Err(FootSkateError::NotAChain(bones[calf].name.clone()));
        }
        let floor = skeleton.rest_floor_y;
        let knee_front_local = bones[thigh].rest_rotation.inverse() * Vec3::NEG_Z;
        Ok(Self {
            thigh,
            calf,
            foot: foot_bone,
            upper_len,
            lower_len,
            ball_local: bones[ball].local_translation,
            heel_local: bones[foot_bone].rest_rotation.inverse()
                * Vec3::new(0.0, floor - bones[foot_bone].rest_head.y, 0.0),
            ball_clearance: bones[ball].rest_head.y - floor,
            knee_front_local,
        })
    }
}

impl Leg {
    /// The sole's contact points, heel and ball, with their heights above the floor (the
    /// ball's rest clearance removed, so a flat foot on the floor gives 0 for both).
    pub(super) fn sole(&self, ankle: Vec3, foot_rotation: Quat, floor_y: f32) -> [(Vec3, f32); 2] {
        let heel = ankle + foot_rotation * self.heel_local;
        let ball = ankle + foot_rotation * self.ball_local;
        [
            (heel, heel.y - floor_y),
            (ball, ball.y - floor_y - self.ball_clearance),
        ]
    }

    /// The contact point in the foot frame: heel (0) to ball (1).
    pub(super) fn contact_offset(&self, pivot: f32) -> Vec3 {
        self.heel_local.lerp(self.ball_local, pivot)
    }
}

/// A foot's contact measurement in one pose.
#[derive(Clone, Copy, Debug)]
pub(super) struct Contact {
    /// Height of the lowest contact point above the floor (rest clearance removed).
    pub(super) height: f32,
    /// Height of the highest one (the whole sole is below it).
    pub(super) top: f32,
    /// Where the contact point is on the sole (0 heel .. 1 ball), unsmoothed.
    pub(super) pivot: f32,
    /// The middle of the sole (between heel and ball), world: its speed is the foot's speed.
    pub(super) mid: Vec3,
}

pub(super) fn contact(
    leg: &Leg,
    ankle: Vec3,
    foot_rotation: Quat,
    floor_y: f32,
    rise: (f32, f32),
) -> Contact {
    let [(heel, h_heel), (ball, h_ball)] = leg.sole(ankle, foot_rotation, floor_y);
    Contact {
        height: h_heel.min(h_ball),
        top: h_heel.max(h_ball),
        pivot: smoothstep(rise.0, rise.1, h_heel - h_ball),
        mid: heel.lerp(ball, 0.5),
    }
}
