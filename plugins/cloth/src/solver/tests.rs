//! Tests of the solver's internals: the eight-particle paths against the one-particle
//! ones, the baseline kernels against the AVX ones, results independent of the threads.

use super::contact::*;
use super::integrate::*;
use super::model::*;
use super::step::*;
use super::sweep::*;
use super::tethers::*;
use crate::collision::Shape;
use crate::frame::{FrameInertia, FrameMotion};
use crate::simd::{Lanes, V3};
use std::sync::atomic::AtomicUsize;

#[test]
fn eight_flags_mark_runs_of_free_attached_and_two_tether_particles() {
    // 20 particles: 0..4 attached, 4..20 free; free ones have two tethers but 15 (one).
    let inverse_mass: Vec<f32> = (0..20).map(|i| if i < 4 { 0.0 } else { 2.0 }).collect();
    let mut tether_start = vec![0u32];
    for i in 0..20u32 {
        let count = match i {
            0..4 => 0,
            15 => 1,
            _ => 2,
        };
        tether_start.push(tether_start[i as usize] + count);
    }
    let flags = eight_flags(&inverse_mass, &tether_start);
    assert_eq!(flags.len(), 20);
    // Independently: each window checked particle by particle.
    for (i, &f) in flags.iter().enumerate() {
        let window: Vec<usize> = (i..i + 8).filter(|&j| j < 20).collect();
        let full = window.len() == 8;
        let free = full && window.iter().all(|&j| j >= 4);
        let attached = full && window.iter().all(|&j| j < 4);
        let two = full && window.iter().all(|&j| j >= 4 && j != 15);
        assert_eq!(f & EIGHT_FREE != 0, free, "free at {i}");
        assert_eq!(f & EIGHT_ATTACHED != 0, attached, "attached at {i}");
        assert_eq!(f & EIGHT_TWO_TETHERS != 0, two, "two tethers at {i}");
    }
    assert_eq!(flags[4], EIGHT_FREE | EIGHT_TWO_TETHERS);
    assert_eq!(flags[8], EIGHT_FREE);
    assert_eq!(flags[12], EIGHT_FREE);
    assert_eq!(flags[13], 0);
}

#[test]
fn clear_two_finds_the_smallest_move_out_of_two_half_spaces() {
    // Independent check: the smallest move out of two half-spaces, by brute force over a
    // grid of moves in their plane.
    let cases = [
        (-0.01, Vec3A::X, -0.004, Vec3A::Y),
        (-0.01, Vec3A::X, -0.004, Vec3A::new(0.6, 0.8, 0.0)),
        (
            -0.003,
            Vec3A::new(0.0, 1.0, 0.0),
            -0.01,
            Vec3A::new(-0.5, 0.866, 0.0),
        ),
        (-0.01, Vec3A::X, -0.002, Vec3A::new(0.999, 0.0447, 0.0)),
    ];
    for (sa, na, sb, nb) in cases {
        let na = na.normalize();
        let nb = nb.normalize();
        let d = clear_two((sa, na), (sb, nb));
        assert!(na.dot(d) >= -sa - 1e-6 && nb.dot(d) >= -sb - 1e-6, "{d}");
        let mut best = f32::INFINITY;
        let n = 400;
        for i in -n..=n {
            for j in -n..=n {
                let m = Vec3A::new(i as f32, j as f32, 0.0) * (0.05 / n as f32);
                if na.dot(m) >= -sa && nb.dot(m) >= -sb {
                    best = best.min(m.length());
                }
            }
        }
        assert!(d.length() <= best + 2e-4, "{} vs {best}", d.length());
    }
    // Opposite normals (pinched): only the deeper push, never a far escape.
    let d = clear_two(
        (-0.01, Vec3A::X),
        (-0.005, -Vec3A::X.lerp(Vec3A::Y, 0.05).normalize()),
    );
    assert!(d.length() <= 0.0101, "{d}");
}

use super::*;
use crate::simd::Baseline8;

