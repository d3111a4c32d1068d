//! The foot-skate corrector's frame (seed 000 §4.5): which foot is constrained (Algorithm 3,
//! adaptive thresholds), the lock, the leg IK and the root relocation (Algorithm 4), the
//! smoothing of a released leg (eq. 4.5-4.6), and the additions to the seed described in the
//! [module docs](super).

use glam::{Quat, Vec3};

use crate::ik::{forward_kinematics, local_from_global, solve_two_bone};
use crate::retarget::AvatarPose;
use crate::smoothing::{fractional_rotation, smooth_toward, smoothing_alpha};

use super::leg::{Correction, Lock, contact, horizontal};
use super::{Foot, FootSkateCorrector, FootSkateStatus};

impl FootSkateCorrector {
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
