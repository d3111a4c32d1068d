//! Calibration of a body to measurements (seed 002 §4.2, done as an optimisation): given any
//! subset of the [`Measure`]s plus gender (and optionally age), find the MakeHuman modifier
//! values whose body, measured by [`BodyModel::measure`], has those measurements.
//!
//! # Method
//!
//! Bounded, regularised non-linear least squares over the macro sliders `height`, `weight`,
//! `muscle`, `proportions` (0..=1), the `measure-*` sliders and the region scale sliders
//! (`neck-scale-horiz`, `torso-scale-depth`, ...; each -1..=1) that move the requested
//! measurements:
//!
//! ```text
//! minimise  Σ_i ((m_i(θ) - t_i) / 1 cm)²  +  μ Σ_k (θ_k - θ⁰_k)²    subject to  lo ≤ θ ≤ hi
//! ```
//!
//! `μ` ([`FitOptions::prior_weight`]) is tiny: it only picks, among the many shapes with the
//! same measurements, the one closest to MakeHuman's default (θ⁰: macros 0.5, measure sliders
//! 0), and keeps unused sliders at rest.
//!
//! * **Outer loop** (landmarks): measure the current body fully ([`BodyModel::measure_with_probe`]:
//!   landmark search over the whole mesh), which also yields a [`MeasureProbe`] that re-measures
//!   nearby shapes at the same anatomical landmarks, reading only ~15% of the vertices.
//! * **Inner loop** (Levenberg-Marquardt on the probe): a forward-difference Jacobian, then
//!   damped Gauss-Newton steps with Broyden rank-one updates of the Jacobian; the bounds are
//!   handled by projection with an active set (a slider at a bound whose gradient pushes
//!   outwards is held there). Only the vertices the probe reads are morphed: linear in the
//!   target weights, each target's deltas on those vertices are gathered once.
//! * The outer loop repeats until the full measurement agrees with the targets
//!   ([`FitOptions::tolerance_cm`]) or stops improving.
//!
//! The reported measurements are always the full [`BodyModel::measure`] of the final body,
//! never the probe's. A body the model cannot reach (a residual above the tolerance) is
//! reported as such ([`FitReport::reachable`], [`FitReport::residuals_cm`], the sliders held at
//! a bound in [`FitReport::at_bounds`]), with the closest body found; nothing is clamped
//! silently.
//!
//! The small dense linear solves (at most ~20 unknowns) use a hand-written Cholesky
//! factorisation: too small to justify a linear-algebra dependency.

use std::collections::{BTreeMap, HashMap};
use std::time::Instant;

use glam::Vec3;
use serde::{Deserialize, Serialize};

use crate::measure::{Measure, MeasureError, MeasureProbe, Measurements};
use crate::model::BodyModel;
use crate::modifiers::{Shape, ShapeError};

/// What to fit: measurements (cm) of one person, their gender and optionally their age.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FitRequest {
    /// 0 = female, 1 = male (MakeHuman's gender slider).
    pub gender: f32,
    /// Age in years (18-90); MakeHuman's default (25) when absent.
    pub age_years: Option<f32>,
    /// The measurements to match, cm.
    pub targets: BTreeMap<Measure, f32>,
}

/// Settings of [`fit`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FitOptions {
    /// A body is reachable when every fitted measurement is within this of its target, cm.
    pub tolerance_cm: f32,
    /// The outer loop stops when every residual is below this, cm.
    pub converged_cm: f32,
    /// Weight of the pull towards the default shape, per unit of slider² (against cm²).
    pub prior_weight: f32,
    /// Full measurements (landmark searches) at most.
    pub max_outer: usize,
    /// Levenberg-Marquardt steps per landmark set at most.
    pub max_inner: usize,
}

impl Default for FitOptions {
    fn default() -> Self {
        Self {
            tolerance_cm: 0.5,
            converged_cm: 0.1,
            prior_weight: 1e-3,
            max_outer: 6,
            max_inner: 12,
        }
    }
}

