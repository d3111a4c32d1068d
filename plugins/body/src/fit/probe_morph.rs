//! The morph of only the vertices a measure probe reads, for the fit's trial bodies (seed 002 §4.2
//! calibration): linear in the target weights, each target's deltas on those vertices gathered once
//! and applied incrementally.

use std::collections::HashMap;

use glam::Vec3;

use crate::model::BodyModel;

/// The morph restricted to the vertices a probe reads: positions = base + Σ w_t · D_t, with
/// each target's deltas on those vertices gathered on first use. Updates are incremental:
/// only the targets whose weight changed since the last call are applied (a finite-difference
/// column changes one or a few), with a full recomputation every [`FULL_MORPH_EVERY`] calls
/// so rounding cannot drift.
pub(super) struct ProbeMorph<'a> {
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
    pub(super) fn new(model: &'a BodyModel, vertices: &[u32]) -> Self {
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
    pub(super) fn apply(&mut self, weights: &[(usize, f32)]) -> &[Vec3] {
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
