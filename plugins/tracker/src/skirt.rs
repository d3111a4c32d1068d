//! A skirt over the legs, found in the depth: below the hip joints, bare legs part at the
//! crotch (a gap, or, pressed together, a crease where the thighs meet); a skirt is one
//! surface across them down to its hem.
//!
//! Why: fitted as skin, a skirt's points drew the thighs forward and the calves down, and the
//! knees bent: the person sank into it (the sun dress, the median man with his true build:
//! hip centre 67 mm low, knees 88 mm forward; docs/STATUS.md, session 51). Where it is
//! found, its points are left out of the tracker's fit ([`crate::fit::Observation::skirt`]);
//! where it is worn but not found ([`SkirtMemory`], below), kept but weighed as a skirt's. The
//! build's fit (`fitroom_measure::build`) drops the skirt's heights either way; the silhouette
//! and free space still hold the legs inside it.
//!
//! How: in 2 cm slabs down from the hip joints of the pose followed into the frame, the
//! pixels between the two joints' columns must all be the person's, and the depth midway
//! between them no more than [`SkirtSettings::crease_m`] behind the depth at the joints'
//! columns (readings averaged, [`crate::denoise`]). The first slab that fails is the fork:
//! bare legs fork 4-10 cm below the joints, a skirt at its hem. A fork
//! [`SkirtSettings::fork_m`] or more below is a skirt's if there the legs part (a crease, or
//! a gap at the middle with the person on both sides below it), not if the person ends
//! (upside down, the flipped trunk is one surface below the followed pose's hips down to
//! the head). Seen from the side, the legs overlap in the image and nothing is judged.
//!
//! The zone is bounded sideways ([`SkirtSettings::width`], [`SkirtSettings::flare`]): a
//! hand hanging beside the skirt keeps its points, so an arm the fit lost there can be found
//! again.
//!
//! A skirt is worn, not a frame's accident: in about half of a dress's frames the fork is
//! not seen (a shin across the middle column, the person turned aside, the cloth creased
//! between walking legs), and there its points, fitted as skin, drew the body down into it.
//! [`SkirtMemory`] keeps the skirt found in enough of the last seconds' frames, its hem as far
//! below the hip joints as when last found; where it is worn but not found, its points are
//! kept, those outside the body pulling weakly ([`crate::fit::FitSettings::skirt_worn_weight`]:
//! left out, a hand or a leg the fit lost there had nothing to find it by).

use std::collections::VecDeque;

use fitroom_depth::{DepthCamera, DepthFrame, HEIGHT, WIDTH};
use glam::Vec3;

use crate::denoise::surface_depth_m;

/// Where a skirt hides the legs: between two heights along the floor's normal, and
/// sideways no further from the middle between the hip joints than the hips' width, flaring
/// below (beyond: a hand hanging beside the skirt).
#[derive(Clone, Debug, PartialEq)]
pub struct SkirtZone {
    pub up: Vec3,
    /// Heights (along `up`, sensor space) of the zone's top and of the hem, metres.
    pub top: f32,
    pub hem: f32,
    /// The middle between the hip joints, and the unit direction from the right one to the
    /// left one across `up`.
    pub centre: Vec3,
    pub across: Vec3,
    /// How far sideways from `centre` the zone reaches at its top, metres, and how much
    /// further per metre down.
    pub half_width_m: f32,
    pub flare: f32,
    /// Found in this frame (its points left out of the fit), or worn, found in the last
    /// frames ([`SkirtMemory`]): its points outside the body pull weakly
    /// ([`crate::fit::FitSettings::skirt_worn_weight`]).
    pub seen: bool,
}

impl SkirtZone {
    /// Whether `p` lies in the zone's heights.
    pub fn in_heights(&self, p: Vec3) -> bool {
        let h = self.up.dot(p);
        h <= self.top && h >= self.hem
    }

    /// Whether `p` lies in the zone.
    pub fn hides(&self, p: Vec3) -> bool {
        let side = (p - self.centre).dot(self.across).abs();
        self.in_heights(p) && side <= self.half_width_m + self.flare * (self.top - self.up.dot(p))
    }
}

