//! How [`ConstraintSet::build`] turns a mesh's stretch, shear and bending constraints into
//! parallel work: each constraint goes to its block, seam or corner (see "Blocks, seams and
//! corners" in the module documentation), is coloured greedily within it and packed into
//! batches of eight whose lanes share no particle, with the bending stencils carrying their
//! pairs' distance constraints.

use std::collections::VecDeque;

use super::stencil::{BendConstraint, bend_stencil};
use super::*;
use crate::fabric::{Fabric, bend_compliance, distance_compliance};
use crate::mesh::MeshTopology;
use crate::order::ParticleOrder;
use crate::simd::offset;

/// Open batches the packer may still add to (a window over the constraint order).
pub(super) const PACK_WINDOW: usize = 32;

/// A distance constraint before packing.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct DistanceConstraint {
    pub(super) i: u32,
    pub(super) j: u32,
    pub(super) rest: f32,
    pub(super) compliance: f32,
    pub(super) wi: f32,
    pub(super) wj: f32,
}

impl ConstraintSet {
    /// Builds the constraints of `topology` (mesh numbering) in the particle numbering of
    /// `order`; `inverse_mass` is in mesh order. Padding particles are numbered from the
    /// particle count on, one per item.
    pub fn build(
        rest: &[glam::Vec3],
        topology: &MeshTopology,
        fabric: &Fabric,
        inverse_mass: &[f32],
        order: &ParticleOrder,
    ) -> Self {
        let to = |v: u32| order.to_solver[v as usize];
        let mut distance = Vec::new();
        let mut stretch = Vec::new();
        // Per distance constraint: whether it is a quad's shear diagonal.
        let mut shear = Vec::new();
        for (stencils, stiffness, is_shear) in [
            (&topology.stretch, fabric.stretch_stiffness_n_m, false),
            (&topology.shear, fabric.shear_stiffness_n_m, true),
        ] {
            for s in stencils {
                let [i, j] = s.vertices;
                let (wi, wj) = (inverse_mass[i as usize], inverse_mass[j as usize]);
                if wi + wj == 0.0 {
                    continue;
                }
                if let Some(compliance) = distance_compliance(stiffness, s.rest_length, s.area) {
                    shear.push(is_shear);
                    distance.push(DistanceConstraint {
                        i: to(i),
                        j: to(j),
                        rest: s.rest_length,
                        compliance,
                        wi,
                        wj,
                    });
                    if !is_shear {
                        stretch.push((i, j, s.rest_length));
                    }
                }
            }
        }
        let mut bend = Vec::new();
        let compliance = bend_compliance(fabric.bend_stiffness_n_m);
        if compliance.is_some() {
            for stencil in &topology.bending {
                let w = stencil.map(|v| inverse_mass[v as usize]);
                if w.iter().sum::<f32>() == 0.0 {
                    continue;
                }
                if let Some(mut c) = bend_stencil(rest, *stencil, w) {
                    c.v = c.v.map(to);
                    bend.push(c);
                }
            }
        }
        // Pairs: each stencil carries the distance constraint of its edge and, across a quad
        // diagonal, the shear constraint of the other diagonal. (Not another edge between its
        // opposite vertices, as where a sliver triangle sits on the edge: that one rides with
        // its own edge's stencil.)
        let pair_index: std::collections::HashMap<(u32, u32), u32> = distance
            .iter()
            .enumerate()
            .map(|(k, c)| ((c.i.min(c.j), c.i.max(c.j)), k as u32))
            .collect();
        let mut claimed = vec![false; distance.len()];
        for c in &mut bend {
            for (pair, (a, b)) in [(c.v[0], c.v[1]), (c.v[2], c.v[3])].into_iter().enumerate() {
                c.pairs[pair] = match pair_index.get(&(a.min(b), a.max(b))) {
                    Some(&k) if !claimed[k as usize] && (pair == 0 || shear[k as usize]) => {
                        claimed[k as usize] = true;
                        k
                    }
                    _ => NONE,
                };
            }
        }
        let paired = claimed;
        // Each constraint's blocks: one block (a block item), two (the seam between a pair of
        // blocks) or more (a corner where blocks meet).
        let blocks = order.blocks();
        let n = order.to_mesh.len();
        let block_of: Vec<u32> = (0..n as u32).map(|i| order.block_of(i)).collect();
        let bend_base = distance.len() as u32;
        let total = distance.len() + bend.len();
        let particles_of = |k: u32| -> ([u32; 4], usize) {
            if k < bend_base {
                let c = &distance[k as usize];
                ([c.i, c.j, 0, 0], 2)
            } else {
                (bend[(k - bend_base) as usize].v, 4)
            }
        };
        let blocks_of = |k: u32| -> (u32, u32, bool) {
            let (ps, count) = particles_of(k);
            let (mut lo, mut hi) = (u32::MAX, 0);
            for &p in &ps[..count] {
                lo = lo.min(block_of[p as usize]);
                hi = hi.max(block_of[p as usize]);
            }
            let more = ps[..count]
                .iter()
                .any(|&p| ![lo, hi].contains(&block_of[p as usize]));
            (lo, hi, more)
        };
        // A particle touched by seam constraints of two different pairs of blocks is a corner
        // particle; constraints at corners (touching a corner particle or three blocks) go to
        // corner items, so that the seams of different pairs share no particle.
        const NO_PAIR: (u32, u32) = (u32::MAX, u32::MAX);
        let mut pair_of_particle = vec![NO_PAIR; n];
        let mut corner = vec![false; n];
        let solved = |k: u32| k >= bend_base || !paired[k as usize];
        for k in (0..total as u32).filter(|&k| solved(k)) {
            let (lo, hi, more) = blocks_of(k);
            if lo == hi {
                continue;
            }
            let (ps, count) = particles_of(k);
            for &p in &ps[..count] {
                let seen = &mut pair_of_particle[p as usize];
                if more || (*seen != NO_PAIR && *seen != (lo, hi)) {
                    corner[p as usize] = true;
                }
                *seen = (lo, hi);
            }
        }
        // Members of each block, of each seam (by pair) and of the corners, in the mesh's order
        // (distance constraints, then bending stencils, offset by the distance count).
        let mut block_members = vec![Vec::new(); blocks];
        let mut seam_members: std::collections::BTreeMap<(u32, u32), Vec<u32>> =
            std::collections::BTreeMap::new();
        let mut corner_members = Vec::new();
        for k in (0..total as u32).filter(|&k| solved(k)) {
            let (lo, hi, more) = blocks_of(k);
            let (ps, count) = particles_of(k);
            if lo == hi {
                block_members[lo as usize].push(k);
            } else if more || ps[..count].iter().any(|&p| corner[p as usize]) {
                corner_members.push(k);
            } else {
                seam_members.entry((lo, hi)).or_default().push(k);
            }
        }
        // Corner constraints fall into small independent clusters (union–find over shared
        // particles); each cluster is an item.
        let mut parent: Vec<u32> = (0..n as u32).collect();
        fn root(parent: &mut [u32], mut p: u32) -> u32 {
            while parent[p as usize] != p {
                let up = parent[parent[p as usize] as usize];
                parent[p as usize] = up;
                p = up;
            }
            p
        }
        for &k in &corner_members {
            let (ps, count) = particles_of(k);
            for &p in &ps[1..count] {
                let (a, b) = (root(&mut parent, ps[0]), root(&mut parent, p));
                if a != b {
                    parent[a.max(b) as usize] = a.min(b);
                }
            }
        }
        let mut clusters: std::collections::BTreeMap<u32, Vec<u32>> =
            std::collections::BTreeMap::new();
        for &k in &corner_members {
            let r = root(&mut parent, particles_of(k).0[0]);
            clusters.entry(r).or_default().push(k);
        }

        // Items: every block, then the seams, then the corner clusters.
        let mut item_members: Vec<Vec<u32>> = block_members;
        let mut separator_levels = Vec::new();
        for group in [
            seam_members.into_values().collect::<Vec<_>>(),
            clusters.into_values().collect(),
        ] {
            let first = item_members.len() as u32;
            item_members.extend(group.into_iter().filter(|m| !m.is_empty()));
            if item_members.len() as u32 > first {
                separator_levels.push((first, item_members.len() as u32));
            }
        }

        let free: Vec<bool> = order
            .to_mesh
            .iter()
            .map(|&m| inverse_mass[m as usize] > 0.0)
            .collect();
        let mut used = vec![0u128; n];
        let mut packer = Packer {
            mask: vec![0; n + PADDING_STRIDE * item_members.len()],
        };
        let mut set = Self {
            bend_compliance: compliance.unwrap_or(0.0),
            distance_count: distance.len(),
            bend_count: bend.len(),
            stretch,
            separator_levels,
            ..Self::default()
        };
        let kind_of = |k: u32| -> RunKind {
            if k < bend_base {
                RunKind::Distance
            } else {
                bend_kind(&bend[(k - bend_base) as usize])
            }
        };
        for (item, members) in item_members.iter().enumerate() {
            let padding = (n + PADDING_STRIDE * item) as u32;
            // Greedy colouring over the item's free particles, distance constraints first
            // (a colour's constraints share no free particle, so the order inside a colour
            // does not change the result); colours past 127 share one last colour.
            let mut colour_of = Vec::with_capacity(members.len());
            for &k in members {
                let (ps, count) = particles_of(k);
                let mut mask = 0u128;
                for &p in &ps[..count] {
                    if free[p as usize] {
                        mask |= used[p as usize];
                    }
                }
                let colour = (!mask).trailing_zeros().min(127);
                for &p in &ps[..count] {
                    if free[p as usize] {
                        used[p as usize] |= 1u128 << colour;
                    }
                }
                colour_of.push(colour);
            }
            for &k in members {
                let (ps, count) = particles_of(k);
                for &p in &ps[..count] {
                    used[p as usize] = 0;
                }
            }
            // Runs: per colour, its distance constraints, then its bending stencils, flat ones
            // first and fewer pairs first; a batch is solved as its most demanding lane needs
            // (curved, pairs): the others give the same result there.
            let class = |k: u32| u8::from(k >= bend_base);
            let mut sorted: Vec<(u32, u8, RunKind, u32)> = members
                .iter()
                .zip(&colour_of)
                .map(|(&k, &colour)| (colour, class(k), kind_of(k), k))
                .collect();
            sorted.sort_by_key(|&(colour, class, kind, _)| (colour, class, kind));
            let r0 = set.runs.len() as u32;
            let mut at = 0;
            while at < sorted.len() {
                let (colour, class, _, _) = sorted[at];
                let mut end = at;
                while end < sorted.len() && (sorted[end].0, sorted[end].1) == (colour, class) {
                    end += 1;
                }
                let ids: Vec<u32> = sorted[at..end].iter().map(|e| e.3).collect();
                at = end;
                // A run is one colour: its batches share no free particle.
                if class == 0 {
                    let start = set.distance.len() as u32;
                    for lanes in packer.pack(&ids, |k| {
                        let c = &distance[k as usize];
                        [c.i, c.j]
                    }) {
                        set.distance.push(distance_batch(&distance, lanes, padding));
                    }
                    set.runs.push(Run {
                        kind: RunKind::Distance,
                        batches: (start, set.distance.len() as u32),
                    });
                } else {
                    let first_run = set.runs.len();
                    for lanes in packer.pack(&ids, |k| bend[(k - bend_base) as usize].v) {
                        let lanes = lanes.map(|k| if k == NONE { NONE } else { k - bend_base });
                        let (batch, side) = bend_batch(&bend, &distance, lanes, padding);
                        // Curved if any lane is, with as many pairs as the lane with most.
                        let (mut curved, mut pairs) = (false, 0);
                        for &k in lanes.iter().filter(|&&k| k != NONE) {
                            if let RunKind::Bend {
                                curved: c,
                                pairs: p,
                            } = bend_kind(&bend[k as usize])
                            {
                                (curved, pairs) = (curved || c, pairs.max(p));
                            }
                        }
                        let kind = RunKind::Bend { curved, pairs };
                        let b = set.bend.len() as u32;
                        set.bend.push(batch);
                        set.bend_side.push(side);
                        let in_colour = set.runs.len() > first_run;
                        match set.runs.last_mut() {
                            Some(run) if in_colour && run.kind == kind && run.batches.1 == b => {
                                run.batches.1 = b + 1;
                            }
                            _ => set.runs.push(Run {
                                kind,
                                batches: (b, b + 1),
                            }),
                        }
                    }
                }
            }
            // The stretch check: the item's distance constraints, standalone or paired.
            let checked: Vec<u32> = members
                .iter()
                .flat_map(|&k| {
                    if k < bend_base {
                        [k, NONE, NONE]
                    } else {
                        let [a, b] = bend[(k - bend_base) as usize].pairs;
                        [a, b, NONE]
                    }
                })
                .filter(|&k| k != NONE)
                .collect();
            let c0 = set.check.len() as u32;
            for chunk in checked.chunks(LANES) {
                let mut b = CheckBatch {
                    i: [offset(padding); LANES],
                    j: [offset(padding); LANES],
                    rest: [f32::INFINITY; LANES],
                };
                for (l, &k) in chunk.iter().enumerate() {
                    let c = &distance[k as usize];
                    (b.i[l], b.j[l], b.rest[l]) = (offset(c.i), offset(c.j), c.rest);
                }
                set.check.push(b);
            }
            set.items.push(ConstraintItem {
                check: (c0, set.check.len() as u32),
                runs: (r0, set.runs.len() as u32),
                padding,
            });
        }
        set
    }
}

