//! What is read out of a garment's simulation: where to draw it (the simulated part a little
//! out along its normals, blending in from the attached part), its positions, and the fit
//! figures: per-vertex strain (the largest stretch of its edges, %) and the gap to the body's
//! colliders, for the garment of seed 000 §3.2.1 (a skinned static part, a simulated one).

use std::ops::Range;
use std::sync::atomic::Ordering;

use glam::{Affine3A, Vec3};

use fitroom_body::colliders::round_cone_distance;
use fitroom_body::{MeshGraph, SegmentError};

use super::GarmentSim;

/// How far out along its normals the simulated part of a garment is drawn, metres. The body
/// colliders sit inside the skin (by 1.5 cm on the trunk and up to 3 cm at the front of the
/// thighs, so that they never stick out of it) and the cloth rests 3 mm over them, so drawn
/// where it is simulated a skirt lets the thighs and belly show through in a stride. Colliders
/// on the skin, or a larger collision offset, stretch the skirt against its skinned waistband
/// instead (tried: a 10-15 mm offset took tethers to 1.7-2.4 on 16_11). Drawing the free
/// cloth a little farther out hides most of it (15 mm left large patches of thigh, 25 mm a
/// few small ones in a long stride) and changes no simulated figure; the app also leaves out
/// the skin the garment surely covers ([`crate::cover`]), which hides the rest.
pub const RENDER_OFFSET_M: f32 = 0.025;

/// Edges over which that offset blends in from the attached part.
pub const RENDER_RAMP_EDGES: u32 = 4;

/// Per vertex of `graph`: `min(1, edges to the nearest attached vertex / RENDER_RAMP_EDGES)`
/// (1 without attached vertices).
pub(super) fn render_weights(
    graph: &MeshGraph,
    attached: &[u32],
) -> Result<Vec<f32>, SegmentError> {
    let mut weights = vec![1.0f32; graph.vertex_count()];
    for (v, hops) in graph.hops_from(attached, RENDER_RAMP_EDGES)? {
        weights[v as usize] = hops as f32 / RENDER_RAMP_EDGES as f32;
    }
    Ok(weights)
}
impl GarmentSim {
    /// Where to draw the garment, and its normals: its positions, the simulated part drawn
    /// [`RENDER_OFFSET_M`] out along its normals (see there), blending in over
    /// [`RENDER_RAMP_EDGES`] edges from the attached part, which is drawn where it is. The
    /// normals are those of the simulated surface (the offset one is parallel to it).
    pub fn render_surface(&self) -> (Vec<Vec3>, Vec<Vec3>) {
        let (mut positions, mut normals) = (Vec::new(), Vec::new());
        self.render_surface_into(&mut positions, &mut normals);
        (positions, normals)
    }

    /// [`Self::render_surface`] into `positions` and `normals` (cleared first), to reuse their
    /// storage frame after frame.
    pub fn render_surface_into(&self, positions: &mut Vec<Vec3>, normals: &mut Vec<Vec3>) {
        self.positions_into(positions);
        fitroom_body::rig::compute_normals_into(positions, &self.triangles, normals);
        for ((p, &n), &w) in positions
            .iter_mut()
            .zip(normals.iter())
            .zip(&self.render_weight)
        {
            if n.is_finite() {
                *p += n * (w * RENDER_OFFSET_M);
            }
        }
    }

    /// Per vertex: the largest stretch of its edges over their rest length, % (negative when
    /// all its edges are compressed).
    pub fn strain_pct(&self) -> Vec<f32> {
        let p = self.positions();
        let mut out = vec![f32::NEG_INFINITY; p.len()];
        for &(a, b, rest) in &self.edges {
            if rest <= 0.0 {
                continue;
            }
            let s = (p[a as usize].distance(p[b as usize]) / rest - 1.0) * 100.0;
            for v in [a, b] {
                let o = &mut out[v as usize];
                *o = o.max(s);
            }
        }
        for o in &mut out {
            if !o.is_finite() {
                *o = 0.0;
            }
        }
        out
    }

    /// Per vertex: distance to the posed body colliders' surface, metres (negative inside).
    pub fn gap_m(&self, skinning: &[Affine3A]) -> Vec<f32> {
        self.gaps(&self.posed_colliders(skinning, &self.anchors(skinning)).0)
    }

    /// Deepest simulated (free) particle inside a collider, metres (0 if none). Attached
    /// particles are where the skinned body puts them, not the solver.
    pub fn max_penetration(&self, skinning: &[Affine3A]) -> f32 {
        self.deepest(&self.posed_colliders(skinning, &self.anchors(skinning)).0)
    }

