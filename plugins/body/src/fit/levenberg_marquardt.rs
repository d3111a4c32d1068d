//! The fit's inner loop (seed 002 §4.2 calibration, done as bounded, regularised least squares):
//! Levenberg-Marquardt on the measure probe, a forward-difference Jacobian with Broyden updates,
//! bounds by projection with an active set.

use super::probe_morph::ProbeMorph;
use super::sliders::Param;
use super::{FitError, FitOptions};
use crate::measure::MeasureProbe;
use crate::model::BodyModel;
use crate::modifiers::Shape;
use fitroom_math::cholesky_solve;

/// Longest step of one slider per Levenberg-Marquardt iteration.
const MAX_STEP: f64 = 0.25;

/// The state of one fit.
pub(super) struct Fitter<'a> {
    pub(super) model: &'a BodyModel,
    pub(super) base: Shape,
    pub(super) params: Vec<Param>,
    /// Requested measures (indices into [`Measure::ALL`]) and their targets.
    ///
    /// [`Measure::ALL`]: crate::measure::Measure::ALL
    pub(super) measures: Vec<(usize, f32)>,
    pub(super) prior: Vec<f32>,
    pub(super) mu: f64,
    pub(super) evaluations: usize,
}

impl Fitter<'_> {
    pub(super) fn shape(&self, x: &[f32]) -> Shape {
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

    pub(super) fn cost(&self, r: &[f64], x: &[f32]) -> f64 {
        let prior: f64 = x
            .iter()
            .zip(&self.prior)
            .map(|(&a, &b)| ((a - b) as f64).powi(2))
            .sum();
        r.iter().map(|v| v * v).sum::<f64>() + self.mu * prior
    }

    /// Levenberg-Marquardt on the probe from `x`; returns the new `x` and the steps taken.
    pub(super) fn inner(
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
