//! Anatomical joint-angle limits (seed 000 §4.4.2, first stage: "constraints on the joint data
//! based on the natural limits of human bones").
//!
//! # Angles
//!
//! Every limited bone's local rotation `L` (relative to its parent bone, as in
//! [`AvatarPose::local_rotations`]) is measured against an *anatomical neutral* `N` of that
//! joint: `D = N^-1 * L`, a rotation in the bone's own neutral frame. `D` is split into
//! `swing * twist` ([`crate::retarget::swing_twist`]) about the bone's +Y axis (head to tail):
//!
//! * **twist**: the rotation about the bone's own axis (axial rotation, pronation/supination,
//!   inversion/eversion);
//! * **swing**: the rotation that moves the bone's axis, written as its rotation vector
//!   `s = angle * axis` (the axis lies in the bone's local XZ plane) and read on two
//!   anatomical axes: `flexion = s . a_flex` and `abduction = s . a_abd`.
//!
//! `a_flex` is the local axis about which the bone's tail moves towards the joint's flexion
//! direction (e.g. the ankle backwards for the knee), `a_abd = ±(Y x a_flex)` the one that
//! moves it towards abduction. Both come from the body's anatomical directions in the neutral
//! pose ([`Anat`]: the avatar faces the sensor, front = -Z, left = -X, up = +Y), expressed in
//! the bone's neutral frame; see [`JointKind::directions`] for the positive sense of each
//! angle. [`JointLimits::axes_report`] prints the axes; on the shipped MakeHuman body (local
//! frames of the *neutral* pose, left side; the right side mirrors Z and the twist sign):
//!
//! | joint (bone) | flexion axis | abduction axis | + twist |
//! |---|---|---|---|
//! | trunk, neck, head (`spine_0x`, `neck_01`, `head`) | +X | -Z (bend left) | +Y (turn left) |
//! | clavicle | ≈ +Z (elevation) | ≈ +X (protraction) | -Y (posterior rotation) |
//! | shoulder (`upperarm`) | (0.92, 0, 0.38) | (-0.38, 0, 0.92) | +Y (internal) |
//! | elbow (`lowerarm`) | (0.99, 0, 0.17) ≈ +X | ≈ +Z | +Y (pronation) |
//! | wrist (`hand`) | (-0.33, 0, -0.94) (palmar) | (0.94, 0, -0.33) (radial) | +Y (pronation) |
//! | hip (`thigh`) | (-0.90, 0, 0.44) | (-0.44, 0, -0.90) | +Y (internal) |
//! | knee (`calf`) | +X (1.00, 0, 0.06) | -Z | +Y (internal) |
//! | ankle (`foot`) | -X (dorsiflexion) | -Z (toe out) | -Y (inversion) |
//!
//! So knee flexion is a rotation about the calf's local +X axis and hip flexion one about
//! (nearly) the thigh's local -X axis. A walking clip (07_01) confirms the signs: the knee
//! flexes 11° in stance and 76-78° in swing with under 1° of mean abduction, the hip goes from
//! -18° (extension) to +44°, the elbow stays 20-67° flexed with 1.4° of abduction.
//!
//! The allowed swing region is the convex "quadrant ellipse" with semi-axes equal to the four
//! range ends (flexion max / extension, abduction max / adduction): in each quadrant
//! `(flex / f)^2 + (abd / a)^2 <= 1`. It contains each pure range exactly and interpolates
//! between them (a shoulder flexed 90° may adduct 0.87 of its pure adduction, a knee flexed
//! 120° may only show 0.55 of its varus/valgus play). The twist range is an interval.
//!
//! # The anatomical neutral
//!
//! The avatar's rest pose (MakeHuman's A-pose: arms 40° abducted, elbows 47° flexed, knees
//! ~8° flexed, trunk bones drawn along the rest curvature, the hand bone's +Y 24° off the
//! middle finger) is *not* the anatomical zero, so limits are not relative to it. The limits
//! act on retargeted poses, so the neutral is the pose the retargeter produces for a performer
//! standing in the anatomical neutral ([`NeutralRule::Kinect`]): each Kinect-driven bone is
//! its rest frame carried onto the bone's Kinect T-pose direction (the retargeter's twist
//! convention), then turned with the sensor's zero-twist frame onto the neutral direction:
//!
//! * trunk, neck, head: vertical (an upright performer gives vertical spine bones);
//! * thigh, calf: vertical (legs straight and parallel, knees forward);
//! * upper arm, forearm, hand: hanging straight down with the forearm's zero twist of the
//!   sensor convention (the forearm and hand twists of the walking clips centre on it, medians
//!   0-7°: the mid position of pronation/supination), and the whole arm turned by
//!   [`ELBOW_HINGE_OFFSET_DEG`] about its axis so that the elbow's observed hinge is pure
//!   flexion (measured on all 15 clips: the same 25-36° on every clip);
//! * forearm twist bone: its rest local rotation (colinear, no twist);
//! * clavicle: lateral, [`KINECT_CLAVICLE_DROP_DEG`] below horizontal (the Kinect shoulder
//!   centre is above the shoulder line);
//! * foot: forward, [`KINECT_FOOT_PITCH_DEG`] below horizontal.
//!
//! Relative to the avatar's rest pose these neutrals differ by the offsets the axes report
//! prints (e.g. elbow 45° of flexion, knee 8°, spine_01 20°, clavicle 34°, hand 39°).
//! Where the Kinect mapping and the avatar's own anatomy disagree (the clavicle is drawn
//! horizontal but the Kinect shoulder bone points 20° down; the hand bone's +Y is not the
//! hand's axis but follows the performer's wrist -> hand direction; the avatar's ankle -> ball
//! bone follows the performer's ankle -> toe vector), the neutral follows the mapping so that
//! clean motion is inside the limits; these are retargeting offsets, not anatomy.
//!
//! # Clamping
//!
//! [`JointLimits::clamp`] projects the swing point onto the allowed region (nearest point in
//! the (flexion, abduction) chart, exact for the ellipse by bisection) and clamps the twist to
//! its interval, then recomposes `N * swing * twist`. A rotation inside the limits is
//! returned unchanged (bit for bit). The projection is continuous, so a trajectory that
//! leaves the region slides along its boundary instead of jumping.
//!
//! # Sources (per joint, see [`LIMIT_TABLE`])
//!
//! * **AAOS**: Greene & Heckman, *The Clinical Measurement of Joint Motion*, American Academy
//!   of Orthopaedic Surgeons, 1994 (the AAOS "average normal" ranges).
//! * **Soucie**: Soucie et al., "Range of motion measurements: reference values and a database
//!   for comparison studies", *Haemophilia* 17(3):500–507, 2011 (healthy 2–69 year-olds;
//!   used for hyperextension of elbow and knee: mean values of a few degrees, larger in women
//!   and children).
//! * **Kapandji**: I. A. Kapandji, *The Physiology of the Joints*, vols. 1–3 (shoulder
//!   adduction with flexion, lumbar/thoracic split of the trunk ranges, carrying angle, tibial
//!   rotation, atlanto-occipital motion).
//! * **Neumann**: D. A. Neumann, *Kinesiology of the Musculoskeletal System*, 2nd ed., 2010
//!   (sternoclavicular joint: elevation 45°, depression 10°, protraction/retraction 15–30°,
//!   posterior rotation 20–35°).
//!
//! Textbook values describe one anatomical joint; several avatar joints are driven by Kinect
//! bones that span more than one anatomical joint or segment (the clavicle by the shoulder
//! centre -> shoulder vector, the lumbar segment by hip centre -> spine, the neck by shoulder
//! centre -> head), and the retargeter maps motion-capture bones onto a differently
//! proportioned rig. Where clean motion capture (15 CMU clips) exceeds a textbook range the
//! range was widened and the row says so (`widened:`); the measured shares are in the test
//! report.
//!
//! # Modules
//!
//! - `anatomy`: the limited joints, the body's anatomical directions and how a joint's
//!   neutral is derived.
//! - `table`: the limits table ([`LIMIT_TABLE`]) with its sources.
//! - `joint`: one limited bone ([`JointLimit`]): its angles, the swing region, the clamp.
//! - here: [`JointLimits`], the limits of a whole skeleton.

