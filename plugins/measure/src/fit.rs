//! Our method: MakeHuman's body fitted to the person seen in the calibration frames, then
//! measured like any body.
//!
//! The unknowns are the shape sliders of [`ShapeSpace`] and the body's placement (a turn
//! about its pelvis and a shift); the pose of the limbs is the tracker's. Minimised, by
//! Gauss-Newton with Levenberg-Marquardt damping and bounds by clamping:
//!
//! ```text
//!   Σ_points ρ(n_i · (p_i - v_i))                    the surface: each averaged point against
//!                                                    the plane of its nearest visible vertex
//! + w_s Σ_vertices ρ(d_out(π(v_j)) z_j / f)          the silhouette: visible skin that falls
//!                                                    outside the person's pixels, in metres
//! + μ Σ_k (x_k - x⁰_k)²                              a weak pull to MakeHuman's default body
//! ```
//!
//! with ρ the Huber loss. The correspondences are found anew at every step (ICP); each
//! slider's effect on the posed skin comes from [`Posing::shape_jacobian`]. The camera sees
//! only the front: the back is where the body model's sliders put it for that front.

use std::collections::BTreeMap;
use std::time::Instant;

use fitroom_body::{BodyModel, Measure, Measurements, Shape, compute_normals};
use fitroom_depth::camera::{HEIGHT, WIDTH};
use fitroom_math::cholesky_solve;
use glam::{Quat, Vec3};
use serde::Serialize;

use crate::MeasureError;
use crate::posed::{Placement, PosedBody, Posing, ShapeSpace};
use crate::prior::GenderPrior;
use crate::silhouette::OutsideDistance;
use crate::view::AveragedView;

/// How the body is fitted.
#[derive(Clone, Debug)]
pub struct FitSettings {
    /// Every `point_step`-th pixel along both axes of the averaged view is a surface point.
    pub point_step: usize,
    /// Gauss-Newton steps at most.
    pub iterations: usize,
    /// Threads for the sliders' effects (the costly part).
    pub threads: usize,
    /// The Huber loss's corner, metres.
    pub robust_m: f32,
    /// A point farther than this from the nearest visible skin has no partner, metres.
    pub reach_m: f32,
    /// Weight of one silhouette vertex against one surface point.
    pub silhouette_weight: f32,
    /// Bones whose turns the fit refines (the tracker's pose is a start: its limbs are
    /// 10-20° off on a still person); empty: the pose is taken as given (a pose known to be
    /// right is better held: refined, it trades with the shape).
    pub refine_bones: Vec<&'static str>,
    /// Pull of the refined turns to the given pose, m² per rad².
    pub pose_prior: f32,
    /// Weight of the shape prior (m² per unit of squared Mahalanobis distance); without a
    /// prior, the pull to the default body (m² per slider unit²).
    pub prior: f32,
}

impl Default for FitSettings {
    fn default() -> Self {
        Self {
            point_step: 2,
            iterations: 10,
            threads: 2,
            robust_m: 0.015,
            reach_m: 0.08,
            silhouette_weight: 1.0,
            refine_bones: REFINED.to_vec(),
            pose_prior: 1e-4,
            prior: 2e-4,
        }
    }
}

/// The body found.
#[derive(Clone, Debug, Serialize)]
pub struct BodyEstimate {
    pub shape: Shape,
    /// The fitted body's full measurement.
    #[serde(skip)]
    pub measurements: Measurements,
    #[serde(skip)]
    pub placement: Placement,
    /// Root mean square of the surface points' distances at the end, metres.
    pub rms_m: f32,
    /// The fit's final cost (data and prior): what compares two fits of the same frames.
    pub cost: f64,
    /// Per measure, one standard deviation, cm: the sliders' posterior covariance (the
    /// prior's weight is the points' error variance, so `weight × H⁻¹`) carried through
    /// each measure's slope along each slider.
    pub uncertainty_cm: Vec<(Measure, f32)>,
    pub points: usize,
    pub iterations: usize,
    pub time_ms: f64,
}

