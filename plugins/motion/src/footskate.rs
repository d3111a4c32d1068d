//! Foot-skate correction (seed 000 §4.5, Algorithms 3 and 4).
//!
//! The retargeted avatar ([`crate::Retargeter`]) takes its bone orientations from the sensor and
//! its root translation from the sensor's hip centre, scaled to the avatar's legs. The feet are
//! never constrained, so a planted foot slides ("skates") whenever the avatar's proportions,
//! the root estimate or the sensor noise disagree with the limb orientations. This module pins
//! the planted foot and solves the legs, in the four steps of seed §4.5.
//!
//! # The foot model
//!
//! Each foot has two sole points rigid with the foot bone: the *heel* (straight below the
//! ankle, on the floor, in the rest pose) and the *ball* (the `ball` bone's head). Their
//! heights above the floor (the ball's rest clearance removed) are 0 for a flat foot. The
//! *contact point* moves along the sole from heel to ball as the heel rises above the ball by
//! [`FootSkateOptions::pivot_rise_m`] (rolling contact: heel strike pivots about the heel,
//! push-off about the ball). A foot's height is its lowest sole point, its speed the
//! horizontal speed of the middle of the sole.
//!
//! # Step 1: which foot is constrained (Algorithm 3) with adaptive thresholds
//!
//! A foot is *not* in contact when it is both above the height threshold and faster than the
//! speed threshold. The constrained foot stays constrained while in contact; when it leaves
//! contact the other foot takes over if it is in contact ("constraint switched"); if neither
//! is, the thresholds are widened (`updateThresholds`, by
//! [`FootSkateOptions::threshold_widening`] up to [`FootSkateOptions::max_threshold_scale`])
//! and the test repeated; if that fails too, no foot is constrained (flight: the seed assumes
//! one foot is always on the ground).
//!
//! The seed adapts its thresholds "to compensate for different sensor and user placements".
//! Here each foot keeps running estimates, updated while it is clearly planted, with the rate
//! `α = 1 - exp(-dt / adapt_time_s)`: its ground height `g` (absorbs the sensor floor error and
//! the retargeter's root height error: on the CMU clips the avatar stands 7 cm below or above
//! the sensor floor), the variance of `h - g` and the mean square of the speed (the speed noise
//! of a planted foot). The thresholds are `g + max(min_height_margin_m, height_noise_factor ·
//! σ_h)` and `max(min_speed_threshold_mps, speed_noise_factor · rms(v))`, times the widening
//! scale, which relaxes back to 1 with the same rate. Clean data give 5 cm and 0.35-0.6 m/s;
//! the jittered test data raise the speed threshold to 1-2.5 m/s.
//!
//! # Step 2-3: lock, IK, root relocation (Algorithm 4)
//!
//! A constrained foot's contact point is recorded when it becomes constrained (where the
//! current output puts it, so locking never jumps) and then held horizontally; its height
//! follows the input (a vertically fixed lock would drag the root down whenever the input
//! foot rises). The ankle target is the held point minus the contact point's offset in the
//! foot frame (the foot keeps its input orientation), and the analytic two-bone IK
//! ([`crate::ik`]) turns thigh and calf so the ankle reaches it exactly, the knee staying in
//! the input's knee plane. If the target is out of reach, the root (pelvis translation) is moved
//! by the remaining mismatch (`d_root = p_constrained - p_new`, Algorithm 4 lines 6-8), so the
//! foot is exact; a mismatch above [`FootSkateOptions::max_root_correction_m`] per frame means
//! the foot has left the floor and releases the lock instead. The root correction decays back
//! to zero with [`FootSkateOptions::root_return_tau_s`] (the IK absorbs the decay while in
//! reach): the pelvis follows the input path, without drift and without jumps.
//!
//! # Step 4: smoothing at the switch (eq. 4.5-4.6)
//!
//! When a foot is released (constraint switched, lifted, or drifted), its leg would jump from
//! the IK solution back to the input. Instead the release offset (how far the lock held the
//! ankle from the input's ankle, horizontally) is kept and faded out: each frame the leg is
//! the fraction `remaining` of the way from the input leg to the leg that keeps the whole
//! offset (IK to `input ankle + offset`), using the fractional quaternion rotation of eq. 4.6
//! ([`crate::smoothing::fractional_rotation`]) per bone, with `remaining = exp(-t /
//! switch_tau_s)`. Because the blend is relative to the moving input, the released foot does
//! not lag behind the swing.
//!
//! # Additions to the seed
//!
//! * **Double support**: the other foot is also locked when it is clearly planted (below the
//!   height threshold *and* slower than the speed threshold) and kept while in contact, so the
//!   landing foot does not skate until the old one lifts ([`FootSkateOptions::lock_both_feet`]).
//!   Only the constrained foot moves the root; the other one is solved as far as it reaches.
//! * **Lift and drift release**: a foot more than [`FootSkateOptions::max_contact_height_m`]
//!   above its ground is never in contact, whatever its speed (the seed's rule would keep a
//!   slowly raised foot pinned); a lock farther than [`FootSkateOptions::max_lock_distance_m`]
//!   (horizontally) from the input foot is released (the user really moved the foot).
//! * **Standing on the floor** ([`FootSkateOptions::stand_on_floor`]): the retargeter's root
//!   height (the performer's hip height scaled by the leg-length ratio) leaves the avatar's
//!   soles 2-9 cm in the floor on the CMU clips (5 cm above it on 11_01). The whole pose moves
//!   vertically by minus the feet's running ground estimate, so planted feet stand on the
//!   floor and a swing foot is no longer dragged through it.
//! * **Low-foot speed limit** ([`FootSkateOptions::max_low_foot_speed_mps`]): a free foot whose
//!   whole sole is near the floor (a lock released by drift, a foot whose noisy input jitters
//!   too fast to lock, a swing foot gliding low before it lands) moves at most 0.5 m/s
//!   horizontally; the excess is held by the leg's fading correction, at most
//!   [`FootSkateOptions::max_low_foot_hold_m`] from the input (farther, the input really
//!   stepped and the foot follows at any speed).
//!
//! The corrector needs the input frames in order. After a gap longer than
//! [`FootSkateOptions::reset_after_s`], or a non-positive `dt`, it starts over.
//!
//! # Measuring foot skating
//!
//! [`foot_skating`] is the share of consecutive-frame pairs in which a foot near the floor
//! slides more than 2.5 cm (at 30 Hz) between the two frames ([`SkateCriteria`]), and
//! [`estimate_floor`] finds the floor the avatar actually stands on (the 5th percentile of the
//! lowest sole point).

