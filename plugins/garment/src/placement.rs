//! Placing flat panels around the body: each wrap of the pattern winds its panels around an
//! axis (vertical, across the shoulders, or along a bone) on a tube that follows the body.
//!
//! At each axial position `h` (every centimetre), the tube's cross-section is the convex hull
//! of the body region's cross-section there (the tape measure of seed 002 §4.2, which bridges
//! concavities), offset outward by a distance `d`; an offset convex curve has perimeter
//! `P + 2πd`, so for a circular body this is the cylinder of radius `girth/2π + ease`.
//!
//! - **Closed rows**: where every panel of a closed wrap is present and their widths add up to
//!   `C ≥ P` (the body's girth there), `d = (C − P)/2π`: the sewn garment's girth is exactly
//!   the pattern's, and the panels lie side by side in the wrap's order, the first one's centre
//!   line at its angle. Side seams then coincide in space.
//! - **Open rows** (a panel missing at that height, e.g. above the armholes, or a garment
//!   smaller than the body): each panel lies at its own angle at its natural width, at
//!   `d = ease`; the seams there are closed by [`crate::GarmentMesh::sew`].
//!
//! A panel point `(x, y)` (cm) goes to axial position `h0 + y` and to the arc length
//! `centre(h) + (x − mid(y))` along the curve, `mid(y)` being the middle of the panel's row
//! at `y`; positions are interpolated between the two neighbouring rows. Counter-clockwise
//! panel triangles thus face outward. Finally, any point closer to the body surface than the
//! clearance (anywhere: an arm near a sleeve) is pushed out along the surface normal.

use glam::{Vec2, Vec3};

use crate::body::{BodySurface, Region};
use crate::error::GarmentError;
use crate::pattern::{Axis, Panel, Wrap, row_extent, y_range};

/// Axial step between tube rows, metres.
const ROW_STEP: f32 = 0.01;
/// Largest angle between samples of an offset corner arc, radians.
const ARC_STEP: f32 = 0.17;

/// The frame of a wrap's axis.
#[derive(Clone, Copy, Debug)]
pub(crate) struct AxisFrame {
    origin: Vec3,
    axis: Vec3,
    /// Angle 0.
    f: Vec3,
    /// Angle 90°: `axis × f`.
    g: Vec3,
    /// Axial coordinate of the panels' y = 0.
    h0: f32,
}

impl AxisFrame {
    pub(crate) fn new(
        body: &BodySurface,
        axis: &Axis,
        garment: &str,
    ) -> Result<Self, GarmentError> {
        match axis {
            Axis::Vertical {
                landmark,
                offset_cm,
            } => Ok(Self {
                origin: Vec3::ZERO,
                axis: Vec3::Y,
                f: Vec3::Z,
                g: Vec3::X,
                h0: body.landmark_y(*landmark) + offset_cm / 100.0,
            }),
            Axis::Lateral { shoulder_fraction } => Ok(Self {
                origin: Vec3::ZERO,
                axis: Vec3::X,
                f: Vec3::Y,
                g: Vec3::Z,
                h0: shoulder_fraction * body.measurements.shoulder_width_cm / 200.0,
            }),
            Axis::Bone { name, offset_cm } => {
                let b = body
                    .bone_index(name)
                    .ok_or_else(|| GarmentError::Placement {
                        garment: garment.to_owned(),
                        problem: format!("the body has no bone \"{name}\""),
                    })?;
                let head = body.rest_pose.heads[b];
                let tail = body.rest_pose.tails[b];
                let axis = (head - tail).normalize_or_zero();
                if axis == Vec3::ZERO {
                    return Err(GarmentError::Placement {
                        garment: garment.to_owned(),
                        problem: format!("bone \"{name}\" has zero length"),
                    });
                }
                let mut f = Vec3::Z - axis * axis.dot(Vec3::Z);
                if f.length() < 0.1 {
                    f = Vec3::Y - axis * axis.dot(Vec3::Y);
                }
                let f = f.normalize();
                Ok(Self {
                    origin: head,
                    axis,
                    f,
                    g: axis.cross(f),
                    h0: offset_cm / 100.0,
                })
            }
        }
    }

