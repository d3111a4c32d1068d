//! Connected components of the readings above the floor, by depth continuity: a scanline
//! labelling with union-find (two passes over the image, row by row, cache-friendly) that
//! gives exactly the components, numbered in the same order, of the flood fill it replaced.
//!
//! That flood fill took the unlabelled readings in raster order and gave each one's new
//! component every reading it reaches, joining a reading `a` to a 4-neighbour `b` when
//! `|za - zb| < join_m + 3 % za`. That test is not symmetric: seen from the farther reading
//! it passes more easily, so a join may hold one way only. A reading's component is therefore
//! that of the first reading, in raster order, that reaches it. Here:
//!
//! 1. joins that hold both ways are unions of provisional labels, each set's root its
//!    smallest label, which is that of its first pixel in raster order (every reading of a
//!    set reaches every other);
//! 2. the rare joins that hold one way only are kept, and followed between the sets, taking
//!    the sets in the order of their roots: as the flood fill did, at the scale of sets.

use fitroom_depth::{HEIGHT, PIXELS, WIDTH};

/// Pixels `start..end` of row `row`: readings joined both ways each to the one on its left
/// (but the first), so one component.
#[derive(Clone, Copy, Debug)]
pub struct Run {
    pub row: u16,
    pub start: u16,
    pub end: u16,
    /// Its provisional label, then (after [`Components::find`]) its component.
    pub component: u32,
}

/// The components of a frame, and the memory their finding reuses from frame to frame.
#[derive(Default)]
pub struct Components {
    /// The runs of a row's readings joined both ways, in raster order; every reading is in
    /// one. Their components are numbered from 1 in the order of their first pixels.
    pub runs: Vec<Run>,
    /// How many components there are.
    pub count: usize,
    /// The provisional labels of two rows' readings: the row being labelled and the one
    /// above, taking turns.
    rows: Vec<u32>,
    /// Union-find over provisional labels: a label's parent is never larger than it.
    parent: Vec<u32>,
    /// Joins that hold one way only, `(from, to)`, between provisional labels.
    one_way: Vec<(u32, u32)>,
    /// Per provisional label, its component (0: not yet known).
    component: Vec<u32>,
    /// Sets still to follow while components are resolved.
    stack: Vec<u32>,
    /// One row's joins, per pixel (bits [`READING`], [`LEFT_TO`], ...).
    flags: Vec<u32>,
}

/// A reading, above the floor band.
const READING: u32 = 1;
/// Joined to the reading on the left; that reading joined to it; both.
const LEFT_TO: u32 = 2;
const LEFT_FROM: u32 = 4;
const LEFT: u32 = LEFT_TO | LEFT_FROM;
/// The same with the reading above.
const UP_TO: u32 = 8;
const UP_FROM: u32 = 16;
const UP: u32 = UP_TO | UP_FROM;

/// Whether flags `f` hold a join one way only.
fn holds_one_way(f: u32) -> bool {
    (f ^ (f >> 1)) & (LEFT_TO | UP_TO) != 0
}

impl Components {
    /// Finds the components of `depth` (per pixel, metres; 0: no reading), readings joined
    /// when `|Δz| < join_m + 3 %` of the depth of the one they are seen from.
    pub fn find(&mut self, depth: &[f32], join_m: f32) {
        assert_eq!(depth.len(), PIXELS);
        self.label_runs(depth, join_m);
        self.resolve();
        for run in &mut self.runs {
            run.component = self.component[run.component as usize];
        }
    }