use glam::{Quat, Vec3};

use crate::ik::{forward_kinematics, local_from_global, solve_two_bone};
use crate::retarget::{AvatarPose, AvatarSkeleton};
use crate::smoothing::{fractional_rotation, smooth_toward, smoothing_alpha};

/// A foot.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Foot {
    Left,
    Right,
}

impl Foot {
    pub const BOTH: [Foot; 2] = [Foot::Left, Foot::Right];

    pub fn index(self) -> usize {
        match self {
            Foot::Left => 0,
            Foot::Right => 1,
        }
    }

    pub fn other(self) -> Foot {
        match self {
            Foot::Left => Foot::Right,
            Foot::Right => Foot::Left,
        }
    }

    fn suffix(self) -> &'static str {
        match self {
            Foot::Left => "_l",
            Foot::Right => "_r",
        }
    }
}

/// Why a skeleton cannot be foot-skate corrected.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum FootSkateError {
    #[error("the avatar skeleton has no bone named '{0}', which the foot-skate filter needs")]
    MissingBone(String),
    #[error("bone '{0}' does not continue along its parent's +Y axis, as the leg IK assumes")]
    NotAChain(String),
}

/// Options of [`FootSkateCorrector`]. Distances in metres, times in seconds.
///
/// The defaults were chosen on the six CMU walking clips of the tests (clean and jittered),
/// so they are tuned on the data they are tested with; the notes give the alternatives tried.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FootSkateOptions {
    /// Smallest height margin above the ground estimate for a foot in contact. Default 5 cm,
    /// the height the skating measure calls "on the floor" (3 cm: 4.2% instead of 3.7% of the
    /// jittered walks' frames skate).
    pub min_height_margin_m: f32,
    /// Height margin in standard deviations of the planted foot's height noise.
    pub height_noise_factor: f32,
    /// Smallest horizontal speed threshold, m/s.
    pub min_speed_threshold_mps: f32,
    /// Speed threshold in RMS speeds of a planted foot (its speed noise).
    pub speed_noise_factor: f32,
    /// Time constant of the running ground / noise estimates.
    pub adapt_time_s: f32,
    /// Factor by which both thresholds widen when neither foot is in contact.
    pub threshold_widening: f32,
    /// Largest total widening.
    pub max_threshold_scale: f32,
    /// A foot higher than this above its ground estimate is never in contact.
    pub max_contact_height_m: f32,
    /// Also lock the other foot while it is clearly planted (double support).
    pub lock_both_feet: bool,
    /// Count a foot whose whole sole (heel and ball) is below the height threshold as clearly
    /// planted whatever its speed (a landing foot). Off by default: on 16_11, whose swing foot
    /// glides along the floor before landing, it made the clean walk skate more (12% -> 16%).
    pub lock_flat_feet: bool,
    /// A lock farther than this (horizontally) from the input foot is released.
    pub max_lock_distance_m: f32,
    /// Largest root move per frame to keep the constrained foot reachable; a lock that would
    /// need more is released instead (the foot has left the floor).
    pub max_root_correction_m: f32,
    /// Heel-over-ball rise at which the contact point starts moving to the ball, and at which
    /// it is at the ball.
    pub pivot_rise_m: (f32, f32),
    /// Time constant of the smoothing of that contact position. Default 0 (off): moving the
    /// contact point is continuous anyway (the lock moves rigidly along the sole), and 0.05 s
    /// changed nothing measurable.
    pub pivot_tau_s: f32,
    /// Time constant of the asymptotic smoothing of a held foot's orientation (removes sensor
    /// jitter from a planted foot). Default 0 (off): 0.1 s lags the push-off rotation and made
    /// clean walks skate more (2.6% -> 3.5%); 0.05 s helps jittered input a little.
    pub planted_foot_tau_s: f32,
    /// Time constant with which a released leg's correction fades (the output turns by the
    /// fraction `exp(-t / τ)` of the correction, eq. 4.6).
    pub switch_tau_s: f32,
    /// After a drift release, no new lock for this long.
    pub relock_wait_s: f32,
    /// Time constant with which the root correction returns to zero.
    pub root_return_tau_s: f32,
    /// A gap between frames longer than this restarts the filter.
    pub reset_after_s: f32,
    /// Move the whole pose vertically so the planted feet stand on the floor (their running
    /// ground estimate). The retargeter's root height (the performer's hip height scaled by
    /// the leg-length ratio) leaves the avatar's soles 2-9 cm in the floor on the CMU clips,
    /// or 5 cm above it (11_01); a swing foot dragged through the floor is skating too.
    pub stand_on_floor: bool,
    /// Largest such shift, either way.
    pub max_floor_shift_m: f32,
    /// Fastest horizontal speed of a free (unlocked) foot whose whole sole is near the floor
    /// (below [`FootSkateOptions::min_height_margin_m`]), m/s: a released lock returns to the
    /// input at this speed, and a jittering low foot cannot slide faster (the skating measure
    /// counts 0.75 m/s). `f32::INFINITY` turns the limit off.
    pub max_low_foot_speed_mps: f32,
    /// Farthest (horizontally) that limit holds a foot from the input's; beyond it the foot
    /// follows the input at any speed (a real step or shuffle).
    pub max_low_foot_hold_m: f32,
}