    fn axial(&self, p: Vec3) -> f32 {
        (p - self.origin).dot(self.axis)
    }

    fn plane(&self, p: Vec3) -> Vec2 {
        let d = p - self.origin;
        Vec2::new(d.dot(self.f), d.dot(self.g))
    }

    fn point(&self, h: f32, q: Vec2) -> Vec3 {
        self.origin + self.axis * h + self.f * q.x + self.g * q.y
    }
}

/// A closed convex curve parameterised by arc length, counter-clockwise.
#[derive(Clone, Debug)]
struct Curve {
    points: Vec<Vec2>,
    /// `cumulative[i]`: arc length at `points[i]`; one more entry for the closing segment.
    cumulative: Vec<f32>,
    centroid: Vec2,
}

impl Curve {
    /// The hull `hull` (counter-clockwise) offset outward by `d`, corners rounded.
    fn offset(hull: &[Vec2], d: f32) -> Curve {
        let n = hull.len();
        let mut points = Vec::with_capacity(n * 3);
        let normal = |i: usize| {
            let e = hull[(i + 1) % n] - hull[i];
            Vec2::new(e.y, -e.x).normalize_or_zero()
        };
        for (i, &corner) in hull.iter().enumerate() {
            let n0 = normal((i + n - 1) % n);
            let n1 = normal(i);
            if d <= 0.0 {
                points.push(corner);
                continue;
            }
            let turn = n0.angle_to(n1).max(0.0);
            let steps = (turn / ARC_STEP).ceil().max(1.0) as usize;
            for s in 0..=steps {
                let dir = Vec2::from_angle(turn * s as f32 / steps as f32).rotate(n0);
                points.push(corner + dir * d);
            }
        }
        points.dedup_by(|a, b| a.distance(*b) < 1e-6);
        let mut cumulative = Vec::with_capacity(points.len() + 1);
        let mut total = 0.0;
        for i in 0..points.len() {
            cumulative.push(total);
            total += points[i].distance(points[(i + 1) % points.len()]);
        }
        cumulative.push(total);
        Curve {
            points,
            cumulative,
            centroid: area_centroid(hull),
        }
    }

    fn perimeter(&self) -> f32 {
        self.cumulative[self.cumulative.len() - 1]
    }

    fn point_at(&self, s: f32) -> Vec2 {
        let total = self.perimeter();
        let s = s.rem_euclid(total.max(f32::MIN_POSITIVE));
        let i = match self.cumulative.binary_search_by(|c| c.total_cmp(&s)) {
            Ok(i) => i.min(self.points.len() - 1),
            Err(i) => i.saturating_sub(1).min(self.points.len() - 1),
        };
        let a = self.points[i];
        let b = self.points[(i + 1) % self.points.len()];
        let len = self.cumulative[i + 1] - self.cumulative[i];
        let t = if len > 0.0 {
            (s - self.cumulative[i]) / len
        } else {
            0.0
        };
        a.lerp(b, t.clamp(0.0, 1.0))
    }

    /// Arc length where the ray from the centroid at `angle` (from the frame's `f`) leaves
    /// the curve.
    fn arc_at_angle(&self, angle: f32) -> f32 {
        let dir = Vec2::from_angle(angle);
        let c = self.centroid;
        let n = self.points.len();
        let mut best = (f32::INFINITY, 0.0);
        for i in 0..n {
            let a = self.points[i];
            let b = self.points[(i + 1) % n];
            let e = b - a;
            let denom = dir.perp_dot(e);
            if denom.abs() < 1e-12 {
                continue;
            }
            // c + t dir = a + u e
            let ac = a - c;
            let t = ac.perp_dot(e) / denom;
            let u = ac.perp_dot(dir) / denom;
            if t > 0.0 && (-1e-5..=1.0 + 1e-5).contains(&u) && t < best.0 {
                best = (t, self.cumulative[i] + u.clamp(0.0, 1.0) * e.length());
            }
        }
        best.1
    }
}

