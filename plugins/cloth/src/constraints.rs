//! Packed XPBD constraints, their projections, and the greedy colouring that batches them.
//!
//! **Distance** (stretch and shear): `C = |xᵢ − xⱼ| − L`, projected as in XPBD (Macklin et
//! al. 2016): `Δλ = −(C + α̃λ) / (wᵢ + wⱼ + α̃)`, `Δxᵢ = wᵢ n Δλ`, `Δxⱼ = −wⱼ n Δλ`.
//!
//! **Isometric bending** (Bergou et al. 2006; as a PBD constraint in Bender, Müller and
//! Macklin's 2015 PBD survey). For an interior edge `x₀x₁` with opposite vertices `x₂`, `x₃`
//! and the rest-shape cotangent weights `K = (c₀₃+c₀₄, c₀₁+c₀₂, −c₀₁−c₀₃, −c₀₂−c₀₄)`, the
//! energy `E = k_b/2 · 3/(A₀+A₁) |Σ Kᵢxᵢ|²` is the 3-vector constraint
//! `C = √(3/(A₀+A₁)) Σ Kᵢxᵢ` with compliance `1/k_b`. `C` is linear in the positions, so its
//! three components share one denominator `Σ wᵢkᵢ² + α̃` and the projection is exact in one
//! step. A flat rest stencil has `C = 0` at rest. For a curved rest shape (a garment modelled
//! in 3-D) the rest value of `C` is stored in the stencil's own frame (edge direction, mean
//! normal of the two triangles, their cross product) and the constraint asks `C` to equal
//! that vector re-expressed in the current frame; this keeps the rest shape the minimum and
//! is invariant to rigid motion. (Bergou's model assumes a flat rest shape; this rest-frame
//! target is our extension.)
//!
//! **Colouring.** Two constraints that share a free particle may not be projected at the same
//! time. Constraints are coloured greedily in a fixed order (each takes the smallest colour
//! none of its free particles has yet; attached particles, whose inverse mass is zero, are
//! never written and do not conflict). Each colour is split into work items that run in
//! parallel. Colours smaller than `TAIL_MIN` (96) constraints would cost a synchronisation each
//! for little work: they are merged into one final *tail* batch projected sequentially, in a
//! fixed order, by a single item. The colouring depends only on the mesh, never on the number
//! of threads.

use glam::Vec3A;

use crate::fabric::{Fabric, bend_compliance, distance_compliance};
use crate::mesh::MeshTopology;
use crate::pool::SharedSlice;

/// Colours with fewer constraints than this are merged into the sequential tail batch.
pub(crate) const TAIL_MIN: usize = 96;
/// Distance constraints per work item.
const DISTANCE_ITEM: usize = 384;
/// Bending constraints per work item.
const BEND_ITEM: usize = 192;

/// A distance constraint with the inverse masses of its particles.
#[derive(Debug, Clone, Copy, PartialEq)]
#[repr(C)]
pub(crate) struct DistanceConstraint {
    pub i: u32,
    pub j: u32,
    pub rest: f32,
    pub compliance: f32,
    pub wi: f32,
    pub wj: f32,
}

/// An isometric bending constraint (one cache line).
#[derive(Debug, Clone, Copy, PartialEq)]
#[repr(C, align(16))]
pub(crate) struct BendConstraint {
    pub v: [u32; 4],
    /// `√(3/(A₀+A₁)) Kᵢ`.
    pub k: [f32; 4],
    /// Inverse masses.
    pub w: [f32; 4],
    /// Rest value of `C` in the stencil frame (edge, normal, binormal); zero when flat.
    pub rest: [f32; 3],
    pub compliance: f32,
}

/// One work item: a range of distance and a range of bending constraints.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct ConstraintItem {
    pub distance: (u32, u32),
    pub bend: (u32, u32),
}

/// All constraints, sorted by colour, with the work items of each colour.
#[derive(Debug, Clone, Default)]
pub(crate) struct ConstraintSet {
    pub distance: Vec<DistanceConstraint>,
    pub distance_is_shear: Vec<bool>,
    pub bend: Vec<BendConstraint>,
    pub items: Vec<ConstraintItem>,
    /// Item range of each colour; the last one is the tail when `has_tail`.
    pub colours: Vec<(u32, u32)>,
    pub has_tail: bool,
}

