//! Collision of a chunk's particles with the swept colliders and planes near it, with
//! friction: the passes over the shapes (eight particles together where they can, one by
//! one where they cannot), the joint push-out of a particle caught where shapes overlap, and
//! the reconciliation of a collider's push with the particle's tethers.

use glam::Vec3A;

use super::model::{EIGHT_ATTACHED, EIGHT_FREE, EIGHT_TWO_TETHERS};
use super::step::StepContext;
use super::sweep::ColliderBounds;
use crate::collision::{Plane, SweptCollider, collide_plane};
use crate::simd::{Isa, LANES, Lanes, V3, dispatch_lanes, offset};

/// Alternations between tethers and collider push-out when they conflict.
pub(super) const RECONCILE_ROUNDS: usize = 8;
/// Rounds of the joint push-out of a particle inside overlapping colliders.
pub(super) const OVERLAP_ROUNDS: usize = 6;
/// Longest joint push-out out of two shapes, in multiples of the deeper one's depth (the
/// crease of two surfaces meeting at 60° or more).
pub(super) const CREASE_REACH: f32 = 2.0;

impl StepContext<'_> {
    /// Tethers, then collision with the colliders and planes near the chunk `range`.
    #[inline(always)]
    pub(super) fn tethers_and_collisions(&self, sub: u32, range: std::ops::Range<usize>) {
        let k = &self.k;
        let m = self.model;
        let colliders = self.swept_of(sub);
        let mut low = Vec3A::splat(f32::INFINITY);
        let mut high = Vec3A::splat(f32::NEG_INFINITY);
        // SAFETY (whole function): particles of `range` belong to this item; attachment
        // targets and colliders are read-only.
        let mut i = range.start;
        while i < range.end {
            let flags = m.eight_at(i, range.end);
            if flags & EIGHT_TWO_TETHERS != 0 {
                // SAFETY: particles `i..i + 8` belong to this item.
                unsafe { self.tethers8(i, sub) };
                // The group's bounds as a tree (short dependency chains).
                // SAFETY: as above.
                let pairs: [(Vec3A, Vec3A); LANES] = std::array::from_fn(|l| unsafe {
                    (self.xs.get(i + l), self.xs_prev.get(i + l))
                });
                let lo = pairs.map(|(p, q)| p.min(q));
                let hi = pairs.map(|(p, q)| p.max(q));
                let lo = [
                    lo[0].min(lo[1]),
                    lo[2].min(lo[3]),
                    lo[4].min(lo[5]),
                    lo[6].min(lo[7]),
                ];
                let hi = [
                    hi[0].max(hi[1]),
                    hi[2].max(hi[3]),
                    hi[4].max(hi[5]),
                    hi[6].max(hi[7]),
                ];
                low = low.min(lo[0].min(lo[1]).min(lo[2].min(lo[3])));
                high = high.max(hi[0].max(hi[1]).max(hi[2].max(hi[3])));
                i += LANES;
                continue;
            }
            if flags & EIGHT_ATTACHED != 0 {
                // No tethers, no bounds.
                i += LANES;
                continue;
            }
            if m.inverse_mass[i] != 0.0 {
                // SAFETY: particle `i` belongs to this item; nothing else touches it in this
                // phase.
                unsafe {
                    let mut p = self.xs.get(i);
                    if m.tether_start[i] != m.tether_start[i + 1] {
                        p = self.apply_tethers(i, p, sub);
                        self.xs.set(i, p);
                    }
                    let q = self.xs_prev.get(i);
                    low = low.min(p).min(q);
                    high = high.max(p).max(q);
                }
            }
            i += 1;
        }
        // No free particle, or a NaN (the guard will see it): no collider, every plane, as
        // the chunk's bounds say nothing.
        let bounded = low.cmple(high).all();
        // Colliders and planes whose bounds meet the chunk's (at most `NEAR` of each; more
        // than that and every one is tested).
        const NEAR: usize = 64;
        let mut near = [0u16; NEAR];
        let mut count = 0usize;
        if bounded {
            for (eight, bounds) in self.swept_bounds_of(sub).iter().enumerate() {
                // SAFETY: the instruction set detected.
                let mut hits = unsafe { overlaps8(k.isa, bounds, low, high) };
                while hits != 0 {
                    let c = eight * LANES + hits.trailing_zeros() as usize;
                    hits &= hits - 1;
                    if count < NEAR {
                        near[count] = c as u16;
                    }
                    count += 1;
                }
            }
        }
        let all: [u16; 0] = [];
        let (near, test_all) = if count > NEAR {
            (&all[..], true)
        } else {
            (&near[..count], false)
        };
        let mut near_planes = [0u8; 8];
        let mut plane_count = 0usize;
        for (c, plane) in self.planes.iter().enumerate() {
            let n = Vec3A::from(plane.normal);
            // The chunk's lowest point along the normal.
            let corner = Vec3A::select(n.cmpge(Vec3A::ZERO), low, high);
            let clearance = n.dot(corner) - plane.offset - k.thickness;
            if !bounded || clearance.is_nan() || clearance < 0.0 {
                if plane_count < near_planes.len() {
                    near_planes[plane_count] = c as u8;
                }
                plane_count += 1;
            }
        }
        let all_planes = plane_count > near_planes.len();
        let plane_count = plane_count.min(near_planes.len());
        let shapes = if test_all {
            colliders.len()
        } else {
            near.len()
        } + if all_planes {
            self.planes.len()
        } else {
            plane_count
        };
        if shapes == 0 {
            return;
        }
        let near = (!test_all).then_some(near);
        let planes = if all_planes {
            None
        } else {
            Some(&near_planes[..plane_count])
        };
        let scene = Scene {
            colliders,
            near,
            planes,
            any_plane: plane_count > 0,
            shapes,
        };
        #[cfg(test)]
        let together = k.group_collisions;
        #[cfg(not(test))]
        let together = true;
        let group = together && near.is_none_or(|n| !n.is_empty());
        // Without a plane near, the pass after the first is made on the eight particles
        // together too (see `collide8`).
        let second = !scene.any_plane && scene.shapes >= 2;
        let mut pass = GroupPass {
            p: [Vec3A::ZERO; LANES],
            last: [0; LANES],
        };
        let mut i = range.start;
        while i < range.end {
            // Eight free particles: collided together, each collider with the lanes its box
            // meets; only what the eight-particle passes leave open is done one by one.
            let flags = m.eight_at(i, range.end);
            if group && flags & EIGHT_FREE != 0 {
                // SAFETY: particles `i..i + 8` belong to this item.
                match unsafe { self.collide_group(i, &scene, second, &mut pass) } {
                    Some((moved, again)) if scene.any_plane => {
                        // The planes (and every pass after the first) one by one.
                        for l in 0..LANES {
                            let last = (moved & (1 << l) != 0).then_some(pass.last[l]);
                            // SAFETY: as above.
                            unsafe {
                                let start = self.xs_prev.get(i + l);
                                let resume = Resume::AfterColliders(last);
                                self.collide_particle(i + l, sub, start, pass.p[l], resume, &scene);
                            }
                        }
                        debug_assert_eq!(again, 0);
                    }
                    Some((moved, again)) => {
                        // A particle no collider moved is done (its position is unchanged).
                        let mut rest = moved;
                        while rest != 0 {
                            let l = rest.trailing_zeros() as usize;
                            rest &= rest - 1;
                            // SAFETY: as above.
                            unsafe {
                                let start = self.xs_prev.get(i + l);
                                if again & (1 << l) != 0 {
                                    let resume = Resume::ThirdPass;
                                    self.collide_particle(
                                        i + l,
                                        sub,
                                        start,
                                        pass.p[l],
                                        resume,
                                        &scene,
                                    );
                                } else {
                                    self.settle(i + l, sub, start, pass.p[l], colliders);
                                }
                            }
                        }
                    }
                    // A position that is not finite: each particle on its own.
                    None => {
                        for i in i..i + LANES {
                            // SAFETY: as above.
                            unsafe {
                                let (start, p) = (self.xs_prev.get(i), self.xs.get(i));
                                self.collide_particle(i, sub, start, p, Resume::Fresh, &scene);
                            }
                        }
                    }
                }
                i += LANES;
                continue;
            }
            if flags & EIGHT_ATTACHED != 0 {
                // Not collided.
                i += LANES;
                continue;
            }
            if m.inverse_mass[i] != 0.0 {
                // SAFETY: particle `i` belongs to this item.
                unsafe {
                    let (start, p) = (self.xs_prev.get(i), self.xs.get(i));
                    self.collide_particle(i, sub, start, p, Resume::Fresh, &scene);
                }
            }
            i += 1;
        }
    }

    /// The collision passes over the colliders (not the planes) that the eight particles
    /// from `i` make together ([`collide8`]; the second only if `second`), into `pass`: the
    /// lanes moved, and those the second pass moved (they need a third, one by one). `None`
    /// if a position is not finite (the one-particle path handles it).
    ///
    /// # Safety
    /// Particles `i..i + 8` belong to the calling item.
    #[inline(always)]
    pub(super) unsafe fn collide_group(
        &self,
        i: usize,
        scene: &Scene<'_>,
        second: bool,
        pass: &mut GroupPass,
    ) -> Option<(u32, u32)> {
        let k = &self.k;
        #[cfg(test)]
        let prune = k.prune_passes;
        #[cfg(not(test))]
        let prune = true;
        // SAFETY: the caller's contract.
        unsafe {
            collide8(
                k.isa,
                self.xs_prev.as_ptr().add(i),
                self.xs.as_ptr().add(i),
                scene,
                (k.thickness, k.friction),
                (second, prune),
                pass,
            )
        }
    }

    /// Stores particle `i`'s position `p` after a collider moved it (from `start` in
    /// substep `sub`), reconciled with its tethers if it left them.
    ///
    /// # Safety
    /// Particle `i` belongs to the calling item.
    #[inline]
    pub(super) unsafe fn settle(
        &self,
        i: usize,
        sub: u32,
        start: Vec3A,
        mut p: Vec3A,
        colliders: &[SweptCollider],
    ) {
        // SAFETY: the caller's contract.
        unsafe {
            if self.tether_violated(i, p, sub) {
                p = self.reconcile(i, start, p, sub, colliders);
            }
            self.xs.set(i, p);
        }
    }

    /// Collides particle `i`, moving from `start` to `p` in substep `sub`, with the scene's
    /// colliders and planes and stores the result; `resume` says which passes were already
    /// made ([`Resume`]).
    ///
    /// A pass tests the colliders, then the planes, in the scene's order, and is repeated
    /// while it moves the particle. The pass after the first tests only the shapes before the
    /// last one that moved it, if the particle ended the first pass within the box of its
    /// path at the start of that pass (the box tested against each collider's bounds): the
    /// shapes after the last mover tested it where it still is, or their bounds missed a box
    /// that holds its new path, and a shape leaves a particle it moved on its skin, where it
    /// does not move it again (`CONTACT_TOLERANCE`). Once a shape moves it in that pass, the
    /// shapes after that one are all tested too: they have not seen it where it now is (a
    /// pass that stopped at the last mover anyway left those moves to the third pass, and
    /// differed from testing every shape: session 13, found when a different block split
    /// moved a skirt's particles between the one-particle and the grouped path). Otherwise,
    /// and in a third pass, every shape is tested.
    ///
    /// # Safety
    /// Particle `i` belongs to the calling item.
    pub(super) unsafe fn collide_particle(
        &self,
        i: usize,
        sub: u32,
        start: Vec3A,
        mut p: Vec3A,
        resume: Resume,
        scene: &Scene<'_>,
    ) {
        let k = &self.k;
        let colliders = scene.colliders;
        let collider_count = scene.near.map_or(colliders.len(), <[u16]>::len);
        let mut touched = resume == Resume::ThirdPass;
        let mut settled = true;
        // Shapes (colliders, then planes) this pass tests: those before `limit`, and every one
        // after a shape has moved the particle in this pass.
        let mut limit = usize::MAX;
        // SAFETY: the caller's contract (the particle's position before the first pass).
        let before = unsafe { self.xs.get(i) };
        let (box_low, box_high) = (start.min(before), start.max(before));
        let passes = if touched { 2..3 } else { 0..3 };
        for pass in passes {
            // The place of the last shape that moved the particle in this pass.
            let mut last: Option<usize> = None;
            match resume {
                Resume::AfterColliders(first_last) if pass == 0 => {
                    last = first_last.map(usize::from)
                }
                _ => {
                    let (seg_low, seg_high) = (start.min(p), start.max(p));
                    let mut test = |place: usize, collider: &SweptCollider| {
                        if place >= limit && last.is_none() {
                            return;
                        }
                        if collider.overlaps(seg_low, seg_high) {
                            let friction = k.friction * collider.friction;
                            let (q, hit) = collider.collide(start, p, k.thickness, friction);
                            if hit {
                                p = q;
                                last = Some(place);
                            }
                        }
                    };
                    match scene.near {
                        None => colliders[..collider_count]
                            .iter()
                            .enumerate()
                            .for_each(|(c, s)| test(c, s)),
                        Some(near) => near
                            .iter()
                            .enumerate()
                            .for_each(|(c, &s)| test(c, &colliders[s as usize])),
                    }
                }
            }
            let mut test_plane = |place: usize, plane: &Plane| {
                if collider_count + place >= limit && last.is_none() {
                    return;
                }
                let q = collide_plane(plane, start, p, k.thickness, k.friction);
                if q != p {
                    p = q;
                    last = Some(collider_count + place);
                }
            };
            match scene.planes {
                None => self
                    .planes
                    .iter()
                    .enumerate()
                    .for_each(|(c, plane)| test_plane(c, plane)),
                Some(near) => near
                    .iter()
                    .enumerate()
                    .for_each(|(c, &plane)| test_plane(c, &self.planes[plane as usize])),
            }
            let Some(last) = last else {
                break;
            };
            touched = true;
            if scene.shapes < 2 {
                break;
            }
            #[cfg(test)]
            let prune = k.prune_passes;
            #[cfg(not(test))]
            let prune = true;
            let in_box = prune && p.cmpge(box_low).all() && p.cmple(box_high).all();
            limit = if pass == 0 && in_box {
                last
            } else {
                usize::MAX
            };
            settled = pass < 2;
        }
        if !settled {
            // Still pushed back and forth after the last pass: caught where two shapes
            // overlap (the thighs in a stride); settle in the crease between them.
            p = match scene.near {
                None => self.resolve_overlaps(p, colliders.iter()),
                Some(near) => {
                    self.resolve_overlaps(p, near.iter().map(|&c| &colliders[c as usize]))
                }
            };
        }
        // SAFETY: the caller's contract.
        unsafe {
            if touched {
                self.settle(i, sub, start, p, colliders);
            } else {
                self.xs.set(i, p);
            }
        }
    }

    /// Moves `p` out of every collider and plane (with the skin): the smallest move that
    /// clears the two most violated shapes, linearised at `p` (their tangent half-spaces),
    /// repeated. One violated shape is a plain push-out; two are solved together, so a particle
    /// caught where two colliders overlap settles in the crease between them instead of being
    /// pushed back and forth (sequential push-outs leave it inside one of them).
    pub(super) fn resolve_overlaps<'c>(
        &self,
        mut p: Vec3A,
        colliders: impl Iterator<Item = &'c SweptCollider> + Clone,
    ) -> Vec3A {
        let thickness = self.k.thickness;
        for _round in 0..OVERLAP_ROUNDS {
            // The two deepest violations: (signed skin distance, outward normal).
            let mut worst: [Option<(f32, Vec3A)>; 2] = [None, None];
            let mut note = |s: f32, n: Vec3A| {
                if s >= 0.0 || s.is_nan() {
                    return;
                }
                if worst[0].is_none_or(|w| s < w.0) {
                    worst[1] = worst[0];
                    worst[0] = Some((s, n));
                } else if worst[1].is_none_or(|w| s < w.0) {
                    worst[1] = Some((s, n));
                }
            };
            for collider in colliders.clone() {
                if collider.contains_point(p) {
                    let (s, n) = collider.skin_distance(p, thickness);
                    note(s, n);
                }
            }
            for plane in self.planes {
                let n = Vec3A::from(plane.normal);
                note(n.dot(p) - plane.offset - thickness, n);
            }
            p += match worst {
                [None, _] => break,
                [Some((s, n)), None] => -s * n,
                [Some(a), Some(b)] => clear_two(a, b),
            };
        }
        p
    }

    /// Resolves a particle that a collider pushed beyond its tether (see the module
    /// documentation). First the particle slides: alternating projections onto its tether
    /// balls and onto the tangent half-space of the collider it rests on, which keeps it on
    /// its side of the collider. If no such point exists (a collider dragging the cloth
    /// farther than the garment reaches), the tether wins and the particle goes to the nearest
    /// collider surface, possibly the far side. The repair is kept out of the velocity.
    ///
    /// # Safety
    /// Particle `i` belongs to the calling item.
    pub(super) unsafe fn reconcile(
        &self,
        i: usize,
        start: Vec3A,
        collided: Vec3A,
        sub: u32,
        colliders: &[SweptCollider],
    ) -> Vec3A {
        let k = &self.k;
        // The surface the particle rests on: the nearest collider (or plane).
        let mut support: Option<(f32, Vec3A)> = None;
        let mut best = f32::INFINITY;
        for collider in colliders {
            if collider.contains_point(collided) {
                let (s, n) = collider.skin_distance(collided, k.thickness);
                if s < best {
                    best = s;
                    support = Some((n.dot(collided) - s, n));
                }
            }
        }
        for plane in self.planes {
            let n = Vec3A::from(plane.normal);
            let s = n.dot(collided) - plane.offset - k.thickness;
            if s < best {
                best = s;
                support = Some((plane.offset + k.thickness, n));
            }
        }
        let mut p = collided;
        let mut slid = false;
        if let Some((offset, n)) = support {
            for _round in 0..RECONCILE_ROUNDS {
                p = self.apply_tethers(i, p, sub);
                let s = n.dot(p) - offset;
                if s >= 0.0 {
                    slid = true;
                    break;
                }
                p -= s * n;
            }
            slid |= !self.tether_violated(i, p, sub);
        }
        if !slid {
            p = self.apply_tethers(i, collided, sub);
        }
        // Out of every collider (a slid particle is at most a rounding error inside).
        p = self.resolve_overlaps(p, colliders.iter());
        // SAFETY: particle `i` belongs to the calling item.
        unsafe { self.xs_prev.set(i, start + (p - collided)) };
        p
    }
}