fn random(seed: &mut u32) -> f32 {
    *seed = seed.wrapping_mul(1664525).wrapping_add(1013904223);
    (*seed >> 8) as f32 / (1u32 << 24) as f32
}

#[test]
fn eight_colliders_boxes_meet_a_chunk_as_each_one_alone_does() {
    // Random spheres' swept boxes, five in a group of eight (three empty lanes), against
    // random chunk boxes, some of them NaN: the lanes set are those whose collider's own
    // test says it meets the chunk, on both instruction sets.
    let mut seed = 4242u32;
    let mut r = |scale: f32| (random(&mut seed) - 0.5) * scale;
    let (mut met, mut missed) = (0, 0);
    for round in 0..500 {
        let colliders: Vec<SweptCollider> = (0..5)
            .map(|_| {
                let a = Vec3A::new(r(1.0), r(1.0), r(1.0));
                let b = a + Vec3A::new(r(0.1), r(0.1), r(0.1));
                let radius = 0.02 + r(0.1).abs();
                SweptCollider::new(Shape::sphere(a, radius), Shape::sphere(b, radius), 0.003)
            })
            .collect();
        let mut bounds = ColliderBounds::EMPTY;
        for (l, c) in colliders.iter().enumerate() {
            bounds.set(l, c);
        }
        let low = Vec3A::new(r(1.0), r(1.0), r(1.0)) - Vec3A::splat(0.25);
        let mut high = low + Vec3A::new(r(1.0), r(1.0), r(1.0)) + Vec3A::splat(0.5);
        if round % 50 == 0 {
            high.y = f32::NAN;
        }
        let want = colliders
            .iter()
            .enumerate()
            .filter(|(_, c)| c.overlaps(low, high))
            .fold(0u32, |bits, (l, _)| bits | 1 << l);
        met += want.count_ones();
        missed += 5 - want.count_ones();
        for isa in [Isa::Baseline, Isa::detect()] {
            // SAFETY: the detected instruction set.
            let got = unsafe { overlaps8(isa, &bounds, low, high) };
            assert_eq!(got, want, "round {round} {isa:?}");
        }
    }
    assert!(met > 100 && missed > 100, "{met} met, {missed} missed");
}

