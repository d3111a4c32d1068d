//! Our method: MakeHuman's body fitted to the person seen in the calibration's views, then
//! measured like any body.
//!
//! The unknowns are the shape sliders of [`ShapeSpace`] (one body, seen in every view) and,
//! per view, the turns of the refined bones and the body's placement (a turn about its
//! pelvis and a shift). Minimised, by Gauss-Newton with Levenberg-Marquardt damping and
//! bounds by clamping, summed over the views:
//!
//! ```text
//!   Σ_points ρ(n_i · (p_i - v_i))                    the surface: each averaged point against
//!                                                    the visible skin's triangle it lies over
//! + Σ_vertices ρ(below the floor)                    the soles: skin under the floor, pushed up
//! + w_s Σ_vertices ρ(d_out(π(v_j)) z_j / f)          the silhouette: visible skin seen where
//!                                                    the scene is free space, in metres
//! + ½ μ (x - m)ᵀ P (x - m)                           the shape prior (mean m, precision P)
//! + ½ μ_p Σ_bones |θ_b|²                             the bones' turns from the pose given
//! ```
//!
//! with ρ the Huber loss. The correspondences are found anew at every step (ICP); each
//! slider's effect on the posed skin comes from [`shape_jacobians`], each bone's from
//! [`carried_weights`] and the bones' heads (the normal equations: `fit/normal.rs`).
//! Facing the camera, it sees the front; the calibration's second view, turned halfway to
//! the side, shows the flank. The back is where the prior puts it for what was seen.

use std::collections::BTreeMap;
use std::time::Instant;

use fitroom_body::{BodyModel, Measure, Measurements, Shape};
use fitroom_math::{Cholesky, cholesky_solve};
use glam::{Quat, Vec3};
use serde::Serialize;

mod normal;
mod residuals;

use crate::MeasureError;
use crate::posed::{Placement, PosedBody, Posing, ShapeSpace, carried_weights, shape_jacobians};
use crate::prior::GenderPrior;
use crate::silhouette::OutsideDistance;
use crate::view::AveragedView;
use normal::ViewJacobian;
use residuals::{Problem, Row, clothed_vertices, faces_of};

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
    /// Weight of a surface point outside the skin against one inside it (1: a bare body;
    /// less: clothes may hang off the body, so what is seen is the skin or in front of it,
    /// and skin beyond the surface seen is the firm evidence).
    pub outside_weight: f32,
    /// Bones whose turns the fit refines (the tracker's pose is a start: its limbs are
    /// 10-20° off on a still person); empty: the pose is taken as given (a pose known to be
    /// right is better held: refined, it trades with the shape).
    pub refine_bones: Vec<&'static str>,
    /// Pull of the refined turns to the given pose, m² per rad².
    pub pose_prior: f32,
    /// A layer of clothing this thick on the trunk and the upper arms (where a shirt is),
    /// metres: the surface seen is the skin moved out along its normals there, and the body
    /// found is the one under it. 0: none.
    pub clothing_m: f32,
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
            outside_weight: 1.0,
            refine_bones: REFINED.to_vec(),
            pose_prior: 1e-4,
            clothing_m: 0.0,
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
    /// Where the body stood in each view.
    #[serde(skip)]
    pub placements: Vec<Placement>,
    /// Root mean square of the surface points' distances at the end, metres.
    pub rms_m: f32,
    /// The same per view, each distance clamped at [`VIEW_RMS_CLAMP_M`] (a view the fit
    /// could not match shows as one much worse than the others).
    pub view_rms_m: Vec<f32>,
    /// The fit's final cost (data and prior), m².
    pub cost: f64,
    /// `ln det` of the final normal matrix (the posterior's precision up to the prior's
    /// weight): how sharply the frames pin the unknowns down, for comparing fits made with
    /// different priors (see [`crate::person`]).
    pub log_det_h: f64,
    /// Per measure, one standard deviation, cm: the sliders' posterior covariance (the
    /// prior's weight is the points' error variance, so `weight × H⁻¹`) carried through
    /// each measure's slope along each slider.
    pub uncertainty_cm: Vec<(Measure, f32)>,
    pub points: usize,
    pub iterations: usize,
    pub time_ms: f64,
}