/// The collision passes of eight particles made together ([`StepContext::collide_group`]).
pub(super) struct GroupPass {
    /// The positions after them.
    pub(super) p: [Vec3A; LANES],
    /// Per lane the first pass moved: the place in the scene's order of the last collider
    /// that moved it.
    pub(super) last: [u16; LANES],
}

/// Where [`StepContext::collide_particle`] starts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Resume {
    /// At the first pass.
    Fresh,
    /// After the first pass's colliders (not its planes); the place in the scene's order of
    /// the last collider that moved the particle (`None`: none did).
    AfterColliders(Option<u16>),
    /// At the third pass: the first two moved the particle.
    ThirdPass,
}

/// Every lane of a group of eight, as bits.
pub(super) const ALL_LANES: u32 = (1 << LANES) - 1;

/// What the particles of one chunk collide with in one substep.
pub(super) struct Scene<'a> {
    /// The substep's colliders.
    pub(super) colliders: &'a [SweptCollider],
    /// The colliders near the chunk (indices into `colliders`), or `None` for all of them.
    pub(super) near: Option<&'a [u16]>,
    /// The planes near the chunk (indices), or `None` for all of them.
    pub(super) planes: Option<&'a [u8]>,
    /// Whether any plane is tested.
    pub(super) any_plane: bool,
    /// How many colliders and planes are tested.
    pub(super) shapes: usize,
}