#[test]
fn eight_particles_collide_as_each_one_alone_does() {
    // Spheres and round cones, moving and turning over the substep, and particles placed
    // around and inside them: the eight-particle pass (both instruction sets) must give
    // the one-particle pass's result bit for bit, lane by lane.
    let mut seed = 777u32;
    let mut r = |scale: f32| (random(&mut seed) - 0.5) * scale;
    let (mut hit_lanes, mut missed_lanes, mut second_lanes) = (0, 0, 0);
    for round in 0..200 {
        let mut swept = Vec::new();
        for c in 0..4 {
            let a = Vec3A::new(r(0.4), r(0.4), r(0.4));
            let shape = |a: Vec3A, b: Vec3A, ra: f32, rb: f32| {
                if c % 2 == 0 {
                    Shape::sphere(a, ra)
                } else {
                    Shape::round_cone(a, b, ra, rb)
                }
            };
            let (b, ra, rb) = (
                a + Vec3A::new(r(0.5), r(0.5), r(0.5)),
                0.05 + r(0.06),
                0.05 + r(0.06),
            );
            // Half the rounds with still colliders.
            let motion = if round % 2 == 0 { 0.05 } else { 0.0 };
            let shift = Vec3A::new(r(motion), r(motion), r(motion));
            let turn = Vec3A::new(r(motion), r(motion), r(motion));
            swept.push(SweptCollider::new(
                shape(a, b, ra, rb),
                shape(a + shift, b + shift + turn, ra, rb),
                0.003,
            ));
        }
        // Each particle near one collider's first sphere; lanes 4 and 5 within a few
        // millimetres of its skin, lanes 6 and 7 on it (cloth resting on the body) and
        // moving 50 µm inwards: resting contacts, decided by the contact tolerance.
        let mut inwards = [Vec3A::ZERO; LANES];
        let start: [Vec3A; LANES] = std::array::from_fn(|l| {
            let c = &swept[l % swept.len()];
            let p = c.start_origin + Vec3A::new(r(0.25), r(0.25), r(0.25));
            if l < 4 {
                return p;
            }
            let (d, n) = c.end.distance_normal(p - c.end.origin);
            let off = if l < 6 { r(0.004) } else { 0.0 };
            inwards[l] = -5e-5 * n;
            p - (d - 0.003 + off) * n
        });
        // Lanes 0 to 5: half move a few centimetres, half a fraction of a millimetre.
        let now: [Vec3A; LANES] = std::array::from_fn(|l| {
            if l >= 6 {
                return start[l] + inwards[l];
            }
            let reach = if l % 2 == 0 { 0.06 } else { 0.0005 };
            start[l] + Vec3A::new(r(reach), r(reach), r(reach))
        });
        let near: Vec<u16> = (0..swept.len() as u16).rev().collect();
        for near in [None, Some(&near[..])] {
            let scene = Scene {
                colliders: &swept,
                near,
                planes: None,
                any_plane: false,
                shapes: swept.len(),
            };
            let order: Vec<usize> = match near {
                None => (0..swept.len()).collect(),
                Some(n) => n.iter().map(|&c| c as usize).collect(),
            };
            let mut expected = now;
            let mut expected_moved = 0u32;
            let mut expected_last = [0u16; LANES];
            for l in 0..LANES {
                let (low, high) = (start[l].min(now[l]), start[l].max(now[l]));
                for (place, &c) in order.iter().enumerate() {
                    if swept[c].overlaps(low, high) {
                        let (q, hit) = swept[c].collide(start[l], expected[l], 0.003, 0.4);
                        if hit {
                            expected[l] = q;
                            expected_moved |= 1 << l;
                            expected_last[l] = place as u16;
                        }
                    }
                }
            }
            // The second pass as the one-particle path makes it (see `collide_particle`):
            // over the colliders before the last mover if the particle stayed within its
            // first path's box, else over all of them; and once one of them has moved it,
            // over all the rest too.
            let mut expected_second = expected;
            let mut expected_again = 0u32;
            for l in (0..LANES).filter(|&l| expected_moved & (1 << l) != 0) {
                let (low, high) = (start[l].min(now[l]), start[l].max(now[l]));
                let in_box = expected[l].cmpge(low).all() && expected[l].cmple(high).all();
                let limit = if in_box {
                    expected_last[l] as usize
                } else {
                    usize::MAX
                };
                let (low, high) = (start[l].min(expected[l]), start[l].max(expected[l]));
                for (place, &c) in order.iter().enumerate() {
                    if place >= limit && expected_again & (1 << l) == 0 {
                        break;
                    }
                    if swept[c].overlaps(low, high) {
                        let (q, hit) = swept[c].collide(start[l], expected_second[l], 0.003, 0.4);
                        if hit {
                            expected_second[l] = q;
                            expected_again |= 1 << l;
                        }
                    }
                }
            }
            for isa in [Isa::Baseline, Isa::detect()] {
                for second in [false, true] {
                    let mut pass = GroupPass {
                        p: [Vec3A::ZERO; LANES],
                        last: [0; LANES],
                    };
                    // SAFETY: eight positions each.
                    let moved = unsafe {
                        collide8(
                            isa,
                            start.as_ptr(),
                            now.as_ptr(),
                            &scene,
                            (0.003, 0.4),
                            (second, true),
                            &mut pass,
                        )
                    };
                    let (want, again) = if second {
                        (expected_second, expected_again)
                    } else {
                        (expected, 0)
                    };
                    assert_eq!(
                        moved,
                        Some((expected_moved, again)),
                        "round {round} {isa:?}"
                    );
                    for l in (0..LANES).filter(|&l| expected_moved & (1 << l) != 0) {
                        assert_eq!(pass.last[l], expected_last[l], "round {round} lane {l}");
                    }
                    hit_lanes += expected_moved.count_ones();
                    missed_lanes += LANES as u32 - expected_moved.count_ones();
                    second_lanes += again.count_ones();
                    for (l, (got, want)) in pass.p.iter().zip(&want).enumerate() {
                        assert_eq!(
                            got.to_array(),
                            want.to_array(),
                            "round {round} lane {l} second {second}"
                        );
                    }
                }
            }
        }
    }
    // Both outcomes were exercised.
    assert!(
        hit_lanes > 500 && missed_lanes > 500 && second_lanes > 0,
        "{hit_lanes} hit, {missed_lanes} not, {second_lanes} in the second pass"
    );
}

