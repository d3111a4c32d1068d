//! The generator of the Kinect v1 skeleton noise model: [`KinectNoiser`] turns clean frames,
//! pushed in order, into noisy ones, each effect drawn from its own seeded ChaCha8 stream (see
//! the [module docs](super) for the effects, their sources and the determinism; the depth
//! error is scaled to Table 6.1 of seed 000, the 2013 Kinect fitting-room thesis).

use std::collections::VecDeque;

use glam::{Quat, Vec3};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};

use crate::frame::{JointSample, KinectJoint, SensorFrame};

use super::KinectNoiseModel;
use super::occlusion::{closest_on_segment, occluded_joints};

/// One frame of a noisy stream, with the bookkeeping needed to line it up with the clean
/// input (see the module docs).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct NoisyFrame {
    /// The noisy frame. Its timestamp is the arrival frame's, its `sequence` counts the noisy
    /// frames emitted.
    pub frame: SensorFrame,
    /// Index (in the clean input) of the frame whose pose this frame shows.
    pub clean_index: usize,
    /// Index (in the clean input) of the frame at whose arrival this frame was emitted;
    /// `arrival_index - clean_index` is the latency in frames (more for a duplicate).
    pub arrival_index: usize,
    /// Whether the frame repeats the previously emitted one (same joints, new timestamp).
    pub duplicate: bool,
}

/// Streams of the ChaCha8 generator, one per effect.
const STREAM_POSITION: u64 = 1;
const STREAM_BONE: u64 = 2;
const STREAM_TWIST: u64 = 3;
const STREAM_SPIKE: u64 = 4;
const STREAM_FRAME: u64 = 5;

/// `(hand, wrist)` per arm.
const ARMS: [(KinectJoint, KinectJoint); 2] = [
    (KinectJoint::HandLeft, KinectJoint::WristLeft),
    (KinectJoint::HandRight, KinectJoint::WristRight),
];

fn is_extremity(joint: KinectJoint) -> bool {
    use KinectJoint::*;
    matches!(
        joint,
        WristLeft
            | HandLeft
            | WristRight
            | HandRight
            | AnkleLeft
            | FootLeft
            | AnkleRight
            | FootRight
    )
}

fn rng_for(seed: u64, stream: u64) -> ChaCha8Rng {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(stream);
    rng
}

fn normal(rng: &mut ChaCha8Rng) -> f32 {
    StandardNormal.sample(rng)
}

/// AR(1) coefficient `exp(-dt / tau)`; 0 (a fresh draw) for the first frame or `tau = 0`.
fn ar_coefficient(dt_s: Option<f64>, tau_s: f32) -> f32 {
    match dt_s {
        Some(dt) if tau_s > 0.0 => (-(dt as f32) / tau_s).exp(),
        _ => 0.0,
    }
}

/// One unit-variance Gauss-Markov step.
fn ar_step(state: f32, phi: f32, innovation: f32) -> f32 {
    phi * state + (1.0 - phi * phi).max(0.0).sqrt() * innovation
}

/// A running hand spike of one arm.
#[derive(Clone, Copy, Debug, Default)]
struct Spike {
    remaining_s: f32,
    offset: Vec3,
}

/// Occlusion bookkeeping of one joint.
#[derive(Clone, Copy, Debug, Default)]
struct JointTrack {
    /// Seconds continuously occluded (0 when visible).
    occluded_s: f32,
    /// The last reported position.
    last_reported: Option<Vec3>,
}

/// The streaming noise engine behind [`NoisySource`](super::NoisySource) and
/// [`corrupt_stream`](super::corrupt_stream): push clean frames in order, get noisy frames
/// out. Deterministic for a given model, seed and frame rate.
#[derive(Clone, Debug)]
pub struct KinectNoiser {
    model: KinectNoiseModel,
    seed: u64,
    latency_frames: usize,
    rng_position: ChaCha8Rng,
    rng_bone: ChaCha8Rng,
    rng_twist: ChaCha8Rng,
    rng_spike: ChaCha8Rng,
    rng_frame: ChaCha8Rng,
    /// Clean frames that arrived and are not shown yet (at most `latency_frames + 1`).
    pending: VecDeque<SensorFrame>,
    /// Clean frames pushed so far.
    arrivals: usize,
    /// Timestamp of the last shown clean frame.
    last_shown_s: Option<f64>,
    position_state: [[f32; 3]; KinectJoint::COUNT],
    bone_state: [f32; KinectJoint::COUNT],
    bone_shared_state: f32,
    twist_state: [f32; KinectJoint::COUNT],
    spikes: [Spike; 2],
    tracks: [JointTrack; KinectJoint::COUNT],
    last_emitted: Option<NoisyFrame>,
    emitted: u64,
}

