//! Summary statistics of a series of samples (timings, strains, fit errors), with one
//! percentile rule for the whole workspace.

/// Mean, median, 95th percentile and maximum of a series, and its length.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Summary {
    pub mean: f64,
    pub p50: f64,
    pub p95: f64,
    pub max: f64,
    pub samples: usize,
}

impl Summary {
    /// The summary of `values` (in any order; non-finite values sort by `f64::total_cmp`).
    /// All zero for no values.
    pub fn of(values: &[f64]) -> Self {
        if values.is_empty() {
            return Self::default();
        }
        let mut sorted = values.to_vec();
        sorted.sort_by(f64::total_cmp);
        Self {
            mean: sorted.iter().sum::<f64>() / sorted.len() as f64,
            p50: percentile(&sorted, 0.5),
            p95: percentile(&sorted, 0.95),
            max: percentile(&sorted, 1.0),
            samples: sorted.len(),
        }
    }
}

/// The `q` quantile (0..=1) of `sorted` (ascending): the value at index `round((n - 1) * q)`.
/// NaN for no values.
pub fn percentile(sorted: &[f64], q: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    let i = ((sorted.len() - 1) as f64 * q).round() as usize;
    sorted[i.min(sorted.len() - 1)]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percentile_is_nearest_rank() {
        let samples: Vec<f64> = (1..=100).map(f64::from).collect();
        let s = Summary::of(&samples);
        assert_eq!(s.p95, 95.0);
        assert_eq!(s.p50, 51.0);
        assert_eq!(s.max, 100.0);
        assert_eq!(s.samples, 100);
        assert!((s.mean - 50.5).abs() < 1e-12);
        assert_eq!(Summary::of(&[3.0]).p95, 3.0);
    }

    #[test]
    fn empty_series() {
        assert_eq!(Summary::of(&[]), Summary::default());
        assert!(percentile(&[], 0.5).is_nan());
    }
}