#[test]
fn eight_particles_with_a_nan_are_left_to_the_one_particle_path() {
    let swept = [SweptCollider::new(
        Shape::sphere(Vec3A::ZERO, 0.1),
        Shape::sphere(Vec3A::ZERO, 0.1),
        0.003,
    )];
    let scene = Scene {
        colliders: &swept,
        near: None,
        planes: None,
        any_plane: false,
        shapes: 1,
    };
    let mut now = [Vec3A::splat(0.05); LANES];
    now[5].y = f32::NAN;
    let mut pass = GroupPass {
        p: [Vec3A::ZERO; LANES],
        last: [0; LANES],
    };
    for isa in [Isa::Baseline, Isa::detect()] {
        // SAFETY: eight positions each.
        let moved = unsafe {
            collide8(
                isa,
                now.as_ptr(),
                now.as_ptr(),
                &scene,
                (0.003, 0.0),
                (true, true),
                &mut pass,
            )
        };
        assert_eq!(moved, None);
    }
}

/// The nearest point of the intersection of two balls to `p`, by brute force: the best of
/// `p` (if inside), its projections onto each sphere (if inside the other) and points of
/// the circle where the spheres meet.
fn brute_force(p: Vec3A, a0: Vec3A, r0: f32, a1: Vec3A, r1: f32) -> Vec3A {
    let inside = |q: Vec3A| (q - a0).length() <= r0 + 1e-5 && (q - a1).length() <= r1 + 1e-5;
    let mut candidates = vec![
        p,
        a0 + (p - a0).normalize() * r0,
        a1 + (p - a1).normalize() * r1,
    ];
    let axis = (a1 - a0).normalize();
    let d = (a1 - a0).length();
    let along = (d * d + r0 * r0 - r1 * r1) / (2.0 * d);
    if r0 * r0 >= along * along {
        let radius = (r0 * r0 - along * along).sqrt();
        let u = Vec3A::from(Vec3::from(axis).any_orthonormal_vector());
        let v = axis.cross(u);
        for k in 0..20_000 {
            let angle = k as f32 / 20_000.0 * std::f32::consts::TAU;
            candidates.push(a0 + along * axis + radius * (angle.cos() * u + angle.sin() * v));
        }
    }
    candidates
        .into_iter()
        .filter(|&q| inside(q))
        .min_by(|a, b| (*a - p).length().total_cmp(&(*b - p).length()))
        .expect("the balls intersect")
}

/// A point, two balls, and the projection of the point onto their intersection.
type Case = (Vec3A, Vec3A, f32, Vec3A, f32, Vec3A);

