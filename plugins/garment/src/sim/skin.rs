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

/// Index of the nearest point of `points` for each of `queries` (a uniform grid of 3 cm cells;
/// falls back to a full search where the neighbourhood is empty).
pub(super) fn nearest(points: &[Vec3], queries: &[Vec3]) -> Vec<usize> {
    use std::collections::HashMap;
    let cell = 0.03f32;
    let key = |p: Vec3| {
        (
            (p.x / cell).floor() as i32,
            (p.y / cell).floor() as i32,
            (p.z / cell).floor() as i32,
        )
    };
    let mut grid: HashMap<(i32, i32, i32), Vec<usize>> = HashMap::new();
    for (i, &p) in points.iter().enumerate() {
        grid.entry(key(p)).or_default().push(i);
    }
    queries
        .iter()
        .map(|&q| {
            let (x, y, z) = key(q);
            let mut best: Option<(f32, usize)> = None;
            for r in 1..=4 {
                for dx in -r..=r {
                    for dy in -r..=r {
                        for dz in -r..=r {
                            if let Some(list) = grid.get(&(x + dx, y + dy, z + dz)) {
                                for &i in list {
                                    let d = points[i].distance_squared(q);
                                    if best.is_none_or(|b| d < b.0) {
                                        best = Some((d, i));
                                    }
                                }
                            }
                        }
                    }
                }
                // Anything found within r cells is exact once r cells cover its distance.
                if let Some((d, _)) = best
                    && d.sqrt() <= (r as f32 - 1.0) * cell
                {
                    break;
                }
            }
            best.map(|b| b.1).unwrap_or_else(|| {
                points
                    .iter()
                    .enumerate()
                    .min_by(|a, b| a.1.distance_squared(q).total_cmp(&b.1.distance_squared(q)))
                    .map_or(0, |(i, _)| i)
            })
        })
        .collect()
}