fn area_centroid(poly: &[Vec2]) -> Vec2 {
    let n = poly.len();
    let mut a = 0.0;
    let mut c = Vec2::ZERO;
    for i in 0..n {
        let (p, q) = (poly[i], poly[(i + 1) % n]);
        let w = p.perp_dot(q);
        a += w;
        c += (p + q) * w;
    }
    if a.abs() < 1e-12 {
        poly.iter().copied().sum::<Vec2>() / n.max(1) as f32
    } else {
        c / (3.0 * a)
    }
}

/// One row of a wrap's tube.
#[derive(Clone, Debug)]
struct Row {
    h: f32,
    curve: Curve,
    /// Arc-length position of each wrap panel's centre line (`None`: absent at this row).
    centres: Vec<Option<f32>>,
    /// Arc length per panel cm/100 (1 unless a closed row is stretched).
    scale: f32,
}

/// What placement reports for each wrap row that was closed, for tests and the designer.
#[derive(Clone, Debug, PartialEq)]
pub struct RowReport {
    pub wrap: String,
    /// Axial position (for vertical wraps: model-space height), metres.
    pub h: f32,
    /// Body girth (convex hull of the region's cross-section), cm.
    pub body_girth_cm: f32,
    /// Sum of the panels' widths at this row, cm.
    pub garment_girth_cm: f32,
    /// Distance of the tube from the body hull, cm.
    pub offset_cm: f32,
    pub closed: bool,
}