mod anatomy;
mod joint;
mod table;

use glam::{Quat, Vec3};

use crate::retarget::{AvatarPose, AvatarSkeleton};

pub use anatomy::{Anat, JointKind, NeutralRule, Side};
pub use joint::{JointAngles, JointLimit, LimitPart, Violation};
pub use table::{LIMIT_TABLE, LimitSpec};

use anatomy::{anat_dir, kinect_neutral};

/// Violations smaller than this are ignored by [`JointLimits::violations`], degrees.
pub const DEFAULT_TOLERANCE_DEG: f32 = 0.5;

/// How far below horizontal the Kinect shoulder bone (shoulder centre -> shoulder) of an
/// upright performer points, degrees. The Kinect shoulder centre (CMU `neck` / `Neck1`) sits
/// 3-5 cm above the shoulder joints and ~17 cm medial; on the clean CMU clips the retargeted
/// clavicle's median elevation against the horizontal is -20..-25° (DAZ export) and -11..-19°
/// (MotionBuilder export).
pub const KINECT_CLAVICLE_DROP_DEG: f32 = 20.0;

/// How far below horizontal the Kinect foot bone (ankle -> foot) of a performer standing
/// flat points, degrees. Measured: a planted foot points 18° below horizontal in 07_01 (DAZ
/// export, ankle -> toe end site) and 13-25° in 16_11 (MotionBuilder export, ankle -> toe
/// base); over whole walking cycles the median is 3-6° (DAZ) and 16° (MotionBuilder) below.
/// 10° is a compromise; the ±10° uncertainty is why the dorsiflexion range was widened.
pub const KINECT_FOOT_PITCH_DEG: f32 = 10.0;