impl BodyEstimate {
    /// The measurements by name, cm.
    pub fn by_name(&self) -> BTreeMap<Measure, f32> {
        Measure::ALL
            .iter()
            .map(|&m| (m, m.of(&self.measurements)))
            .collect()
    }
}

/// The bones whose turns are refined by default: the trunk, the limbs and the head.
pub const REFINED: [&str; 15] = [
    "spine_01",
    "spine_03",
    "neck_01",
    "clavicle_l",
    "clavicle_r",
    "upperarm_l",
    "upperarm_r",
    "lowerarm_l",
    "lowerarm_r",
    "thigh_l",
    "thigh_r",
    "calf_l",
    "calf_r",
    "foot_l",
    "foot_r",
];

/// Scene this far behind the skin is free space in front of the background, metres.
const FREE_M: f32 = 0.15;

/// Pixels per side of the tiles the visible skin is binned in for the partner search.
const TILE: usize = 8;

/// Points fewer than this cannot say much about a body.
const MIN_POINTS: usize = 500;

/// One residual's row: value, weight, and where it touches the body (vertex, direction);
/// a surface point's or a silhouette vertex's.
struct Row {
    surface: bool,
    r: f32,
    w: f32,
    vertex: usize,
    dir: Vec3,
}

/// Fits `model`'s body to `view`, the limbs posed by `locals` (per bone, from rest), starting
/// from `start` placed at `placement`.
pub fn fit_body(
    model: &BodyModel,
    view: &AveragedView,
    locals: &[Quat],
    placement: Placement,
    start: &Shape,
    prior: Option<&GenderPrior>,
    settings: &FitSettings,
) -> Result<BodyEstimate, MeasureError> {
    let began = Instant::now();
    let (points, pixels) = view.points_and_pixels(settings.point_step);
    if points.len() < MIN_POINTS {
        return Err(MeasureError::TooFewPoints {
            points: points.len(),
            need: MIN_POINTS,
        });
    }
    let outside = OutsideDistance::new(&view.mask);
    let space = ShapeSpace {
        base: start.clone(),
        ..ShapeSpace::full()
    };
    let mut posing = Posing::new(model, locals.to_vec());
    let bones: Vec<usize> = settings
        .refine_bones
        .iter()
        .filter_map(|name| model.bone_index(name))
        .collect();
    let nb = bones.len() * 3;
    let n = space.len();
    let mu = f64::from(settings.prior);
    // The pull: mu * P (x - m), P the prior's precision, or the identity about the default.
    let (mean, precision) = match prior.and_then(|p| Some((p.mean.clone(), p.precision()?))) {
        Some((m, p)) if m.len() == n => (m, p.iter().map(|v| v * mu).collect::<Vec<f64>>()),
        _ => {
            let mut p = vec![0.0; n * n];
            for k in 0..n {
                p[k * n + k] = mu;
            }
            (space.rest(), p)
        }
    };
    let pull = Pull { mean, precision };
    let mut x = space.values(start);
    let mut place = placement;
    let problem = Problem {
        model,
        view,
        points: &points,
        pixels: &pixels,
        outside: &outside,
        settings,
    };
    let mut body = posing.body(&space.shape(&x), &place)?;
    let mut rows = problem.rows(&body);
    // How far each refined bone has turned from the pose given (rotation vectors).
    let mut turns = vec![0.0f32; nb];
    let mut cost = problem.cost(&rows, &x, &pull);
    let mut lambda = 1e-3f64;
    let mut iterations = 0;
    // Unknowns: [sliders, bone turns, body turn, shift].
    let unknowns = n + nb + 6;
    let (turn_at, shift_at) = (n + nb, n + nb + 3);
    let mut last_h: Option<Vec<f64>> = None;
    let mut shape_columns: Vec<Vec<Vec3>> = Vec::new();
    while iterations < settings.iterations {
        iterations += 1;
        // Shape, pose and placement together. (Alternating, shape then pose then shape,
        // was worse on both paths: a pose fitted to the wrong shape bends to match it.)
        // The sliders' effect on the skin changes slowly with the shape: made anew every
        // third step (it is ~60 % of a step's cost; on 40 subjects every step, every second
        // and every third gave the same errors within 0.05 cm, and the bench went 1.06 ->
        // 0.64 s).
        if iterations % 3 == 1 || shape_columns.is_empty() {
            shape_columns = posing.shape_jacobian(&space, &x, &body, &place, settings.threads)?;
        }
        let pose_columns = posing.pose_jacobian(&body, &place, &bones);
        let columns: Vec<&Vec<Vec3>> = shape_columns.iter().chain(&pose_columns).collect();
        // Normal equations over [sliders, turn, shift].
        let mut h = vec![0.0f64; unknowns * unknowns];
        let mut g = vec![0.0f64; unknowns];
        let mut row = vec![0.0f64; unknowns];
        let mut nonzero: Vec<usize> = Vec::with_capacity(unknowns);
        for rw in &rows {
            let v = body.vertices[rw.vertex];
            for (k, c) in columns.iter().enumerate() {
                row[k] = f64::from(rw.dir.dot(c[rw.vertex]));
            }
            let turn = (v - place.pelvis).cross(rw.dir);
            for a in 0..3 {
                row[turn_at + a] = f64::from(turn[a]);
                row[shift_at + a] = f64::from(rw.dir[a]);
            }
            let (w, r) = (f64::from(rw.w), f64::from(rw.r));
            // A bone moves only the skin it carries: most rows touch few bones.
            nonzero.clear();
            nonzero.extend((0..unknowns).filter(|&i| row[i] != 0.0));
            for (a, &i) in nonzero.iter().enumerate() {
                let wi = w * row[i];
                g[i] += wi * r;
                for &j in &nonzero[..=a] {
                    h[i * unknowns + j] += wi * row[j];
                }
            }
        }
        for i in 0..unknowns {
            for j in 0..i {
                h[j * unknowns + i] = h[i * unknowns + j];
            }
        }
        let grad = pull.gradient(&x);
        for i in 0..n {
            g[i] += grad[i];
            for j in 0..n {
                h[i * unknowns + j] += pull.precision[i * n + j];
            }
        }
        // The bone turns, pulled weakly to the pose given (kept as `turns`).
        let pose_mu = f64::from(settings.pose_prior);
        for (k, t) in turns.iter().enumerate() {
            h[(n + k) * unknowns + n + k] += pose_mu;
            g[n + k] += pose_mu * f64::from(*t);
        }
        last_h = Some(h.clone());
        // Damped steps until one lowers the cost.
        let mut improved = false;
        for _ in 0..6 {
            let mut a = h.clone();
            for i in 0..unknowns {
                a[i * unknowns + i] += lambda * h[i * unknowns + i].max(1e-9);
            }
            let neg: Vec<f64> = g.iter().map(|v| -v).collect();
            let step = cholesky_solve(&a, &neg, unknowns).ok_or(MeasureError::Singular)?;
            let mut tx = x.clone();
            for (k, p) in space.params.iter().enumerate() {
                let (lo, hi) = p.bounds();
                tx[k] = (x[k] + step[k] as f32).clamp(lo, hi);
            }
            let v3 =
                |at: usize| Vec3::new(step[at] as f32, step[at + 1] as f32, step[at + 2] as f32);
            let tplace = place.moved(v3(turn_at), v3(shift_at));
            let mut tposing = posing.clone();
            let mut tturns = turns.clone();
            for (i, &b) in bones.iter().enumerate() {
                let d = v3(n + 3 * i);
                tposing.locals = tposing.turned(&body.rest, b, d);
                for a in 0..3 {
                    tturns[3 * i + a] += d[a];
                }
            }
            let tbody = tposing.body(&space.shape(&tx), &tplace)?;
            let trows = problem.rows(&tbody);
            let tcost = problem.cost(&trows, &tx, &pull) + pose_cost(&tturns, settings.pose_prior);
            if tcost < cost {
                (x, place, body, rows, cost) = (tx, tplace, tbody, trows, tcost);
                (posing, turns) = (tposing, tturns);
                lambda = (lambda * 0.3).max(1e-6);
                improved = true;
                break;
            }
            lambda *= 10.0;
        }
        if !improved {
            break;
        }
    }
    let shape = space.shape(&x);
    let (measurements, probe) = model.measure_with_probe(&body.positions)?;
    let uncertainty_cm = match &last_h {
        Some(h) => uncertainty(&posing, &space, &x, &body, &probe, h, unknowns, mu)?,
        None => Vec::new(),
    };
    let surface: Vec<f32> = rows.iter().filter(|r| r.surface).map(|r| r.r).collect();
    let rms_m = (surface.iter().map(|r| r * r).sum::<f32>() / surface.len().max(1) as f32).sqrt();
    Ok(BodyEstimate {
        shape,
        measurements,
        placement: place,
        rms_m,
        cost,
        uncertainty_cm,
        points: points.len(),
        iterations,
        time_ms: began.elapsed().as_secs_f64() * 1e3,
    })
}