#[test]
fn two_tethers_project_onto_the_nearest_point_of_both_balls() {
    let mut seed = 7u32;
    let mut r = || random(&mut seed);
    let mut points = Vec::new();
    for _ in 0..64 {
        let a0 = Vec3A::new(r(), r(), r()) * 0.2;
        let a1 = a0 + Vec3A::new(r() - 0.5, r() - 0.5, r() - 0.5) * 0.1;
        let (r0, r1) = (0.3 + 0.3 * r(), 0.3 + 0.3 * r());
        let p = a0 + Vec3A::new(r() - 0.5, r() - 0.7, r() - 0.5) * 1.6;
        let q = project_on_two_balls(p, a0, r0, a1, r1).expect("intersecting balls");
        let expected = brute_force(p, a0, r0, a1, r1);
        assert!(
            (q - p).length() <= (expected - p).length() + 2e-4,
            "{p}: {q} vs {expected}"
        );
        assert!((q - a0).length() <= r0 * (1.0 + 1e-5) && (q - a1).length() <= r1 * (1.0 + 1e-5));
        points.push((p, a0, r0, a1, r1, q));
    }
    // Eight at a time, in lanes, give the same points.
    for group in points.chunks(LANES) {
        let lanes = |f: &dyn Fn(&Case) -> Vec3A| V3 {
            x: Baseline8::load(&std::array::from_fn(|l| f(&group[l]).x)),
            y: Baseline8::load(&std::array::from_fn(|l| f(&group[l]).y)),
            z: Baseline8::load(&std::array::from_fn(|l| f(&group[l]).z)),
        };
        let scalars =
            |f: &dyn Fn(&Case) -> f32| Baseline8::load(&std::array::from_fn(|l| f(&group[l])));
        let (q, fallback, _) = project_on_two_balls_lanes(
            lanes(&|g| g.0),
            lanes(&|g| g.1),
            scalars(&|g| g.2),
            lanes(&|g| g.3),
            scalars(&|g| g.4),
        );
        assert_eq!(fallback, 0);
        let [x, y, z] = q.to_arrays();
        for (l, g) in group.iter().enumerate() {
            let q = Vec3A::new(x[l], y[l], z[l]);
            assert!((q - g.5).length() < 1e-5, "lane {l}: {q} vs {}", g.5);
        }
    }
}

/// A 40 × 30 cylinder from `base` (radius, height), pinned at its top ring, on 2 threads.
fn skirt_on_two_threads(base: Vec3, radius: f32, height: f32) -> ClothSolver {
    let mesh = ClothMesh::cylinder(base, radius, height, 40, 30).expect("a valid skirt");
    let top: Vec<u32> = ClothMesh::cylinder_ring(40, 30).collect();
    let settings = SolverSettings {
        threads: 2,
        ..SolverSettings::default()
    };
    ClothSolver::new(&mesh, Fabric::cotton(), &top, settings).expect("a valid cloth")
}

/// `share_out` runs every item exactly once, on the workers too when they are awake, and
/// a call from inside an item (the workers are busy with it) runs its items on that
/// thread alone instead of waiting for itself.
#[test]
fn share_out_runs_each_item_once_and_a_nested_call_alone() {
    let mut cloth = skirt_on_two_threads(Vec3::ZERO, 0.3, 0.5);
    let mut on_two = false;
    // Until the worker takes part: a sleeping one is not used, nor any while the steps
    // run on one thread after a stall (a busy machine); steps end that.
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(30);
    'tries: while std::time::Instant::now() < deadline {
        cloth.step(1.0 / 120.0).expect("a valid step");
        for _ in 0..20 {
            cloth.prewake();
            let runs: Vec<AtomicUsize> = (0..64).map(|_| AtomicUsize::new(0)).collect();
            let (nested_threads, nested_items) = (AtomicUsize::new(0), AtomicUsize::new(0));
            let used = cloth.share_out(runs.len(), &|k| {
                runs[k].fetch_add(1, Ordering::Relaxed);
                let inner = cloth.share_out(3, &|_| {
                    nested_items.fetch_add(1, Ordering::Relaxed);
                });
                nested_threads.fetch_max(inner, Ordering::Relaxed);
            });
            assert!(runs.iter().all(|r| r.load(Ordering::Relaxed) == 1));
            assert_eq!(nested_items.load(Ordering::Relaxed), 3 * runs.len());
            if used == 2 {
                // The workers were busy with the outer call, so no inner one used them.
                assert_eq!(nested_threads.load(Ordering::Relaxed), 1);
                on_two = true;
                break 'tries;
            }
            // The outer call ran alone (the worker was still waking up); an inner call
            // may then have found it awake and used it: the items still ran once each.
            assert_eq!(used, 1);
        }
    }
    assert!(on_two, "the worker never took part");
}