/// Places the (graded) panels' 2D vertices of one wrap. `vertices[k]` are the 2D points of
/// panel `wrap.panels[k].0`.
pub(crate) fn place_wrap(
    body: &BodySurface,
    wrap: &Wrap,
    panels: &[Panel],
    vertices: &[&[Vec2]],
    garment: &str,
    report: &mut Vec<RowReport>,
) -> Result<Vec<Vec<Vec3>>, GarmentError> {
    let frame = AxisFrame::new(body, &wrap.axis, garment)?;
    let fail = |problem: String| GarmentError::Placement {
        garment: garment.to_owned(),
        problem,
    };
    // Axial extent of the wrap's panels.
    let ranges: Vec<(f32, f32)> = wrap
        .panels
        .iter()
        .map(|&(p, _)| y_range(&panels[p].outline))
        .collect();
    let lo = ranges.iter().map(|r| r.0).fold(f32::INFINITY, f32::min);
    let hi = ranges.iter().map(|r| r.1).fold(f32::NEG_INFINITY, f32::max);
    let h_start = frame.h0 + lo / 100.0 - ROW_STEP;
    let rows_n = (((hi - lo) / 100.0 + 2.0 * ROW_STEP) / ROW_STEP).ceil() as usize + 1;

    // The region's triangles with their corners' axial coordinates.
    let region = wrap.around;
    let tris: Vec<[u32; 3]> = (0..body.triangles.len())
        .filter(|&t| region.contains(body.part_of_triangle(t)))
        .map(|t| body.triangles[t])
        .collect();
    let axial: Vec<f32> = body.positions.iter().map(|&p| frame.axial(p)).collect();

    let ease = wrap.ease_cm / 100.0;
    let mut rows: Vec<Option<Row>> = Vec::with_capacity(rows_n);
    for k in 0..rows_n {
        let h = h_start + k as f32 * ROW_STEP;
        let section = section_points(body, &frame, &tris, &axial, h);
        let hull = fitroom_body::measure::convex_hull(&section);
        if hull.len() < 3 {
            rows.push(None);
            continue;
        }
        let body_perimeter: f32 = (0..hull.len())
            .map(|i| hull[i].distance(hull[(i + 1) % hull.len()]))
            .sum();
        // Panel widths at this row (metres), tolerant of one row step beyond their ends.
        let widths: Vec<Option<f32>> = wrap
            .panels
            .iter()
            .zip(&ranges)
            .map(|(&(p, _), &(y0, y1))| {
                let y = (h - frame.h0) * 100.0;
                if y < y0 - ROW_STEP * 100.0 || y > y1 + ROW_STEP * 100.0 {
                    return None;
                }
                row_extent(&panels[p].outline, y.clamp(y0, y1)).map(|(a, b)| (b - a) / 100.0)
            })
            .collect();
        let all_present = widths.iter().all(Option::is_some);
        let total: f32 = widths.iter().flatten().sum();
        let closed = wrap.closed && all_present && total >= body_perimeter;
        let offset = if closed {
            (total - body_perimeter) / std::f32::consts::TAU
        } else {
            ease
        };
        let curve = Curve::offset(&hull, offset);
        let mut centres = vec![None; wrap.panels.len()];
        let scale;
        if closed {
            scale = curve.perimeter() / total.max(f32::MIN_POSITIVE);
            let first = curve.arc_at_angle(wrap.panels[0].1.to_radians());
            let mut s = first - 0.5 * widths[0].unwrap_or(0.0) * scale;
            for (i, w) in widths.iter().enumerate() {
                let w = w.unwrap_or(0.0) * scale;
                centres[i] = Some(s + 0.5 * w);
                s += w;
            }
        } else {
            scale = 1.0;
            for (i, w) in widths.iter().enumerate() {
                if w.is_some() {
                    centres[i] = Some(curve.arc_at_angle(wrap.panels[i].1.to_radians()));
                }
            }
        }
        if all_present {
            report.push(RowReport {
                wrap: wrap.name.clone(),
                h,
                body_girth_cm: body_perimeter * 100.0,
                garment_girth_cm: total * 100.0,
                offset_cm: offset * 100.0,
                closed,
            });
        }
        rows.push(Some(Row {
            h,
            curve,
            centres,
            scale,
        }));
    }
    if rows.iter().all(Option::is_none) {
        return Err(fail(format!(
            "wrap \"{}\" finds no body of region {:?} along its axis",
            wrap.name, region
        )));
    }
    // Rows without body (beyond the region's end) copy the nearest row that has one.
    let filled: Vec<Row> = (0..rows.len())
        .map(|k| {
            let nearest = (0..rows.len())
                .filter(|&j| rows[j].is_some())
                .min_by_key(|&j| j.abs_diff(k))
                .unwrap_or(k);
            let mut row = rows[nearest].clone();
            if let Some(r) = row.as_mut() {
                r.h = h_start + k as f32 * ROW_STEP;
            }
            row
        })
        .collect::<Option<Vec<Row>>>()
        .ok_or_else(|| fail(format!("wrap \"{}\" has no body rows", wrap.name)))?;

    let mut out = Vec::with_capacity(wrap.panels.len());
    for (i, &(p, _)) in wrap.panels.iter().enumerate() {
        let (y0, y1) = ranges[i];
        let outline = &panels[p].outline;
        let mut placed = Vec::with_capacity(vertices[i].len());
        for &v in vertices[i] {
            let h = frame.h0 + v.y / 100.0;
            let f = ((h - h_start) / ROW_STEP).clamp(0.0, (filled.len() - 1) as f32);
            let k0 = (f.floor() as usize).min(filled.len() - 1);
            let k1 = (k0 + 1).min(filled.len() - 1);
            let t = f - k0 as f32;
            let (a, b) = row_extent(outline, v.y.clamp(y0, y1)).unwrap_or((v.x, v.x));
            let u = (v.x - 0.5 * (a + b)) / 100.0;
            let at = |row: &Row| -> Result<Vec3, GarmentError> {
                let centre = row.centres[i]
                    .or_else(|| nearest_centre(&filled, i, row.h))
                    .ok_or_else(|| {
                        fail(format!(
                            "panel \"{}\" has no row on the body",
                            panels[p].name
                        ))
                    })?;
                let q = row.curve.point_at(centre + u * row.scale);
                Ok(frame.point(row.h, q))
            };
            let pa = at(&filled[k0])?;
            let pb = at(&filled[k1])?;
            placed.push(pa.lerp(pb, t));
        }
        out.push(placed);
    }
    Ok(out)
}

