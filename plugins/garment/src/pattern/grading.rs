//! Grading: a pattern's panels scaled from the base size to another, across by the girth
//! ratio of their grading rows' measures and along by the length ratio (see [Grading] in the
//! module docs; sizes as in seed 002, EN 13402).
//!
//! [Grading]: super#grading

use fitroom_body::Measure;
use glam::Vec2;

use super::{Panel, Pattern};

impl Pattern {
    /// Index of the size labelled `label`.
    pub fn size_index(&self, label: &str) -> Option<usize> {
        self.sizes.iter().position(|s| s.label == label)
    }

    /// The size labels, smallest first.
    pub fn size_labels(&self) -> Vec<&str> {
        self.sizes.iter().map(|s| s.label.as_str()).collect()
    }

    /// The panels graded to size `size` (index into [`Pattern::sizes`]); see the
    /// [module docs](super#grading).
    pub fn graded_panels(&self, size: usize) -> Vec<Panel> {
        let base = &self.sizes[self.base_size];
        let target = &self.sizes[size.min(self.sizes.len() - 1)];
        self.panels
            .iter()
            .map(|panel| {
                let ratio = |m: Measure| match (base.body_cm.get(&m), target.body_cm.get(&m)) {
                    (Some(&b), Some(&t)) if b > 0.0 => t / b,
                    _ => 1.0,
                };
                let rows: Vec<(f32, f32)> = panel
                    .grade_width
                    .iter()
                    .map(|&(y, m)| (y, ratio(m)))
                    .collect();
                let length = match (panel.grade_length, base.length_cm, target.length_cm) {
                    (true, Some(b), Some(t)) if b > 0.0 => t / b,
                    _ => 1.0,
                };
                let outline = panel
                    .outline
                    .iter()
                    .map(|p| Vec2::new(p.x * width_ratio(&rows, p.y), p.y * length))
                    .collect();
                Panel {
                    outline,
                    ..panel.clone()
                }
            })
            .collect()
    }
}

/// The horizontal grading ratio at height `y`: piecewise linear between the rows, constant
/// beyond them, 1 without rows.
fn width_ratio(rows: &[(f32, f32)], y: f32) -> f32 {
    match rows {
        [] => 1.0,
        [(_, r)] => *r,
        _ => {
            if y <= rows[0].0 {
                return rows[0].1;
            }
            for w in rows.windows(2) {
                let ((y0, r0), (y1, r1)) = (w[0], w[1]);
                if y <= y1 {
                    let t = if y1 > y0 { (y - y0) / (y1 - y0) } else { 1.0 };
                    return r0 + (r1 - r0) * t;
                }
            }
            rows[rows.len() - 1].1
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn width_ratio_interpolates() {
        let rows = [(0.0, 1.0), (10.0, 2.0)];
        assert_eq!(width_ratio(&rows, -5.0), 1.0);
        assert_eq!(width_ratio(&rows, 5.0), 1.5);
        assert_eq!(width_ratio(&rows, 20.0), 2.0);
        assert_eq!(width_ratio(&[], 3.0), 1.0);
    }
}