/// How a skirt is found.
#[derive(Clone, Copy, Debug)]
pub struct SkirtSettings {
    /// The legs must stay one surface this far below the hip joints, metres (bare legs
    /// part at the crotch, 8-12 cm below). 0: no skirt looked for.
    pub fork_m: f32,
    /// A crease this deep at the middle between the hip joints' columns is two legs, metres.
    pub crease_m: f32,
    /// Height of the slabs the surface is judged in, metres.
    pub slab_m: f32,
    /// The zone's half-width at the hip joints as a multiple of half their spacing, and its
    /// flare (metres sideways per metre down).
    pub width: f32,
    pub flare: f32,
    /// A skirt found in at least `memory_share` of the frames of the last `memory_s` seconds
    /// is worn in the frames it is not found in ([`SkirtMemory`]); 0 s: each frame alone.
    pub memory_s: f32,
    pub memory_share: f32,
}

impl Default for SkirtSettings {
    fn default() -> Self {
        Self {
            fork_m: 0.25,
            // Bare legs on the acceptance set's recordings show +14 to +46 mm within 8 cm of
            // the hip joints; the sun dress -40 to +13 mm down to its hem.
            crease_m: 0.03,
            slab_m: 0.02,
            // Hands hang 2.2-2.6 times the hip joints' half spacing from their middle (the
            // acceptance set's dress recordings, medians per body). Mean error over those
            // recordings: 64.0 mm with 2.0 and 0.5, 64.3 with 1.5 and 0.3, 64.2 unbounded.
            width: 2.0,
            flare: 0.5,
            // Found on bare legs in at most 8 frames of any 2 s, and never in 10 % of any
            // 3 s (the acceptance set's 180 bare and T-shirt recordings, both noise sets);
            // with the sun dress in 10 % of the last 3 s in 78 % of the frames, against 41 %
            // found frame by frame.
            memory_s: 3.0,
            memory_share: 0.1,
        }
    }
}

/// The skirt in `frame` (the person's pixels `mask`), judged about the hip joints `left`,
/// `right` (sensor space) of the pose followed into the frame; `None`: no skirt (or the hips
/// seen too much from the side to tell).
pub fn skirt_zone(
    frame: &DepthFrame,
    mask: &[bool],
    up: Vec3,
    left: Vec3,
    right: Vec3,
    settings: &SkirtSettings,
) -> Option<SkirtZone> {
    if settings.fork_m <= 0.0 {
        return None;
    }
    let camera = frame.camera;
    if !legs_apart_in_image(&camera, left, right) {
        return None;
    }
    let (pl, pr) = (camera.project(left)?, camera.project(right)?);
    let mid = (left + right) * 0.5;
    let (a, b) = (pl.x.min(pr.x), pl.x.max(pr.x));
    let (ca, cb) = (a.round() as usize, b.round() as usize);
    let cm = ((a + b) * 0.5).round() as usize;
    if cb >= WIDTH {
        return None;
    }
    let depth = |x: usize, y: usize| surface_depth_m(&frame.depth_mm, mask, x, y, 2);
    let person = |x: usize, y: usize| {
        let k = y * WIDTH + x;
        mask.get(k).copied().unwrap_or(false) && frame.depth_mm.get(k).is_some_and(|&mm| mm > 0)
    };
    // A gap at the middle with the person on either side of it (the strip widened by half on
    // each side: knees stand closer than hips).
    let half = (cb - ca) / 2;
    let (lo, hi) = (ca.saturating_sub(half), (cb + half).min(WIDTH - 1));
    let legs_apart = |y: usize| {
        !person(cm, y) && (lo..cm).any(|x| person(x, y)) && (cm + 1..=hi).any(|x| person(x, y))
    };
    let row_at = |d: f32| {
        camera
            .project(mid - up * d)
            .map(|p| p.y.round().max(0.0) as usize)
    };
    let mut s = 0.0f32;
    // Whether the fork is the legs parting, not the body ending (an upside-down person's
    // head, the image's edge).
    let mut parted = false;
    while s < 1.0 {
        let (Some(r0), Some(r1)) = (row_at(s), row_at(s + settings.slab_m)) else {
            return None;
        };
        // Down to the image's bottom edge: a skirt is judged where it is seen.
        if r0 >= HEIGHT {
            break;
        }
        let r1 = r1.min(HEIGHT - 1);
        let (mut filled, mut total) = (0usize, 0usize);
        let (mut sm, mut nm, mut ss, mut ns) = (0.0f32, 0usize, 0.0f32, 0usize);
        for y in r0..=r1.max(r0) {
            for x in ca..=cb {
                total += 1;
                if person(x, y) {
                    filled += 1;
                }
            }
            if let Some(d) = depth(cm, y) {
                sm += d;
                nm += 1;
            }
            for x in [ca, cb] {
                if let Some(d) = depth(x, y) {
                    ss += d;
                    ns += 1;
                }
            }
        }
        let full = total > 0 && filled * 10 >= total * 9;
        let crease = if nm > 0 && ns > 0 {
            sm / nm as f32 - ss / ns as f32
        } else {
            f32::INFINITY
        };
        if !full || crease > settings.crease_m {
            // The legs parting: a crease, or, in most rows of the 6 cm from the fork (the
            // slab that holds the hem is half skirt), a gap at the middle with the person
            // on either side.
            parted = full
                || match row_at(s + 3.0 * settings.slab_m) {
                    Some(end) => {
                        let rows = r0..=end.clamp(r0, HEIGHT - 1);
                        let n = rows.clone().count();
                        rows.filter(|&y| legs_apart(y)).count() * 2 >= n
                    }
                    None => false,
                };
            break;
        }
        s += settings.slab_m;
    }
    (parted && s >= settings.fork_m).then(|| SkirtZone::below(up, left, right, s, settings))
}