impl Scene<'_> {
    /// The collider at place `c` of the scene's order.
    #[inline]
    pub(super) fn collider(&self, c: usize) -> &SweptCollider {
        match self.near {
            None => &self.colliders[c],
            Some(near) => &self.colliders[near[c] as usize],
        }
    }
}

/// The collision passes over the scene's colliders of eight particles (`start`: at the
/// substep start, `now`: now, both eight consecutive particles), made together in lanes as
/// [`StepContext::collide_particle`] makes them for each particle: the first pass, and if
/// `second`, the second one for the lanes the first moved (`prune`: testing only the
/// colliders before the last mover of a particle that stayed within its box, and all those
/// after a collider that moves it again; tests turn it off). A collider tests the lanes
/// whose path box meets its own. Returns the lanes moved and those the second pass moved
/// (they need the third pass, made one by one), and writes the positions after the passes,
/// and per lane moved in the first pass the place in the scene's order of the last collider
/// that moved it, to `out`; `None` (and nothing useful in `out`) if a position is not
/// finite, or the first pass made one so.
///
/// # Safety
/// `start` and `now` point at eight particles that the calling item owns.
#[inline]
pub(super) unsafe fn collide8(
    isa: Isa,
    start: *const Vec3A,
    now: *const Vec3A,
    scene: &Scene<'_>,
    contact: (f32, f32),
    passes: (bool, bool),
    out: &mut GroupPass,
) -> Option<(u32, u32)> {
    dispatch_lanes!(
        isa,
        collide8_with(
            start: *const Vec3A,
            now: *const Vec3A,
            scene: &Scene<'_>,
            contact: (f32, f32),
            passes: (bool, bool),
            out: &mut GroupPass,
        ) -> Option<(u32, u32)>
    )
}