/// Twist of the hanging arm's neutral about its axis (the person's left arm turned
/// internally, i.e. the front towards medial; mirrored on the right), degrees. The elbow is a
/// hinge; through the retargeter its observed hinge axis (the swing axis of the forearm against
/// the upper arm) lies 25-36° (median 27°, the same on all 15 CMU clips, both BVH exports) from
/// the forward-flexion axis of the sensor's zero-twist frame: the source skeleton's humeral
/// twist in its T-pose. Turning the neutral of the whole arm (upper arm, forearm, hand) by this
/// angle makes elbow flexion a pure flexion, and centres the humeral rotation.
pub const ELBOW_HINGE_OFFSET_DEG: f32 = 27.0;

/// Options of [`JointLimits::new`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LimitOptions {
    /// Share of the forearm twist range given to the proximal forearm bone; must match
    /// [`crate::RetargetOptions::forearm_twist_share_proximal`].
    pub forearm_twist_share_proximal: f32,
    /// Violations up to this many degrees are not reported.
    pub tolerance_deg: f32,
}

impl Default for LimitOptions {
    fn default() -> Self {
        Self {
            forearm_twist_share_proximal: crate::RetargetOptions::default()
                .forearm_twist_share_proximal,
            tolerance_deg: DEFAULT_TOLERANCE_DEG,
        }
    }
}

/// The limits of every joint of an avatar skeleton.
#[derive(Clone, Debug, PartialEq)]
pub struct JointLimits {
    joints: Vec<JointLimit>,
    /// Index into `joints` per bone.
    by_bone: Vec<Option<usize>>,
    tolerance_rad: f32,
}

impl JointLimits {
    /// Builds the limits of [`LIMIT_TABLE`] for the bones of `skeleton` that exist (a missing
    /// bone is simply not limited; see [`JointLimits::joints`]).
    pub fn new(skeleton: &AvatarSkeleton, options: LimitOptions) -> Self {
        Self::from_table(skeleton, LIMIT_TABLE, options)
    }