impl Default for FootSkateOptions {
    fn default() -> Self {
        Self {
            min_height_margin_m: 0.05,
            height_noise_factor: 3.0,
            min_speed_threshold_mps: 0.35,
            speed_noise_factor: 3.0,
            adapt_time_s: 2.0,
            threshold_widening: 1.5,
            max_threshold_scale: 2.25,
            max_contact_height_m: 0.10,
            lock_both_feet: true,
            lock_flat_feet: false,
            max_lock_distance_m: 0.15,
            max_root_correction_m: 0.03,
            pivot_rise_m: (0.01, 0.03),
            pivot_tau_s: 0.0,
            planted_foot_tau_s: 0.0,
            switch_tau_s: 0.05,
            relock_wait_s: 0.2,
            root_return_tau_s: 0.5,
            reset_after_s: 0.5,
            stand_on_floor: true,
            max_floor_shift_m: 0.2,
            max_low_foot_speed_mps: 0.5,
            max_low_foot_hold_m: 0.2,
        }
    }
}

/// The leg bones and their fixed geometry.
#[derive(Clone, Debug)]
struct Leg {
    thigh: usize,
    calf: usize,
    foot: usize,
    upper_len: f32,
    lower_len: f32,
    /// Ball (toe base) in the foot frame.
    ball_local: Vec3,
    /// Heel contact point in the foot frame: on the rest floor, straight below the ankle.
    heel_local: Vec3,
    /// Rest height of the ball above the rest floor (the heel point's is 0).
    ball_clearance: f32,
    /// The knee's forward direction in the thigh frame (the IK pole for a straight leg).
    knee_front_local: Vec3,
}

/// A held foot position.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Lock {
    /// The contact point's horizontal position, world (sensor) space (`y` unused: the contact
    /// point keeps the input's height).
    point: Vec3,
    /// Where the contact point is on the sole: 0 heel (ankle), 1 ball.
    pivot: f32,
}

/// The fading correction of a released leg: the horizontal offset of its ankle from the input
/// at the release (where the lock held it), of which the share `remaining` is still applied.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Correction {
    offset: Vec3,
    /// The held foot's orientation relative to the input's at the release.
    foot: Quat,
    remaining: f32,
}

#[derive(Clone, Debug, PartialEq)]
struct FootState {
    ground: f32,
    height_var: f32,
    speed_sq: f32,
    lock: Option<Lock>,
    correction: Option<Correction>,
    relock_wait_s: f32,
    prev_contact: Option<Vec3>,
    /// Last output's sole points (heel, ball), world, with their heights above the floor.
    prev_output_sole: Option<[(Vec3, f32); 2]>,
    /// Smoothed contact position on the sole (0 heel .. 1 ball).
    pivot: Option<f32>,
    /// Smoothed orientation of a held foot.
    foot_rotation: Option<Quat>,
}

impl FootState {
    fn new() -> Self {
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

/// What the corrector currently does (for display and tests).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FootSkateStatus {
    /// The constrained foot of Algorithm 3 (`None` in flight).
    pub constrained: Option<Foot>,
    /// Which feet are held (left, right).
    pub locked: [bool; 2],
    /// Current root correction.
    pub root_offset: Vec3,
    /// Current thresholds per foot: height above the floor (m) and speed (m/s).
    pub height_threshold_m: [f32; 2],
    pub speed_threshold_mps: [f32; 2],
}

/// Counters.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FootSkateStats {
    pub frames: u64,
    /// Constraint switches between the feet.
    pub switches: u64,
    /// Frames with no foot constrained.
    pub flight_frames: u64,
    /// Frames in which the root had to move to keep the constrained foot exact.
    pub root_relocations: u64,
    /// Locks released because the input foot moved too far from them.
    pub drift_releases: u64,
}

/// The foot-skate filter. See the module docs.
#[derive(Clone, Debug)]
pub struct FootSkateCorrector {
    skeleton: AvatarSkeleton,
    pub options: FootSkateOptions,
    legs: [Leg; 2],
    feet: [FootState; 2],
    constrained: Option<Foot>,
    threshold_scale: f32,
    root_offset: Vec3,
    /// Last frame's horizontal offset of each output ankle from where the input (with the root
    /// correction) put it.
    prev_ankle_offset: Option<[Vec3; 2]>,
    initialized: bool,
    status: Option<FootSkateStatus>,
    pub stats: FootSkateStats,
}

