//! The weighted-mean morph of seed 002 (Uğur 2008, parametric bodies for virtual dressing) §4.4,
//! eq. 4.6, on any mesh: a vertex moves by the mean of the morph amounts of the segments that reach
//! it, weighted by their propagation weights.

use glam::Vec3;

use super::{SegmentError, SegmentWeights};

/// The segments' weights per vertex, ready for the weighted-mean morph of seed eq. 4.6.
#[derive(Clone, Debug, PartialEq)]
pub struct AreaBlend {
    vertex_count: usize,
    area_count: usize,
    offsets: Vec<u32>,
    /// `(area, weight)` per vertex, rows given by `offsets`.
    entries: Vec<(u32, f32)>,
}

impl AreaBlend {
    /// Collects `areas` (area `j` is `areas[j]`) over `vertex_count` vertices.
    pub fn new(vertex_count: usize, areas: &[SegmentWeights]) -> Result<Self, SegmentError> {
        let mut rows: Vec<Vec<(u32, f32)>> = vec![Vec::new(); vertex_count];
        for (j, area) in areas.iter().enumerate() {
            if area.weights.len() != area.vertices.len() {
                return Err(SegmentError::Length {
                    field: "SegmentWeights::weights",
                    got: area.weights.len(),
                    expected: area.vertices.len(),
                    fix: "give one weight per vertex",
                });
            }
            for (&v, &w) in area.vertices.iter().zip(&area.weights) {
                let Some(row) = rows.get_mut(v as usize) else {
                    return Err(SegmentError::VertexIndex {
                        field: "SegmentWeights::vertices",
                        vertex: v,
                        vertex_count,
                    });
                };
                if !(w.is_finite() && w >= 0.0) {
                    return Err(SegmentError::BadValue {
                        field: "SegmentWeights::weights",
                        value: w,
                        expected: "a finite weight >= 0",
                    });
                }
                if w > 0.0 {
                    row.push((j as u32, w));
                }
            }
        }
        let mut offsets = Vec::with_capacity(vertex_count + 1);
        let mut entries = Vec::new();
        offsets.push(0);
        for row in rows {
            entries.extend_from_slice(&row);
            offsets.push(entries.len() as u32);
        }
        Ok(Self {
            vertex_count,
            area_count: areas.len(),
            offsets,
            entries,
        })
    }

    pub fn vertex_count(&self) -> usize {
        self.vertex_count
    }

    pub fn area_count(&self) -> usize {
        self.area_count
    }

    /// The `(area, weight)` memberships of vertex `v`.
    ///
    /// # Panics
    /// If `v` is not below [`AreaBlend::vertex_count`].
    pub fn memberships(&self, v: usize) -> &[(u32, f32)] {
        &self.entries[self.offsets[v] as usize..self.offsets[v + 1] as usize]
    }

    fn check_amounts(&self, amounts: &[f32]) -> Result<(), SegmentError> {
        if amounts.len() != self.area_count {
            return Err(SegmentError::Length {
                field: "amounts",
                got: amounts.len(),
                expected: self.area_count,
                fix: "give one amount per area (0 for the areas that do not morph)",
            });
        }
        if let Some(&u) = amounts.iter().find(|u| !u.is_finite()) {
            return Err(SegmentError::BadValue {
                field: "amounts",
                value: u,
                expected: "a finite morph amount (0 to 1 interpolates)",
            });
        }
        Ok(())
    }

    /// The multiplier `Σ_j u_j w_kj / Σ_j w_kj` of eq. 4.6 for each vertex `k` (0 where no area
    /// reaches), for the amounts `u_j` = `amounts[j]`.
    pub fn multipliers(&self, amounts: &[f32]) -> Result<Vec<f32>, SegmentError> {
        self.check_amounts(amounts)?;
        Ok((0..self.vertex_count)
            .map(|k| {
                let (mut num, mut den) = (0.0f32, 0.0f32);
                for &(j, w) in self.memberships(k) {
                    num += amounts[j as usize] * w;
                    den += w;
                }
                if den > 0.0 { num / den } else { 0.0 }
            })
            .collect())
    }

    /// Eq. 4.6 towards one target model: `b_k = s_k + (t_k - s_k) · multiplier_k`. Vertices at
    /// and past [`AreaBlend::vertex_count`] (helpers) and vertices with multiplier 0 are copied
    /// from `source` exactly.
    pub fn morph_towards(
        &self,
        source: &[Vec3],
        target: &[Vec3],
        amounts: &[f32],
    ) -> Result<Vec<Vec3>, SegmentError> {
        self.check_source(source)?;
        if target.len() != source.len() {
            return Err(SegmentError::Length {
                field: "target",
                got: target.len(),
                expected: source.len(),
                fix: "give the target model's positions, one per source vertex",
            });
        }
        let a = self.multipliers(amounts)?;
        let mut out = source.to_vec();
        for (k, &a) in a.iter().enumerate() {
            if a != 0.0 {
                out[k] = source[k] + (target[k] - source[k]) * a;
            }
        }
        Ok(out)
    }

    /// The generalised eq. 4.6 with one displacement field per area:
    /// `b_k = s_k + Σ_j u_j w_kj δ_j(k) / Σ_j w_kj`, where `displacement(j, k)` = `δ_j(k)` is
    /// asked only where `u_j ≠ 0`. With `δ_j(k) = t_k - s_k` for every `j` this is
    /// [`AreaBlend::morph_towards`].
    pub fn morph_with(
        &self,
        source: &[Vec3],
        amounts: &[f32],
        mut displacement: impl FnMut(usize, usize) -> Vec3,
    ) -> Result<Vec<Vec3>, SegmentError> {
        self.check_source(source)?;
        self.check_amounts(amounts)?;
        let mut out = source.to_vec();
        for (k, out_k) in out.iter_mut().enumerate().take(self.vertex_count) {
            let ms = self.memberships(k);
            if ms.iter().all(|&(j, _)| amounts[j as usize] == 0.0) {
                continue;
            }
            let mut num = Vec3::ZERO;
            let mut den = 0.0f32;
            for &(j, w) in ms {
                let u = amounts[j as usize];
                if u != 0.0 {
                    num += displacement(j as usize, k) * (u * w);
                }
                den += w;
            }
            *out_k = source[k] + num / den;
        }
        Ok(out)
    }

    fn check_source(&self, source: &[Vec3]) -> Result<(), SegmentError> {
        if source.len() < self.vertex_count {
            return Err(SegmentError::Length {
                field: "source",
                got: source.len(),
                expected: self.vertex_count,
                fix: "pass the positions of the mesh the areas were built on",
            });
        }
        Ok(())
    }
}
