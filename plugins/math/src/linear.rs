//! Small dense linear algebra: the Cholesky solve of the normal equations of fitroom's
//! least-squares fits (at most a few dozen unknowns: too small to justify a linear-algebra
//! dependency).

/// The Cholesky factor `L` (`a = L Lᵀ`) of a symmetric positive definite matrix.
#[derive(Clone, Debug)]
pub struct Cholesky {
    l: Vec<f64>,
    n: usize,
}

impl Cholesky {
    /// Factors `a` (n×n, row-major; only its lower triangle is read); `None` if `a` is not
    /// positive definite.
    pub fn new(a: &[f64], n: usize) -> Option<Self> {
        if a.len() < n * n {
            return None;
        }
        let mut l = vec![0.0f64; n * n];
        for i in 0..n {
            for j in 0..=i {
                let mut s = a[i * n + j];
                for k in 0..j {
                    s -= l[i * n + k] * l[j * n + k];
                }
                if i == j {
                    if s <= 0.0 || !s.is_finite() {
                        return None;
                    }
                    l[i * n + i] = s.sqrt();
                } else {
                    l[i * n + j] = s / l[j * n + j];
                }
            }
        }
        Some(Self { l, n })
    }

    /// Solves `a x = b` (a `b` shorter than `a` is taken as padded with zeros).
    pub fn solve(&self, b: &[f64]) -> Vec<f64> {
        let (l, n) = (&self.l, self.n);
        let mut y = vec![0.0; n];
        for i in 0..n {
            let mut s = b.get(i).copied().unwrap_or(0.0);
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
        x
    }

    /// `ln det a` (twice the sum of the logarithms of `L`'s diagonal).
    pub fn log_det(&self) -> f64 {
        2.0 * (0..self.n)
            .map(|i| self.l[i * self.n + i].ln())
            .sum::<f64>()
    }
}

/// Solves `a x = b` for a symmetric positive definite `a` (n×n, row-major) by Cholesky;
/// `None` if `a` is not positive definite.
pub fn cholesky_solve(a: &[f64], b: &[f64], n: usize) -> Option<Vec<f64>> {
    Cholesky::new(a, n).map(|c| c.solve(b))
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
    fn log_det_matches_the_determinant() {
        // det [[4, 2, 0], [2, 3, 1], [0, 1, 5]] = 4 (15 - 1) - 2 (10 - 0) = 36, by cofactors.
        let a = [4.0, 2.0, 0.0, 2.0, 3.0, 1.0, 0.0, 1.0, 5.0];
        let c = Cholesky::new(&a, 3).expect("SPD");
        assert!((c.log_det() - 36f64.ln()).abs() < 1e-12, "{}", c.log_det());
        // And it solves: a [1, 1, 1] = [6, 6, 6].
        let x = c.solve(&[6.0, 6.0, 6.0]);
        assert!(x.iter().all(|v| (v - 1.0).abs() < 1e-12), "{x:?}");
    }
}
