//! The fit's residuals: each surface point against the skin's triangle it lies over, the
//! silhouette's skin seen in free space, the skin below the floor; and their cost.

use fitroom_body::{BodyModel, compute_normals};
use fitroom_depth::camera::{HEIGHT, WIDTH};
use glam::Vec3;

use super::FitSettings;
use crate::posed::PosedBody;
use crate::silhouette::OutsideDistance;
use crate::view::AveragedView;

/// Scene this far behind the skin is free space in front of the background, metres.
const FREE_M: f32 = 0.15;

/// Pixels per side of the tiles the visible skin is binned in for the partner search.
const TILE: usize = 4;

/// Rings of tiles searched about a point's at most, whatever the reach (a bound for points
/// very near the camera).
const MAX_RINGS: usize = 16;

/// One residual's row: value, weight, and where it touches the body (a point of the skin
/// as a blend of up to three vertices, and the direction it is measured along); a surface
/// point's or a silhouette vertex's.
pub(super) struct Row {
    pub(super) surface: bool,
    pub(super) r: f32,
    pub(super) w: f32,
    pub(super) vertices: [u32; 3],
    pub(super) blend: [f32; 3],
    pub(super) dir: Vec3,
}

impl Row {
    /// The row's skin point's motion, of per-vertex motions `c`.
    pub(super) fn at(&self, c: &[Vec3]) -> Vec3 {
        let [a, b, d] = self.vertices.map(|v| c[v as usize]);
        a * self.blend[0] + b * self.blend[1] + d * self.blend[2]
    }
}

/// What the residuals are computed from.
pub(super) struct Problem<'a> {
    pub(super) model: &'a BodyModel,
    pub(super) view: &'a AveragedView,
    pub(super) points: Vec<Vec3>,
    /// Where each point is seen (pixel).
    pub(super) pixels: Vec<(f32, f32)>,
    pub(super) outside: OutsideDistance,
    /// Per body vertex, the triangles it is a corner of.
    pub(super) faces_of: &'a [Vec<u32>],
    /// Per body vertex, whether the clothing layer covers it ([`clothed_vertices`]; empty:
    /// no layer).
    pub(super) layer: &'a [bool],
    pub(super) settings: &'a FitSettings,
}

/// Per body vertex of `model`, whether a layer of clothing `t` thick covers it
/// ([`fitroom_tracker::model::clothed_vertices`]). Empty when `t` is 0.
pub(super) fn clothed_vertices(model: &BodyModel, t: f32) -> Vec<bool> {
    if t <= 0.0 {
        return Vec::new();
    }
    fitroom_tracker::model::clothed_vertices(model)
}

/// Per vertex of `count`, the triangles of `triangles` it is a corner of.
pub(super) fn faces_of(count: usize, triangles: &[[u32; 3]]) -> Vec<Vec<u32>> {
    let mut out = vec![Vec::new(); count];
    for (f, t) in triangles.iter().enumerate() {
        for &v in t {
            if let Some(list) = out.get_mut(v as usize) {
                list.push(f as u32);
            }
        }
    }
    out
}