/// Whether the hip joints `left`, `right` face the sensor enough that the legs below them do
/// not overlap in the image (10 cm apart across the line of sight).
pub fn legs_apart_in_image(camera: &DepthCamera, left: Vec3, right: Vec3) -> bool {
    let (Some(pl), Some(pr)) = (camera.project(left), camera.project(right)) else {
        return false;
    };
    let z = ((left + right) * 0.5).z.max(0.5);
    (pl.x - pr.x).abs() >= 0.1 * camera.fx / z
}

impl SkirtZone {
    /// The zone of a skirt whose hem is `drop_m` below the hip joints `left`, `right`.
    pub fn below(up: Vec3, left: Vec3, right: Vec3, drop_m: f32, settings: &SkirtSettings) -> Self {
        let mid = (left + right) * 0.5;
        let top = up.dot(mid);
        let across = (left - right) - up * up.dot(left - right);
        SkirtZone {
            up,
            top,
            hem: top - drop_m,
            centre: mid,
            across: across.normalize_or_zero(),
            half_width_m: settings.width * across.length() * 0.5,
            flare: settings.flare,
            seen: true,
        }
    }

    /// How far the hem is below the hip joints, metres.
    pub fn drop_m(&self) -> f32 {
        self.top - self.hem
    }
}

/// The most frames [`SkirtMemory`] holds (10 s at 30 Hz).
const MEMORY_FRAMES: usize = 300;

/// The skirts found in the last frames ([`SkirtSettings::memory_s`]).
#[derive(Clone, Debug, Default)]
pub struct SkirtMemory {
    /// Each frame judged in the window: its time, s, and the hem's drop below the hip
    /// joints, metres, if a skirt was found in it.
    frames: VecDeque<(f64, Option<f32>)>,
}

impl SkirtMemory {
    /// Notes the frame at `time_s` and the skirt found in it, if any.
    pub fn note(&mut self, time_s: f64, found: Option<&SkirtZone>, settings: &SkirtSettings) {
        // Time going back (a recording replayed from its start) is a new window.
        if self.frames.back().is_some_and(|&(t, _)| t > time_s) {
            self.frames.clear();
        }
        self.frames
            .push_back((time_s, found.map(SkirtZone::drop_m)));
        let since = time_s - f64::from(settings.memory_s);
        // Bounded also by count: a stalled clock must not grow the window for ever.
        while self.frames.front().is_some_and(|&(t, _)| t < since)
            || self.frames.len() > MEMORY_FRAMES
        {
            self.frames.pop_front();
        }
    }

    /// The hem's drop below the hip joints of the skirt worn (the last found), metres, if one
    /// was found in enough of the window's frames.
    pub fn worn(&self, settings: &SkirtSettings) -> Option<f32> {
        if settings.memory_s <= 0.0 {
            return None;
        }
        // Judged over at least half the window (a few frames are no evidence either way).
        let (Some(&(first, _)), Some(&(last, _))) = (self.frames.front(), self.frames.back())
        else {
            return None;
        };
        let found = self.frames.iter().filter(|(_, d)| d.is_some()).count();
        let enough = found as f32 >= settings.memory_share * self.frames.len() as f32;
        if last - first < 0.5 * f64::from(settings.memory_s) || found == 0 || !enough {
            return None;
        }
        self.frames.iter().rev().find_map(|&(_, d)| d)
    }