pub(super) fn distance_batch(
    constraints: &[DistanceConstraint],
    lanes: [u32; LANES],
    padding: u32,
) -> DistanceBatch {
    let mut b = DistanceBatch {
        i: [offset(padding); LANES],
        j: [offset(padding); LANES],
        rest: [1.0; LANES],
        // Empty lanes: a harmless non-zero denominator.
        compliance: [1.0; LANES],
        wi: [0.0; LANES],
        wj: [0.0; LANES],
    };
    for (l, &k) in lanes.iter().enumerate() {
        if k == NONE {
            continue;
        }
        let c = &constraints[k as usize];
        b.i[l] = offset(c.i);
        b.j[l] = offset(c.j);
        b.rest[l] = c.rest;
        b.compliance[l] = c.compliance;
        b.wi[l] = c.wi;
        b.wj[l] = c.wj;
    }
    b
}

/// How a stencil is solved: curved or flat, and how many pairs (pair 1 needs pair 0's slot).
pub(super) fn bend_kind(c: &BendConstraint) -> RunKind {
    RunKind::Bend {
        curved: c.rest != [0.0; 3],
        pairs: if c.pairs[1] != NONE {
            2
        } else {
            u8::from(c.pairs[0] != NONE)
        },
    }
}

pub(super) fn bend_batch(
    constraints: &[BendConstraint],
    distance: &[DistanceConstraint],
    lanes: [u32; LANES],
    padding: u32,
) -> (BendBatch, BendSide) {
    let mut side = BendSide {
        rest: [[0.0; LANES]; 3],
        pair_compliance: [[0.0; LANES]; 2],
    };
    let mut b = BendBatch {
        v: [[offset(padding); LANES]; 4],
        // Empty lanes: zero weights (a harmless non-zero denominator, see
        // `inverse_denominators`) and no pairs.
        k: [[0.0; LANES]; 4],
        w: [[0.0; LANES]; 4],
        drest: [[NO_PAIR_REST; LANES]; 2],
    };
    for (l, &k) in lanes.iter().enumerate() {
        if k == NONE {
            continue;
        }
        let c = &constraints[k as usize];
        for (p, &d) in c.pairs.iter().enumerate() {
            if d == NONE {
                continue;
            }
            let d = &distance[d as usize];
            b.drest[p][l] = d.rest;
            side.pair_compliance[p][l] = d.compliance;
        }
        for q in 0..4 {
            b.v[q][l] = offset(c.v[q]);
            b.k[q][l] = c.k[q];
            b.w[q][l] = c.w[q];
        }
        for q in 0..3 {
            side.rest[q][l] = c.rest[q];
        }
    }
    (b, side)
}