    /// First pass: gives each run of a row a provisional label, joined to those above it.
    ///
    /// A row's joins are tested first, for all its pixels at once (that loop vectorises);
    /// then each run takes the label of the runs above it joined both ways (their sets
    /// united when there are several), or a new one.
    fn label_runs(&mut self, depth: &[f32], join_m: f32) {
        let Self {
            rows,
            runs,
            parent,
            one_way,
            flags,
            ..
        } = self;
        rows.resize(2 * WIDTH, 0);
        flags.resize(WIDTH, 0);
        parent.clear();
        parent.push(0);
        one_way.clear();
        runs.clear();
        // The row above the first: no readings. Labels are read only where there are
        // readings (those of the row above where it has some, even at the first row: none).
        let no_depth = [0.0; WIDTH];
        for j in 0..HEIGHT {
            let (even, odd) = rows.split_at_mut(WIDTH);
            let (labels, labels_up) = if j % 2 == 0 { (even, odd) } else { (odd, even) };
            let labels_up = &*labels_up;
            let depth_up = match j {
                0 => &no_depth[..],
                _ => &depth[(j - 1) * WIDTH..j * WIDTH],
            };
            let any = row_joins(join_m, &depth[j * WIDTH..(j + 1) * WIDTH], depth_up, flags);
            let flags = &flags[..];
            // Each run: its label so far (0: none yet) and the last label above it was
            // joined to, to skip the pixels joined to the same set as the one before.
            let mut i = 0;
            while i < WIDTH {
                if flags[i] & READING == 0 {
                    i += 1;
                    continue;
                }
                let start = i;
                let (mut mine, mut last_up) = (0, 0);
                loop {
                    if flags[i] & UP == UP && labels_up[i] != last_up {
                        last_up = labels_up[i];
                        mine = match mine {
                            0 => last_up,
                            mine => union(parent, mine, last_up),
                        };
                    }
                    i += 1;
                    if i == WIDTH || flags[i] & LEFT != LEFT {
                        break;
                    }
                }
                if mine == 0 {
                    mine = parent.len() as u32;
                    parent.push(mine);
                }
                labels[start..i].fill(mine);
                runs.push(Run {
                    row: j as u16,
                    start: start as u16,
                    end: i as u16,
                    component: mine,
                });
            }
            if any {
                for (i, &f) in flags.iter().enumerate().filter(|&(_, &f)| holds_one_way(f)) {
                    let mine = labels[i];
                    let left = (f & LEFT, labels[i.saturating_sub(1)]);
                    let up = ((f & UP) >> 2, labels_up[i]);
                    for (joins, theirs) in [left, up] {
                        match joins {
                            LEFT_TO => one_way.push((mine, theirs)),
                            LEFT_FROM => one_way.push((theirs, mine)),
                            _ => {}
                        }
                    }
                }
            }
        }
    }

    /// Second step: the component of each provisional label, following the one-way joins
    /// between sets from the sets taken in the order of their roots (their first pixels).
    fn resolve(&mut self) {
        let Self {
            parent,
            one_way,
            component,
            stack,
            ..
        } = self;
        let labels = parent.len();
        // Every label straight to its root (a parent is never larger than its child).
        for l in 1..labels {
            parent[l] = parent[parent[l] as usize];
        }
        for edge in one_way.iter_mut() {
            *edge = (parent[edge.0 as usize], parent[edge.1 as usize]);
        }
        one_way.retain(|&(from, to)| from != to);
        one_way.sort_unstable();
        one_way.dedup();
        component.clear();
        component.resize(labels, 0);
        let mut count = 0;
        for root in 1..labels {
            if parent[root] as usize != root || component[root] != 0 {
                continue;
            }
            count += 1;
            component[root] = count;
            stack.clear();
            stack.push(root as u32);
            while let Some(from) = stack.pop() {
                let first = one_way.partition_point(|&(f, _)| f < from);
                for &(_, to) in one_way[first..].iter().take_while(|&&(f, _)| f == from) {
                    if component[to as usize] == 0 {
                        component[to as usize] = count;
                        stack.push(to);
                    }
                }
            }
        }
        for l in 1..labels {
            component[l] = component[parent[l] as usize];
        }
        self.count = count as usize;
    }
}

/// Fills `flags` with the joins of each reading of a row (`depth`) to its left and upper
/// neighbours (`depth_up`, the row above); returns whether any holds one way only.
/// Branch-free, so that it vectorises.
fn row_joins(join_m: f32, depth: &[f32], depth_up: &[f32], flags: &mut [u32]) -> bool {
    let pixel = |z: f32, left: f32, up: f32| {
        let reading = z > 0.0;
        let (has_left, has_up) = (reading & (left > 0.0), reading & (up > 0.0));
        let (to_left, to_up) = ((left - z).abs(), (up - z).abs());
        let reach = join_m + 0.03 * z;
        (u32::from(reading) * READING)
            | (u32::from(has_left & (to_left < reach)) * LEFT_TO)
            | (u32::from(has_left & (to_left < join_m + 0.03 * left)) * LEFT_FROM)
            | (u32::from(has_up & (to_up < reach)) * UP_TO)
            | (u32::from(has_up & (to_up < join_m + 0.03 * up)) * UP_FROM)
    };
    flags[0] = pixel(depth[0], 0.0, depth_up[0]);
    for (((f, &z), &left), &up) in flags[1..]
        .iter_mut()
        .zip(&depth[1..])
        .zip(&depth[..WIDTH - 1])
        .zip(&depth_up[1..])
    {
        *f = pixel(z, left, up);
    }
    // `holds_one_way` of each, or-ed (a fold without early exit vectorises).
    flags.iter().fold(0, |any, &f| any | (f ^ (f >> 1))) & (LEFT_TO | UP_TO) != 0
}

