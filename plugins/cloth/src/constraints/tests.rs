//! Tests of the constraint set: items and batch lanes never share a particle, flat and
//! curved stencils, the stretch check.

use crate::fabric::Fabric;
use crate::mesh::MeshTopology;
use crate::order::ParticleOrder;
use crate::simd::{Isa, offset};
use glam::Vec3A;

use super::*;
use crate::mesh::ClothMesh;
use glam::Vec3;

fn build(mesh: &ClothMesh, w: &[f32]) -> (ConstraintSet, ParticleOrder) {
    let topo = MeshTopology::new(mesh);
    let free: Vec<bool> = w.iter().map(|&w| w > 0.0).collect();
    let order = ParticleOrder::new(mesh.positions(), &free);
    let set = ConstraintSet::build(mesh.positions(), &topo, &Fabric::cotton(), w, &order);
    (set, order)
}

/// The particles item `k`'s constraints touch, without its padding particle.
fn item_particles(set: &ConstraintSet, k: usize) -> Vec<u32> {
    let padding = set.items[k].padding;
    set.item_particles(k).filter(|&v| v != padding).collect()
}

#[test]
fn parallel_items_and_batch_lanes_never_share_a_particle() {
    let mesh = ClothMesh::cylinder(Vec3::ZERO, 0.3, 0.6, 48, 40).unwrap();
    let mut w = vec![1.0f32; mesh.vertex_count()];
    for v in ClothMesh::cylinder_ring(48, 40) {
        w[v as usize] = 0.0;
    }
    let (set, order) = build(&mesh, &w);
    assert!(order.blocks() >= 2);
    let n = mesh.vertex_count();
    // Lanes of a batch.
    for b in &set.distance {
        let mut v: Vec<u32> =
            b.i.into_iter()
                .chain(b.j)
                .map(|o| o / 16)
                .filter(|&v| v < n as u32)
                .collect();
        let len = v.len();
        v.sort_unstable();
        v.dedup();
        assert_eq!(v.len(), len, "a distance batch repeats a particle");
    }
    for b in &set.bend {
        let mut v: Vec<u32> =
            b.v.into_iter()
                .flatten()
                .map(|o| o / 16)
                .filter(|&v| v < n as u32)
                .collect();
        let len = v.len();
        v.sort_unstable();
        v.dedup();
        assert_eq!(v.len(), len, "a bending batch repeats a particle");
    }
    // Items of one phase: the blocks, then the seams, then the corners.
    let mut phases = vec![(0u32, order.blocks() as u32)];
    phases.extend(set.separator_levels.iter().copied());
    for (a, b) in phases {
        let mut owner = vec![u32::MAX; n];
        for k in a..b {
            for v in item_particles(&set, k as usize) {
                assert!(
                    owner[v as usize] == u32::MAX || owner[v as usize] == k,
                    "items {k} and {} share particle {v}",
                    owner[v as usize]
                );
                owner[v as usize] = k;
            }
        }
    }
    // Block items touch only their block's particles.
    for k in 0..order.blocks() {
        let range = order.block_start[k]..order.block_start[k + 1];
        for v in item_particles(&set, k) {
            assert!(range.contains(&v), "block {k} touches particle {v}");
        }
    }
    // Every constraint is in exactly one lane: a distance constraint standalone or as a
    // stencil's pair, with the stencil's own edge (pair 0) or its other diagonal (pair 1).
    let lanes = |v: &[u32]| v.iter().filter(|&&o| o / 16 < n as u32).count();
    let mut pairs = Vec::new();
    for b in &set.distance {
        for l in 0..LANES {
            if b.i[l] / 16 < n as u32 {
                pairs.push((b.i[l].min(b.j[l]), b.i[l].max(b.j[l])));
            }
        }
    }
    let standalone = pairs.len();
    for b in &set.bend {
        for (pair, (qa, qb)) in [(0, 1), (2, 3)].into_iter().enumerate() {
            for l in 0..LANES {
                if b.drest[pair][l] != NO_PAIR_REST {
                    let (i, j) = (b.v[qa][l], b.v[qb][l]);
                    assert!(b.drest[pair][l] > 0.0);
                    pairs.push((i.min(j), i.max(j)));
                }
            }
        }
    }
    assert_eq!(pairs.len(), set.distance_count);
    pairs.sort_unstable();
    pairs.dedup();
    assert_eq!(
        pairs.len(),
        set.distance_count,
        "a distance constraint is solved twice"
    );
    // Every lane's pairs are solved by its run's kernel.
    for run in &set.runs {
        let RunKind::Bend { pairs, .. } = run.kind else {
            continue;
        };
        for b in &set.bend[run.batches.0 as usize..run.batches.1 as usize] {
            for pair in 0..2 {
                if pair as u8 >= pairs {
                    assert!(
                        (0..LANES).all(|l| b.drest[pair][l] == NO_PAIR_REST),
                        "a lane's pair {pair} is in a run solving {pairs} pairs"
                    );
                }
            }
        }
    }
    // Nearly all of them ride with a stencil.
    assert!(
        standalone * 10 < set.distance_count,
        "{standalone} standalone"
    );
    let bend: usize = set.bend.iter().map(|b| lanes(&b.v[0])).sum();
    assert_eq!(bend, set.bend_count);
    // The stretch check sees every distance constraint once.
    let mut checked: Vec<(u32, u32)> = set
        .check
        .iter()
        .flat_map(|b| (0..LANES).map(move |l| (b.i[l], b.j[l], b.rest[l])))
        .filter(|&(_, _, rest)| rest.is_finite())
        .map(|(i, j, _)| (i.min(j), i.max(j)))
        .collect();
    checked.sort_unstable();
    assert_eq!(checked, pairs);
    // Batches are nearly full.
    assert!(set.bend.len() * LANES < set.bend_count * 11 / 10);
}