/// One standard deviation per measure (see [`BodyEstimate::uncertainty_cm`]); `h` is the
/// last step's normal matrix over `unknowns` (the sliders first).
#[allow(clippy::too_many_arguments)]
fn uncertainty(
    posing: &Posing,
    space: &ShapeSpace,
    x: &[f32],
    body: &PosedBody,
    probe: &fitroom_body::measure::MeasureProbe,
    h: &[f64],
    unknowns: usize,
    variance: f64,
) -> Result<Vec<(Measure, f32)>, MeasureError> {
    let n = space.len();
    let triangles = &posing.model.triangles;
    let at = probe.measure(&body.positions, triangles);
    let base = posing.dense_weights(&body.weights);
    // Slopes: cm per slider unit, per measure.
    let mut slopes = vec![[0.0f32; 12]; n];
    for (k, slope) in slopes.iter_mut().enumerate() {
        let (moved, step) = posing.stepped(space, x, &body.positions, &base, k)?;
        let m = probe.measure(&moved, triangles);
        for i in 0..12 {
            slope[i] = (m[i] - at[i]) / step;
        }
    }
    // The sliders' block of the inverse.
    let mut cov = vec![0.0f64; n * n];
    for j in 0..n {
        let mut e = vec![0.0; unknowns];
        e[j] = 1.0;
        let col = cholesky_solve(h, &e, unknowns).ok_or(MeasureError::Singular)?;
        for i in 0..n {
            cov[i * n + j] = col[i] * variance;
        }
    }
    Ok(Measure::ALL
        .iter()
        .enumerate()
        .map(|(m, &measure)| {
            let mut v = 0.0f64;
            for i in 0..n {
                for j in 0..n {
                    v += f64::from(slopes[i][m]) * cov[i * n + j] * f64::from(slopes[j][m]);
                }
            }
            (measure, v.max(0.0).sqrt() as f32)
        })
        .collect())
}

