//! Our hand-state classifier: the hand region's metric features ([`super::region`]), each
//! over the body's expected hand length so one model serves a child and a tall man, read by
//! logistic regression (trained by Newton's method with a small ridge, on synthetic hands:
//! [`crate::synth`]). The model is data (`assets/gesture/hands.ron`, written by `fitroom
//! gesture train`), embedded as the default.

// The small matrix and vector loops read as the algebra they are with indices.
#![allow(clippy::needless_range_loop)]

use fitroom_depth::DepthFrame;

use super::region::{BANDS, HandFeatures, HandJoints, hand_region};
use crate::HandState;

/// The number of inputs the model reads.
pub const INPUTS: usize = 6 + BANDS;

/// The fewest pixels a hand's region may have to be judged (a hand at 3.5 m has about 60).
pub const MIN_PIXELS: u32 = 12;

/// The model's inputs: the features over powers of the hand length `l` (so they are
/// unitless and the same for any body size).
pub fn inputs(f: &HandFeatures, l: f32) -> [f32; INPUTS] {
    let mut x = [0.0; INPUTS];
    x[0] = f.area_m2 / (l * l);
    x[1] = f.length_m / l;
    x[2] = f.depth_spread_m / l;
    x[3] = f.solidity;
    x[4] = f.mean_offset_m / l;
    // The widest band: an open hand's spread fingers, a fist's knuckles.
    x[5] = f.widths_m.iter().fold(0.0f32, |a, &b| a.max(b)) / l;
    for (k, w) in f.widths_m.iter().enumerate() {
        x[6 + k] = w / l;
    }
    x
}

/// A trained hand-state model: ours (standardised inputs, weights, bias) and the seed's
/// threshold on its own score.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct HandModel {
    pub mean: Vec<f32>,
    pub scale: Vec<f32>,
    pub weights: Vec<f32>,
    pub bias: f32,
    /// The seed's method: open above this score.
    pub seed_threshold: f32,
    /// What it was trained on (for the record).
    pub trained_on: String,
}

#[derive(Debug, thiserror::Error)]
pub enum ModelError {
    #[error("{file}: {reason} (re-create it with `fitroom gesture train --out {file}`)")]
    Parse { file: String, reason: String },
    #[error(
        "{file}: the model has {got} inputs where this build reads {expected} (re-create it with `fitroom gesture train --out {file}`)"
    )]
    Inputs {
        file: String,
        got: usize,
        expected: usize,
    },
}

/// The model the product ships.
const EMBEDDED: &str = include_str!("../../../../assets/gesture/hands.ron");

impl HandModel {
    /// The shipped model (`assets/gesture/hands.ron`).
    pub fn embedded() -> Result<Self, ModelError> {
        Self::parse(EMBEDDED, "assets/gesture/hands.ron")
    }

    /// A model from RON text (`file` names it in errors).
    pub fn parse(text: &str, file: &str) -> Result<Self, ModelError> {
        let model: Self = ron::from_str(text).map_err(|e| ModelError::Parse {
            file: file.to_string(),
            reason: e.to_string(),
        })?;
        for len in [model.mean.len(), model.scale.len(), model.weights.len()] {
            if len != INPUTS {
                return Err(ModelError::Inputs {
                    file: file.to_string(),
                    got: len,
                    expected: INPUTS,
                });
            }
        }
        Ok(model)
    }

    /// The model's probability that the hand of inputs `x` is open.
    pub fn p_open(&self, x: &[f32; INPUTS]) -> f32 {
        let mut z = self.bias;
        for k in 0..INPUTS {
            z += self.weights[k] * (x[k] - self.mean[k]) / self.scale[k];
        }
        1.0 / (1.0 + (-z).exp())
    }
}

/// One frame's look at a hand.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HandLook {
    /// Open or closed by the probability's side of 1/2; unknown when the hand is not seen
    /// well enough (out of view, too few pixels).
    pub state: HandState,
    pub p_open: f32,
    pub features: Option<HandFeatures>,
}

impl HandLook {
    pub const UNSEEN: Self = Self {
        state: HandState::Unknown,
        p_open: 0.5,
        features: None,
    };
}

/// Our method's look at the hand at `joints` in `frame`.
pub fn look(frame: &DepthFrame, joints: &HandJoints, model: &HandModel) -> HandLook {
    let Some(region) = hand_region(frame, joints) else {
        return HandLook::UNSEEN;
    };
    let f = region.features(&frame.camera);
    if f.pixels < MIN_PIXELS {
        return HandLook {
            features: Some(f),
            ..HandLook::UNSEEN
        };
    }
    let p = model.p_open(&inputs(&f, joints.hand_length_m()));
    HandLook {
        state: if p >= 0.5 {
            HandState::Open
        } else {
            HandState::Closed
        },
        p_open: p,
        features: Some(f),
    }
}

/// A labelled training example: the model's inputs, the seed's score, whether the hand is
/// open.
#[derive(Clone, Copy, Debug)]
pub struct Example {
    pub inputs: Option<[f32; INPUTS]>,
    pub seed_score: Option<f32>,
    pub open: bool,
}

