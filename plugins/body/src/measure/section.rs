//! Plane cross-sections of a triangle mesh, the cut the tape measure follows (after seed 002 (Uğur
//! 2008, parametric bodies for virtual dressing) §4.2): the crossed triangles joined into loops,
//! and the triangles binned by height so that a horizontal section visits only the ones that can
//! cross its plane.

use glam::{Vec2, Vec3};

/// One connected piece of a plane cross-section of a mesh.
#[derive(Clone, Debug, PartialEq)]
pub struct SectionLoop {
    /// Points in order along the cut, in the plane's 2D coordinates (metres).
    pub points: Vec<Vec2>,
    /// The same points in 3D.
    pub points_3d: Vec<Vec3>,
    /// The mesh edge each point lies on (vertex indices, smaller first).
    pub edges: Vec<(u32, u32)>,
    /// Whether the chain closes on itself (it does on a closed mesh).
    pub closed: bool,
}

impl SectionLoop {
    /// Length along the cut (the tape laid on the skin, concavities followed).
    pub fn length(&self) -> f32 {
        let mut l: f32 = self.points.windows(2).map(|w| w[0].distance(w[1])).sum();
        if self.closed && self.points.len() > 2 {
            l += self.points[self.points.len() - 1].distance(self.points[0]);
        }
        l
    }

    /// Whether `p` is inside the polygon of the points (even-odd rule; an open chain is
    /// closed by its last-to-first edge).
    pub fn contains(&self, p: Vec2) -> bool {
        let n = self.points.len();
        let mut inside = false;
        for i in 0..n {
            let (a, b) = (self.points[i], self.points[(i + 1) % n]);
            if (a.y > p.y) != (b.y > p.y) && p.x < a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x) {
                inside = !inside;
            }
        }
        inside
    }

    /// Centroid of the points.
    pub fn centroid(&self) -> Vec2 {
        self.points.iter().copied().sum::<Vec2>() / self.points.len().max(1) as f32
    }
}

/// A cutting plane with an orthonormal 2D frame: 2D coordinates are `(dot(p - origin, u),
/// dot(p - origin, v))`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plane {
    pub origin: Vec3,
    pub normal: Vec3,
    pub u: Vec3,
    pub v: Vec3,
}

impl Plane {
    /// The horizontal plane y = `h`; 2D coordinates are `(x, z)`.
    pub fn horizontal(h: f32) -> Self {
        Self {
            origin: Vec3::new(0.0, h, 0.0),
            normal: Vec3::Y,
            u: Vec3::X,
            v: Vec3::Z,
        }
    }

    /// The plane through `origin` with normal `normal` (normalised here); the 2D frame's `u`
    /// is the model X axis made perpendicular to the normal (or Z if the normal is along X).
    pub fn new(origin: Vec3, normal: Vec3) -> Self {
        let normal = normal.normalize();
        let seed = if normal.x.abs() < 0.9 {
            Vec3::X
        } else {
            Vec3::Z
        };
        let u = (seed - normal * seed.dot(normal)).normalize();
        let v = normal.cross(u);
        Self {
            origin,
            normal,
            u,
            v,
        }
    }

    fn distance(&self, p: Vec3) -> f32 {
        (p - self.origin).dot(self.normal)
    }

    fn project(&self, p: Vec3) -> Vec2 {
        let d = p - self.origin;
        Vec2::new(d.dot(self.u), d.dot(self.v))
    }
}

/// Cuts the triangles with `plane` and joins the pieces into loops. A vertex exactly on the
/// plane counts as on its positive side, so each crossed edge gives exactly one point and
/// loops of a closed mesh close.
pub fn cross_section(
    positions: &[Vec3],
    triangles: &[[u32; 3]],
    plane: &Plane,
) -> Vec<SectionLoop> {
    cross_section_of(positions, triangles.iter(), plane)
}

/// [`cross_section`] of the triangles `triangles` yields (a subset of a mesh's triangles that
/// holds every triangle the plane crosses, e.g. from a [`HeightIndex`]).
pub fn cross_section_of<'t>(
    positions: &[Vec3],
    triangles: impl Iterator<Item = &'t [u32; 3]>,
    plane: &Plane,
) -> Vec<SectionLoop> {
    let side = |i: u32| plane.distance(positions[i as usize]) >= 0.0;
    // Segments as pairs of crossed edges.
    let mut segments: Vec<[(u32, u32); 2]> = Vec::new();
    for t in triangles {
        let s = [side(t[0]), side(t[1]), side(t[2])];
        if s[0] == s[1] && s[1] == s[2] {
            continue;
        }
        let mut crossed = [(0, 0); 2];
        let mut n = 0;
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            if s[k] != s[(k + 1) % 3] {
                crossed[n] = (a.min(b), a.max(b));
                n += 1;
            }
        }
        segments.push(crossed);
    }
    loops_from_segments(positions, plane, &segments)
}

/// Triangles binned by height, so that a horizontal cross-section visits only the triangles
/// that can cross its plane (a body has ~26k triangles; a section crosses ~300).
#[derive(Clone, Debug)]
pub struct HeightIndex {
    y0: f32,
    bin_m: f32,
    bins: Vec<Vec<u32>>,
}