/// The pull of the bone turns to the pose given.
fn pose_cost(turns: &[f32], weight: f32) -> f64 {
    0.5 * f64::from(weight) * turns.iter().map(|t| f64::from(*t).powi(2)).sum::<f64>()
}

/// The prior's pull on the sliders: `½ (x - mean)ᵀ precision (x - mean)`.
struct Pull {
    mean: Vec<f32>,
    precision: Vec<f64>,
}

impl Pull {
    fn gradient(&self, x: &[f32]) -> Vec<f64> {
        let n = self.mean.len();
        let d: Vec<f64> = x
            .iter()
            .zip(&self.mean)
            .map(|(a, b)| f64::from(a - b))
            .collect();
        (0..n)
            .map(|i| (0..n).map(|j| self.precision[i * n + j] * d[j]).sum())
            .collect()
    }

    fn cost(&self, x: &[f32]) -> f64 {
        let d: Vec<f64> = x
            .iter()
            .zip(&self.mean)
            .map(|(a, b)| f64::from(a - b))
            .collect();
        0.5 * self
            .gradient(x)
            .iter()
            .zip(&d)
            .map(|(g, d)| g * d)
            .sum::<f64>()
    }
}

/// What the residuals are computed from.
struct Problem<'a> {
    model: &'a BodyModel,
    view: &'a AveragedView,
    points: &'a [Vec3],
    /// Where each point is seen (pixel).
    pixels: &'a [(f32, f32)],
    outside: &'a OutsideDistance,
    settings: &'a FitSettings,
}