impl ConstraintSet {
    pub fn build(
        rest: &[glam::Vec3],
        topology: &MeshTopology,
        fabric: &Fabric,
        inverse_mass: &[f32],
    ) -> Self {
        let mut distance = Vec::new();
        let mut is_shear = Vec::new();
        for (stencils, stiffness, shear) in [
            (&topology.stretch, fabric.stretch_stiffness_n_m, false),
            (&topology.shear, fabric.shear_stiffness_n_m, true),
        ] {
            for s in stencils {
                let [i, j] = s.vertices;
                let (wi, wj) = (inverse_mass[i as usize], inverse_mass[j as usize]);
                if wi + wj == 0.0 {
                    continue;
                }
                if let Some(compliance) = distance_compliance(stiffness, s.rest_length, s.area) {
                    distance.push(DistanceConstraint {
                        i,
                        j,
                        rest: s.rest_length,
                        compliance,
                        wi,
                        wj,
                    });
                    is_shear.push(shear);
                }
            }
        }
        let mut bend = Vec::new();
        if let Some(compliance) = bend_compliance(fabric.bend_stiffness_n_m) {
            for stencil in &topology.bending {
                let w = stencil.map(|v| inverse_mass[v as usize]);
                if w.iter().sum::<f32>() == 0.0 {
                    continue;
                }
                if let Some(c) = bend_stencil(rest, *stencil, w, compliance) {
                    bend.push(c);
                }
            }
        }

        // Greedy colouring over distance constraints, then bending constraints.
        let n = inverse_mass.len();
        let mut used = vec![0u128; n];
        let tail = u32::MAX;
        let mut colour_of = |vertices: &[u32]| -> u32 {
            let mut mask = 0u128;
            for &v in vertices {
                if inverse_mass[v as usize] > 0.0 {
                    mask |= used[v as usize];
                }
            }
            let colour = (!mask).trailing_zeros();
            if colour >= 128 {
                return tail;
            }
            for &v in vertices {
                if inverse_mass[v as usize] > 0.0 {
                    used[v as usize] |= 1u128 << colour;
                }
            }
            colour
        };
        let distance_colour: Vec<u32> = distance.iter().map(|c| colour_of(&[c.i, c.j])).collect();
        let bend_colour: Vec<u32> = bend.iter().map(|c| colour_of(&c.v)).collect();

        let mut size = [0usize; 128];
        for &c in distance_colour.iter().chain(bend_colour.iter()) {
            if c != tail {
                size[c as usize] += 1;
            }
        }
        // Rank of each colour: big colours keep their order, small ones go to the tail.
        let mut rank = [u32::MAX; 128];
        let mut colours_kept = 0u32;
        for c in 0..128 {
            if size[c] >= TAIL_MIN {
                rank[c] = colours_kept;
                colours_kept += 1;
            }
        }
        let rank_of = |c: u32| -> u32 {
            if c == tail || rank[c as usize] == u32::MAX {
                colours_kept
            } else {
                rank[c as usize]
            }
        };
        let mut distance_order: Vec<usize> = (0..distance.len()).collect();
        distance_order.sort_by_key(|&k| rank_of(distance_colour[k]));
        let mut bend_order: Vec<usize> = (0..bend.len()).collect();
        bend_order.sort_by_key(|&k| rank_of(bend_colour[k]));
        let distance_rank: Vec<u32> = distance_order
            .iter()
            .map(|&k| rank_of(distance_colour[k]))
            .collect();
        let bend_rank: Vec<u32> = bend_order
            .iter()
            .map(|&k| rank_of(bend_colour[k]))
            .collect();
        let distance_sorted: Vec<DistanceConstraint> =
            distance_order.iter().map(|&k| distance[k]).collect();
        let shear_sorted: Vec<bool> = distance_order.iter().map(|&k| is_shear[k]).collect();
        let bend_sorted: Vec<BendConstraint> = bend_order.iter().map(|&k| bend[k]).collect();

        let range_of = |ranks: &[u32], r: u32| -> (u32, u32) {
            let a = ranks.partition_point(|&x| x < r) as u32;
            let b = ranks.partition_point(|&x| x <= r) as u32;
            (a, b)
        };
        let mut items = Vec::new();
        let mut colours = Vec::new();
        for r in 0..colours_kept {
            let first = items.len() as u32;
            let (a, b) = range_of(&distance_rank, r);
            let mut k = a;
            while k < b {
                let e = (k + DISTANCE_ITEM as u32).min(b);
                items.push(ConstraintItem {
                    distance: (k, e),
                    bend: (0, 0),
                });
                k = e;
            }
            let (a, b) = range_of(&bend_rank, r);
            let mut k = a;
            while k < b {
                let e = (k + BEND_ITEM as u32).min(b);
                items.push(ConstraintItem {
                    distance: (0, 0),
                    bend: (k, e),
                });
                k = e;
            }
            colours.push((first, items.len() as u32));
        }
        let tail_distance = range_of(&distance_rank, colours_kept);
        let tail_bend = range_of(&bend_rank, colours_kept);
        let has_tail = tail_distance.0 < tail_distance.1 || tail_bend.0 < tail_bend.1;
        if has_tail {
            let first = items.len() as u32;
            items.push(ConstraintItem {
                distance: tail_distance,
                bend: tail_bend,
            });
            colours.push((first, first + 1));
        }
        Self {
            distance: distance_sorted,
            distance_is_shear: shear_sorted,
            bend: bend_sorted,
            items,
            colours,
            has_tail,
        }
    }