impl BodyEstimate {
    /// The points' RMS in the view the fit matched worst, metres.
    pub fn worst_view_rms_m(&self) -> f32 {
        self.view_rms_m.iter().copied().fold(0.0, f32::max)
    }

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

/// Distances clamped at this for [`BodyEstimate::view_rms_m`], metres.
pub const VIEW_RMS_CLAMP_M: f32 = 0.03;

/// Points fewer than this cannot say much about a body.
const MIN_POINTS: usize = 500;

/// One view of the person: the frames of one stance averaged, the limbs' pose in it (per
/// bone, from rest) and where the body stands. The calibration has two: facing the camera,
/// then a quarter turn (the side the front view cannot see).
#[derive(Clone, Copy, Debug)]
pub struct ViewPose<'a> {
    pub view: &'a AveragedView,
    pub locals: &'a [Quat],
    pub placement: Placement,
}

/// What the fit keeps per view.
struct ViewState<'a> {
    problem: Problem<'a>,
    posing: Posing<'a>,
    place: Placement,
    body: PosedBody,
    rows: Vec<Row>,
    /// How far each refined bone has turned from the pose given (rotation vectors).
    turns: Vec<f32>,
    /// Per vertex, its motion per unit of each slider (vertex-major).
    shape_columns: Vec<Vec3>,
}

/// A view's pose after a trial step.
struct Trial<'a> {
    posing: Posing<'a>,
    place: Placement,
    body: PosedBody,
    rows: Vec<Row>,
    turns: Vec<f32>,
}