    /// Forgets the frames noted (another person).
    pub fn clear(&mut self) {
        self.frames.clear();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn zone(drop_m: f32) -> SkirtZone {
        let settings = SkirtSettings::default();
        let (left, right) = (Vec3::new(0.1, 0.0, 2.5), Vec3::new(-0.1, 0.0, 2.5));
        SkirtZone::below(Vec3::Y, left, right, drop_m, &settings)
    }

    /// Notes `frames` frames at 30 Hz from `start_s`, a skirt `drop_m` below the hips found
    /// in those for which `found(k)` holds.
    fn note(
        memory: &mut SkirtMemory,
        start_s: f64,
        frames: usize,
        drop_m: f32,
        found: impl Fn(usize) -> bool,
    ) {
        let settings = SkirtSettings::default();
        for k in 0..frames {
            let z = found(k).then(|| zone(drop_m));
            memory.note(start_s + k as f64 / 30.0, z.as_ref(), &settings);
        }
    }

    #[test]
    fn a_skirt_found_in_enough_of_the_last_seconds_is_worn() {
        let settings = SkirtSettings::default();
        let mut memory = SkirtMemory::default();
        // One frame in five for 3 s: worn, the hem as far below as last found.
        note(&mut memory, 0.0, 45, 0.4, |k| k % 5 == 0);
        note(&mut memory, 1.5, 45, 0.5, |k| k % 5 == 0);
        assert_eq!(memory.worn(&settings), Some(0.5));
        // Then not found for long: the share falls below 10 % of the last 3 s.
        note(&mut memory, 3.0, 80, 0.5, |_| false);
        assert_eq!(memory.worn(&settings), None);
    }

    #[test]
    fn a_few_frames_or_a_rare_find_are_no_skirt() {
        let settings = SkirtSettings::default();
        // Found in every frame, but for 1 s only: too short a window to judge.
        let mut memory = SkirtMemory::default();
        note(&mut memory, 0.0, 30, 0.4, |_| true);
        assert_eq!(memory.worn(&settings), None);
        // One frame in 15 over 3 s (bare legs taken for a skirt now and then).
        note(&mut memory, 1.0, 90, 0.4, |k| k % 15 == 0);
        assert!(memory.worn(&settings).is_none());
        // Time going back (a recording replayed) starts a new window: 2 s without a skirt
        // after one worn is none (the frames before the jump would have made it worn).
        note(&mut memory, 0.0, 90, 0.4, |_| true);
        assert!(memory.worn(&settings).is_some());
        note(&mut memory, 0.0, 60, 0.4, |_| false);
        assert_eq!(memory.worn(&settings), None);
        // Cleared (another person): none.
        note(&mut memory, 2.0, 90, 0.4, |_| true);
        assert!(memory.worn(&settings).is_some());
        memory.clear();
        assert_eq!(memory.worn(&settings), None);
        // Switched off.
        let off = SkirtSettings {
            memory_s: 0.0,
            ..settings
        };
        note(&mut memory, 0.0, 90, 0.4, |_| true);
        assert!(memory.worn(&settings).is_some());
        assert_eq!(memory.worn(&off), None);
    }

    #[test]
    fn a_zone_below_the_hips_reaches_the_hem_and_flares() {
        let z = zone(0.5);
        assert!((z.drop_m() - 0.5).abs() < 1e-6);
        // The hips 0.2 m apart, the zone twice their half spacing wide at the top.
        assert!(z.hides(Vec3::new(0.19, -0.01, 2.5)));
        assert!(!z.hides(Vec3::new(0.21, -0.01, 2.5)));
        // 0.4 m down it reaches 0.2 m further out; not below the hem nor above the top.
        assert!(z.hides(Vec3::new(0.39, -0.4, 2.5)));
        assert!(!z.hides(Vec3::new(0.0, -0.55, 2.5)));
        assert!(!z.hides(Vec3::new(0.0, 0.05, 2.5)));
    }
}