impl KinectNoiser {
    /// A noiser for a stream of nominal rate `fps` (used only to turn `latency_s` into whole
    /// frames; a non-positive or non-finite rate counts as 30). The model is
    /// [sanitized](KinectNoiseModel::sanitized).
    pub fn new(model: &KinectNoiseModel, seed: u64, fps: f64) -> Self {
        let model = model.sanitized();
        let fps = if fps.is_finite() && fps > 0.0 {
            fps
        } else {
            30.0
        };
        let latency_frames = (f64::from(model.latency_s) * fps).round().clamp(0.0, 1e6) as usize;
        Self {
            model,
            seed,
            latency_frames,
            rng_position: rng_for(seed, STREAM_POSITION),
            rng_bone: rng_for(seed, STREAM_BONE),
            rng_twist: rng_for(seed, STREAM_TWIST),
            rng_spike: rng_for(seed, STREAM_SPIKE),
            rng_frame: rng_for(seed, STREAM_FRAME),
            pending: VecDeque::new(),
            arrivals: 0,
            last_shown_s: None,
            position_state: [[0.0; 3]; KinectJoint::COUNT],
            bone_state: [0.0; KinectJoint::COUNT],
            bone_shared_state: 0.0,
            twist_state: [0.0; KinectJoint::COUNT],
            spikes: [Spike::default(); 2],
            tracks: [JointTrack::default(); KinectJoint::COUNT],
            last_emitted: None,
            emitted: 0,
        }
    }

    /// The (sanitized) model in use.
    pub fn model(&self) -> &KinectNoiseModel {
        &self.model
    }

    pub fn seed(&self) -> u64 {
        self.seed
    }

    /// The latency in whole frames, `round(latency_s * fps)`.
    pub fn latency_frames(&self) -> usize {
        self.latency_frames
    }

    /// Clean frames pushed so far.
    pub fn arrivals(&self) -> usize {
        self.arrivals
    }

    /// Feeds the next clean frame; returns the noisy frame emitted at its arrival, if any (none
    /// during the first `latency_frames` arrivals and for a dropped frame).
    pub fn push(&mut self, clean: &SensorFrame) -> Option<NoisyFrame> {
        let arrival_index = self.arrivals;
        self.arrivals += 1;
        let arrival_s = clean.timestamp_s;
        self.pending.push_back(clean.clone());
        if self.pending.len() <= self.latency_frames {
            return None;
        }
        let shown = self.pending.pop_front()?;
        let clean_index = arrival_index - self.latency_frames;
        let dt_s = self.last_shown_s.map(|last| {
            let dt = shown.timestamp_s - last;
            if dt.is_finite() {
                dt.clamp(0.0, 60.0)
            } else {
                0.0
            }
        });
        self.last_shown_s = Some(shown.timestamp_s);

        let joints = self.corrupt_pose(&shown, dt_s);

        let fate: f32 = self.rng_frame.random();
        let model = &self.model;
        if fate < model.drop_probability {
            return None;
        }
        let repeat = fate < model.drop_probability + model.duplicate_probability;
        let out = match (&self.last_emitted, repeat) {
            (Some(previous), true) => NoisyFrame {
                frame: SensorFrame {
                    timestamp_s: arrival_s,
                    sequence: self.emitted,
                    joints: previous.frame.joints,
                },
                clean_index: previous.clean_index,
                arrival_index,
                duplicate: true,
            },
            _ => NoisyFrame {
                frame: SensorFrame {
                    timestamp_s: arrival_s,
                    sequence: self.emitted,
                    joints,
                },
                clean_index,
                arrival_index,
                duplicate: false,
            },
        };
        self.emitted += 1;
        self.last_emitted = Some(out.clone());
        Some(out)
    }

