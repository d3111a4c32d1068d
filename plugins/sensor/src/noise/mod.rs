//! A seeded Kinect v1 skeleton noise model: turns a clean skeleton stream (for example a
//! [`BvhSource`](crate::BvhSource) replaying real mocap) into a stream with the errors of a
//! Kinect v1 skeleton tracker, reproducibly for a given `u64` seed.
//!
//! # What is modelled
//!
//! Per shown clean frame, in this order (symbols are the fields of [`KinectNoiseModel`]):
//!
//! 1. **Latency.** The noisy frame emitted when clean frame `k` arrives shows clean frame
//!    `k - L`, `L = round(latency_s * fps)`; it carries the timestamp of frame `k` (its arrival
//!    time). No frame is emitted for the first `L` arrivals. Default `latency_s = 0.1` s
//!    (3 frames at 30 Hz): an *assumption*. Livingston, Sebastian, Ai & Decker, "Performance
//!    measurements for the Microsoft Kinect skeleton", IEEE VR 2012, measured the SDK
//!    skeleton's latency; their figure was not at hand, so check it before relying on 0.1 s.
//! 2. **Bone-length noise.** Each bone (parent -> joint offset) is scaled by
//!    `s_j = 1 + bone_length_sigma * (sqrt(c) * g + sqrt(1 - c) * b_j)`, clamped to
//!    `[0.5, 1.5]`, with `c = bone_length_shared_fraction`, `g` one whole-skeleton unit
//!    Gauss-Markov process and `b_j` one per bone (correlation time
//!    `bone_length_correlation_time_s`). The skeleton is rebuilt root first,
//!    `p'_j = p'_parent + s_j * (p_j - p_parent)`, so a scaled bone moves its whole subtree.
//!    Kinect v1 skeletons have no fixed bone lengths (every joint is estimated separately), so
//!    their bone lengths vary from frame to frame (Wang, Kurillo, Ofli & Bajcsy, "Evaluation
//!    of pose tracking accuracy in the first and second generations of Microsoft Kinect",
//!    ICHI 2015, evaluate Kinect bone-length estimates against mocap); the default 1.5 % comes
//!    on top of the variation the independent joint noise already causes (an *assumption*;
//!    together they give a forearm-length standard deviation of about 4 % at 2.5 m).
//! 3. **Position noise**, per joint, anisotropic and growing quadratically with depth `z`
//!    (metres along the optical axis) like the Kinect v1 depth error:
//!
//!    ```text
//!    sigma_axial(z)   = k_j * (c0 + c2 * (z - z0)^2)       along the line of sight
//!    sigma_lateral(z) = lateral_sigma_ratio * sigma_axial(z)   across it (2 axes)
//!    ```
//!
//!    with `c0 = axial_sigma_c0_m = 0.00128 m`, `c2 = axial_sigma_c2_per_m = 0.00203 /m`,
//!    `z0 = axial_sigma_z0_m = 0.4 m`: the axial depth-noise model of Nguyen, Izadi & Lovell,
//!    "Modeling Kinect sensor noise for improved 3D reconstruction and tracking", 3DIMPVT 2012
//!    (`0.0012 + 0.0019 (z - 0.4)^2` m), scaled by 1.068 so that `sigma_axial(3 m) = 1.50 cm`,
//!    the Kinect error at 3 m of Table 6.1 of the seed thesis (0.5 / 1.5 / 4 cm at 1 / 3 / 5 m,
//!    after Khoshelham & Oude Elberink, "Accuracy and resolution of Kinect depth data for
//!    indoor mapping applications", Sensors 12(2), 2012, whose random depth error grows with
//!    `z^2`; the thesis text quotes them as "two centimeters" at 3 m, so 1.5 cm is the lower of
//!    the two). The model gives 0.2 / 1.5 / 4.4 cm at 1 / 3 / 5 m.
//!    `k_j = extremity_sigma_scale` (1.3) for wrists, hands, ankles and feet, 1 otherwise
//!    (*assumption*: extremities are the least reliable Kinect joints). The lateral ratio 0.5
//!    is an *assumption*: the per-pixel lateral noise of Nguyen et al. is only
//!    `0.8 px * z / f` (about 4 mm at 3 m with `f ≈ 585 px`), but a skeleton joint's lateral
//!    error is dominated by the body-part inference, not by the pixel noise. The line of sight
//!    is `a = p / |p|`; the lateral axes are `e1 = normalize(Y x a)` (horizontal) and
//!    `e2 = a x e1`. The noise is
//!    `n_j = sigma_lateral (v_1 e1 + v_2 e2) + sigma_axial v_3 a`, where each `v_i` is a
//!    unit-variance mix of a temporally correlated and a white part:
//!    `v = sqrt(1 - w) u + sqrt(w) eps`, `w = white_noise_fraction` (0.2), `eps ~ N(0, 1)` and
//!    `u` a first-order Gauss-Markov (AR(1)) process, `u_t = phi u_{t-1} + sqrt(1 - phi^2) eps'`,
//!    `phi = exp(-dt / noise_correlation_time_s)` with `dt` the time between shown frames
//!    (0.2 s: an *assumption*; Kinect skeleton jitter is visibly smooth over a few frames). At
//!    30 Hz the lag-1 autocorrelation of `v` is `(1 - w) phi = 0.68`.
//! 4. **Hand spikes.** Per arm, a spike starts with probability
//!    `1 - exp(-hand_spike_rate_hz * dt)` per frame (when none is running), lasts a uniform
//!    time in `[hand_spike_min_duration_s, hand_spike_max_duration_s]` and displaces the hand by
//!    a constant offset `~ N(0, hand_spike_sigma_m^2 I)` and the wrist by `wrist_spike_share`
//!    of it: the jumps of the Kinect's hand joints when the small hand blob is confused with
//!    the forearm or the body. Wang et al. (2015) model Kinect joint offsets as a Gaussian plus
//!    a uniform outlier component; these spikes play the outlier part (rate 0.3 /s,
//!    sigma 5 cm, 33-200 ms are *assumptions*).
//! 5. **Self-occlusion and the view limits** (geometric tests on the *clean* shown pose). The
//!    body is a set of capsules ([`BodyVolumes`]): the trunk (hip centre - shoulder centre),
//!    both trunk sides (shoulder - hip), the head (a sphere), upper arms, forearms, thighs and
//!    shanks. A joint (all but hip centre, spine and shoulder centre) is *occluded* when the
//!    line of sight from the sensor (the origin) to a point `occlusion_margin_m` (5 cm) in front
//!    of the joint passes within `radius - occlusion_inset_m` (inset 3 cm) of the axis of a
//!    capsule that neither ends at the joint nor contains it ([`occluded_joints`]). This is the
//!    depth-image test "the joint projects well inside the silhouette of a body part that is
//!    nearer to the sensor", done in 3D: it catches the far-side shoulder, hip and limbs of a
//!    person turned sideways, a hand behind the back or the head, a knee behind the other leg;
//!    the inset keeps a joint grazed by an edge (an elbow beside the trunk) tracked. A joint is
//!    also hidden when it is outside the depth camera's view
//!    ([`KinectNoiseModel::in_view`]: 57° x 43° field of view, 0.8-4.0 m depth range, the
//!    Kinect for Windows v1 specification), treated like occlusion (an *assumption* about the
//!    SDK; note that the clean walk clips, placed at 2.5 m, walk towards and past the sensor
//!    and so leave the view, see `BvhSourceOptions::start_distance_m`, or keep them on the
//!    spot with `BvhSourceOptions::treadmill`). A hidden joint is reported **inferred**
//!    (`confidence = inferred_confidence`, 0.5, always `<= 0.5`, i.e. rejected by a `> 0.5`
//!    gate) at a biased, late position: a held estimate `h` starts
//!    at the joint's last reported position and follows
//!    `h += (1 - exp(-dt / inferred_lag_s)) * (target - h)` with
//!    `target = noisy + (inferred_sigma_scale - 1) n_j + inferred_body_pull * (c - p_clean)`,
//!    `c` the nearest point of the clean trunk segment (the Kinect guesses hidden joints
//!    towards the body and late). After `not_tracked_after_s` (1 s) of continuous hiding the
//!    joint becomes **not tracked** (`confidence = 0`); its position stays the held estimate
//!    (meaningless, like the SDK's). The occluder radii, margin, inset, lag, pull and the 1 s
//!    are *assumptions* (rounded adult body dimensions; the seed thesis names self-occlusion,
//!    worst "in lateral views of the user", as the main cause of the unnatural movements its
//!    motion filters must handle).
//! 6. **Orientations**, per the contract of
//!    [`JointSample::orientation`](crate::frame::JointSample::orientation): with `Q` the clean
//!    orientation of the bone ending at `j` and `d` the noisy bone (noisy `p_j - p_parent`,
//!    after all the above), the orientation is `twist(d, theta_j) * arc(Q * Y -> d) * Q`, so
//!    its +Y points exactly along the noisy bone, with `theta_j = twist_sigma_deg * t_j` and
//!    `t_j` a unit Gauss-Markov process (correlation time `noise_correlation_time_s`; 3° is an
//!    *assumption*). The hip centre (pelvis) gets `arc(clean hip line -> noisy hip line) * Q`
//!    with the hip line `hip_left - hip_right`.
//! 7. **Dropped and duplicated frames.** Per emitted slot one uniform `u`: `u <
//!    drop_probability` drops the frame (nothing emitted; the noise processes still advance),
//!    `u < drop_probability + duplicate_probability` repeats the previously emitted frame's
//!    joints with the new timestamp and sequence number (USB / SDK hiccups; 1 % each is an
//!    *assumption*).
//!
//! The emitted `sequence` counts the noisy frames emitted (0, 1, 2, ...).
//!
//! # Determinism
//!
//! All randomness comes from ChaCha8 ([`rand_chacha::ChaCha8Rng`], a portable stream cipher)
//! seeded with `seed_from_u64(seed)`, one stream
//! ([`ChaCha8Rng::set_stream`](rand_chacha::ChaCha8Rng::set_stream)) per effect
//! (position, bone length, twist, hand spikes, frame fate); every shown frame draws a fixed
//! count of numbers from each stream. So the same seed and the same input give a bit-identical
//! output, and changing one effect's parameters (or switching it off) leaves the random numbers
//! of the others unchanged.
//!
//! # Lining up noisy and clean frames
//!
//! [`corrupt_stream`] and [`NoisySource::advance_detailed`] return [`NoisyFrame`]s: the frame
//! plus `clean_index` (the index of the clean input frame whose pose it shows:
//! `arrival_index - L` for a fresh frame, the repeated frame's for a duplicate) and
//! `arrival_index` (the input frame at whose arrival it was emitted; its timestamp is that
//! frame's). An evaluator compares `frame` with `clean[clean_index]` for the noise and with
//! `clean[arrival_index]` for the total error including latency. Indices count the frames
//! passed in (for [`NoisySource`], the frames its inner source emitted since the wrap).
//!
//! # Modules
//!
//! - `model`: the model's parameters ([`KinectNoiseModel`], [`BodyVolumes`]) and its noise
//!   functions of depth.
//! - `validate`: their ranges checked ([`KinectNoiseModel::validate`]) or clamped
//!   ([`KinectNoiseModel::sanitized`]).
//! - `noiser`: the generator, [`KinectNoiser`], and the [`NoisyFrame`]s it emits.
//! - `occlusion`: the self-occlusion test ([`occluded_joints`]).
//! - here: [`corrupt_stream`] and [`NoisySource`], the generator applied to a stream.