/// Why a fit cannot be made.
#[derive(Debug, thiserror::Error)]
pub enum FitError {
    #[error("no measurements to fit; give at least one of: {}", Measure::names())]
    NoTargets,
    #[error(
        "measurement `{measure}` is {value} cm, outside the accepted range {min}..={max} cm \
         (an adult body; check the unit: centimetres)"
    )]
    OutOfRange {
        measure: Measure,
        value: f32,
        min: f32,
        max: f32,
    },
    #[error("`gender` is {0}, outside the accepted range 0..=1 (0 = female, 1 = male)")]
    Gender(f32),
    #[error("`age` is {0} years, outside the accepted range 18..=90")]
    Age(f32),
    #[error(transparent)]
    Shape(#[from] ShapeError),
    #[error("measuring a trial body: {0}")]
    Measure(#[from] MeasureError),
}

/// The result of [`fit`].
#[derive(Clone, Debug, Serialize)]
pub struct FitReport {
    /// The fitted shape (save it as `shape.ron`).
    pub shape: Shape,
    /// The requested measurements, cm.
    pub targets: BTreeMap<Measure, f32>,
    /// The full measurement of the fitted body (all measures, landmark heights included).
    pub achieved: Measurements,
    /// Achieved minus requested, cm, per requested measure.
    pub residuals_cm: BTreeMap<Measure, f32>,
    /// Whether every residual is within the tolerance.
    pub reachable: bool,
    /// The tolerance used, cm.
    pub tolerance_cm: f32,
    /// Sliders that ended at a bound (`weight = 1`, `measures["neck-circ"] = -1`): the
    /// model's limits that an unreachable body ran into.
    pub at_bounds: Vec<String>,
    /// Full measurements (landmark searches).
    pub outer_iterations: usize,
    /// Levenberg-Marquardt steps over all landmark sets.
    pub iterations: usize,
    /// Probe evaluations (trial bodies).
    pub evaluations: usize,
    pub time_ms: f64,
}

/// One free slider.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Param {
    Height,
    Weight,
    Muscle,
    Proportions,
    Slider(&'static str),
    Region(&'static str),
}

impl Param {
    fn bounds(self) -> (f32, f32) {
        match self {
            Param::Slider(_) | Param::Region(_) => (-1.0, 1.0),
            _ => (0.0, 1.0),
        }
    }

    fn rest(self) -> f32 {
        match self {
            Param::Slider(_) | Param::Region(_) => 0.0,
            _ => 0.5,
        }
    }

    fn name(self) -> String {
        match self {
            Param::Height => "height".into(),
            Param::Weight => "weight".into(),
            Param::Muscle => "muscle".into(),
            Param::Proportions => "proportions".into(),
            Param::Slider(s) => format!("measures[\"{s}\"]"),
            Param::Region(s) => format!("regions[\"{s}\"]"),
        }
    }

    fn set(self, shape: &mut Shape, v: f32) {
        match self {
            Param::Height => shape.height = v,
            Param::Weight => shape.weight = v,
            Param::Muscle => shape.muscle = v,
            Param::Proportions => shape.proportions = v,
            Param::Slider(s) => {
                shape.measures.insert(s.to_owned(), v);
            }
            Param::Region(s) => {
                shape.regions.insert(s.to_owned(), v);
            }
        }
    }

    /// The measures this slider moves (from a sensitivity scan of the MakeHuman targets:
    /// each slider at -1 and +1 on the default female and male bodies, effects above 0.3 cm).
    fn moves(self, m: Measure) -> bool {
        use Measure::*;
        match self {
            Param::Height | Param::Weight | Param::Muscle | Param::Proportions => true,
            Param::Slider(s) => match s {
                "bust-circ" | "frontchest-dist" => matches!(m, Bust | Underbust | Waist | Neck),
                "underbust-circ" => matches!(m, Bust | Underbust | Waist | NavelWaist),
                "waist-circ" => matches!(m, Bust | Underbust | Waist | NavelWaist),
                "hips-circ" => matches!(m, Hip | Thigh | NavelWaist),
                "thigh-circ" => matches!(m, Thigh),
                "calf-circ" | "knee-circ" => matches!(m, Calf),
                "neck-circ" => matches!(m, Neck),
                "neck-height" => matches!(m, Neck | Stature),
                "shoulder-dist" => matches!(m, ShoulderWidth | Bust | Neck),
                "upperleg-height" | "lowerleg-height" => matches!(m, Stature | InsideLeg),
                "napetowaist-dist" | "waisttohip-dist" => {
                    matches!(m, Stature | Neck | Bust | Underbust | Hip | NavelWaist)
                }
                "upperarm-length" | "lowerarm-length" => matches!(m, ArmLength),
                _ => false,
            },
            Param::Region(s) => match s {
                "neck-scale-depth" | "neck-scale-horiz" | "neck-back-scale-depth" => {
                    matches!(m, Neck)
                }
                "neck-scale-vert" => matches!(m, Neck | Stature),
                "torso-scale-depth" | "torso-scale-horiz" => matches!(
                    m,
                    ShoulderWidth | Neck | Bust | Underbust | Waist | NavelWaist
                ),
                "torso-scale-vert" => matches!(m, Stature | NavelWaist),
                "hip-scale-depth" | "hip-scale-horiz" => {
                    matches!(m, Underbust | Waist | NavelWaist | Hip | Thigh)
                }
                "upperleg-scale-depth" | "upperleg-scale-horiz" => matches!(m, Hip | Thigh),
                "lowerleg-scale-depth" | "lowerleg-scale-horiz" => matches!(m, Calf),
                "lowerleg-scale-vert" => matches!(m, Stature | InsideLeg),
                "upperarm-scale-horiz" | "lowerarm-scale-horiz" => matches!(m, ArmLength),
                _ => false,
            },
        }
    }
}

/// Longest step of one slider per Levenberg-Marquardt iteration.
const MAX_STEP: f64 = 0.25;

/// The measure sliders the fit may use.
const SLIDERS: [&str; 17] = [
    "bust-circ",
    "underbust-circ",
    "frontchest-dist",
    "waist-circ",
    "hips-circ",
    "thigh-circ",
    "calf-circ",
    "knee-circ",
    "neck-circ",
    "neck-height",
    "shoulder-dist",
    "upperleg-height",
    "lowerleg-height",
    "napetowaist-dist",
    "waisttohip-dist",
    "upperarm-length",
    "lowerarm-length",
];

/// The region scale sliders the fit may use (MakeHuman's `*-scale-*` targets of the neck,
/// torso, hip and limbs; the ones with an effect on a measurement).
const REGIONS: [&str; 15] = [
    "neck-scale-depth",
    "neck-scale-horiz",
    "neck-back-scale-depth",
    "neck-scale-vert",
    "torso-scale-depth",
    "torso-scale-horiz",
    "torso-scale-vert",
    "hip-scale-depth",
    "hip-scale-horiz",
    "upperleg-scale-depth",
    "upperleg-scale-horiz",
    "lowerleg-scale-depth",
    "lowerleg-scale-horiz",
    "upperarm-scale-horiz",
    "lowerarm-scale-horiz",
];

/// MakeHuman's age slider for an age in years (0.5 = 25, 1 = 90; linear in between, as
/// MakeHuman's `setAgeYears`).
pub fn age_slider(years: f32) -> f32 {
    if years < 25.0 {
        0.1875 + (years - 10.0) / (25.0 - 10.0) * (0.5 - 0.1875)
    } else {
        0.5 + (years - 25.0) / (90.0 - 25.0) * 0.5
    }
}

impl FitRequest {
    /// Checks the request: at least one target, every value finite and in the plausible
    /// range of its measure, gender in 0..=1, age in 18..=90.
    pub fn validate(&self) -> Result<(), FitError> {
        if self.targets.is_empty() {
            return Err(FitError::NoTargets);
        }
        if !(0.0..=1.0).contains(&self.gender) {
            return Err(FitError::Gender(self.gender));
        }
        if let Some(a) = self.age_years
            && !(18.0..=90.0).contains(&a)
        {
            return Err(FitError::Age(a));
        }
        for (&measure, &value) in &self.targets {
            let (min, max) = measure.plausible_range_cm();
            if !(min..=max).contains(&value) {
                return Err(FitError::OutOfRange {
                    measure,
                    value,
                    min,
                    max,
                });
            }
        }
        Ok(())
    }
}

/// The morph restricted to the vertices a probe reads: positions = base + Σ w_t · D_t, with
/// each target's deltas on those vertices gathered on first use. Updates are incremental:
/// only the targets whose weight changed since the last call are applied (a finite-difference
/// column changes one or a few), with a full recomputation every [`FULL_MORPH_EVERY`] calls
/// so rounding cannot drift.
struct ProbeMorph<'a> {
    model: &'a BodyModel,
    vertices: Vec<u32>,
    /// Per target index: (vertex index, delta in metres).
    deltas: HashMap<usize, Vec<(u32, Vec3)>>,
    /// Whole-mesh positions; only `vertices` are kept up to date.
    scratch: Vec<Vec3>,
    /// The weights `scratch` holds, sorted by target.
    applied: Vec<(usize, f32)>,
    since_full: usize,
}

/// Calls of [`ProbeMorph::apply`] between full recomputations.
const FULL_MORPH_EVERY: usize = 64;

impl<'a> ProbeMorph<'a> {
    fn new(model: &'a BodyModel, vertices: &[u32]) -> Self {
        Self {
            model,
            vertices: vertices.to_vec(),
            deltas: HashMap::new(),
            scratch: model.positions.clone(),
            applied: Vec::new(),
            since_full: 0,
        }
    }

    fn target(&mut self, index: usize) -> &[(u32, Vec3)] {
        let (model, vertices) = (self.model, &self.vertices);
        self.deltas.entry(index).or_insert_with(|| {
            let Some(t) = model.targets.get(index) else {
                return Vec::new();
            };
            // Merge join of two increasing index lists.
            let mut out = Vec::new();
            let (mut i, mut j) = (0, 0);
            while i < t.indices.len() && j < vertices.len() {
                match t.indices[i].cmp(&vertices[j]) {
                    std::cmp::Ordering::Less => i += 1,
                    std::cmp::Ordering::Greater => j += 1,
                    std::cmp::Ordering::Equal => {
                        let d = t.deltas[i];
                        out.push((
                            vertices[j],
                            Vec3::new(d[0] as f32, d[1] as f32, d[2] as f32) * t.scale_m,
                        ));
                        i += 1;
                        j += 1;
                    }
                }
            }
            out
        })
    }

    /// Morphs the probe's vertices to `weights`.
    fn apply(&mut self, weights: &[(usize, f32)]) -> &[Vec3] {
        let mut new: Vec<(usize, f32)> = weights.to_vec();
        new.sort_by_key(|w| w.0);
        new.dedup_by(|b, a| {
            // Same target twice: sum into the kept one.
            if a.0 == b.0 {
                a.1 += b.1;
                true
            } else {
                false
            }
        });
        if self.since_full >= FULL_MORPH_EVERY {
            for &v in &self.vertices {
                self.scratch[v as usize] = self.model.positions[v as usize];
            }
            self.applied.clear();
            self.since_full = 0;
        }
        // Weight changes: merge the two sorted lists.
        let mut changes: Vec<(usize, f32)> = Vec::new();
        let (mut i, mut j) = (0, 0);
        while i < new.len() || j < self.applied.len() {
            let (a, b) = (new.get(i), self.applied.get(j));
            match (a, b) {
                (Some(&(ta, wa)), Some(&(tb, wb))) if ta == tb => {
                    if wa != wb {
                        changes.push((ta, wa - wb));
                    }
                    i += 1;
                    j += 1;
                }
                (Some(&(ta, wa)), Some(&(tb, _))) if ta < tb => {
                    changes.push((ta, wa));
                    i += 1;
                }
                (Some(&(ta, wa)), None) => {
                    changes.push((ta, wa));
                    i += 1;
                }
                (_, Some(&(tb, wb))) => {
                    changes.push((tb, -wb));
                    j += 1;
                }
                (None, None) => break,
            }
        }
        for (t, dw) in changes {
            let deltas = self.target(t).to_vec();
            for (v, d) in deltas {
                self.scratch[v as usize] += d * dw;
            }
        }
        self.applied = new;
        self.since_full += 1;
        &self.scratch
    }
}

/// Solves `a x = b` for a symmetric positive definite `a` (n×n, row-major) by Cholesky;
/// `None` if `a` is not positive definite.
fn cholesky_solve(a: &[f64], b: &[f64], n: usize) -> Option<Vec<f64>> {
    let mut l = vec![0.0f64; n * n];
    for i in 0..n {
        for j in 0..=i {
            let mut s = a[i * n + j];
            for k in 0..j {
                s -= l[i * n + k] * l[j * n + k];
            }
            if i == j {
                if s <= 0.0 {
                    return None;
                }
                l[i * n + i] = s.sqrt();
            } else {
                l[i * n + j] = s / l[j * n + j];
            }
        }
    }
    let mut y = vec![0.0; n];
    for i in 0..n {
        let mut s = b[i];
        for k in 0..i {
            s -= l[i * n + k] * y[k];
        }
        y[i] = s / l[i * n + i];
    }
    let mut x = vec![0.0; n];
    for i in (0..n).rev() {
        let mut s = y[i];
        for k in i + 1..n {
            s -= l[k * n + i] * x[k];
        }
        x[i] = s / l[i * n + i];
    }
    Some(x)
}

/// The state of one fit.
struct Fitter<'a> {
    model: &'a BodyModel,
    base: Shape,
    params: Vec<Param>,
    /// Requested measures (indices into [`Measure::ALL`]) and their targets.
    measures: Vec<(usize, f32)>,
    prior: Vec<f32>,
    mu: f64,
    evaluations: usize,
}