/// One collider's test in a pass of [`collide8`]: the lanes of `active` whose path box (from
/// `path.0` to `path.1`) meets the collider's are collided at `p`, which takes the moved
/// ones' new positions; returns the lanes moved.
#[inline(always)]
pub(super) fn collide_near<L: Lanes>(
    collider: &SweptCollider,
    (start, box_end): (V3<L>, V3<L>),
    p: &mut V3<L>,
    active: L,
    (thickness, friction): (f32, f32),
) -> L {
    let lanes = collider.overlaps_lanes(start, box_end).and(active);
    if lanes.bits() == 0 {
        return lanes;
    }
    let friction = friction * collider.friction;
    let (q, hit) = collider.collide_lanes(start, *p, lanes, thickness, friction);
    if hit.bits() != 0 {
        *p = V3::select(hit, q, *p);
    }
    hit
}

#[inline(always)]
pub(super) unsafe fn collide8_with<L: Lanes>(
    start: *const Vec3A,
    now: *const Vec3A,
    scene: &Scene<'_>,
    contact: (f32, f32),
    (second, prune): (bool, bool),
    out: &mut GroupPass,
) -> Option<(u32, u32)> {
    let index: [u32; LANES] = std::array::from_fn(|l| offset(l as u32));
    // SAFETY: the caller's contract.
    let (s, first) = unsafe { (L::gather(start, &index), L::gather(now, &index)) };
    // (No closures: they would not inherit the caller's target features.) `|v|² · 0` is zero
    // for a finite `v` and NaN for an infinite or NaN one (or one too large to square, which
    // the one-particle path then handles too).
    let zero = L::splat(0.0);
    if (s.dot(s) * zero)
        .is_nan()
        .or((first.dot(first) * zero).is_nan())
        .bits()
        != 0
    {
        return None;
    }
    let count = scene.near.map_or(scene.colliders.len(), <[u16]>::len);
    // Masks: no lane.
    let mut moved = zero;
    let mut last = zero;
    let mut p = first;
    let every = zero.le(zero);
    for c in 0..count {
        let hit = collide_near(scene.collider(c), (s, first), &mut p, every, contact);
        if hit.bits() != 0 {
            last = L::select(hit, L::splat(c as f32), last);
            moved = moved.or(hit);
        }
    }
    let mut again = zero;
    if second && moved.bits() != 0 {
        // The second pass, over the lanes the first moved: the colliders before the last
        // mover if the particle stayed within the box of its path at the start of the first
        // pass (and every one after a collider that moves it again), else all of them. (A
        // position the first pass made not finite: the whole group one by one, as for a
        // non-finite input.)
        let p1 = p;
        if (p1.dot(p1) * zero).is_nan().bits() != 0 {
            return None;
        }
        let in_box =
            s.x.le(p1.x)
                .or(first.x.le(p1.x))
                .and(s.y.le(p1.y).or(first.y.le(p1.y)))
                .and(s.z.le(p1.z).or(first.z.le(p1.z)))
                .and(p1.x.le(s.x).or(p1.x.le(first.x)))
                .and(p1.y.le(s.y).or(p1.y.le(first.y)))
                .and(p1.z.le(s.z).or(p1.z.le(first.z)));
        let in_box = if prune { in_box } else { zero };
        let mut limit = L::select(in_box, last, L::splat(f32::INFINITY));
        for c in 0..count {
            let active = moved.and(limit.gt(L::splat(c as f32)));
            if active.bits() != 0 {
                let hit = collide_near(scene.collider(c), (s, p1), &mut p, active, contact);
                again = again.or(hit);
                // Moved again: the shapes after this one may now touch it (as one that
                // tests every shape finds).
                limit = L::select(hit, L::splat(f32::INFINITY), limit);
            }
        }
    }
    // SAFETY: `out.p` holds eight positions.
    unsafe { L::scatter(out.p.as_mut_ptr(), &index, p) };
    let last = last.to_array();
    out.last = std::array::from_fn(|l| last[l] as u16);
    Some((moved.bits(), again.bits()))
}