impl Problem<'_> {
    /// The residual rows of `body`: the surface points, then the silhouette.
    fn rows(&self, body: &PosedBody) -> Vec<Row> {
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
        let mut tiles: Vec<Vec<u32>> = vec![Vec::new(); tw * th];
        let tile_of = |u: f32, v: f32| -> Option<(usize, usize)> {
            let (tu, tv) = ((u / TILE as f32).floor(), (v / TILE as f32).floor());
            ((0.0..tw as f32).contains(&tu) && (0.0..th as f32).contains(&tv))
                .then_some((tu as usize, tv as usize))
        };
        let mut seen_at = vec![None; body.vertices.len()];
        for (i, v) in body.vertices.iter().enumerate() {
            if !facing[i] {
                continue;
            }
            let Some(px) = cam.project(*v) else {
                continue;
            };
            seen_at[i] = Some(px);
            if let Some((tu, tv)) = tile_of(px.x, px.y) {
                tiles[tv * tw + tu].push(i as u32);
            }
        }
        let huber = |r: f32| {
            let a = r.abs();
            if a <= s.robust_m { 1.0 } else { s.robust_m / a }
        };
        let mut rows = Vec::with_capacity(self.points.len() + 2000);
        let reach2 = s.reach_m * s.reach_m;
        for (&p, &(pu, pv)) in self.points.iter().zip(self.pixels) {
            let Some((tu, tv)) = tile_of(pu, pv) else {
                continue;
            };
            let mut best: Option<(f32, u32)> = None;
            for y in tv.saturating_sub(1)..(tv + 2).min(th) {
                for x in tu.saturating_sub(1)..(tu + 2).min(tw) {
                    for &i in &tiles[y * tw + x] {
                        let d2 = body.vertices[i as usize].distance_squared(p);
                        if d2 <= reach2 && best.is_none_or(|(b, bi)| d2 < b || (d2 == b && i < bi))
                        {
                            best = Some((d2, i));
                        }
                    }
                }
            }
            let Some((_, i)) = best else {
                continue;
            };
            let i = i as usize;
            let n = normals[i];
            let r = n.dot(p - body.vertices[i]);
            // The residual is the point minus the skin: moving the skin along n lowers it.
            rows.push(Row {
                surface: true,
                r: -r,
                w: huber(r),
                vertex: i,
                dir: n,
            });
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
            // Only where the scene shows free space in front of the skin: behind it (the
            // wall through the gap) or nothing. A surface at the skin's depth is the person
            // left out of the mask (the soles, cut off with the floor).
            let (u, vv) = (px.x.round() as usize, px.y.round() as usize);
            let scene = self.view.scene_m[vv * WIDTH + u];
            if scene > 0.0 && scene < v.z + FREE_M {
                continue;
            }
            let metres = (d - 1.0) * v.z / cam.fx;
            let dir = Vec3::new(-grad.x, -grad.y, 0.0).normalize_or_zero();
            rows.push(Row {
                surface: false,
                r: metres,
                w: s.silhouette_weight * huber(metres),
                vertex: j,
                dir,
            });
        }
        rows
    }

    fn cost(&self, rows: &[Row], x: &[f32], pull: &Pull) -> f64 {
        let c = self.settings.robust_m;
        let data: f64 = rows
            .iter()
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
            .sum();
        data + pull.cost(x)
    }
}