    /// Advances every random process by one shown frame and returns the corrupted joints.
    fn corrupt_pose(
        &mut self,
        clean: &SensorFrame,
        dt_s: Option<f64>,
    ) -> [JointSample; KinectJoint::COUNT] {
        let m = self.model.clone();
        let dt = dt_s.unwrap_or(0.0) as f32;

        // Random processes: a fixed count of draws per stream and frame.
        let phi = ar_coefficient(dt_s, m.noise_correlation_time_s);
        let (w_ar, w_white) = (
            (1.0 - m.white_noise_fraction).sqrt(),
            m.white_noise_fraction.sqrt(),
        );
        let mut unit_noise = [Vec3::ZERO; KinectJoint::COUNT];
        for (state, out) in self.position_state.iter_mut().zip(unit_noise.iter_mut()) {
            let mut v = [0.0f32; 3];
            for (axis, value) in state.iter_mut().zip(v.iter_mut()) {
                let innovation = normal(&mut self.rng_position);
                let white = normal(&mut self.rng_position);
                *axis = ar_step(*axis, phi, innovation);
                *value = w_ar * *axis + w_white * white;
            }
            *out = Vec3::from_array(v);
        }
        let phi_bone = ar_coefficient(dt_s, m.bone_length_correlation_time_s);
        self.bone_shared_state =
            ar_step(self.bone_shared_state, phi_bone, normal(&mut self.rng_bone));
        for state in self.bone_state.iter_mut() {
            *state = ar_step(*state, phi_bone, normal(&mut self.rng_bone));
        }
        for state in self.twist_state.iter_mut() {
            *state = ar_step(*state, phi, normal(&mut self.rng_twist));
        }
        let start_probability = 1.0 - (-m.hand_spike_rate_hz * dt).exp();
        for spike in self.spikes.iter_mut() {
            let start: f32 = self.rng_spike.random();
            let offset = Vec3::new(
                normal(&mut self.rng_spike),
                normal(&mut self.rng_spike),
                normal(&mut self.rng_spike),
            );
            let length: f32 = self.rng_spike.random();
            spike.remaining_s = (spike.remaining_s - dt).max(0.0);
            if spike.remaining_s <= 0.0 && dt_s.is_some() && start < start_probability {
                spike.remaining_s = m.hand_spike_min_duration_s
                    + length * (m.hand_spike_max_duration_s - m.hand_spike_min_duration_s);
                spike.offset = offset * m.hand_spike_sigma_m;
            }
        }

        let clean_pos = clean.joints.map(|s| s.position);
        let usable = clean
            .joints
            .map(|s| s.position.is_finite() && s.orientation.is_finite());

        // Bone lengths.
        let mut pos = clean_pos;
        if m.bone_length_sigma > 0.0 {
            let (shared, own) = (
                m.bone_length_shared_fraction.sqrt(),
                (1.0 - m.bone_length_shared_fraction).sqrt(),
            );
            for joint in KinectJoint::ALL {
                let j = joint.index();
                if let Some(parent) = joint.parent() {
                    let p = parent.index();
                    if usable[j] && usable[p] {
                        let scale = (1.0
                            + m.bone_length_sigma
                                * (shared * self.bone_shared_state + own * self.bone_state[j]))
                            .clamp(0.5, 1.5);
                        pos[j] = pos[p] + scale * (clean_pos[j] - clean_pos[p]);
                    }
                }
            }
        }

        // Depth-dependent anisotropic position noise.
        let mut noise = [Vec3::ZERO; KinectJoint::COUNT];
        for joint in KinectJoint::ALL {
            let j = joint.index();
            if !usable[j] {
                continue;
            }
            let scale = if is_extremity(joint) {
                m.extremity_sigma_scale
            } else {
                1.0
            };
            // Capped at 1 m (z > 22 m) so that absurd inputs cannot overflow to infinity.
            let axial = (scale * m.axial_sigma_m(clean_pos[j].z)).min(1.0);
            let lateral = m.lateral_sigma_ratio * axial;
            let (e1, e2, a) = sight_basis(clean_pos[j]);
            let v = unit_noise[j];
            noise[j] = e1 * (lateral * v.x) + e2 * (lateral * v.y) + a * (axial * v.z);
            pos[j] += noise[j];
        }

        // Hand spikes.
        for ((hand, wrist), spike) in ARMS.iter().zip(self.spikes.iter()) {
            if spike.remaining_s > 0.0 {
                if usable[hand.index()] {
                    pos[hand.index()] += spike.offset;
                }
                if usable[wrist.index()] {
                    pos[wrist.index()] += spike.offset * m.wrist_spike_share;
                }
            }
        }

        // Self-occlusion on the clean pose.
        let occluded = if m.occlusion_enabled {
            occluded_joints(
                &clean_pos,
                &usable,
                &m.body,
                m.occlusion_margin_m,
                m.occlusion_inset_m,
            )
        } else {
            [false; KinectJoint::COUNT]
        };
        let hidden: [bool; KinectJoint::COUNT] = std::array::from_fn(|j| {
            occluded[j] || (m.view_limits_enabled && usable[j] && !m.in_view(clean_pos[j]))
        });
        let trunk = (
            clean_pos[KinectJoint::HipCenter.index()],
            clean_pos[KinectJoint::ShoulderCenter.index()],
        );
        let follow = if m.inferred_lag_s > 0.0 {
            1.0 - (-dt / m.inferred_lag_s).exp()
        } else {
            1.0
        };
        let mut confidence = [1.0f32; KinectJoint::COUNT];
        for joint in KinectJoint::ALL {
            let j = joint.index();
            let track = &mut self.tracks[j];
            if !usable[j] {
                pos[j] = track.last_reported.unwrap_or(Vec3::ZERO);
                confidence[j] = 0.0;
                continue;
            }
            if hidden[j] {
                track.occluded_s += dt;
                let toward_body = closest_on_segment(clean_pos[j], trunk.0, trunk.1) - clean_pos[j];
                let target = pos[j]
                    + noise[j] * (m.inferred_sigma_scale - 1.0)
                    + toward_body * m.inferred_body_pull;
                let held = match track.last_reported {
                    Some(last) if dt_s.is_some() => last + (target - last) * follow,
                    _ => target,
                };
                pos[j] = if held.is_finite() { held } else { target };
                confidence[j] = if track.occluded_s > m.not_tracked_after_s {
                    0.0
                } else {
                    m.inferred_confidence
                };
            } else {
                track.occluded_s = 0.0;
            }
            track.last_reported = Some(pos[j]);
        }

        // Orientations from the noisy bones.
        let twist_sigma = m.twist_sigma_deg.to_radians();
        let mut joints = [JointSample::default(); KinectJoint::COUNT];
        for joint in KinectJoint::ALL {
            let j = joint.index();
            let clean_q = clean.joints[j].orientation;
            let orientation = if !usable[j] {
                Quat::IDENTITY
            } else {
                match joint.parent() {
                    Some(parent) => {
                        let bone = pos[j] - pos[parent.index()];
                        let swung = swing_to(clean_q, clean_q * Vec3::Y, bone);
                        let axis = bone.normalize_or_zero();
                        if axis == Vec3::ZERO || twist_sigma == 0.0 {
                            swung
                        } else {
                            (Quat::from_axis_angle(axis, twist_sigma * self.twist_state[j]) * swung)
                                .normalize()
                        }
                    }
                    None => {
                        let (l, r) = (KinectJoint::HipLeft.index(), KinectJoint::HipRight.index());
                        swing_to(clean_q, clean_pos[l] - clean_pos[r], pos[l] - pos[r])
                    }
                }
            };
            joints[j] = JointSample {
                position: pos[j],
                orientation,
                confidence: confidence[j],
            };
        }
        joints
    }
}

/// `arc(from -> to) * q`; `q` itself when either direction is degenerate or they agree.
fn swing_to(q: Quat, from: Vec3, to: Vec3) -> Quat {
    let (from, to) = (from.normalize_or_zero(), to.normalize_or_zero());
    if from == Vec3::ZERO || to == Vec3::ZERO || from == to {
        return q;
    }
    let swung = (Quat::from_rotation_arc(from, to) * q).normalize();
    if swung.is_finite() { swung } else { q }
}

/// `(e1, e2, a)`: `a` the line of sight to `p`, `e1` horizontal across it, `e2 = a x e1`.
fn sight_basis(p: Vec3) -> (Vec3, Vec3, Vec3) {
    let a = p.normalize_or(Vec3::Z);
    let e1 = Vec3::Y.cross(a).normalize_or(Vec3::X);
    let e2 = a.cross(e1).normalize_or(Vec3::Y);
    (e1, e2, a)
}