impl Fitter<'_> {
    fn shape(&self, x: &[f32]) -> Shape {
        let mut s = self.base.clone();
        for (p, &v) in self.params.iter().zip(x) {
            p.set(&mut s, v);
        }
        s.measures.retain(|_, v| *v != 0.0);
        s.regions.retain(|_, v| *v != 0.0);
        s
    }

    /// Residuals (cm) of the probe's measurement of the body `x`.
    fn residuals(
        &mut self,
        x: &[f32],
        probe: &MeasureProbe,
        morph: &mut ProbeMorph,
    ) -> Result<Vec<f64>, FitError> {
        self.evaluations += 1;
        let weights = self.shape(x).target_weights(self.model)?;
        let positions = morph.apply(&weights);
        let m = probe.measure(positions, &self.model.triangles);
        // A trial body the probe cannot measure (a landmark section lost) counts as infinitely
        // far: the step is rejected.
        Ok(self
            .measures
            .iter()
            .map(|&(i, t)| {
                let r = (m[i] - t) as f64;
                if r.is_finite() { r } else { f64::INFINITY }
            })
            .collect())
    }

    fn cost(&self, r: &[f64], x: &[f32]) -> f64 {
        let prior: f64 = x
            .iter()
            .zip(&self.prior)
            .map(|(&a, &b)| ((a - b) as f64).powi(2))
            .sum();
        r.iter().map(|v| v * v).sum::<f64>() + self.mu * prior
    }

    /// Levenberg-Marquardt on the probe from `x`; returns the new `x` and the steps taken.
    fn inner(
        &mut self,
        mut x: Vec<f32>,
        probe: &MeasureProbe,
        morph: &mut ProbeMorph,
        options: &FitOptions,
        trust: f32,
    ) -> Result<(Vec<f32>, usize), FitError> {
        let (m, n) = (self.measures.len(), self.params.len());
        // The sliders' bounds, within `trust` of the start.
        let bounds: Vec<(f32, f32)> = self
            .params
            .iter()
            .zip(&x)
            .map(|(p, &v)| {
                let (lo, hi) = p.bounds();
                (lo.max(v - trust), hi.min(v + trust))
            })
            .collect();
        let mut r = self.residuals(&x, probe, morph)?;
        // Forward differences, stepping away from the nearer bound.
        let mut jac = vec![0.0f64; m * n];
        for k in 0..n {
            let (lo, hi) = self.params[k].bounds();
            let h = if x[k] + 0.02 <= hi { 0.02 } else { -0.02 };
            let mut xp = x.clone();
            xp[k] = (x[k] + h).clamp(lo, hi);
            let rp = self.residuals(&xp, probe, morph)?;
            for i in 0..m {
                let d = (rp[i] - r[i]) / h as f64;
                jac[i * n + k] = if d.is_finite() { d } else { 0.0 };
            }
        }
        let mut lambda = 1e-3f64;
        let mut cost = self.cost(&r, &x);
        let mut steps = 0;
        for _ in 0..options.max_inner {
            if r.iter()
                .all(|v| v.abs() < 0.5 * options.converged_cm as f64)
            {
                break;
            }
            steps += 1;
            // Gradient of the cost / 2.
            let grad: Vec<f64> = (0..n)
                .map(|k| {
                    (0..m).map(|i| jac[i * n + k] * r[i]).sum::<f64>()
                        + self.mu * (x[k] - self.prior[k]) as f64
                })
                .collect();
            // Active set: at a bound with the descent direction pointing out.
            let free: Vec<usize> = (0..n)
                .filter(|&k| {
                    let (lo, hi) = bounds[k];
                    !((x[k] <= lo && grad[k] > 0.0) || (x[k] >= hi && grad[k] < 0.0))
                })
                .collect();
            if free.is_empty() {
                break;
            }
            let nf = free.len();
            let mut accepted = false;
            for _ in 0..8 {
                let mut a = vec![0.0f64; nf * nf];
                let mut b = vec![0.0f64; nf];
                for (p, &kp) in free.iter().enumerate() {
                    for (q, &kq) in free.iter().enumerate() {
                        a[p * nf + q] = (0..m).map(|i| jac[i * n + kp] * jac[i * n + kq]).sum();
                    }
                    a[p * nf + p] += self.mu;
                    a[p * nf + p] *= 1.0 + lambda;
                    a[p * nf + p] += 1e-9;
                    b[p] = -grad[kp];
                }
                let Some(delta) = cholesky_solve(&a, &b, nf) else {
                    lambda *= 10.0;
                    continue;
                };
                // A trust region on top of the damping: the targets are piecewise linear
                // (MakeHuman's min/average/max interpolation), so long steps mislead.
                let longest = delta.iter().fold(0.0f64, |a, d| a.max(d.abs()));
                let scale = if longest > MAX_STEP {
                    MAX_STEP / longest
                } else {
                    1.0
                };
                let mut xn = x.clone();
                for (p, &k) in free.iter().enumerate() {
                    let (lo, hi) = bounds[k];
                    xn[k] = (x[k] + (delta[p] * scale) as f32).clamp(lo, hi);
                }
                let rn = self.residuals(&xn, probe, morph)?;
                let cn = self.cost(&rn, &xn);
                if cn < cost {
                    // Broyden update with the step taken (accepted steps only: a rejected
                    // step is often across a kink and would spoil the Jacobian).
                    let dx: Vec<f64> = (0..n).map(|k| (xn[k] - x[k]) as f64).collect();
                    let dx2: f64 = dx.iter().map(|d| d * d).sum();
                    if dx2 > 1e-12 {
                        for i in 0..m {
                            let pred: f64 = (0..n).map(|k| jac[i * n + k] * dx[k]).sum();
                            let err = (rn[i] - r[i]) - pred;
                            for k in 0..n {
                                jac[i * n + k] += err * dx[k] / dx2;
                            }
                        }
                    }
                    x = xn;
                    r = rn;
                    cost = cn;
                    lambda = (lambda / 3.0).max(1e-7);
                    accepted = true;
                    break;
                }
                lambda *= 4.0;
            }
            if !accepted {
                break;
            }
        }
        Ok((x, steps))
    }
}