fn smoothstep(e0: f32, e1: f32, x: f32) -> f32 {
    if e1 <= e0 {
        return if x >= e1 { 1.0 } else { 0.0 };
    }
    let t = ((x - e0) / (e1 - e0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

fn horizontal(v: Vec3) -> Vec3 {
    Vec3::new(v.x, 0.0, v.z)
}

impl Leg {
    /// Where the ankle is with the hip at `hip` and the thigh and shin turned by `rot[0]` and
    /// `rot[1]` (bones along +Y).
    fn ankle(&self, hip: Vec3, rot: &[Quat; 3]) -> Vec3 {
        hip + rot[0] * Vec3::Y * self.upper_len + rot[1] * Vec3::Y * self.lower_len
    }

    fn new(skeleton: &AvatarSkeleton, foot: Foot) -> Result<Self, FootSkateError> {
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
    fn sole(&self, ankle: Vec3, foot_rotation: Quat, floor_y: f32) -> [(Vec3, f32); 2] {
        let heel = ankle + foot_rotation * self.heel_local;
        let ball = ankle + foot_rotation * self.ball_local;
        [
            (heel, heel.y - floor_y),
            (ball, ball.y - floor_y - self.ball_clearance),
        ]
    }

    /// The contact point in the foot frame: heel (0) to ball (1).
    fn contact_offset(&self, pivot: f32) -> Vec3 {
        self.heel_local.lerp(self.ball_local, pivot)
    }
}

/// A foot's contact measurement in one pose.
#[derive(Clone, Copy, Debug)]
struct Contact {
    /// Height of the lowest contact point above the floor (rest clearance removed).
    height: f32,
    /// Height of the highest one (the whole sole is below it).
    top: f32,
    /// Where the contact point is on the sole (0 heel .. 1 ball), unsmoothed.
    pivot: f32,
    /// The middle of the sole (between heel and ball), world: its speed is the foot's speed.
    mid: Vec3,
}

fn contact(leg: &Leg, ankle: Vec3, foot_rotation: Quat, floor_y: f32, rise: (f32, f32)) -> Contact {
    let [(heel, h_heel), (ball, h_ball)] = leg.sole(ankle, foot_rotation, floor_y);
    Contact {
        height: h_heel.min(h_ball),
        top: h_heel.max(h_ball),
        pivot: smoothstep(rise.0, rise.1, h_heel - h_ball),
        mid: heel.lerp(ball, 0.5),
    }
}

impl FootSkateCorrector {
    pub fn new(
        skeleton: AvatarSkeleton,
        options: FootSkateOptions,
    ) -> Result<Self, FootSkateError> {
        let legs = [
            Leg::new(&skeleton, Foot::Left)?,
            Leg::new(&skeleton, Foot::Right)?,
        ];
        Ok(Self {
            skeleton,
            options,
            legs,
            feet: [FootState::new(), FootState::new()],
            constrained: None,
            threshold_scale: 1.0,
            root_offset: Vec3::ZERO,
            prev_ankle_offset: None,
            initialized: false,
            status: None,
            stats: FootSkateStats::default(),
        })
    }

    pub fn skeleton(&self) -> &AvatarSkeleton {
        &self.skeleton
    }

    /// Forgets locks, estimates and the root correction.
    pub fn reset(&mut self) {
        self.feet = [FootState::new(), FootState::new()];
        self.constrained = None;
        self.threshold_scale = 1.0;
        self.root_offset = Vec3::ZERO;
        self.prev_ankle_offset = None;
        self.initialized = false;
        self.status = None;
    }

    /// The state after the last [`FootSkateCorrector::correct`].
    pub fn status(&self) -> Option<FootSkateStatus> {
        self.status
    }

    fn thresholds(&self, foot: Foot) -> (f32, f32) {
        let o = &self.options;
        let s = &self.feet[foot.index()];
        let margin = o
            .min_height_margin_m
            .max(o.height_noise_factor * s.height_var.max(0.0).sqrt());
        let speed = o
            .min_speed_threshold_mps
            .max(o.speed_noise_factor * s.speed_sq.max(0.0).sqrt());
        (
            s.ground + margin * self.threshold_scale,
            speed * self.threshold_scale,
        )
    }

    /// IK of leg `k` from its (root-corrected) hip to `target` (ankle), keeping the input's
    /// knee plane; the foot keeps its input orientation.
    fn solve_leg(&self, k: usize, pose: &AvatarPose, root_offset: Vec3, target: Vec3) -> [Quat; 3] {
        let leg = &self.legs[k];
        let hip = pose.heads[leg.thigh] + root_offset;
        // Pole: the input knee's offset from the hip-ankle line, plus a little of the knee's
        // forward direction so a straight input leg still has a bend side.
        let knee_in = pose.heads[leg.calf] + root_offset;
        let ankle_in = pose.heads[leg.foot] + root_offset;
        let axis = (ankle_in - hip).normalize_or_zero();
        let off = knee_in - hip;
        let perp = off - axis * axis.dot(off);
        let pole = perp + pose.rotations[leg.thigh] * leg.knee_front_local * 0.01;
        let s = solve_two_bone(
            hip,
            leg.upper_len,
            leg.lower_len,
            target,
            pole,
            pose.rotations[leg.thigh],
            pose.rotations[leg.calf],
        );
        [s.upper, s.lower, pose.rotations[leg.foot]]
    }

    /// The output of an unlocked leg: the input, or while a released leg's correction fades,
    /// the fraction `remaining` of the way from the input to the leg that keeps the whole
    /// release offset (eq. 4.5-4.6: `Q_d = Q_held * Q_input^-1` turned by that fraction).
    fn free_leg(&self, k: usize, pose: &AvatarPose, root_offset: Vec3) -> [Quat; 3] {
        let leg = &self.legs[k];
        let input = [
            pose.rotations[leg.thigh],
            pose.rotations[leg.calf],
            pose.rotations[leg.foot],
        ];
        let Some(corr) = self.feet[k].correction else {
            return input;
        };
        let target = pose.heads[leg.foot] + root_offset + corr.offset;
        let held = self.solve_leg(k, pose, root_offset, target);
        [
            fractional_rotation(input[0], held[0], corr.remaining),
            fractional_rotation(input[1], held[1], corr.remaining),
            (fractional_rotation(Quat::IDENTITY, corr.foot, corr.remaining) * input[2]).normalize(),
        ]
    }

    /// Slows a free leg whose whole sole is near the floor to
    /// [`FootSkateOptions::max_low_foot_speed_mps`]: its lower sole point may move at most that
    /// far from the last output's since the last frame (horizontally); the excess becomes the
    /// leg's correction (held by IK, faded out as the foot lifts or slows).
    fn limit_low_foot(
        &mut self,
        k: usize,
        pose: &AvatarPose,
        root_offset: Vec3,
        floor_y: f32,
        dt: f32,
        rot: &mut [Quat; 3],
    ) {
        let o = self.options;
        let Some(prev) = self.feet[k].prev_output_sole else {
            return;
        };
        if !(o.max_low_foot_speed_mps.is_finite() && dt > 0.0) {
            return;
        }
        let leg = &self.legs[k];
        let hip = pose.heads[leg.thigh] + root_offset;
        let ankle = leg.ankle(hip, rot);
        // Heights here are above the floor the output stands on (the pose is already shifted).
        let sole = leg.sole(ankle, rot[2], floor_y);
        let margin = o.min_height_margin_m;
        let low = |p: &[(Vec3, f32); 2]| p[0].1.max(p[1].1) < margin;
        if !(low(&sole) && low(&prev)) {
            return;
        }
        let j = if sole[0].1 <= sole[1].1 { 0 } else { 1 };
        let step = horizontal(sole[j].0 - prev[j].0);
        let allowed = o.max_low_foot_speed_mps * dt;
        let len = step.length();
        if len <= allowed || len.is_nan() {
            return;
        }
        let input_ankle = pose.heads[leg.foot] + root_offset;
        // Held back at most this far from the input.
        let mut offset = horizontal(ankle - step * (1.0 - allowed / len) - input_ankle);
        let longest = o.max_low_foot_hold_m;
        if offset.length() > longest {
            offset *= longest / offset.length();
        }
        let target = Vec3::new(input_ankle.x + offset.x, ankle.y, input_ankle.z + offset.z);
        let mut solved = self.solve_leg(k, pose, root_offset, target);
        solved[2] = rot[2];
        self.feet[k].correction = Some(Correction {
            offset: horizontal(target - input_ankle),
            foot: (rot[2] * pose.rotations[leg.foot].inverse()).normalize(),
            remaining: 1.0,
        });
        *rot = solved;
    }

    /// Corrects `pose` (the retargeter's output for this frame, sensor space) in place: the
    /// planted foot stays where it was planted, the legs are re-solved, the root moved if the
    /// leg cannot reach; `heads`, `rotations` and `local_rotations` stay consistent, and all
    /// bone lengths are the skeleton's. `floor_y` is the floor height, `dt` the time since the
    /// previous frame (seconds). A pose of another skeleton or with non-finite values is left
    /// as it is.
    pub fn correct(&mut self, pose: &mut AvatarPose, floor_y: f32, dt: f32) {
        let n = self.skeleton.bones.len();
        if pose.heads.len() < n
            || pose.rotations.len() < n
            || pose.local_rotations.len() < n
            || !floor_y.is_finite()
            || !pose.heads.iter().all(|h| h.is_finite())
            || !pose.rotations.iter().all(|q| q.is_finite())
        {
            return;
        }
        let o = self.options;
        let dt_ok = dt > 0.0 && dt <= o.reset_after_s;
        if !dt_ok || !self.initialized {
            self.reset();
        }
        self.stats.frames += 1;
        let dt = if self.initialized { dt } else { 0.0 };

        // 1. Measure the input feet.
        let mut measured = [None; 2];
        let mut speeds = [0.0f32; 2];
        let pivot_alpha = smoothing_alpha(dt, o.pivot_tau_s);
        for foot in Foot::BOTH {
            let leg = &self.legs[foot.index()];
            let mut c = contact(
                leg,
                pose.heads[leg.foot],
                pose.rotations[leg.foot],
                floor_y,
                o.pivot_rise_m,
            );
            let state = &mut self.feet[foot.index()];
            speeds[foot.index()] = match state.prev_contact {
                Some(p) if dt > 0.0 => horizontal(c.mid - p).length() / dt,
                _ => 0.0,
            };
            c.pivot = match state.pivot {
                Some(p) => p + pivot_alpha * (c.pivot - p),
                None => c.pivot,
            };
            state.pivot = Some(c.pivot);
            measured[foot.index()] = Some(c);
        }
        let [Some(cl), Some(cr)] = measured else {
            return;
        };
        let contacts = [cl, cr];

        if !self.initialized {
            // Algorithm 3, first frame: the lower foot is constrained; its height is the
            // threshold reference.
            let ground = cl.height.min(cr.height);
            for s in &mut self.feet {
                s.ground = ground;
            }
            self.constrained = Some(if cl.height <= cr.height {
                Foot::Left
            } else {
                Foot::Right
            });
            self.initialized = true;
        }

        // 2. Which foot is constrained (Algorithm 3).
        let relax = smoothing_alpha(dt, o.adapt_time_s);
        self.threshold_scale = 1.0 + (self.threshold_scale - 1.0) * (1.0 - relax);
        let in_contact = |this: &Self, foot: Foot| {
            let (y_thr, v_thr) = this.thresholds(foot);
            let c = contacts[foot.index()];
            let lifted = c.height > this.feet[foot.index()].ground + o.max_contact_height_m;
            let high_and_fast = c.height > y_thr && speeds[foot.index()] > v_thr;
            !lifted && !high_and_fast
        };
        let mut constrained = self.constrained;
        loop {
            let current = constrained.filter(|&f| in_contact(self, f));
            if current.is_some() {
                constrained = current;
                break;
            }
            let candidates: Vec<Foot> = match constrained {
                Some(f) => vec![f.other()],
                None => Foot::BOTH.to_vec(),
            };
            let next = candidates
                .into_iter()
                .filter(|&f| in_contact(self, f))
                .min_by(|a, b| {
                    contacts[a.index()]
                        .height
                        .total_cmp(&contacts[b.index()].height)
                });
            if let Some(f) = next {
                if constrained.is_some() {
                    self.stats.switches += 1;
                }
                constrained = Some(f);
                break;
            }
            // Neither foot: widen the thresholds and try again (updateThresholds; restart).
            let widened = (self.threshold_scale * o.threshold_widening).min(o.max_threshold_scale);
            if widened <= self.threshold_scale + 1e-6 {
                constrained = None;
                break;
            }
            self.threshold_scale = widened;
        }
        self.constrained = constrained;
        if constrained.is_none() {
            self.stats.flight_frames += 1;
        }

        // Which feet are to be held: the constrained one; the other one is locked when it is
        // clearly planted (low and slow) and then kept while in contact (hysteresis).
        let mut want = [false; 2];
        let mut clearly_planted = [false; 2];
        for foot in Foot::BOTH {
            let k = foot.index();
            let (y_thr, v_thr) = self.thresholds(foot);
            // Low and slow, or the whole sole down (a landing foot: heel and ball low).
            clearly_planted[k] = (contacts[k].height <= y_thr && speeds[k] <= v_thr)
                || (o.lock_flat_feet && contacts[k].top <= y_thr);
            let state = &self.feet[k];
            want[k] = state.relock_wait_s <= 0.0
                && (constrained == Some(foot)
                    || (o.lock_both_feet
                        && (clearly_planted[k]
                            || (state.lock.is_some() && in_contact(self, foot)))));
        }

        // Adapt the estimates of the feet that are clearly planted: ground height, height noise
        // and speed noise.
        let adapt = smoothing_alpha(dt, o.adapt_time_s);
        for foot in Foot::BOTH {
            let k = foot.index();
            if want[k] && clearly_planted[k] && dt > 0.0 {
                let s = &mut self.feet[k];
                let h = contacts[k].height;
                s.ground += adapt * (h - s.ground);
                s.height_var += adapt * ((h - s.ground).powi(2) - s.height_var);
                s.speed_sq += adapt * (speeds[k].powi(2) - s.speed_sq);
            }
        }

        // Floor contact: the whole pose moves vertically so the planted feet's ground estimate
        // is the floor (the retargeter's leg-ratio root height leaves the avatar a few
        // centimetres in or above it).
        let floor_shift = if o.stand_on_floor {
            let ground = 0.5 * (self.feet[0].ground + self.feet[1].ground);
            (-ground).clamp(-o.max_floor_shift_m, o.max_floor_shift_m)
        } else {
            0.0
        };
        if floor_shift != 0.0 {
            for h in &mut pose.heads {
                h.y += floor_shift;
            }
        }

        // 3. Locks: roll, drift release and release (the released leg keeps the lock's offset
        // from the input and fades it out), the free legs' output, then new locks where the free
        // legs put the feet (no jump).
        let root_decay = 1.0 - smoothing_alpha(dt, o.root_return_tau_s);
        let mut root_offset = self.root_offset * root_decay;
        let fade = 1.0 - smoothing_alpha(dt, o.switch_tau_s);
        let prev_offsets = self.prev_ankle_offset;
        for foot in Foot::BOTH {
            let k = foot.index();
            let leg = &self.legs[k];
            let c = contacts[k];
            let input = [
                pose.rotations[leg.thigh],
                pose.rotations[leg.calf],
                pose.rotations[leg.foot],
            ];
            let state = &mut self.feet[k];
            if let Some(corr) = &mut state.correction {
                corr.remaining *= fade;
                if corr.remaining < 0.01 {
                    state.correction = None;
                }
            }
            let Some(lock) = &mut state.lock else {
                continue;
            };
            // The held foot's orientation: the input's, smoothed.
            let foot_rot = match state.foot_rotation {
                Some(q) => smooth_toward(q, input[2], dt, o.planted_foot_tau_s, f32::INFINITY),
                None => input[2],
            };
            state.foot_rotation = Some(foot_rot);
            // Rolling contact: move the lock along the sole with the contact point.
            lock.point += horizontal(
                foot_rot * (leg.contact_offset(c.pivot) - leg.contact_offset(lock.pivot)),
            );
            lock.pivot = c.pivot;
            let input_point = pose.heads[leg.foot] + input[2] * leg.contact_offset(c.pivot);
            if horizontal(lock.point - input_point - root_offset).length() > o.max_lock_distance_m {
                // Drift release: wait before locking again.
                state.relock_wait_s = o.relock_wait_s;
                want[k] = false;
                self.stats.drift_releases += 1;
            }
            if !want[k] {
                state.lock = None;
                state.correction = prev_offsets.map(|p| Correction {
                    offset: p[k],
                    foot: (foot_rot * input[2].inverse()).normalize(),
                    remaining: 1.0,
                });
                state.foot_rotation = None;
            }
        }
        let mut out_rot = [[Quat::IDENTITY; 3]; 2];
        for foot in Foot::BOTH {
            let k = foot.index();
            out_rot[k] = self.free_leg(k, pose, root_offset);
            if self.feet[k].lock.is_none() {
                // A new lock starts where the slowed foot is.
                self.limit_low_foot(k, pose, root_offset, floor_y, dt, &mut out_rot[k]);
            }
        }
        for foot in Foot::BOTH {
            let k = foot.index();
            let leg = &self.legs[k];
            let state = &mut self.feet[k];
            if want[k] && state.lock.is_none() {
                let rot = &out_rot[k];
                let hip = pose.heads[leg.thigh] + root_offset;
                let ankle = leg.ankle(hip, rot);
                let pivot = contacts[k].pivot;
                state.lock = Some(Lock {
                    point: ankle + rot[2] * leg.contact_offset(pivot),
                    pivot,
                });
                state.foot_rotation = Some(rot[2]);
                state.correction = None;
            }
        }

        // IK: the constrained foot first; it moves the root when out of reach.
        let order = match constrained {
            Some(Foot::Right) => [Foot::Right, Foot::Left],
            _ => [Foot::Left, Foot::Right],
        };
        for (rank, foot) in order.into_iter().enumerate() {
            let k = foot.index();
            let Some(lock) = self.feet[k].lock else {
                continue;
            };
            let leg = &self.legs[k];
            let foot_rot = self.feet[k]
                .foot_rotation
                .unwrap_or(pose.rotations[leg.foot]);
            // The held contact point: locked horizontally, at the input's height.
            let input_y = (pose.heads[leg.foot]
                + pose.rotations[leg.foot] * leg.contact_offset(lock.pivot))
            .y;
            let point = Vec3::new(lock.point.x, input_y, lock.point.z);
            let target = point - foot_rot * leg.contact_offset(lock.pivot);
            let hip = pose.heads[leg.thigh] + root_offset;
            if rank == 0 && constrained == Some(foot) {
                // Algorithm 4, lines 6-8: relocate the root by the mismatch.
                let reach_max = 0.999 * (leg.upper_len + leg.lower_len);
                let reach_min = 1.001 * (leg.upper_len - leg.lower_len).abs() + 1e-4;
                let d = target - hip;
                let dist = d.length();
                let needed = if dist > reach_max {
                    d - d / dist * reach_max
                } else if dist < reach_min && dist > 1e-9 {
                    d - d / dist * reach_min
                } else {
                    Vec3::ZERO
                };
                if needed.length() > o.max_root_correction_m {
                    // The foot has left its lock (the leg cannot reach it without dragging the
                    // pelvis): release it instead.
                    let state = &mut self.feet[k];
                    state.lock = None;
                    state.relock_wait_s = o.relock_wait_s;
                    state.correction = prev_offsets.map(|p| Correction {
                        offset: p[k],
                        foot: (foot_rot * pose.rotations[leg.foot].inverse()).normalize(),
                        remaining: 1.0,
                    });
                    state.foot_rotation = None;
                    // (Its leg is posed free by the final pass below.)
                    self.stats.drift_releases += 1;
                    continue;
                }
                if needed != Vec3::ZERO {
                    root_offset += needed;
                    self.stats.root_relocations += 1;
                }
            }
            let mut solved = self.solve_leg(k, pose, root_offset, target);
            solved[2] = foot_rot;
            out_rot[k] = solved;
        }

        // The free legs again on the final root (the constrained foot may have moved it).
        for foot in Foot::BOTH {
            let k = foot.index();
            if self.feet[k].lock.is_none() {
                out_rot[k] = self.free_leg(k, pose, root_offset);
                self.limit_low_foot(k, pose, root_offset, floor_y, dt, &mut out_rot[k]);
            }
        }

        // 4. Write the pose: leg frames, locals, root translation, forward kinematics.
        let input_ankles: [Vec3; 2] =
            std::array::from_fn(|k| pose.heads[self.legs[k].foot] + root_offset);
        for foot in Foot::BOTH {
            let k = foot.index();
            let leg = &self.legs[k];
            pose.rotations[leg.thigh] = out_rot[k][0];
            pose.rotations[leg.calf] = out_rot[k][1];
            pose.rotations[leg.foot] = out_rot[k][2];
        }
        local_from_global(&self.skeleton, pose);
        for (i, bone) in self.skeleton.bones.iter().enumerate() {
            if bone.parent.is_none() {
                pose.heads[i] += root_offset;
            }
        }
        forward_kinematics(&self.skeleton, pose);

        // Bookkeeping.
        self.root_offset = root_offset;
        self.prev_ankle_offset = Some(std::array::from_fn(|k| {
            horizontal(pose.heads[self.legs[k].foot] - input_ankles[k])
        }));
        for foot in Foot::BOTH {
            let k = foot.index();
            let s = &mut self.feet[k];
            s.prev_contact = Some(contacts[k].mid);
            let leg = &self.legs[k];
            s.prev_output_sole =
                Some(leg.sole(pose.heads[leg.foot], pose.rotations[leg.foot], floor_y));
            s.relock_wait_s = (s.relock_wait_s - dt).max(0.0);
        }
        let th = [self.thresholds(Foot::Left), self.thresholds(Foot::Right)];
        self.status = Some(FootSkateStatus {
            constrained,
            locked: [self.feet[0].lock.is_some(), self.feet[1].lock.is_some()],
            root_offset,
            height_threshold_m: [th[0].0, th[1].0],
            speed_threshold_mps: [th[0].1, th[1].1],
        });
    }
}

/// Which height decides whether a foot is "below `height_m`" in [`SkateCriteria`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FootHeight {
    /// The whole sole (heel *and* ball) is below the threshold: the foot is down. Swing-phase
    /// frames with a low toe but a raised heel do not count.
    WholeFoot,
    /// Its lowest point (heel *or* ball) is below the threshold. Also counts the swing foot
    /// whose toe passes the floor at a few centimetres (normal toe clearance is 1-2 cm), so it
    /// is far from zero even for clean walking.
    LowestPoint,
}

/// The foot-skating measure: in a pair of consecutive frames a foot is *on the floor* when its
/// height (see [`FootHeight`]; heel = the sole point below the ankle, ball = the ball joint
/// minus its rest height, both rigid with the foot) is below `height_m` in both frames, and it
/// *skates* when its lowest sole point (the lower one in the later frame) moves more than
/// `slide_m` horizontally between them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SkateCriteria {
    pub height_m: f32,
    pub slide_m: f32,
    pub foot_height: FootHeight,
}

impl Default for SkateCriteria {
    /// 5 cm and 2.5 cm per frame (at 30 Hz: 0.75 m/s), whole foot.
    fn default() -> Self {
        Self {
            height_m: 0.05,
            slide_m: 0.025,
            foot_height: FootHeight::WholeFoot,
        }
    }
}

/// The result of [`foot_skating`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SkateReport {
    /// Consecutive frame pairs examined.
    pub pairs: usize,
    /// Pairs in which at least one foot skates.
    pub skating_pairs: usize,
    /// Pairs in which each foot (left, right) skates.
    pub per_foot: [usize; 2],
    /// Pairs in which each foot is on the floor.
    pub on_floor: [usize; 2],
    /// Largest slide of a foot on the floor, metres.
    pub max_slide_m: f32,
}

impl SkateReport {
    /// Share of frame pairs with a skating foot.
    pub fn ratio(&self) -> f32 {
        if self.pairs == 0 {
            0.0
        } else {
            self.skating_pairs as f32 / self.pairs as f32
        }
    }
}

/// Measures foot skating over a sequence of poses of `skeleton` (see [`SkateCriteria`]).
pub fn foot_skating(
    skeleton: &AvatarSkeleton,
    poses: &[AvatarPose],
    floor_y: f32,
    criteria: SkateCriteria,
) -> Result<SkateReport, FootSkateError> {
    let legs = [
        Leg::new(skeleton, Foot::Left)?,
        Leg::new(skeleton, Foot::Right)?,
    ];
    let n = skeleton.bones.len();
    let points = |leg: &Leg, pose: &AvatarPose| -> Option<[(Vec3, f32); 2]> {
        if pose.heads.len() < n || pose.rotations.len() < n {
            return None;
        }
        Some(leg.sole(pose.heads[leg.foot], pose.rotations[leg.foot], floor_y))
    };
    let mut report = SkateReport::default();
    for pair in poses.windows(2) {
        report.pairs += 1;
        let mut skates = false;
        for (k, leg) in legs.iter().enumerate() {
            let (Some(a), Some(b)) = (points(leg, &pair[0]), points(leg, &pair[1])) else {
                continue;
            };
            let low = |p: &[(Vec3, f32); 2]| match criteria.foot_height {
                FootHeight::WholeFoot => p[0].1.max(p[1].1) < criteria.height_m,
                FootHeight::LowestPoint => p[0].1.min(p[1].1) < criteria.height_m,
            };
            if !(low(&a) && low(&b)) {
                continue;
            }
            report.on_floor[k] += 1;
            let j = if b[0].1 <= b[1].1 { 0 } else { 1 };
            let slide = horizontal(b[j].0 - a[j].0).length();
            if slide.is_finite() {
                report.max_slide_m = report.max_slide_m.max(slide);
            }
            if slide > criteria.slide_m || !slide.is_finite() {
                report.per_foot[k] += 1;
                skates = true;
            }
        }
        if skates {
            report.skating_pairs += 1;
        }
    }
    Ok(report)
}

/// The height (sensor y) of the floor the avatar actually stands on in `poses`: the 5th
/// percentile over the frames of the lowest foot point (heel = ankle or ball, each minus its
/// rest height above the floor). The retargeter's root height is only as good as its leg-ratio
/// scaling: on the CMU clips the avatar's feet end up several centimetres below or above the
/// sensor floor, which would make a fixed-floor skating measure meaningless. `None` without
/// usable poses.
pub fn estimate_floor(
    skeleton: &AvatarSkeleton,
    poses: &[AvatarPose],
) -> Result<Option<f32>, FootSkateError> {
    let legs = [
        Leg::new(skeleton, Foot::Left)?,
        Leg::new(skeleton, Foot::Right)?,
    ];
    let n = skeleton.bones.len();
    let mut lows: Vec<f32> = poses
        .iter()
        .filter(|p| p.heads.len() >= n && p.rotations.len() >= n)
        .map(|p| {
            legs.iter()
                .map(|leg| {
                    let [(_, heel), (_, ball)] =
                        leg.sole(p.heads[leg.foot], p.rotations[leg.foot], 0.0);
                    heel.min(ball)
                })
                .fold(f32::INFINITY, f32::min)
        })
        .filter(|y| y.is_finite())
        .collect();
    if lows.is_empty() {
        return Ok(None);
    }
    lows.sort_by(f32::total_cmp);
    Ok(Some(lows[(lows.len() - 1) / 20]))
}