    /// Number of parallel colours (not counting the tail).
    pub fn parallel_colours(&self) -> usize {
        self.colours.len() - usize::from(self.has_tail)
    }
}

fn cot(a: glam::Vec3, b: glam::Vec3) -> f32 {
    let cross = a.cross(b).length();
    if cross < 1e-20 { 0.0 } else { a.dot(b) / cross }
}

fn bend_stencil(
    rest: &[glam::Vec3],
    v: [u32; 4],
    w: [f32; 4],
    compliance: f32,
) -> Option<BendConstraint> {
    let [x0, x1, x2, x3] = v.map(|i| rest[i as usize]);
    let e0 = x1 - x0;
    let e1 = x2 - x0;
    let e2 = x3 - x0;
    let e3 = x2 - x1;
    let e4 = x3 - x1;
    let c01 = cot(e0, e1);
    let c02 = cot(e0, e2);
    let c03 = cot(-e0, e3);
    let c04 = cot(-e0, e4);
    let a0 = 0.5 * e0.cross(e1).length();
    let a1 = 0.5 * e0.cross(e2).length();
    if a0 + a1 <= 0.0 || (a0 + a1).is_nan() {
        return None;
    }
    let scale = (3.0 / (a0 + a1)).sqrt();
    let k = [
        scale * (c03 + c04),
        scale * (c01 + c02),
        scale * (-c01 - c03),
        scale * (-c02 - c04),
    ];
    if !k.iter().all(|k| k.is_finite()) {
        return None;
    }
    // Relative to x₀ (the weights sum to zero) to keep rounding small.
    let y = k[1] * e0 + k[2] * e1 + k[3] * e2;
    let frame = stencil_frame(
        Vec3A::from(x0),
        Vec3A::from(x1),
        Vec3A::from(x2),
        Vec3A::from(x3),
    )?;
    let y = Vec3A::from(y);
    // Flat at rest: the weighted sum vanishes up to rounding (it is dimensionless, about
    // the dihedral angle in radians).
    let rest_value = if y.length() < 1e-4 {
        [0.0; 3]
    } else {
        [y.dot(frame.0), y.dot(frame.1), y.dot(frame.2)]
    };
    Some(BendConstraint {
        v,
        k,
        w,
        rest: rest_value,
        compliance,
    })
}

/// Edge direction, mean normal and binormal of a bending stencil, if not degenerate.
#[inline]
fn stencil_frame(p0: Vec3A, p1: Vec3A, p2: Vec3A, p3: Vec3A) -> Option<(Vec3A, Vec3A, Vec3A)> {
    let e0 = p1 - p0;
    let normal = e0.cross(p2 - p0) + (p3 - p0).cross(e0);
    let el = e0.length();
    let nl = normal.length();
    if !(el > 1e-12 && nl > 1e-9 * el * el) {
        return None;
    }
    let t = e0 / el;
    let n = normal / nl;
    Some((t, n, t.cross(n)))
}

/// Projects distance constraints `range` (XPBD). `first` means λ starts at zero.
#[inline]
pub(crate) fn solve_distance(
    constraints: &[DistanceConstraint],
    lambda: &SharedSlice<'_, f32>,
    x: &SharedSlice<'_, Vec3A>,
    range: (u32, u32),
    inv_h2: f32,
    keep_lambda: bool,
    first: bool,
) {
    let (lo, hi) = (range.0 as usize, range.1 as usize);
    for (k, c) in constraints.iter().enumerate().take(hi).skip(lo) {
        // SAFETY: indices were validated at build time; the colouring gives this item
        // exclusive access to particles i and j in this phase.
        unsafe {
            let pi = x.get(c.i as usize);
            let pj = x.get(c.j as usize);
            let d = pi - pj;
            let len = d.length();
            if len < 1e-9 {
                continue;
            }
            let n = d / len;
            let alpha = c.compliance * inv_h2;
            let lam = if keep_lambda && !first {
                lambda.get(k)
            } else {
                0.0
            };
            let dl = -(len - c.rest + alpha * lam) / (c.wi + c.wj + alpha);
            if keep_lambda {
                lambda.set(k, lam + dl);
            }
            x.set(c.i as usize, pi + (c.wi * dl) * n);
            x.set(c.j as usize, pj - (c.wj * dl) * n);
        }
    }
}

