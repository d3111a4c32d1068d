//! Parts of the person that a depth edge cut off from the rest of them. Turned to the side,
//! the far arm hangs behind the body: its shoulder is hidden, and where it shows past the
//! back it lies tens of centimetres deeper than the body beside it, so the labelling makes
//! it a component of its own; a hand held out towards the sensor can part from the arm the
//! same way. Such a component borders the person in the image, is small, lies within the
//! person's depth (give or take an arm), and does not stand on the floor (a box or a chair
//! beside them does; a second person, behind, is a person of their own and much deeper).
//!
//! Without them the tracker saw no far arm (its fit left the arm where the last frame had
//! it) and the measurement lost a thousand pixels of the turned view.
//!
//! A component mostly made of the last frame's person's pixels is theirs whatever its size,
//! depth or height: bowing deep towards the sensor, the trunk comes in front of the thighs,
//! half a metre nearer than the legs, and with the hands hanging near the floor it looks like
//! a person of its own. A part may border the person through another part (the head, parted
//! from that trunk).

use fitroom_depth::{HEIGHT, WIDTH};

use super::Stats;
use super::components::Run;

/// A part has at least this many pixels: slivers (the neck under the chin, a few pixels
/// cut off by the edge's noise) tell the tracker little.
const MIN_PIXELS: usize = 40;
/// A part is smaller than this (frontal area), m²: an arm is about 0.07 m² at 2.5 m.
const MAX_AREA_M2: f32 = 0.2;
/// A part lies at most this much deeper than the person's deepest reading, metres (an arm
/// hanging behind a body turned sideways; a second person passing behind is farther).
const BEHIND_M: f32 = 0.4;
/// ... and at most this much nearer than their nearest one (a hand held out), metres.
const IN_FRONT_M: f32 = 0.6;
/// A part's lowest point is at least this high above the floor, metres: what stands on
/// the floor beside the person is not theirs.
const ABOVE_FLOOR_M: f32 = 0.15;
/// A part reaches at most this far beside the person, sensor x, metres.
const REACH_M: f32 = 0.9;
/// Pixels without a reading bridged between a part and the person (the projector's
/// shadow falls beside a depth edge).
const GAP_PX: usize = 4;
/// A part borders the person along at least this many of its pixels.
const MIN_TOUCH: usize = 4;

/// Fills `parts` with the components (numbers of `runs`) that are parts of the `person`
/// component, whose pixels are `mask`, each with the count of its pixels that border the
/// person or a part joined before (up to [`MIN_TOUCH`]), and adds their pixels to `mask`;
/// `people` are the other components that look like people themselves. (`parts` is the
/// segmenter's scratch: no allocation per frame.)
pub(super) fn parts_of(
    person: u32,
    mask: &mut [bool],
    raw_mm: &[u16],
    runs: &[Run],
    stats: &[Stats],
    people: &[usize],
    parts: &mut Vec<(u32, usize)>,
) {
    parts.clear();
    let Some(p) = stats.get(person as usize) else {
        return;
    };
    let candidate = |c: usize, s: &Stats| {
        c != 0
            && c != person as usize
            && !s.too_large
            && s.pixels >= MIN_PIXELS
            && (s.was_theirs()
                || (!people.contains(&c)
                    && s.area_m2 <= MAX_AREA_M2
                    && s.bottom_m >= ABOVE_FLOOR_M
                    && s.min.z >= p.min.z - IN_FRONT_M))
            && s.max.z <= p.max.z + BEHIND_M
            && s.min.x >= p.min.x - REACH_M
            && s.max.x <= p.max.x + REACH_M
    };
    parts.extend(
        stats
            .iter()
            .enumerate()
            .filter(|&(c, s)| candidate(c, s))
            .map(|(c, _)| (c as u32, 0)),
    );
    if parts.is_empty() {
        return;
    }
    // Candidates are few (none in most frames): found among them by a look along the list.
    // A part may border the person through another part (a head parted from the trunk that
    // a deep bow parted from the legs): looked at again while parts join.
    let mut joined = 0;
    loop {
        for (_, touches) in &mut parts[joined..] {
            *touches = 0;
        }
        for run in runs {
            let Some((_, touches)) = parts[joined..]
                .iter_mut()
                .find(|(c, _)| *c == run.component)
            else {
                continue;
            };
            let (row, start, end) = (
                usize::from(run.row),
                usize::from(run.start),
                usize::from(run.end),
            );
            for col in start..end {
                if *touches >= MIN_TOUCH {
                    break;
                }
                let ends = [(col == start, Step::Left), (col + 1 == end, Step::Right)];
                let sideways = ends.iter().filter(|(at, _)| *at).map(|(_, s)| *s);
                let touching = [Step::Up, Step::Down]
                    .into_iter()
                    .chain(sideways)
                    .any(|step| reaches_person(mask, raw_mm, row, col, step));
                *touches += usize::from(touching);
            }
        }
        // The parts that touch move to the front, after those joined before, and join.
        let before = joined;
        for k in before..parts.len() {
            if parts[k].1 >= MIN_TOUCH {
                parts.swap(joined, k);
                super::fill(mask, runs, parts[joined].0);
                joined += 1;
            }
        }
        if joined == before || joined == parts.len() {
            break;
        }
    }
    parts.truncate(joined);
}

#[derive(Clone, Copy)]
enum Step {
    Left,
    Right,
    Up,
    Down,
}

/// Whether, from pixel (`row`, `col`) one `step` at a time, the person's pixels are reached
/// across at most [`GAP_PX`] pixels without a reading.
fn reaches_person(mask: &[bool], raw_mm: &[u16], row: usize, col: usize, step: Step) -> bool {
    let (mut r, mut c) = (row, col);
    for _ in 0..=GAP_PX {
        let next = match step {
            Step::Left => c.checked_sub(1).map(|c| (r, c)),
            Step::Right => (c + 1 < WIDTH).then_some((r, c + 1)),
            Step::Up => r.checked_sub(1).map(|r| (r, c)),
            Step::Down => (r + 1 < HEIGHT).then_some((r + 1, c)),
        };
        let Some(at) = next else {
            return false;
        };
        (r, c) = at;
        let k = r * WIDTH + c;
        if mask[k] {
            return true;
        }
        if raw_mm[k] > 0 {
            return false;
        }
    }
    false
}
