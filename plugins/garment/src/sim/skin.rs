//! The garment's skin weights: every vertex takes those of its nearest body vertex, smoothed
//! over the garment's mesh, so that the garment can be skinned like the body (seed 000
//! §3.2.1: the static part of a garment is skinned), and the blend of two bone transforms a
//! reset sweeps through.

use glam::{Affine3A, Vec3};

use fitroom_body::MeshGraph;

/// Blends two bone transforms by `t`: scale and translation linearly, rotation by slerp.
pub(crate) fn lerp_affine(a: &Affine3A, b: &Affine3A, t: f32) -> Affine3A {
    let (sa, ra, ta) = a.to_scale_rotation_translation();
    let (sb, rb, tb) = b.to_scale_rotation_translation();
    Affine3A::from_scale_rotation_translation(sa.lerp(sb, t), ra.slerp(rb, t), ta.lerp(tb, t))
}

/// Smoothing passes of the garment's skin weights over its mesh.
pub(super) const SKIN_SMOOTHING: usize = 12;

/// Skin weights averaged with the mesh neighbours' `passes` times (Jacobi), then cut to the
/// four largest and renormalised.
pub(super) fn smooth_skin(
    skin: Vec<([u16; 4], [f32; 4])>,
    graph: &MeshGraph,
    bones: usize,
    passes: usize,
) -> Vec<([u16; 4], [f32; 4])> {
    let n = skin.len();
    let mut dense = vec![0.0f32; n * bones];
    for (v, (j, w)) in skin.iter().enumerate() {
        for k in 0..4 {
            if let Some(slot) = dense.get_mut(v * bones + j[k] as usize) {
                *slot += w[k];
            }
        }
    }
    let mut next = dense.clone();
    for _ in 0..passes {
        for v in 0..n {
            let neighbours = graph.neighbours(v);
            let count = (neighbours.len() + 1) as f32;
            for b in 0..bones {
                let mut sum = dense[v * bones + b];
                for &u in neighbours {
                    sum += dense[u as usize * bones + b];
                }
                next[v * bones + b] = sum / count;
            }
        }
        std::mem::swap(&mut dense, &mut next);
    }
    (0..n)
        .map(|v| {
            let row = &dense[v * bones..(v + 1) * bones];
            let mut idx: Vec<usize> = (0..bones).collect();
            idx.sort_by(|&a, &b| row[b].total_cmp(&row[a]));
            let mut j = [0u16; 4];
            let mut w = [0.0f32; 4];
            for k in 0..4.min(bones) {
                j[k] = idx[k] as u16;
                w[k] = row[idx[k]];
            }
            let total: f32 = w.iter().sum();
            if total > 0.0 {
                for x in &mut w {
                    *x /= total;
                }
            }
            (j, w)
        })
        .collect()
}

/// Index of the nearest point of `points` for each of `queries` (exact, through a grid of
/// 3 cm cells; 0 for a query that is not finite or when there are no points).
pub(super) fn nearest(points: &[Vec3], queries: &[Vec3]) -> Vec<usize> {
    let grid = fitroom_math::CellGrid::of_points(points, 0.03);
    queries
        .iter()
        .map(|&q| {
            grid.nearest(q, |i| Some(points[i as usize].distance_squared(q)))
                .map_or(0, |(i, _)| i as usize)
        })
        .collect()
}