/// Projects isometric bending constraints `range` (XPBD).
#[inline]
pub(crate) fn solve_bend(
    constraints: &[BendConstraint],
    lambda: &SharedSlice<'_, Vec3A>,
    x: &SharedSlice<'_, Vec3A>,
    range: (u32, u32),
    inv_h2: f32,
    keep_lambda: bool,
    first: bool,
) {
    let (lo, hi) = (range.0 as usize, range.1 as usize);
    for (k, c) in constraints.iter().enumerate().take(hi).skip(lo) {
        // SAFETY: as in `solve_distance`.
        unsafe {
            let p = [
                x.get(c.v[0] as usize),
                x.get(c.v[1] as usize),
                x.get(c.v[2] as usize),
                x.get(c.v[3] as usize),
            ];
            let mut value =
                c.k[1] * (p[1] - p[0]) + c.k[2] * (p[2] - p[0]) + c.k[3] * (p[3] - p[0]);
            if c.rest != [0.0; 3] {
                let Some((t, n, b)) = stencil_frame(p[0], p[1], p[2], p[3]) else {
                    continue;
                };
                value -= c.rest[0] * t + c.rest[1] * n + c.rest[2] * b;
            }
            let alpha = c.compliance * inv_h2;
            let denom = c.w[0] * c.k[0] * c.k[0]
                + c.w[1] * c.k[1] * c.k[1]
                + c.w[2] * c.k[2] * c.k[2]
                + c.w[3] * c.k[3] * c.k[3]
                + alpha;
            let lam = if keep_lambda && !first {
                lambda.get(k)
            } else {
                Vec3A::ZERO
            };
            let dl = -(value + alpha * lam) / denom;
            if keep_lambda {
                lambda.set(k, lam + dl);
            }
            for (q, &pq) in p.iter().enumerate() {
                if c.w[q] > 0.0 {
                    x.set(c.v[q] as usize, pq + (c.w[q] * c.k[q]) * dl);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::ClothMesh;
    use glam::Vec3;

    #[test]
    fn colours_never_share_a_free_particle() {
        let mesh = ClothMesh::grid(Vec3::ZERO, Vec3::X, Vec3::Y, 24, 20).unwrap();
        let topo = MeshTopology::new(&mesh);
        let mut w = vec![1.0f32; mesh.vertex_count()];
        w[0] = 0.0;
        w[24] = 0.0;
        let set = ConstraintSet::build(mesh.positions(), &topo, &Fabric::cotton(), &w);
        assert!(set.parallel_colours() >= 8);
        for (c, &(a, b)) in set.colours.iter().enumerate() {
            if set.has_tail && c + 1 == set.colours.len() {
                continue;
            }
            let mut seen = vec![false; mesh.vertex_count()];
            for item in &set.items[a as usize..b as usize] {
                let d = &set.distance[item.distance.0 as usize..item.distance.1 as usize];
                let bends = &set.bend[item.bend.0 as usize..item.bend.1 as usize];
                let vertices = d
                    .iter()
                    .flat_map(|c| [c.i, c.j])
                    .chain(bends.iter().flat_map(|c| c.v));
                for v in vertices {
                    if w[v as usize] > 0.0 {
                        assert!(!seen[v as usize], "colour {c} reuses particle {v}");
                        seen[v as usize] = true;
                    }
                }
            }
        }
        let total: usize = set
            .items
            .iter()
            .map(|i| (i.distance.1 - i.distance.0 + i.bend.1 - i.bend.0) as usize)
            .sum();
        assert_eq!(total, set.distance.len() + set.bend.len());
    }

    #[test]
    fn flat_stencils_have_zero_rest_curvature_and_curved_ones_do_not() {
        let flat = ClothMesh::grid(Vec3::ZERO, Vec3::X, Vec3::Z, 4, 4).unwrap();
        let topo = MeshTopology::new(&flat);
        let w = vec![1.0; flat.vertex_count()];
        let set = ConstraintSet::build(flat.positions(), &topo, &Fabric::cotton(), &w);
        assert!(set.bend.iter().all(|b| b.rest == [0.0; 3]));
        let tube = ClothMesh::cylinder(Vec3::ZERO, 0.2, 0.3, 16, 4).unwrap();
        let topo = MeshTopology::new(&tube);
        let w = vec![1.0; tube.vertex_count()];
        let set = ConstraintSet::build(tube.positions(), &topo, &Fabric::cotton(), &w);
        assert!(set.bend.iter().any(|b| b.rest != [0.0; 3]));
    }
}