#[test]
fn work_hints_are_checked_and_keep_results_independent_of_threads() {
    let mesh = ClothMesh::cylinder(Vec3::ZERO, 0.3, 0.5, 40, 30).expect("a valid skirt");
    let top: Vec<u32> = ClothMesh::cylinder_ring(40, 30).collect();
    let n = mesh.vertex_count();
    let build = |work: &[f32], threads: usize| {
        let settings = SolverSettings {
            threads,
            ..SolverSettings::default()
        };
        ClothSolver::new_balanced(&mesh, Fabric::cotton(), &top, settings, work)
    };
    let err = |work: &[f32]| build(work, 1).err().map(|e| e.to_string());
    assert_eq!(
        err(&vec![1.0; n - 1]),
        Some(format!(
            "expected {n} work hints (one per vertex), got {}",
            n - 1
        ))
    );
    let mut work = vec![1.0; n];
    work[7] = f32::NAN;
    assert!(err(&work).is_some_and(|e| e.contains("work hint of vertex 7")));
    work[7] = -1.0;
    assert!(err(&work).is_some_and(|e| e.contains("0 or more")));
    // The particles on one side (x < 0) three times the work: a different split of the
    // blocks, the same bits on one thread and two.
    let work: Vec<f32> = mesh
        .positions()
        .iter()
        .map(|p| if p.x < 0.0 { 3.0 } else { 1.0 })
        .collect();
    let run = |threads: usize| {
        let mut cloth = build(&work, threads).expect("a valid cloth");
        let ball = [Sphere::new(Vec3::new(0.05, 0.2, 0.0), 0.31)];
        cloth.set_colliders(&ball, &[]).expect("a valid collider");
        for _ in 0..30 {
            cloth.step(1.0 / 120.0).expect("a valid step");
        }
        position_bits(&cloth)
    };
    assert_eq!(run(1), run(2));
    let plain = ClothSolver::new(&mesh, Fabric::cotton(), &top, SolverSettings::default())
        .expect("a valid cloth");
    let hinted = build(&work, 2).expect("a valid cloth");
    assert_ne!(
        plain.model.order.block_start, hinted.model.order.block_start,
        "the hint did not move the split"
    );
}

/// The cloth's positions as bits, for comparisons that must be exact.
fn position_bits(cloth: &ClothSolver) -> Vec<[u32; 3]> {
    cloth
        .positions()
        .iter()
        .map(|p| p.to_array().map(f32::to_bits))
        .collect()
}

#[test]
fn the_baseline_and_avx_kernels_give_the_same_bits() {
    if Isa::detect() != Isa::Avx {
        return;
    }
    let run = |isa: Isa| {
        let mut cloth = skirt_on_two_threads(Vec3::new(0.0, 0.4, 0.0), 0.25, 0.6);
        cloth.isa = isa;
        cloth.set_wind(Some(Wind::new(Vec3::new(1.0, 0.0, 0.5), 1.0, 0.3, 3)));
        let legs = |t: f32| {
            [
                Sphere::new(Vec3::new(-0.1, 0.95, 0.0), 0.12),
                Sphere::new(Vec3::new(-0.1, 0.5, 0.3 * t.sin()), 0.07),
                Sphere::new(Vec3::new(0.0, 1.0, 0.05), 0.15),
            ]
        };
        for step in 0..40 {
            cloth
                .set_colliders(&legs(step as f32 * 0.1), &[[0, 1]])
                .expect("valid colliders");
            cloth.step(1.0 / 120.0).expect("a valid step");
        }
        position_bits(&cloth)
    };
    assert_eq!(run(Isa::Baseline), run(Isa::Avx));
}

