//! The part of a garment the cloth solver steps ([`simulated_part`]: its free vertices and the
//! attached ones that share a constraint with them; the rest of the static part, skinned as
//! in seed 000 §3.2.1, is not stepped), and each vertex's share of the step's work for the
//! solver's split between its threads.

use glam::Vec3;

use fitroom_body::colliders::BodyColliders;

/// [`GarmentSim`]'s mark of a garment vertex the solver does not step.
pub(super) const NOT_SIMULATED: u32 = u32::MAX;

/// The part of a garment (`vertex_count` vertices, `triangles`, `attached` ones following the
/// body) that the solver steps: its vertices (increasing) and its triangles in their numbering.
///
/// That is every triangle with a free vertex, and every triangle that shares an edge with one
/// (so that each bending stencil, which spans the two triangles of an edge, and each distance
/// constraint with a free particle is whole), with their vertices and any free vertex in no
/// triangle. The attached vertices left out (the inside of a skinned bodice) share no
/// constraint with a free particle, and tethers run to the nearest attached vertices along the
/// mesh, which border the free ones: leaving them out changes no constraint and no tether of
/// the free cloth. A garment without free vertices keeps them all.
pub fn simulated_part(
    vertex_count: usize,
    triangles: &[[u32; 3]],
    attached: &[u32],
) -> (Vec<u32>, Vec<[u32; 3]>) {
    let mut is_attached = vec![false; vertex_count];
    for &v in attached {
        if let Some(a) = is_attached.get_mut(v as usize) {
            *a = true;
        }
    }
    let free = |v: u32| !is_attached.get(v as usize).copied().unwrap_or(true);
    if !(0..vertex_count as u32).any(free) {
        return ((0..vertex_count as u32).collect(), triangles.to_vec());
    }
    let edge = |t: &[u32; 3], k: usize| {
        let (a, b) = (t[k], t[(k + 1) % 3]);
        (a.min(b), a.max(b))
    };
    let with_free = |t: &[u32; 3]| t.iter().any(|&v| free(v));
    let free_edges: std::collections::HashSet<(u32, u32)> = triangles
        .iter()
        .filter(|t| with_free(t))
        .flat_map(|t| (0..3).map(move |k| edge(t, k)))
        .collect();
    let kept: Vec<&[u32; 3]> = triangles
        .iter()
        .filter(|t| with_free(t) || (0..3).any(|k| free_edges.contains(&edge(t, k))))
        .collect();
    let mut keep: Vec<bool> = (0..vertex_count as u32).map(free).collect();
    for t in &kept {
        for &v in t.iter() {
            if let Some(k) = keep.get_mut(v as usize) {
                *k = true;
            }
        }
    }
    let vertices: Vec<u32> = (0..vertex_count as u32)
        .filter(|&v| keep[v as usize])
        .collect();
    let mut number = vec![NOT_SIMULATED; vertex_count];
    for (i, &v) in vertices.iter().enumerate() {
        number[v as usize] = i as u32;
    }
    let triangles = kept
        .into_iter()
        .map(|t| t.map(|v| number[v as usize]))
        .collect();
    (vertices, triangles)
}

/// Free vertices nearer than this to a collider in the rest pose are "near" for [`work_hints`].
const NEAR_BODY_M: f32 = 0.03;
/// The extra work of a near vertex, in units of a free vertex's.
const NEAR_EXTRA_WORK: f32 = 0.8;
/// The work of an attached vertex (it follows its target in every substep), in units of a
/// free vertex's.
const ATTACHED_WORK: f32 = 0.1;

/// Each vertex's share of a step's work, for the solver's split of the garment between its
/// threads ([`ClothSolver::new_balanced`]): [`ATTACHED_WORK`] for an attached vertex, 1 for a
/// free one, and more for a free one lying against the body at rest, which will be tested
/// against colliders and pushed out in most substeps. The weights are fitted to the
/// 4,000-particle dress's measured work per thread (session 13, one thread: a free vertex
/// ~0.23 µs a step, 0.13 for its constraints and 0.10 for its own work; a near one ~0.20
/// more; an attached one ~0.02).
pub(super) fn work_hints(
    positions: &[Vec3],
    attached: &[u32],
    colliders: &BodyColliders,
) -> Vec<f32> {
    let mut work: Vec<f32> = positions
        .iter()
        .map(|&p| {
            if colliders.signed_distance(p) < NEAR_BODY_M {
                1.0 + NEAR_EXTRA_WORK
            } else {
                1.0
            }
        })
        .collect();
    for &v in attached {
        if let Some(w) = work.get_mut(v as usize) {
            *w = ATTACHED_WORK;
        }
    }
    work
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A strip of 2 × 8 vertices attached at its first four columns: the solver steps the
    /// free columns, the attached column next to them and the one vertex of the column before
    /// that a triangle sharing an edge with a free triangle brings in.
    #[test]
    fn the_simulated_part_is_the_free_cloth_and_the_triangles_around_it() {
        let mut triangles = Vec::new();
        for i in 0..7u32 {
            let (a, b, c, d) = (i, i + 1, i + 8, i + 9);
            triangles.push([a, b, d]);
            triangles.push([a, d, c]);
        }
        let attached: Vec<u32> = (0..4).chain(8..12).collect();
        let (vertices, part) = simulated_part(16, &triangles, &attached);
        // [3, 4, 12] and [3, 12, 11] hold free vertices; [2, 3, 11] shares their edge 3-11
        // (the bending stencil across it reaches the free vertex 12), so vertex 2 comes in;
        // [2, 11, 10] shares no edge with a free triangle, so vertex 10 stays out.
        let expected: Vec<u32> = (2..8).chain(11..16).collect();
        assert_eq!(vertices, expected);
        assert_eq!(
            part.len(),
            2 * 4 + 1,
            "four free quads and one triangle around them"
        );
        for t in &part {
            for &v in t {
                assert!((v as usize) < vertices.len());
            }
        }
        // Nothing free: everything is kept.
        let all: Vec<u32> = (0..16).collect();
        let (vertices, part) = simulated_part(16, &triangles, &all);
        assert_eq!(vertices, all);
        assert_eq!(part, triangles);
    }
}