    /// Builds limits from a custom table.
    pub fn from_table(
        skeleton: &AvatarSkeleton,
        table: &[LimitSpec],
        options: LimitOptions,
    ) -> Self {
        let bones = &skeleton.bones;
        let n = bones.len();
        let find = |name: &str| skeleton.index_of(name);
        let share = if options.forearm_twist_share_proximal.is_finite() {
            options.forearm_twist_share_proximal.clamp(0.0, 1.0)
        } else {
            0.5
        };

        let rule_of = |i: usize| -> Option<(JointKind, Side)> {
            let name = bones[i].name.as_str();
            table.iter().find_map(|spec| {
                let base = spec.kind.bone_base();
                if !spec.kind.sided() {
                    return (name == base).then_some((spec.kind, Side::Center));
                }
                match name.strip_prefix(base) {
                    Some("_l") => Some((spec.kind, Side::Left)),
                    Some("_r") => Some((spec.kind, Side::Right)),
                    _ => None,
                }
            })
        };

        // Rest palm normal and radial direction per side (sensor space), from the finger
        // bases: along = middle base - hand head, radial = index base - little finger base,
        // palm = along x radial (left) / radial x along (right).
        let hand_dirs = |side: Side| -> Option<(Vec3, Vec3)> {
            let sfx = if side == Side::Left { "_l" } else { "_r" };
            let hand = bones[find(&format!("hand{sfx}"))?].rest_head;
            let index = bones[find(&format!("index_01{sfx}"))?].rest_head;
            let pinky = bones[find(&format!("pinky_01{sfx}"))?].rest_head;
            let middle = bones[find(&format!("middle_01{sfx}"))?].rest_head;
            let along = (middle - hand).try_normalize()?;
            let radial = (index - pinky).try_normalize()?;
            let palm = if side == Side::Left {
                along.cross(radial)
            } else {
                radial.cross(along)
            };
            Some((palm.try_normalize()?, radial))
        };

        // Neutral global frames, parents first. A bone without a rule keeps its rest local
        // rotation under its (neutral) parent.
        let mut neutral_global: Vec<Quat> = Vec::with_capacity(n);
        let mut kinds: Vec<Option<(JointKind, Side)>> = Vec::with_capacity(n);
        for (i, bone) in bones.iter().enumerate() {
            let parent_neutral = match bone.parent {
                Some(p) if p < i => neutral_global[p],
                _ => Quat::IDENTITY,
            };
            let candidate = (parent_neutral * bone.rest_local_rotation).normalize();
            let kind = rule_of(i);
            kinds.push(kind);
            let global = match kind {
                None => candidate,
                Some((kind, side)) => match kind.neutral_rule() {
                    NeutralRule::RestLocal => candidate,
                    NeutralRule::Kinect(a, drop_deg) => {
                        let frame =
                            kinect_neutral(&bone.name, bone.rest_rotation, a, side, drop_deg)
                                .unwrap_or(candidate);
                        if matches!(
                            kind,
                            JointKind::Shoulder | JointKind::Elbow | JointKind::Wrist
                        ) {
                            // The humeral twist of the source's T-pose (see
                            // ELBOW_HINGE_OFFSET_DEG), applied to the whole hanging arm.
                            let sign = if side == Side::Left { 1.0 } else { -1.0 };
                            (Quat::from_axis_angle(
                                Vec3::NEG_Y,
                                sign * ELBOW_HINGE_OFFSET_DEG.to_radians(),
                            ) * frame)
                                .normalize()
                        } else {
                            frame
                        }
                    }
                },
            };
            neutral_global.push(global);
        }

        // Local neutrals, axes and ranges.
        let mut joints = Vec::new();
        let mut by_bone = vec![None; n];
        for (i, bone) in bones.iter().enumerate() {
            let Some((kind, side)) = kinds[i] else {
                continue;
            };
            let Some(spec) = table.iter().find(|s| s.kind == kind) else {
                continue;
            };
            let parent_neutral = match bone.parent {
                Some(p) if p < i => neutral_global[p],
                _ => Quat::IDENTITY,
            };
            let neutral = (parent_neutral.inverse() * neutral_global[i]).normalize();
            let (palmar, radial) = if kind == JointKind::Wrist {
                match hand_dirs(side) {
                    // Carried from the rest hand into its neutral frame, in sensor space.
                    Some((p, r)) => {
                        let to_neutral = neutral_global[i] * bone.rest_rotation.inverse();
                        (to_neutral * p, to_neutral * r)
                    }
                    None => continue,
                }
            } else {
                (Vec3::ZERO, Vec3::ZERO)
            };
            let (flex, abd, probe, towards) = kind.directions();
            let to_local = neutral_global[i].inverse();
            let local = |a: Anat| to_local * anat_dir(a, side, palmar, radial);
            let y = Vec3::Y;
            let flexion_axis = {
                let a = y.cross(local(flex));
                Vec3::new(a.x, 0.0, a.z).try_normalize()
            };
            let Some(flexion_axis) = flexion_axis else {
                continue;
            };
            let abduction_axis = {
                let candidate = y.cross(flexion_axis);
                let wanted = y.cross(local(abd));
                if candidate.dot(wanted) >= 0.0 {
                    candidate
                } else {
                    -candidate
                }
            };
            let twist_sign = {
                let p = local(probe);
                if y.cross(p).dot(local(towards)) >= 0.0 {
                    1.0
                } else {
                    -1.0
                }
            };
            let rad = |r: (f32, f32)| (r.0.to_radians(), r.1.to_radians());
            let mut twist = rad(spec.twist_deg);
            match kind {
                JointKind::Elbow => twist = (twist.0 * share, twist.1 * share),
                JointKind::ForearmTwist => {
                    twist = (twist.0 * (1.0 - share), twist.1 * (1.0 - share))
                }
                _ => {}
            }
            by_bone[i] = Some(joints.len());
            joints.push(JointLimit {
                bone: i,
                name: bone.name.clone(),
                kind,
                side,
                neutral,
                flexion_axis,
                abduction_axis,
                twist_sign,
                flexion: rad(spec.flexion_deg),
                abduction: rad(spec.abduction_deg),
                twist,
            });
        }
        Self {
            joints,
            by_bone,
            tolerance_rad: options.tolerance_deg.max(0.0).to_radians(),
        }
    }