impl HeightIndex {
    /// Bins of 1 cm over the vertical extent of `triangles`.
    pub fn new(positions: &[Vec3], triangles: &[[u32; 3]]) -> Self {
        let bin_m = 0.01;
        let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
        for t in triangles {
            for &v in t {
                let y = positions[v as usize].y;
                lo = lo.min(y);
                hi = hi.max(y);
            }
        }
        if !(lo.is_finite() && hi.is_finite()) {
            return Self {
                y0: 0.0,
                bin_m,
                bins: Vec::new(),
            };
        }
        let n = ((hi - lo) / bin_m).floor() as usize + 1;
        let mut bins = vec![Vec::new(); n];
        for (i, t) in triangles.iter().enumerate() {
            let ys = t.map(|v| positions[v as usize].y);
            let (a, b) = (ys[0].min(ys[1]).min(ys[2]), ys[0].max(ys[1]).max(ys[2]));
            let (ba, bb) = (
                (((a - lo) / bin_m).floor() as usize).min(n - 1),
                (((b - lo) / bin_m).floor() as usize).min(n - 1),
            );
            for bin in &mut bins[ba..=bb] {
                bin.push(i as u32);
            }
        }
        Self {
            y0: lo,
            bin_m,
            bins,
        }
    }

    /// Indices of the triangles whose height range may contain `h`.
    pub fn candidates(&self, h: f32) -> &[u32] {
        let f = ((h - self.y0) / self.bin_m).floor();
        if !(f >= 0.0 && (f as usize) < self.bins.len()) {
            return &[];
        }
        &self.bins[f as usize]
    }

    /// The horizontal cross-section at height `h`.
    pub fn slice(&self, positions: &[Vec3], triangles: &[[u32; 3]], h: f32) -> Vec<SectionLoop> {
        cross_section_of(
            positions,
            self.candidates(h).iter().map(|&t| &triangles[t as usize]),
            &Plane::horizontal(h),
        )
    }
}

fn loops_from_segments(
    positions: &[Vec3],
    plane: &Plane,
    segments: &[[(u32, u32); 2]],
) -> Vec<SectionLoop> {
    // Each edge is shared by at most two segments (manifold mesh): sort the (edge, segment,
    // slot) triples and link the pairs.
    let key = |e: (u32, u32)| ((e.0 as u64) << 32) | e.1 as u64;
    let mut ends: Vec<(u64, u32, u8)> = Vec::with_capacity(segments.len() * 2);
    for (i, s) in segments.iter().enumerate() {
        ends.push((key(s[0]), i as u32, 0));
        ends.push((key(s[1]), i as u32, 1));
    }
    ends.sort_unstable();
    let mut links = vec![[usize::MAX; 2]; segments.len()];
    for w in ends.windows(2) {
        if w[0].0 == w[1].0 {
            links[w[0].1 as usize][w[0].2 as usize] = w[1].1 as usize;
            links[w[1].1 as usize][w[1].2 as usize] = w[0].1 as usize;
        }
    }
    let point = |e: (u32, u32)| {
        let (pa, pb) = (positions[e.0 as usize], positions[e.1 as usize]);
        let (da, db) = (plane.distance(pa), plane.distance(pb));
        let t = if da == db { 0.5 } else { da / (da - db) };
        pa.lerp(pb, t)
    };
    let other = |seg: usize, e: (u32, u32)| -> Option<usize> {
        let slot = if segments[seg][0] == e { 0 } else { 1 };
        let o = links[seg][slot];
        (o != usize::MAX && o != seg).then_some(o)
    };
    let mut used = vec![false; segments.len()];
    let mut loops = Vec::new();
    let mut walk = |start: usize, entry: (u32, u32), used: &mut Vec<bool>| {
        let mut edges = vec![entry];
        let (mut cur, mut entry) = (start, entry);
        loop {
            used[cur] = true;
            let s = segments[cur];
            let exit = if s[0] == entry { s[1] } else { s[0] };
            edges.push(exit);
            match other(cur, exit) {
                Some(next) if !used[next] => {
                    cur = next;
                    entry = exit;
                }
                _ => break,
            }
        }
        let closed = edges.len() > 2 && edges.first() == edges.last();
        if closed {
            edges.pop();
        }
        let points_3d: Vec<Vec3> = edges.iter().map(|&e| point(e)).collect();
        loops.push(SectionLoop {
            points: points_3d.iter().map(|&p| plane.project(p)).collect(),
            points_3d,
            edges,
            closed,
        });
    };
    // Open chains first (from an end: an edge crossed by one segment only), then loops.
    for i in 0..segments.len() {
        if used[i] {
            continue;
        }
        if let Some(&end) = segments[i].iter().find(|&&e| other(i, e).is_none()) {
            walk(i, end, &mut used);
        }
    }
    for i in 0..segments.len() {
        if !used[i] {
            walk(i, segments[i][0], &mut used);
        }
    }
    loops
}