/// Joins the sets of labels `a` and `b` (the smaller root the root, paths halved on the
/// way); returns the joined set's root.
fn union(parent: &mut [u32], a: u32, b: u32) -> u32 {
    let (a, b) = (find(parent, a), find(parent, b));
    let (root, child) = if a < b { (a, b) } else { (b, a) };
    parent[child as usize] = root;
    root
}

/// The root of label `l`'s set, halving its path.
fn find(parent: &mut [u32], mut l: u32) -> u32 {
    while parent[l as usize] != l {
        let grandparent = parent[parent[l as usize] as usize];
        parent[l as usize] = grandparent;
        l = grandparent;
    }
    l
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The flood fill the labelling replaced: seeds in raster order, a stack, each popped
    /// reading joining its unlabelled 4-neighbours within `join_m + 3 %` of its own depth.
    fn flood_fill(depth: &[f32], join_m: f32) -> Vec<u32> {
        let mut component = vec![0; PIXELS];
        let (mut count, mut stack) = (0, Vec::new());
        for seed in 0..PIXELS {
            if depth[seed] == 0.0 || component[seed] != 0 {
                continue;
            }
            count += 1;
            component[seed] = count;
            stack.push(seed);
            while let Some(k) = stack.pop() {
                let (i, j, z) = (k % WIDTH, k / WIDTH, depth[k]);
                let neighbours = [
                    (i > 0).then(|| k - 1),
                    (i + 1 < WIDTH).then_some(k + 1),
                    (j > 0).then(|| k - WIDTH),
                    (j + 1 < HEIGHT).then_some(k + WIDTH),
                ];
                for n in neighbours.into_iter().flatten() {
                    let q = depth[n];
                    if component[n] == 0 && q > 0.0 && (q - z).abs() < join_m + 0.03 * z {
                        component[n] = count;
                        stack.push(n);
                    }
                }
            }
        }
        component
    }

    /// Depth images where joins often hold one way only: surfaces whose depth steps by
    /// about the join threshold, with holes; each seed a different mix.
    fn frame(seed: u64, join_m: f32) -> Vec<f32> {
        let mut state = seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1;
        let mut random = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 40) as f32 / (1u64 << 24) as f32
        };
        let holes = 0.02 + 0.2 * random();
        let steps = 0.05 + 0.5 * random();
        let mut depth = vec![0.0; PIXELS];
        for k in 0..PIXELS {
            // Along the row, or down from the row above, sometimes a step near the
            // threshold (either side of it, either way); readings to the millimetre.
            let from = match (k % WIDTH, k / WIDTH) {
                (0, 0) => 2.0,
                (0, _) => depth[k - WIDTH],
                _ if random() < 0.5 && k >= WIDTH => depth[k - WIDTH],
                _ => depth[k - 1],
            };
            let from: f32 = if from == 0.0 {
                1.0 + 3.0 * random()
            } else {
                from
            };
            let z = if random() < steps {
                let step = (join_m + 0.03 * from) * (0.97 + 0.06 * random());
                from + if random() < 0.5 { step } else { -step }
            } else {
                from + 0.002 * (random() - 0.5)
            };
            depth[k] = if random() < holes {
                0.0
            } else {
                ((z.clamp(0.5, 4.5) * 1000.0).round() * 0.001).max(0.5)
            };
        }
        depth
    }

    /// The components and their numbering are the flood fill's, and one-way joins were
    /// there to be resolved.
    #[test]
    fn the_components_are_those_of_the_flood_fill() {
        let join_m = 0.04;
        let mut components = Components::default();
        for seed in 1..=12 {
            let depth = frame(seed, join_m);
            components.find(&depth, join_m);
            let mut label = vec![0; PIXELS];
            for run in &components.runs {
                let row = usize::from(run.row) * WIDTH;
                label[row + usize::from(run.start)..row + usize::from(run.end)].fill(run.component);
            }
            let truth = flood_fill(&depth, join_m);
            assert!(components.one_way.len() > 10, "seed {seed}: too easy");
            assert_eq!(components.count, *truth.iter().max().unwrap() as usize);
            let first_difference = (0..PIXELS).find(|&k| label[k] != truth[k]);
            assert_eq!(first_difference, None, "seed {seed}");
        }
    }
}