#[test]
fn flat_stencils_have_zero_rest_curvature_and_curved_ones_do_not() {
    let flat = ClothMesh::grid(Vec3::ZERO, Vec3::X, Vec3::Z, 4, 4).unwrap();
    let (set, _) = build(&flat, &vec![1.0; flat.vertex_count()]);
    assert!(set.bend_count > 0);
    let is_curved = |kind: RunKind| matches!(kind, RunKind::Bend { curved: true, .. });
    assert!(set.runs.iter().all(|r| !is_curved(r.kind)));
    let tube = ClothMesh::cylinder(Vec3::ZERO, 0.2, 0.3, 16, 4).unwrap();
    let (set, _) = build(&tube, &vec![1.0; tube.vertex_count()]);
    assert!(set.runs.iter().any(|r| is_curved(r.kind)));
    for run in set.runs.iter().filter(|r| r.kind != RunKind::Distance) {
        for side in &set.bend_side[run.batches.0 as usize..run.batches.1 as usize] {
            let curved = side.rest.iter().flatten().any(|&r| r != 0.0);
            assert_eq!(curved, is_curved(run.kind));
        }
    }
}

/// The stretch check on both instruction sets against a plain loop over the pairs: the
/// same largest ratio and lane, and the first NaN.
#[test]
fn stretch_check_finds_the_largest_ratio_and_the_first_nan() {
    let n = 200u32;
    let mut seed = 12345u32;
    let mut next = || {
        seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
        (seed >> 8) as f32 / (1u32 << 24) as f32
    };
    let mut x: Vec<Vec3A> = (0..n).map(|_| Vec3A::new(next(), next(), next())).collect();
    let batches: Vec<CheckBatch> = (0..37)
        .map(|_| {
            let mut pick = || ((next() * n as f32) as u32).min(n - 1);
            let (i, j): (Vec<u32>, Vec<u32>) = (0..LANES).map(|_| (pick(), pick())).unzip();
            CheckBatch {
                i: std::array::from_fn(|l| offset(i[l])),
                j: std::array::from_fn(|l| offset(j[l])),
                rest: std::array::from_fn(|_| 0.05 + next()),
            }
        })
        .collect();
    let plain = |x: &[Vec3A], first: usize| {
        let mut worst = (0.0f32, u32::MAX);
        for (k, c) in batches.iter().enumerate() {
            for l in 0..LANES {
                let (i, j) = (c.i[l] as usize / 16, c.j[l] as usize / 16);
                let ratio2 = (x[i] - x[j]).length_squared() / (c.rest[l] * c.rest[l]);
                let lane = ((first + k) * LANES + l) as u32;
                if ratio2.is_nan() {
                    return (f32::NAN, lane);
                }
                if ratio2 > worst.0 {
                    worst = (ratio2, lane);
                }
            }
        }
        worst
    };
    let mut isas = vec![Isa::Baseline];
    if Isa::detect() != Isa::Baseline {
        isas.push(Isa::detect());
    }
    for nan in [false, true] {
        if nan {
            let c = &batches[20];
            x[c.j[5] as usize / 16].y = f32::NAN;
        }
        let expected = plain(&x, 3);
        assert_eq!(expected.0.is_nan(), nan);
        for &isa in &isas {
            // SAFETY: every index is a particle of `x`, which nothing writes.
            let got = unsafe { max_stretch_squared(isa, &batches, 3, x.as_ptr()) };
            assert_eq!(got.1, expected.1, "{isa:?}, NaN {nan}");
            assert!(
                got.0.to_bits() == expected.0.to_bits() || (nan && got.0.is_nan()),
                "{isa:?}: {} against {}",
                got.0,
                expected.0
            );
        }
    }
}