mod model;
mod noiser;
mod occlusion;
mod validate;

use crate::frame::SensorFrame;
use crate::source::{SensorSource, SourceError};

pub use model::{BodyVolumes, KinectNoiseModel, NoiseModelError};
pub use noiser::{KinectNoiser, NoisyFrame};
pub use occlusion::occluded_joints;

/// Corrupts a whole clean stream (frames in order, e.g. 30 Hz) with `model` and `seed`; the
/// pure-function form of [`NoisySource`] for evaluation. The frame rate used to turn the
/// latency into frames is `1 / median(frame interval)` of `clean` (30 Hz for fewer than two
/// frames). Same inputs, same output, bit for bit; the output equals what a [`NoisySource`]
/// with the same rate emits for the same frames.
pub fn corrupt_stream(
    clean: &[SensorFrame],
    model: &KinectNoiseModel,
    seed: u64,
) -> Vec<NoisyFrame> {
    let mut intervals: Vec<f64> = clean
        .windows(2)
        .map(|w| w[1].timestamp_s - w[0].timestamp_s)
        .filter(|dt| dt.is_finite() && *dt > 0.0)
        .collect();
    intervals.sort_by(f64::total_cmp);
    let fps = intervals
        .get(intervals.len() / 2)
        .map_or(30.0, |median| 1.0 / median);
    let mut noiser = KinectNoiser::new(model, seed, fps);
    clean
        .iter()
        .filter_map(|frame| noiser.push(frame))
        .collect()
}