#[test]
fn new_settings_between_steps_step_as_a_cloth_built_with_them() {
    // The phase program is kept from step to step while substeps, iterations and the
    // aerodynamics stay; changing them must step as a cloth built with the new ones.
    let spheres = [
        Sphere::new(Vec3::new(-0.1, 0.85, 0.0), 0.12),
        Sphere::new(Vec3::new(0.1, 0.85, 0.0), 0.12),
    ];
    let later = SolverSettings {
        threads: 2,
        substeps: 4,
        iterations: 2,
        ..SolverSettings::default()
    };
    let run = |cloth: &mut ClothSolver, steps: usize| {
        for _ in 0..steps {
            cloth.set_colliders(&spheres, &[]).expect("valid colliders");
            cloth.step(1.0 / 120.0).expect("a valid step");
        }
    };
    let mut changed = skirt_on_two_threads(Vec3::ZERO, 0.22, 0.95);
    let rest: Vec<Vec3> = changed.positions().iter().map(|&p| p.into()).collect();
    run(&mut changed, 5);
    changed.set_settings(later).expect("valid settings");
    changed.reset_to(&rest).expect("valid positions");
    run(&mut changed, 20);
    let mut built = skirt_on_two_threads(Vec3::ZERO, 0.22, 0.95);
    built.set_settings(later).expect("valid settings");
    run(&mut built, 20);
    assert_eq!(position_bits(&changed), position_bits(&built));
    // With the old program it would not: 10 substeps, 1 iteration.
    let mut kept = skirt_on_two_threads(Vec3::ZERO, 0.22, 0.95);
    run(&mut kept, 20);
    assert_ne!(position_bits(&kept), position_bits(&built));
}

#[test]
fn grouped_and_one_by_one_collisions_give_the_same_bits() {
    // A skirt tethered to its waist, around overlapping spheres and capsules (hips, swinging
    // thighs, pelvis) and standing on the floor: colliding eight particles together must
    // give the one-particle pass's positions bit for bit, through the later passes, the
    // floor, the crease between overlapping shapes and the tether repairs; and a second
    // pass over only the shapes before the last mover (and all after one that moves it
    // again) the positions of one over all. (With the blocks split at 1/32 instead of
    // 1/8, a pass that stopped at the last mover regardless differed here at step 29.)
    // One thigh is frictionless: both paths take each collider's share of the friction.
    let run_with = |group: bool, colliders: bool, prune: bool, thigh_friction: f32| {
        let mut cloth = skirt_on_two_threads(Vec3::ZERO, 0.22, 0.95);
        cloth.group_collisions = group;
        cloth.prune_passes = prune;
        cloth
            .set_planes(&[Plane::floor(0.0)])
            .expect("a valid floor");
        for step in 0..60 {
            let swing = 0.35 * (step as f32 * 0.15).sin();
            let spheres = [
                Sphere::new(Vec3::new(-0.1, 0.85, 0.0), 0.12),
                Sphere::new(Vec3::new(-0.1, 0.45, swing), 0.07),
                Sphere::new(Vec3::new(0.1, 0.85, 0.0), 0.12).with_friction(thigh_friction),
                Sphere::new(Vec3::new(0.1, 0.45, -swing), 0.07).with_friction(thigh_friction),
                Sphere::new(Vec3::new(0.0, 0.95, 0.03), 0.16),
                // A foot by the hem, which lies on the floor.
                Sphere::new(Vec3::new(0.2, 0.04, swing), 0.06),
            ];
            if colliders {
                cloth
                    .set_colliders(&spheres, &[[0, 1], [2, 3]])
                    .expect("valid colliders");
            }
            cloth.step(1.0 / 120.0).expect("a valid step");
        }
        position_bits(&cloth)
    };
    let run = |group: bool, colliders: bool, prune: bool| run_with(group, colliders, prune, 0.0);
    let grouped = run(true, true, true);
    assert_eq!(grouped, run(false, true, true));
    // The second pass gives what testing every shape again gives.
    assert_eq!(grouped, run(true, true, false));
    // The colliders did move the cloth, and the frictionless thigh let it slide.
    assert_ne!(grouped, run(true, false, true));
    assert_ne!(grouped, run_with(true, true, true, 1.0));
}