/// Greedy packing of constraints into batches whose lanes share no particle.
pub(super) struct Packer {
    /// Per particle: the open batches (bits of window slots) that already hold it. All zero
    /// between calls.
    pub(super) mask: Vec<u32>,
}

impl Packer {
    /// Packs `ids` (in this order of preference) into batches; `particles(id)` lists a
    /// constraint's particles. Each constraint goes into the oldest open batch that holds
    /// none of its particles, or a new one; a full batch, or the oldest one when the window
    /// is full, is emitted.
    pub(super) fn pack<const K: usize>(
        &mut self,
        ids: &[u32],
        particles: impl Fn(u32) -> [u32; K],
    ) -> Vec<[u32; LANES]> {
        let mut out = Vec::with_capacity(ids.len().div_ceil(LANES));
        let mut slots = [[NONE; LANES]; PACK_WINDOW];
        let mut fill = [0usize; PACK_WINDOW];
        let mut open: VecDeque<usize> = VecDeque::with_capacity(PACK_WINDOW);
        let mut free: Vec<usize> = (0..PACK_WINDOW).rev().collect();
        for &c in ids {
            let ps = particles(c);
            let taken = ps.iter().fold(0u32, |m, &p| m | self.mask[p as usize]);
            let s = match open.iter().position(|&s| taken & (1 << s) == 0) {
                Some(at) => open[at],
                None => {
                    if free.is_empty() {
                        let oldest = open.pop_front().expect("a full window has open slots");
                        close(
                            oldest,
                            &mut slots,
                            &mut fill,
                            &mut self.mask,
                            &mut out,
                            &particles,
                        );
                        free.push(oldest);
                    }
                    let s = free.pop().expect("a slot was just freed");
                    open.push_back(s);
                    s
                }
            };
            slots[s][fill[s]] = c;
            fill[s] += 1;
            for p in ps {
                self.mask[p as usize] |= 1 << s;
            }
            if fill[s] == LANES {
                // Full: emit it now (`close` reads the slot before clearing it).
                let at = open.iter().position(|&o| o == s).expect("s is open");
                open.remove(at);
                close(
                    s,
                    &mut slots,
                    &mut fill,
                    &mut self.mask,
                    &mut out,
                    &particles,
                );
                free.push(s);
            }
        }
        while let Some(s) = open.pop_front() {
            close(
                s,
                &mut slots,
                &mut fill,
                &mut self.mask,
                &mut out,
                &particles,
            );
        }
        out
    }
}

/// Emits the batch in window slot `s` and frees the slot.
pub(super) fn close<const K: usize>(
    s: usize,
    slots: &mut [[u32; LANES]; PACK_WINDOW],
    fill: &mut [usize; PACK_WINDOW],
    mask: &mut [u32],
    out: &mut Vec<[u32; LANES]>,
    particles: &impl Fn(u32) -> [u32; K],
) {
    for &c in &slots[s][..fill[s]] {
        for p in particles(c) {
            mask[p as usize] &= !(1u32 << s);
        }
    }
    out.push(slots[s]);
    slots[s] = [NONE; LANES];
    fill[s] = 0;
}