/// A [`SensorSource`] wrapper that passes every frame of `inner` through a [`KinectNoiser`].
/// Deterministic given the seed: the same seed and the same inner frames give a bit-identical
/// stream.
#[derive(Clone, Debug)]
pub struct NoisySource<S> {
    inner: S,
    noiser: KinectNoiser,
    name: String,
}

impl<S: SensorSource> NoisySource<S> {
    /// Wraps `inner`; the latency is rounded to whole frames of `inner.fps()`. The name is
    /// `"noisy:<inner name>"`.
    pub fn new(inner: S, model: &KinectNoiseModel, seed: u64) -> Self {
        let noiser = KinectNoiser::new(model, seed, f64::from(inner.fps()));
        let name = format!("noisy:{}", inner.name());
        Self {
            inner,
            noiser,
            name,
        }
    }

    pub fn inner(&self) -> &S {
        &self.inner
    }

    pub fn into_inner(self) -> S {
        self.inner
    }

    pub fn noiser(&self) -> &KinectNoiser {
        &self.noiser
    }

    /// Like [`SensorSource::advance`] but with the [`NoisyFrame`] bookkeeping; `clean_index`
    /// and `arrival_index` count the frames `inner` emitted since the wrap.
    pub fn advance_detailed(&mut self, dt_s: f64) -> Result<Vec<NoisyFrame>, SourceError> {
        let clean = self.inner.advance(dt_s)?;
        Ok(clean.iter().filter_map(|f| self.noiser.push(f)).collect())
    }
}

impl<S: SensorSource> SensorSource for NoisySource<S> {
    fn name(&self) -> &str {
        &self.name
    }

    fn fps(&self) -> f32 {
        self.inner.fps()
    }

    fn advance(&mut self, dt_s: f64) -> Result<Vec<SensorFrame>, SourceError> {
        Ok(self
            .advance_detailed(dt_s)?
            .into_iter()
            .map(|f| f.frame)
            .collect())
    }
}