#[test]
fn eight_particles_integrate_as_one_does_in_a_moving_frame() {
    let motion = FrameMotion {
        velocity: Vec3::new(0.3, 0.0, -0.2),
        acceleration: Vec3::new(1.5, -0.4, 2.0),
        angular_velocity: Vec3::new(0.2, 3.0, -0.5),
        angular_acceleration: Vec3::new(-4.0, 12.0, 1.0),
        to_local: glam::Quat::from_rotation_y(0.4),
        pose: RigidTransform::IDENTITY,
    };
    let inertia = FrameInertia::FULL;
    let h = 1.0 / 1200.0;
    let k = StepConstants {
        substeps: 10,
        h,
        inv_h: 1.0 / h,
        inv_h2: 1.0 / (h * h),
        bend_alpha: 0.0,
        damping: 0.999,
        gravity: Vec3A::new(0.0, -9.81, 0.0),
        keep_lambda: false,
        aero: false,
        isa: Isa::detect(),
        thickness: 0.003,
        friction: 0.3,
        max_velocity: 5.0,
        frame: Some(FrameTerms {
            linear: Vec3A::from(motion.acceleration * inertia.linear),
            euler: Vec3A::from(motion.angular_acceleration * inertia.angular),
            coriolis: Vec3A::from(2.0 * motion.angular_velocity * inertia.angular),
            omega: Vec3A::from(motion.angular_velocity),
            centrifugal: inertia.centrifugal,
            air_velocity: Vec3A::ZERO,
            air_omega: Vec3A::ZERO,
            motion,
        }),
        colliders: 0,
        group_collisions: true,
        prune_passes: true,
        air_density: 0.0,
        drag: 0.0,
        lift: 0.0,
        time: 0.0,
    };
    let mut seed = 7u32;
    let mut point =
        |scale: f32| Vec3A::new(random(&mut seed), random(&mut seed), random(&mut seed)) * scale;
    let p: Vec<Vec3A> = (0..LANES).map(|_| point(0.5)).collect();
    // One particle moves faster than the cap.
    let moved: Vec<f32> = (0..LANES)
        .map(|l| if l == 3 { 0.02 } else { 0.002 })
        .collect();
    let prev: Vec<Vec3A> = p
        .iter()
        .zip(&moved)
        .map(|(&p, &m)| p - point(1.0).normalize_or_zero() * m)
        .collect();
    let external: Vec<Vec3A> = (0..LANES).map(|_| point(2.0)).collect();
    for isa in [Isa::Baseline, Isa::detect()] {
        let (mut xs, mut xs_prev) = (p.clone(), prev.clone());
        // SAFETY: eight particles in each buffer.
        unsafe {
            integrate_free(
                isa,
                [xs.as_mut_ptr(), xs_prev.as_mut_ptr()],
                external.as_ptr(),
                &StepConstants { isa, ..k },
            )
        };
        for l in 0..LANES {
            let mut vel = (p[l] - prev[l]) * k.inv_h;
            if vel.length() > k.max_velocity {
                vel = vel * (k.max_velocity / vel.length());
            }
            let vel = predict_velocity(&k, p[l], vel, external[l]);
            assert!(
                (xs[l] - (p[l] + vel * h)).length() <= 1e-6,
                "{l}: {} vs {}",
                xs[l],
                p[l] + vel * h
            );
            assert_eq!(xs_prev[l], p[l]);
        }
    }
}

#[test]
fn a_nan_position_stays_nan_through_the_tethers() {
    let (a0, a1) = (Vec3A::ZERO, Vec3A::X * 0.05);
    assert!(project_on_two_balls(Vec3A::NAN, a0, 0.5, a1, 0.5).is_none());
    let nan = V3 {
        x: Baseline8::splat(f32::NAN),
        y: Baseline8::splat(0.0),
        z: Baseline8::splat(0.0),
    };
    let splat = |v: Vec3A| V3 {
        x: Baseline8::splat(v.x),
        y: Baseline8::splat(v.y),
        z: Baseline8::splat(v.z),
    };
    let r = Baseline8::splat(0.5);
    let (_, fallback, _) = project_on_two_balls_lanes(nan, splat(a0), r, splat(a1), r);
    assert_eq!(fallback, 0xFF);
}
