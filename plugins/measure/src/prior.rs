//! What bodies are like: the distribution of the shape sliders over real people, learned from
//! ANSUR II subjects (their measurements fitted with [`fitroom_body::fit`]), one Gaussian per
//! gender. The camera sees only the front; how deep a body is behind that front, where its
//! waist's back is, comes from how the sliders go together in people (a broad front and a
//! deep trunk together). Without it the fit fell back to MakeHuman's default behind the
//! front and took 2-5 cm off the girths of heavy men.

use std::path::Path;

use fitroom_body::ansur::AnsurSubject;
use fitroom_body::{BodyModel, FitOptions, FitRequest, fit};
use fitroom_math::Cholesky;
use serde::{Deserialize, Serialize};

use crate::posed::ShapeSpace;

/// The sliders' mean and covariance over the people of one gender.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GenderPrior {
    pub subjects: usize,
    pub mean: Vec<f32>,
    /// Row-major, `mean.len()` squared.
    pub covariance: Vec<f32>,
}

/// The shape prior: the slider names (in [`ShapeSpace::full`] order) and one Gaussian per
/// gender.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ShapePrior {
    pub source: String,
    pub sliders: Vec<String>,
    pub female: GenderPrior,
    pub male: GenderPrior,
}

#[derive(Debug, thiserror::Error)]
pub enum PriorError {
    #[error("cannot read the shape prior '{path}': {why}")]
    Read { path: String, why: String },
    #[error(
        "the shape prior '{path}' is for other sliders ({found} of them; this build fits {expected}): make it anew with `fitroom measure prior`"
    )]
    Sliders {
        path: String,
        found: usize,
        expected: usize,
    },
    #[error("no subjects to learn a prior from")]
    NoSubjects,
}

/// The shipped prior.
pub const SHIPPED: &str = include_str!("../../../assets/bodies/shape-prior.ron");

impl ShapePrior {
    /// The prior shipped with fitroom (`assets/bodies/shape-prior.ron`).
    pub fn shipped() -> Result<Self, PriorError> {
        Self::from_ron(SHIPPED, "assets/bodies/shape-prior.ron")
    }

    pub fn load(path: &Path) -> Result<Self, PriorError> {
        let text = std::fs::read_to_string(path).map_err(|e| PriorError::Read {
            path: path.display().to_string(),
            why: e.to_string(),
        })?;
        Self::from_ron(&text, &path.display().to_string())
    }

    pub fn from_ron(text: &str, path: &str) -> Result<Self, PriorError> {
        let prior: ShapePrior = ron::from_str(text).map_err(|e| PriorError::Read {
            path: path.into(),
            why: e.to_string(),
        })?;
        let expected = ShapeSpace::full()
            .params
            .iter()
            .map(|p| p.name())
            .collect::<Vec<_>>();
        let n = expected.len();
        let fits = |g: &GenderPrior| g.mean.len() == n && g.covariance.len() == n * n;
        if prior.sliders != expected || !fits(&prior.female) || !fits(&prior.male) {
            return Err(PriorError::Sliders {
                path: path.into(),
                found: prior.sliders.len(),
                expected: n,
            });
        }
        Ok(prior)
    }

    pub fn of(&self, female: bool) -> &GenderPrior {
        if female { &self.female } else { &self.male }
    }
}

impl GenderPrior {
    /// The precision (inverse covariance, row-major f64), the covariance first made
    /// well-conditioned: each slider's variance at least (0.02)², which also lets a fixed
    /// slider (gender within one gender) move a little.
    pub fn precision(&self) -> Option<Vec<f64>> {
        let n = self.mean.len();
        let c = self.covariance_factor()?;
        let mut out = vec![0.0; n * n];
        for j in 0..n {
            let mut e = vec![0.0; n];
            e[j] = 1.0;
            let col = c.solve(&e);
            for i in 0..n {
                out[i * n + j] = col[i];
            }
        }
        Some(out)
    }

    /// `ln det` of [`Self::precision`]: a narrow prior's density is high where it is.
    pub fn log_det_precision(&self) -> Option<f64> {
        Some(-self.covariance_factor()?.log_det())
    }

    /// The well-conditioned covariance, factored.
    fn covariance_factor(&self) -> Option<Cholesky> {
        let n = self.mean.len();
        let mut c: Vec<f64> = self.covariance.iter().map(|&v| f64::from(v)).collect();
        for i in 0..n {
            c[i * n + i] += 4e-4;
        }
        Cholesky::new(&c, n)
    }
}

/// Learns the prior from `subjects` (fitting each to their measurements, on `threads`
/// threads); `progress(done, total)` after each.
pub fn learn(
    model: &BodyModel,
    subjects: &[AnsurSubject],
    threads: usize,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<ShapePrior, PriorError> {
    if subjects.is_empty() {
        return Err(PriorError::NoSubjects);
    }
    let space = ShapeSpace::full();
    let done = std::sync::atomic::AtomicUsize::new(0);
    let shapes = fitroom_math::parallel_map(subjects, threads, |s| {
        let request = FitRequest {
            gender: if s.female { 0.0 } else { 1.0 },
            age_years: None,
            targets: s.measurements.clone(),
        };
        let out = fit(model, &request, &FitOptions::default())
            .ok()
            .map(|r| (s.female, space.values(&r.shape)));
        progress(
            done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1,
            subjects.len(),
        );
        out
    });
    let gaussian = |female: bool| {
        let xs: Vec<&Vec<f32>> = shapes
            .iter()
            .flatten()
            .filter(|(f, _)| *f == female)
            .map(|(_, x)| x)
            .collect();
        let n = space.len();
        let count = xs.len().max(1) as f64;
        let mut mean = vec![0.0f64; n];
        for x in &xs {
            for (m, v) in mean.iter_mut().zip(x.iter()) {
                *m += f64::from(*v) / count;
            }
        }
        let mut cov = vec![0.0f64; n * n];
        for x in &xs {
            for i in 0..n {
                for j in 0..n {
                    cov[i * n + j] +=
                        (f64::from(x[i]) - mean[i]) * (f64::from(x[j]) - mean[j]) / count;
                }
            }
        }
        GenderPrior {
            subjects: xs.len(),
            mean: mean.iter().map(|&v| v as f32).collect(),
            covariance: cov.iter().map(|&v| v as f32).collect(),
        }
    };
    Ok(ShapePrior {
        source: format!(
            "ANSUR II: {} subjects fitted with fitroom_body::fit (sliders of fitroom_measure::ShapeSpace::full)",
            subjects.len()
        ),
        sliders: space.params.iter().map(|p| p.name()).collect(),
        female: gaussian(true),
        male: gaussian(false),
    })
}