/// The smallest displacement `d` with `n_a·d ≥ -s_a` and `n_b·d ≥ -s_b` (both `s < 0`: the
/// depths inside two half-spaces with unit normals `n_a`, `n_b`).
#[inline]
pub(super) fn clear_two((sa, na): (f32, Vec3A), (sb, nb): (f32, Vec3A)) -> Vec3A {
    // One push alone may clear both.
    let da = -sa * na;
    if nb.dot(da) >= -sb {
        return da;
    }
    let db = -sb * nb;
    if na.dot(db) >= -sa {
        return db;
    }
    // Both active: d = α n_a + β n_b with n_a·d = -s_a and n_b·d = -s_b.
    let c = na.dot(nb);
    let det = 1.0 - c * c;
    if det < 1e-4 {
        // (Anti)parallel normals: no finite crease; take the deeper push.
        return if sa < sb { da } else { db };
    }
    let alpha = (-sa + c * sb) / det;
    let beta = (-sb + c * sa) / det;
    let d = alpha * na + beta * nb;
    // Nearly opposite normals (a particle pinched between two shapes) put the linearised crease
    // far away: there the deeper push alone is taken.
    let deeper = if sa < sb { da } else { db };
    if d.length_squared() > CREASE_REACH * CREASE_REACH * deeper.length_squared() {
        deeper
    } else {
        d
    }
}

/// The lanes of `bounds` whose box meets the box from `low` to `high`, as bits: the same
/// comparisons as [`SweptCollider::overlaps`] makes for each.
///
/// # Safety
/// None beyond the instruction set's (see `dispatch_lanes`).
#[inline]
pub(super) unsafe fn overlaps8(isa: Isa, bounds: &ColliderBounds, low: Vec3A, high: Vec3A) -> u32 {
    dispatch_lanes!(
        isa,
        overlaps8_with(bounds: &ColliderBounds, low: Vec3A, high: Vec3A) -> u32
    )
}

#[inline(always)]
pub(super) unsafe fn overlaps8_with<L: Lanes>(
    bounds: &ColliderBounds,
    low: Vec3A,
    high: Vec3A,
) -> u32 {
    let mut meets = L::splat(0.0).le(L::splat(0.0));
    for axis in 0..3 {
        let (lo, hi) = (L::load(&bounds.min[axis]), L::load(&bounds.max[axis]));
        meets = meets
            .and(lo.le(L::splat(high[axis])))
            .and(L::splat(low[axis]).le(hi));
    }
    meets.bits()
}
