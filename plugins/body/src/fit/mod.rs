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
//!
//! # Where things are
//!
//! - this module: the request, options and report, and the outer loop ([`fit`]);
//! - `sliders`: the MakeHuman sliders the fit may move, and which measures each one moves;
//! - `probe_morph`: the morph of only the vertices a [`MeasureProbe`] reads;
//! - `levenberg_marquardt`: the inner loop and its Cholesky solve.

mod levenberg_marquardt;
mod probe_morph;
mod sliders;

pub use sliders::{Param, REGIONS, SLIDERS, age_slider};

use std::collections::BTreeMap;
use std::time::Instant;

use serde::{Deserialize, Serialize};

use self::levenberg_marquardt::Fitter;
use self::probe_morph::ProbeMorph;
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