    fn gaps(&self, posed: &[(Vec3, Vec3, f32, f32)]) -> Vec<f32> {
        self.positions().iter().map(|&q| gap(q, posed)).collect()
    }

    fn deepest(&self, posed: &[(Vec3, Vec3, f32, f32)]) -> f32 {
        self.deepest_of(posed, 0..self.solver.particle_count())
    }

    /// [`Self::deepest`] over the particles of `range` (never negative, never NaN; possibly
    /// -0.0).
    fn deepest_of(&self, posed: &[(Vec3, Vec3, f32, f32)], range: Range<usize>) -> f32 {
        let start = range.start;
        self.solver.positions()[range]
            .iter()
            .enumerate()
            .filter(|(i, _)| {
                self.solver
                    .attached()
                    .binary_search(&((start + i) as u32))
                    .is_err()
            })
            .fold(0.0f32, |m, (_, &q)| m.max(-gap(q.into(), posed)))
    }

    /// The largest stretch over its rest length of the edges of `range`, the garment at `p`,
    /// % (0 if none is stretched; never NaN): the largest of [`Self::strain_pct`] over them.
    fn max_strain_pct_of(&self, p: &[Vec3], range: Range<usize>) -> f32 {
        self.edges[range]
            .iter()
            .filter(|e| e.2 > 0.0)
            .map(|&(a, b, rest)| (p[a as usize].distance(p[b as usize]) / rest - 1.0) * 100.0)
            .fold(0.0, f32::max)
    }

    /// [`Self::deepest`] and the largest edge stretch ([`Self::max_strain_pct_of`] of every
    /// edge), the work shared out to the solver's threads in pieces (the same results: each
    /// is the largest of its pieces'). Besides taking half the time, this keeps the workers
    /// awake for the next step, as the steps of a frame find them when nothing is measured
    /// between them.
    pub(super) fn measure_on_threads(
        &self,
        posed: &[(Vec3, Vec3, f32, f32)],
        p: &[Vec3],
    ) -> (f32, f32) {
        const PIECES: usize = 16;
        let posing = &self.posing;
        posing.deepest.store(0, Ordering::Relaxed);
        posing.strain.store(0, Ordering::Relaxed);
        let (particles, edges) = (self.solver.particle_count(), self.edges.len());
        let piece = |count: usize, k: usize| {
            let size = count.div_ceil(PIECES);
            (k * size).min(count)..((k + 1) * size).min(count)
        };
        self.solver.share_out(PIECES, &|k| {
            // Both maxima are at least zero and never NaN, and the bits of such floats order
            // as they do; `+ 0.0` turns a maximum of -0.0 (whose bits would beat every
            // positive float's) into +0.0.
            let deepest = self.deepest_of(posed, piece(particles, k)) + 0.0;
            posing
                .deepest
                .fetch_max(deepest.to_bits(), Ordering::Relaxed);
            let strain = self.max_strain_pct_of(p, piece(edges, k)) + 0.0;
            posing.strain.fetch_max(strain.to_bits(), Ordering::Relaxed);
        });
        (
            f32::from_bits(posing.deepest.load(Ordering::Relaxed)),
            f32::from_bits(posing.strain.load(Ordering::Relaxed)),
        )
    }
}

/// Signed distance from `q` to the nearest of the `posed` colliders (negative inside).
fn gap(q: Vec3, posed: &[(Vec3, Vec3, f32, f32)]) -> f32 {
    posed
        .iter()
        .map(|&(a, b, ra, rb)| round_cone_distance(q, a, b, ra, rb))
        .fold(f32::INFINITY, f32::min)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_render_offset_blends_in_from_the_attached_part() {
        // A strip of 2 x 8 vertices, attached at its first column.
        let mut triangles = Vec::new();
        for i in 0..7u32 {
            let (a, b, c, d) = (i, i + 1, i + 8, i + 9);
            triangles.push([a, b, d]);
            triangles.push([a, d, c]);
        }
        // One more vertex in no triangle.
        let graph = MeshGraph::new(17, &triangles).expect("a valid mesh");
        let w = render_weights(&graph, &[0, 8]).expect("valid attachments");
        let expected = |i: u32| (i as f32 / RENDER_RAMP_EDGES as f32).min(1.0);
        for i in 0..8u32 {
            assert_eq!(w[i as usize], expected(i), "top {i}");
            assert_eq!(w[i as usize + 8], expected(i), "bottom {i}");
        }
        assert_eq!(w[16], 1.0, "the isolated vertex");
        // Nothing attached: drawn out everywhere.
        assert!(
            render_weights(&graph, &[])
                .expect("no attachments")
                .iter()
                .all(|&x| x == 1.0)
        );
    }
}