/// Trains both methods on `examples`: ours by logistic regression (Newton's method on the
/// standardised inputs, ridge `1e-2`), the seed's threshold as the one that classifies the
/// most examples right. Examples a method cannot read (no region) are left out of its
/// training.
pub fn train(examples: &[Example], trained_on: String) -> HandModel {
    let rows: Vec<(&[f32; INPUTS], bool)> = examples
        .iter()
        .filter_map(|e| e.inputs.as_ref().map(|x| (x, e.open)))
        .collect();
    let n = rows.len().max(1) as f32;
    let mut mean = vec![0.0f32; INPUTS];
    for (x, _) in &rows {
        for k in 0..INPUTS {
            mean[k] += x[k] / n;
        }
    }
    let mut scale = vec![0.0f32; INPUTS];
    for (x, _) in &rows {
        for k in 0..INPUTS {
            scale[k] += (x[k] - mean[k]).powi(2) / n;
        }
    }
    for s in &mut scale {
        *s = s.sqrt().max(1e-6);
    }
    // Newton's method on the ridge-penalised log-likelihood; [bias, weights...].
    const D: usize = INPUTS + 1;
    let mut beta = [0.0f64; D];
    let z_of = |x: &[f32; INPUTS]| {
        let mut z = [0.0f64; D];
        z[0] = 1.0;
        for k in 0..INPUTS {
            z[k + 1] = f64::from((x[k] - mean[k]) / scale[k]);
        }
        z
    };
    let ridge = 1e-2 * f64::from(n);
    for _ in 0..25 {
        let mut grad = [0.0f64; D];
        let mut hess = vec![0.0f64; D * D];
        for (x, open) in &rows {
            let z = z_of(x);
            let s: f64 = z.iter().zip(&beta).map(|(a, b)| a * b).sum();
            let p = 1.0 / (1.0 + (-s).exp());
            let y = if *open { 1.0 } else { 0.0 };
            let w = (p * (1.0 - p)).max(1e-9);
            for i in 0..D {
                grad[i] += (y - p) * z[i];
                for j in 0..D {
                    hess[i * D + j] += w * z[i] * z[j];
                }
            }
        }
        for i in 1..D {
            grad[i] -= ridge * beta[i];
            hess[i * D + i] += ridge;
        }
        // The ridge-penalised Hessian is positive definite.
        let Some(step) = fitroom_math::linear::Cholesky::new(&hess, D).map(|c| c.solve(&grad))
        else {
            break;
        };
        let mut size = 0.0;
        for i in 0..D {
            beta[i] += step[i];
            size += step[i].abs();
        }
        if size < 1e-9 {
            break;
        }
    }
    HandModel {
        mean,
        scale,
        weights: beta[1..].iter().map(|&b| b as f32).collect(),
        bias: beta[0] as f32,
        seed_threshold: best_threshold(examples),
        trained_on,
    }
}

/// The threshold on the seed's score that classifies the most examples right (open above).
fn best_threshold(examples: &[Example]) -> f32 {
    let mut scored: Vec<(f32, bool)> = examples
        .iter()
        .filter_map(|e| e.seed_score.map(|s| (s, e.open)))
        .collect();
    scored.sort_by(|a, b| a.0.total_cmp(&b.0));
    // With the threshold below the k-th score: the first k are called closed.
    let opens = scored.iter().filter(|s| s.1).count();
    let (mut right, mut best, mut at) = (opens, opens, f32::NEG_INFINITY);
    for (k, (s, open)) in scored.iter().enumerate() {
        right = if *open { right - 1 } else { right + 1 };
        let next = scored.get(k + 1).map_or(s + 1e-3, |n| n.0);
        if right > best && next > *s {
            best = right;
            at = 0.5 * (s + next);
        }
    }
    at
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two separable clouds along input 0: the model puts them on their sides, and the
    /// seed's threshold falls between its scores.
    #[test]
    fn training_separates_two_clouds() {
        let mut examples = Vec::new();
        for k in 0..40 {
            let jitter = (k as f32 * 0.37).sin() * 0.2;
            let mut x = [0.5; INPUTS];
            let open = k % 2 == 0;
            x[0] = if open { 2.0 } else { 1.0 } + jitter;
            x[1] += jitter;
            examples.push(Example {
                inputs: Some(x),
                seed_score: Some(if open { 0.3 } else { 0.1 } + jitter * 0.1),
                open,
            });
        }
        let model = train(&examples, "test".into());
        for e in &examples {
            let p = model.p_open(e.inputs.as_ref().unwrap());
            assert_eq!(p > 0.5, e.open, "p = {p}");
        }
        assert!(model.seed_threshold > 0.12 && model.seed_threshold < 0.28);
        let text = ron::to_string(&model).unwrap();
        assert_eq!(HandModel::parse(&text, "x.ron").unwrap(), model);
        assert!(HandModel::parse("(mean: [1.0])", "x.ron").is_err());
    }
}