/// Fits `model`'s body, one shape seen in every one of `views`, starting from `start`.
pub fn fit_body(
    model: &BodyModel,
    views: &[ViewPose],
    start: &Shape,
    prior: Option<&GenderPrior>,
    settings: &FitSettings,
) -> Result<BodyEstimate, MeasureError> {
    let began = Instant::now();
    let space = ShapeSpace {
        base: start.clone(),
        ..ShapeSpace::full()
    };
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
    let shape = space.shape(&x);
    let mut points_total = 0;
    let faces = faces_of(model.body_vertex_count as usize, &model.triangles);
    let layer = clothed_vertices(model, settings.clothing_m);
    let carried = carried_weights(model, &bones, model.body_vertex_count as usize);
    let mut states: Vec<ViewState> = Vec::with_capacity(views.len());
    for vp in views {
        let (points, pixels) = vp.view.points_and_pixels(settings.point_step);
        points_total += points.len();
        let problem = Problem {
            model,
            view: vp.view,
            points,
            pixels,
            outside: OutsideDistance::new(&vp.view.mask),
            faces_of: &faces,
            layer: &layer,
            settings,
        };
        let posing = Posing::new(model, vp.locals.to_vec());
        let body = posing.body(&shape, &vp.placement)?;
        let rows = problem.rows(&body);
        states.push(ViewState {
            problem,
            posing,
            place: vp.placement,
            body,
            rows,
            turns: vec![0.0; nb],
            shape_columns: Vec::new(),
        });
    }
    if states.is_empty() || points_total < MIN_POINTS {
        return Err(MeasureError::TooFewPoints {
            points: points_total,
            need: MIN_POINTS,
        });
    }
    let total_cost = |states: &[ViewState], x: &[f32]| -> f64 {
        pull.cost(x)
            + states
                .iter()
                .map(|s| s.problem.cost(&s.rows) + pose_cost(&s.turns, settings.pose_prior))
                .sum::<f64>()
    };
    let mut cost = total_cost(&states, &x);
    let mut lambda = 1e-3f64;
    let mut iterations = 0;
    // Unknowns: the sliders, then per view [bone turns, body turn, shift].
    let per_view = nb + 6;
    let unknowns = n + per_view * states.len();
    let mut last_h: Option<Vec<f64>> = None;
    while iterations < settings.iterations {
        iterations += 1;
        // Shape, pose and placement together. (Alternating, shape then pose then shape,
        // was worse on both paths: a pose fitted to the wrong shape bends to match it.)
        // The sliders' effect on the skin changes slowly with the shape: made anew every
        // third step (it is ~60 % of a step's cost; on 40 subjects every step, every second
        // and every third gave the same errors within 0.05 cm, and the bench went 1.06 ->
        // 0.64 s).
        if iterations % 3 == 1 || states[0].shape_columns.is_empty() {
            let poses: Vec<(&Posing, &Placement, &[Vec3])> = states
                .iter()
                .map(|s| (&s.posing, &s.place, s.body.vertices.as_slice()))
                .collect();
            let columns = shape_jacobians(&space, &x, &states[0].body, &poses, settings.threads)?;
            for (s, c) in states.iter_mut().zip(columns) {
                s.shape_columns = c;
            }
        }
        // Normal equations.
        let mut h = vec![0.0f64; unknowns * unknowns];
        let mut g = vec![0.0f64; unknowns];
        for (vi, s) in states.iter().enumerate() {
            let at = n + vi * per_view;
            let heads = s.posing.bone_heads(&s.body.rest, &s.place, &bones);
            let jac = ViewJacobian {
                shape: &s.shape_columns,
                sliders: n,
                carried: &carried,
                heads: &heads,
                rotation: s.place.rotation,
                pelvis: s.place.pelvis,
            };
            normal::add_view(
                &mut h,
                &mut g,
                unknowns,
                at,
                &jac,
                &s.rows,
                &s.body.vertices,
            );
            // The bone turns, pulled weakly to the pose given.
            let pose_mu = f64::from(settings.pose_prior);
            for (k, t) in s.turns.iter().enumerate() {
                h[(at + k) * unknowns + at + k] += pose_mu;
                g[at + k] += pose_mu * f64::from(*t);
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
            let tshape = space.shape(&tx);
            let v3 =
                |at: usize| Vec3::new(step[at] as f32, step[at + 1] as f32, step[at + 2] as f32);
            let mut tried: Vec<Trial> = Vec::with_capacity(states.len());
            let mut morphed: Option<PosedBody> = None;
            for (vi, s) in states.iter().enumerate() {
                let at = n + vi * per_view;
                let tplace = s.place.moved(v3(at + nb), v3(at + nb + 3));
                let mut tposing = s.posing.clone();
                let mut tturns = s.turns.clone();
                for (i, &b) in bones.iter().enumerate() {
                    let d = v3(at + 3 * i);
                    tposing.locals = tposing.turned(&s.body.rest, b, d);
                    for a in 0..3 {
                        tturns[3 * i + a] += d[a];
                    }
                }
                // The morph is the same in every view: made once, posed per view.
                let tbody = match &morphed {
                    Some(m) => tposing.repose(m, &tplace),
                    None => tposing.body(&tshape, &tplace)?,
                };
                morphed.get_or_insert_with(|| tbody.clone());
                let trows = s.problem.rows(&tbody);
                tried.push(Trial {
                    posing: tposing,
                    place: tplace,
                    body: tbody,
                    rows: trows,
                    turns: tturns,
                });
            }
            let tcost = pull.cost(&tx)
                + states
                    .iter()
                    .zip(&tried)
                    .map(|(s, t)| {
                        s.problem.cost(&t.rows) + pose_cost(&t.turns, settings.pose_prior)
                    })
                    .sum::<f64>();
            if tcost < cost {
                (x, cost) = (tx, tcost);
                for (s, t) in states.iter_mut().zip(tried) {
                    (s.posing, s.place, s.body, s.rows, s.turns) =
                        (t.posing, t.place, t.body, t.rows, t.turns);
                }
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
    let first = &states[0];
    let shape = space.shape(&x);
    let (measurements, probe) = model.measure_with_probe(&first.body.positions)?;
    let factor = last_h.as_deref().and_then(|h| Cholesky::new(h, unknowns));
    let uncertainty_cm = match &factor {
        Some(h) => uncertainty(&first.posing, &space, &x, &first.body, &probe, h, mu)?,
        None => Vec::new(),
    };
    let log_det_h = factor.as_ref().map_or(f64::NAN, Cholesky::log_det);
    let surface: Vec<f32> = states
        .iter()
        .flat_map(|s| s.rows.iter().filter(|r| r.surface).map(|r| r.r))
        .collect();
    let rms_m = (surface.iter().map(|r| r * r).sum::<f32>() / surface.len().max(1) as f32).sqrt();
    let view_rms_m = states
        .iter()
        .map(|s| {
            let r: Vec<f32> = s
                .rows
                .iter()
                .filter(|r| r.surface)
                .map(|r| r.r.abs().min(VIEW_RMS_CLAMP_M))
                .collect();
            (r.iter().map(|v| v * v).sum::<f32>() / r.len().max(1) as f32).sqrt()
        })
        .collect();
    Ok(BodyEstimate {
        shape,
        measurements,
        placements: states.iter().map(|s| s.place).collect(),
        rms_m,
        view_rms_m,
        cost,
        log_det_h,
        uncertainty_cm,
        points: points_total,
        iterations,
        time_ms: began.elapsed().as_secs_f64() * 1e3,
    })
}

/// One standard deviation per measure (see [`BodyEstimate::uncertainty_cm`]); `h` is the
/// last step's normal matrix, factored (the sliders first).
fn uncertainty(
    posing: &Posing,
    space: &ShapeSpace,
    x: &[f32],
    body: &PosedBody,
    probe: &fitroom_body::measure::MeasureProbe,
    h: &Cholesky,
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
        let mut e = vec![0.0; n];
        e[j] = 1.0;
        let col = h.solve(&e);
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