impl Problem<'_> {
    /// The triangle at vertex `i` that `p` lies over (its projection inside; the nearest
    /// plane of those): its normal, corners and `p`'s projection's barycentric weights. A
    /// point over none of them (off the skin: a limb the pose has not reached yet) is held
    /// against the vertex's tangent plane: the plane of a triangle it is not over can pass
    /// near it at any slant.
    fn face_under(
        &self,
        body: &PosedBody,
        normals: &[Vec3],
        i: u32,
        p: Vec3,
    ) -> (Vec3, [u32; 3], [f32; 3]) {
        let v = &body.vertices;
        let mut best: Option<(f32, Vec3, [u32; 3], [f32; 3])> = None;
        for &f in self
            .faces_of
            .get(i as usize)
            .map_or(&[][..], |l| l.as_slice())
        {
            let t = self.model.triangles[f as usize];
            let [a, b, c] = t.map(|k| v[k as usize]);
            let cross = (b - a).cross(c - a);
            let area2 = cross.length_squared();
            if area2 <= 0.0 {
                continue;
            }
            let n = cross / area2.sqrt();
            let d = n.dot(p - a);
            let q = p - n * d;
            // Barycentric weights of q from the sub-triangles' signed areas.
            let wa = (b - q).cross(c - q).dot(cross) / area2;
            let wb = (c - q).cross(a - q).dot(cross) / area2;
            let wc = 1.0 - wa - wb;
            if wa < -1e-4 || wb < -1e-4 || wc < -1e-4 {
                continue;
            }
            if best.is_none_or(|(s, ..)| d.abs() < s) {
                best = Some((d.abs(), n, t, [wa, wb, wc]));
            }
        }
        match best {
            Some((_, n, t, blend)) => (n, t, blend),
            None => (normals[i as usize], [i; 3], [1.0, 0.0, 0.0]),
        }
    }

    /// The residual rows of `body` (under the clothing layer, if any): the surface points,
    /// then the silhouette. The layer moves the surface, not the rows' motions: a vertex
    /// moved by the sliders carries its layer along.
    pub(super) fn rows(&self, body: &PosedBody) -> Vec<Row> {
        let t = self.settings.clothing_m;
        if t <= 0.0 || self.layer.is_empty() {
            return self.rows_of(body);
        }
        let normals = compute_normals(&body.vertices, &self.model.triangles);
        let mut clothed = body.clone();
        for ((v, n), &on) in clothed.vertices.iter_mut().zip(&normals).zip(self.layer) {
            if on {
                *v += *n * t;
            }
        }
        self.rows_of(&clothed)
    }

    fn rows_of(&self, body: &PosedBody) -> Vec<Row> {
        let s = self.settings;
        let normals = compute_normals(&body.vertices, &self.model.triangles);
        // Skin the camera can see: turned towards it.
        let facing: Vec<bool> = body
            .vertices
            .iter()
            .zip(&normals)
            .map(|(v, n)| n.dot(v.normalize_or_zero()) < -0.05)
            .collect();
        // The visible skin binned by where it is seen, in tiles of TILE pixels: a point's
        // partner is looked for among the skin seen in its tile and the ones around it.
        let cam = &self.view.camera;
        let (tw, th) = (WIDTH.div_ceil(TILE), HEIGHT.div_ceil(TILE));
        let tile_of = |u: f32, v: f32| -> Option<(usize, usize)> {
            let (tu, tv) = ((u / TILE as f32).floor(), (v / TILE as f32).floor());
            ((0.0..tw as f32).contains(&tu) && (0.0..th as f32).contains(&tv))
                .then_some((tu as usize, tv as usize))
        };
        let mut seen_at = vec![None; body.vertices.len()];
        let mut tile_at = vec![usize::MAX; body.vertices.len()];
        // The tiles' skin, tile after tile (row-major), each tile's vertices in index order:
        // the three tiles of a row of the neighbourhood are one run of memory.
        let mut start = vec![0usize; tw * th + 1];
        for (i, v) in body.vertices.iter().enumerate() {
            if !facing[i] {
                continue;
            }
            let Some(px) = cam.project(*v) else {
                continue;
            };
            seen_at[i] = Some(px);
            if let Some((tu, tv)) = tile_of(px.x, px.y) {
                tile_at[i] = tv * tw + tu;
                start[tile_at[i] + 1] += 1;
            }
        }
        for t in 0..tw * th {
            start[t + 1] += start[t];
        }
        let mut fill = start.clone();
        let mut binned = vec![(Vec3::ZERO, 0u32); start[tw * th]];
        for (i, &t) in tile_at.iter().enumerate() {
            if t != usize::MAX {
                binned[fill[t]] = (body.vertices[i], i as u32);
                fill[t] += 1;
            }
        }
        let huber = |r: f32| {
            let a = r.abs();
            if a <= s.robust_m { 1.0 } else { s.robust_m / a }
        };
        let mut rows = Vec::with_capacity(self.points.len() + 2000);
        let reach2 = s.reach_m * s.reach_m;
        for (&p, &(pu, pv)) in self.points.iter().zip(&self.pixels) {
            let Some((tu, tv)) = tile_of(pu, pv) else {
                continue;
            };
            // Ring after ring of tiles about the point's, until the nearest skin found is
            // nearer than anything outside the rings can be (a vertex seen k tiles away is
            // at least k tiles' width away across the line of sight), or the rings cover the
            // reach. (Capped at 12 px, 5 cm, the fit of a tall woman from the women's mean
            // body, 19 cm shorter, ended 6 cm short: her shins' points found no partners.)
            let mut best: Option<(f32, u32)> = None;
            let mut scan = |y: usize, a: usize, b: usize| {
                for &(v, i) in &binned[start[y * tw + a]..start[y * tw + b + 1]] {
                    let d2 = v.distance_squared(p);
                    if d2 <= reach2 && best.is_none_or(|(b, bi)| d2 < b || (d2 == b && i < bi)) {
                        best = Some((d2, i));
                    }
                }
                best
            };
            for ring in 0..=MAX_RINGS {
                let (x0, x1) = (tu.saturating_sub(ring), (tu + ring).min(tw - 1));
                let mut found = None;
                for y in tv.saturating_sub(ring)..=(tv + ring).min(th - 1) {
                    if y.abs_diff(tv) == ring {
                        found = scan(y, x0, x1);
                        continue;
                    }
                    if tu >= ring {
                        found = scan(y, tu - ring, tu - ring);
                    }
                    if tu + ring < tw {
                        found = scan(y, tu + ring, tu + ring);
                    }
                }
                let covered = (ring * TILE) as f32 * p.z / cam.fx;
                if found.is_some_and(|(d2, _)| d2 <= covered * covered) || covered >= s.reach_m {
                    break;
                }
            }
            let Some((_, i)) = best else {
                continue;
            };
            // The point against the skin's triangle it lies over (the camera films the
            // triangles: against the nearest vertex's tangent plane, every point of a convex
            // patch lies inside it, and the fit shrank the body: on exact depth, from the
            // true shape, chest -0.3 cm, hip -0.7 cm).
            let (n, vertices, blend) = self.face_under(body, &normals, i, p);
            let r = n.dot(p - body.vertices[i as usize]);
            // The residual is the point minus the skin: moving the skin along n lowers it.
            rows.push(Row {
                surface: true,
                r: -r,
                w: huber(r) * if r > 0.0 { s.outside_weight } else { 1.0 },
                vertices,
                blend,
                dir: n,
            });
        }
        // Skin below the floor, pushed up: the tracker's pixels lose the soles with the
        // floor, and without them nothing held the feet (through the tracker the bodies
        // came out 1 cm tall, the legs reaching into the floor).
        if let Some(floor) = self.view.floor {
            for (j, v) in body.vertices.iter().enumerate() {
                let below = -floor.height(*v);
                if below > 0.0 {
                    rows.push(Row {
                        surface: false,
                        r: below,
                        w: huber(below),
                        vertices: [j as u32; 3],
                        blend: [1.0, 0.0, 0.0],
                        // Rows grow along `dir` (as the surface's and silhouette's): down.
                        dir: -floor.normal,
                    });
                }
            }
        }
        // Visible skin outside the person's pixels, pulled back in.
        for (j, v) in body.vertices.iter().enumerate() {
            let Some(px) = seen_at[j] else {
                continue;
            };
            let Some((d, grad)) = self.outside.at(px.x, px.y) else {
                continue;
            };
            // A pixel of slack: the mask's edge flickers and the skin's edge is sampled.
            if d <= 1.0 {
                continue;
            }
            // Only where the scene shows free space in front of the skin: a reading behind
            // it (the wall through the gap). A surface at the skin's depth is the person
            // left out of the mask (the soles, cut off with the floor); no reading says
            // nothing (the Kinect loses the body's edges and the projector's shadow beside
            // them: taken as free space, the tracker's mask, which leaves them out, made
            // every girth 1-2 cm small).
            let (u, vv) = (px.x.round() as usize, px.y.round() as usize);
            let scene = self.view.scene_m[vv * WIDTH + u];
            if scene <= 0.0 || scene < v.z + FREE_M {
                continue;
            }
            let metres = (d - 1.0) * v.z / cam.fx;
            let dir = Vec3::new(-grad.x, -grad.y, 0.0).normalize_or_zero();
            rows.push(Row {
                surface: false,
                r: metres,
                w: s.silhouette_weight * huber(metres),
                vertices: [j as u32; 3],
                blend: [1.0, 0.0, 0.0],
                dir,
            });
        }
        rows
    }

    /// The data term of `rows`.
    pub(super) fn cost(&self, rows: &[Row]) -> f64 {
        let c = self.settings.robust_m;
        rows.iter()
            .map(|r| {
                let a = r.r.abs();
                let scale = r.w.max(0.0) / if a <= c { 1.0 } else { c / a };
                let loss = if a <= c {
                    0.5 * a * a
                } else {
                    c * (a - 0.5 * c)
                };
                f64::from(scale * loss)
            })
            .sum()
    }
}