    /// The limited joints.
    pub fn joints(&self) -> &[JointLimit] {
        &self.joints
    }

    /// The limit of a bone, if it has one.
    pub fn joint(&self, bone: usize) -> Option<&JointLimit> {
        self.by_bone
            .get(bone)
            .copied()
            .flatten()
            .map(|k| &self.joints[k])
    }

    /// The nearest allowed local rotation of `bone` (relative to its parent); the input itself
    /// if allowed or if the bone is not limited.
    pub fn clamp(&self, bone: usize, local: Quat) -> Quat {
        match self.joint(bone) {
            Some(j) => j.clamp(local),
            None => local,
        }
    }

    /// Clamps every limited joint of `pose` and recomputes its global rotations and heads
    /// (the roots keep their heads). Returns the number of joints changed.
    pub fn clamp_pose(&self, skeleton: &AvatarSkeleton, pose: &mut AvatarPose) -> usize {
        let mut changed = 0;
        for j in &self.joints {
            if let Some(local) = pose.local_rotations.get_mut(j.bone) {
                let clamped = j.clamp(*local);
                if clamped != *local {
                    *local = clamped;
                    changed += 1;
                }
            }
        }
        if changed > 0 {
            crate::ik::forward_kinematics(skeleton, pose);
        }
        changed
    }

    /// The joints of `pose` outside their limits by more than the tolerance.
    pub fn violations(&self, pose: &AvatarPose) -> Vec<Violation> {
        let mut out = Vec::new();
        for j in &self.joints {
            let Some(&local) = pose.local_rotations.get(j.bone) else {
                continue;
            };
            let angles = j.angles(local);
            let (swing, twist, _) = j.excess(angles);
            let deg = JointAngles {
                flexion: angles.flexion.to_degrees(),
                abduction: angles.abduction.to_degrees(),
                twist: angles.twist.to_degrees(),
            };
            for (part, excess) in [(LimitPart::Swing, swing), (LimitPart::Twist, twist)] {
                if excess > self.tolerance_rad || excess.is_nan() {
                    out.push(Violation {
                        bone: j.bone,
                        kind: j.kind,
                        side: j.side,
                        part,
                        excess_deg: excess.to_degrees(),
                        angles_deg: deg,
                    });
                }
            }
        }
        out
    }

    /// A human-readable list of each joint's local axes (neutral frame) and neutral offset
    /// from the rest pose.
    pub fn axes_report(&self, skeleton: &AvatarSkeleton) -> String {
        let mut s = String::new();
        for j in &self.joints {
            let rest = skeleton.bones[j.bone].rest_local_rotation;
            let offset = (j.neutral.inverse() * rest).normalize();
            let a = j.angles(rest);
            s.push_str(&format!(
                "{:<18} flex axis {:>6.2?} abd axis {:>6.2?} twist sign {:+} | rest = \
                 flex {:+6.1} abd {:+6.1} twist {:+6.1} (offset {:5.1}°)\n",
                j.name,
                j.flexion_axis,
                j.abduction_axis,
                j.twist_sign,
                a.flexion.to_degrees(),
                a.abduction.to_degrees(),
                a.twist.to_degrees(),
                offset.angle_between(Quat::IDENTITY).to_degrees(),
            ));
        }
        s
    }
}