/// The centre of panel `i` in the row nearest to `h` that has it.
fn nearest_centre(rows: &[Row], i: usize, h: f32) -> Option<f32> {
    rows.iter()
        .filter_map(|r| r.centres.get(i).copied().flatten().map(|c| (r.h, c)))
        .min_by(|a, b| (a.0 - h).abs().total_cmp(&(b.0 - h).abs()))
        .map(|(_, c)| c)
}

/// The points where the region's triangle edges cross the plane at axial position `h`.
fn section_points(
    body: &BodySurface,
    frame: &AxisFrame,
    tris: &[[u32; 3]],
    axial: &[f32],
    h: f32,
) -> Vec<Vec2> {
    let mut out = Vec::new();
    for t in tris {
        let a = t.map(|v| axial[v as usize] - h);
        if (a[0] >= 0.0) == (a[1] >= 0.0) && (a[1] >= 0.0) == (a[2] >= 0.0) {
            continue;
        }
        for k in 0..3 {
            let (i, j) = (k, (k + 1) % 3);
            if (a[i] >= 0.0) != (a[j] >= 0.0) {
                let s = a[i] / (a[i] - a[j]);
                let p = body.positions[t[i] as usize].lerp(body.positions[t[j] as usize], s);
                out.push(frame.plane(p));
            }
        }
    }
    out
}

/// Pushes every point closer to the body than `clearance` (or inside it) out along the
/// surface normal to `clearance`. Returns how many moved.
pub fn push_outside(body: &BodySurface, positions: &mut [Vec3], clearance: f32) -> usize {
    let mut moved = 0;
    for p in positions.iter_mut() {
        if let Some(s) = body.nearest(*p, None)
            && s.signed_distance < clearance
        {
            *p = s.point + s.normal * clearance;
            moved += 1;
        }
    }
    moved
}

/// `count` points evenly spaced along the body's cross-section hull at model height `y`
/// (region `region`) offset outward by `offset_m`, starting at the front (+Z) and going
/// toward the wearer's left (+X): a ring of a tube garment. Empty if the region has no
/// cross-section at that height.
pub fn tube_ring(
    body: &BodySurface,
    region: Region,
    y: f32,
    offset_m: f32,
    count: usize,
) -> Vec<Vec3> {
    let frame = AxisFrame {
        origin: Vec3::ZERO,
        axis: Vec3::Y,
        f: Vec3::Z,
        g: Vec3::X,
        h0: 0.0,
    };
    let tris: Vec<[u32; 3]> = (0..body.triangles.len())
        .filter(|&t| region.contains(body.part_of_triangle(t)))
        .map(|t| body.triangles[t])
        .collect();
    let axial: Vec<f32> = body.positions.iter().map(|p| p.y).collect();
    let hull = fitroom_body::measure::convex_hull(&section_points(body, &frame, &tris, &axial, y));
    if hull.len() < 3 || count == 0 {
        return Vec::new();
    }
    let curve = Curve::offset(&hull, offset_m.max(0.0));
    let start = curve.arc_at_angle(0.0);
    let step = curve.perimeter() / count as f32;
    (0..count)
        .map(|i| frame.point(y, curve.point_at(start + step * i as f32)))
        .collect()
}