/// Fits a body to `request` (see the [module docs](self)).
pub fn fit(
    model: &BodyModel,
    request: &FitRequest,
    options: &FitOptions,
) -> Result<FitReport, FitError> {
    let start = Instant::now();
    request.validate()?;
    let mut base = Shape {
        gender: request.gender,
        ..Shape::default()
    };
    if let Some(a) = request.age_years {
        base.age = age_slider(a).clamp(0.0, 1.0);
    }
    let targets: Vec<(usize, f32)> = request
        .targets
        .iter()
        .filter_map(|(m, &t)| Measure::ALL.iter().position(|a| a == m).map(|i| (i, t)))
        .collect();
    let mut params = vec![
        Param::Height,
        Param::Weight,
        Param::Muscle,
        Param::Proportions,
    ];
    params.extend(
        SLIDERS
            .iter()
            .map(|&s| Param::Slider(s))
            .filter(|p| request.targets.keys().any(|&m| p.moves(m))),
    );
    params.extend(
        REGIONS
            .iter()
            .map(|&s| Param::Region(s))
            .filter(|p| request.targets.keys().any(|&m| p.moves(m))),
    );
    let prior: Vec<f32> = params.iter().map(|p| p.rest()).collect();
    let mut fitter = Fitter {
        model,
        base,
        params,
        measures: targets,
        prior: prior.clone(),
        mu: options.prior_weight as f64,
        evaluations: 0,
    };

    // The outer loop: a full measurement (new landmarks and probe) at each trial; a trial that
    // is worse than the best so far (the landmarks moved against the probe's prediction) is
    // retried from the best with half the trust radius.
    struct Best {
        cost: f64,
        x: Vec<f32>,
        measured: Measurements,
        probe: MeasureProbe,
    }
    let mut x = prior;
    let mut best: Option<Best> = None;
    let (mut outer, mut iterations) = (0, 0);
    let mut trust = 1.0f32;
    loop {
        let shape = fitter.shape(&x);
        let body = model.shaped(&shape)?;
        let (measured, probe) = model.measure_with_probe(&body.positions)?;
        outer += 1;
        let r: Vec<f64> = fitter
            .measures
            .iter()
            .map(|&(i, t)| (Measure::ALL[i].of(&measured) - t) as f64)
            .collect();
        let cost = fitter.cost(&r, &x);
        let worst = r.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        if best.as_ref().is_none_or(|b| cost < b.cost) {
            best = Some(Best {
                cost,
                x: x.clone(),
                measured,
                probe,
            });
        } else {
            trust *= 0.5;
        }
        if worst < options.converged_cm as f64 || trust < 0.1 || outer >= options.max_outer {
            break;
        }
        let Some(b) = best.as_ref() else {
            break;
        };
        let mut morph = ProbeMorph::new(model, b.probe.vertices());
        let (xn, steps) = fitter.inner(b.x.clone(), &b.probe, &mut morph, options, trust)?;
        iterations += steps;
        x = xn;
    }
    let Some(Best {
        x,
        measured: achieved,
        ..
    }) = best
    else {
        return Err(FitError::NoTargets);
    };
    let residuals_cm: BTreeMap<Measure, f32> = request
        .targets
        .iter()
        .map(|(&m, &t)| (m, m.of(&achieved) - t))
        .collect();
    let reachable = residuals_cm
        .values()
        .all(|r| r.abs() <= options.tolerance_cm);
    let at_bounds = fitter
        .params
        .iter()
        .zip(&x)
        .filter(|(p, v)| {
            let (lo, hi) = p.bounds();
            **v <= lo || **v >= hi
        })
        .map(|(p, v)| format!("{} = {v}", p.name()))
        .collect();
    Ok(FitReport {
        shape: fitter.shape(&x),
        targets: request.targets.clone(),
        achieved,
        residuals_cm,
        reachable,
        tolerance_cm: options.tolerance_cm,
        at_bounds,
        outer_iterations: outer,
        iterations,
        evaluations: fitter.evaluations,
        time_ms: start.elapsed().as_secs_f64() * 1e3,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cholesky_solves_a_known_system() {
        // A = [[4, 2], [2, 3]], x = [1, -2] -> b = [0, -4].
        let x = cholesky_solve(&[4.0, 2.0, 2.0, 3.0], &[0.0, -4.0], 2).expect("SPD");
        assert!(
            (x[0] - 1.0).abs() < 1e-12 && (x[1] + 2.0).abs() < 1e-12,
            "{x:?}"
        );
        assert!(cholesky_solve(&[1.0, 2.0, 2.0, 1.0], &[0.0, 0.0], 2).is_none());
    }

    #[test]
    fn age_slider_matches_makehuman_anchors() {
        assert!((age_slider(25.0) - 0.5).abs() < 1e-6);
        assert!((age_slider(90.0) - 1.0).abs() < 1e-6);
        assert!((age_slider(10.0) - 0.1875).abs() < 1e-6);
    }
}
