//! Segment-local morphing and the roughness measure (seed 002 §4.3-4.4, §7.1): propagation
//! weights, the weighted mean of eq. 4.6 on a hand-built strip, roughness on flat and noisy
//! grids, the body's segments, a waist-only girth edit on the MakeHuman body, and the roughness
//! study of Figures 7.3-7.5 (`--nocapture` prints its table).

mod common;

use std::collections::{BTreeSet, VecDeque};
use std::sync::OnceLock;

use fitroom_body::BodyModel;
use fitroom_body::segments::{
    AreaBlend, BodySegment, BodySegmentation, Decay, GIRTH_TOLERANCE_CM, MeshGraph, Propagation,
    RoughnessStudy, RoughnessStudyConfig, SegmentEdit, SegmentError, SegmentMorph, SegmentTarget,
    SegmentWeights, StudyTarget, edit_waist_girth, roughness_study_with,
};
use glam::Vec3;

fn model() -> &'static BodyModel {
    common::asset_model()
}

fn segmentation() -> &'static BodySegmentation {
    static SEGMENTATION: OnceLock<BodySegmentation> = OnceLock::new();
    SEGMENTATION.get_or_init(|| {
        BodySegmentation::new(model()).unwrap_or_else(|e| panic!("segmenting the body: {e}"))
    })
}

fn study() -> &'static RoughnessStudy {
    static STUDY: OnceLock<RoughnessStudy> = OnceLock::new();
    STUDY.get_or_init(|| {
        roughness_study_with(model(), segmentation(), &RoughnessStudyConfig::default())
            .unwrap_or_else(|e| panic!("roughness study: {e}"))
    })
}

// ---------------------------------------------------------------------------------------------
// Hand-built meshes and independent computations

/// A strip of `columns` columns of two vertices (bottom `2i`, top `2i + 1`, at x = i), two
/// triangles between neighbouring columns: a column's vertices touch only the columns next to
/// it, so the graph distance between columns is their index difference.
fn strip(columns: u32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let positions = (0..columns)
        .flat_map(|i| [Vec3::new(i as f32, 0.0, 0.0), Vec3::new(i as f32, 1.0, 0.0)])
        .collect();
    let triangles = (0..columns - 1)
        .flat_map(|i| {
            let (b0, t0, b1, t1) = (2 * i, 2 * i + 1, 2 * i + 2, 2 * i + 3);
            [[b0, b1, t0], [b1, t1, t0]]
        })
        .collect();
    (positions, triangles)
}

/// An `n` x `n` grid in the plane z = 0 with 1 m spacing (integer coordinates, so that the
/// means of a flat grid are exact), each square split along the same diagonal.
fn grid(n: u32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let positions = (0..n * n)
        .map(|v| Vec3::new((v % n) as f32, (v / n) as f32, 0.0))
        .collect();
    let mut triangles = Vec::new();
    for y in 0..n - 1 {
        for x in 0..n - 1 {
            let v = y * n + x;
            triangles.push([v, v + 1, v + n + 1]);
            triangles.push([v, v + n + 1, v + n]);
        }
    }
    (positions, triangles)
}

/// The 1-rings of a mesh, built independently of the crate.
fn rings(vertex_count: usize, triangles: &[[u32; 3]]) -> Vec<BTreeSet<u32>> {
    let mut r = vec![BTreeSet::new(); vertex_count];
    for t in triangles {
        for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
            r[a as usize].insert(b);
            r[b as usize].insert(a);
        }
    }
    r
}

/// Graph distances from `core` (`None`: unreachable), breadth-first over `rings`.
fn distances(rings: &[BTreeSet<u32>], core: &[u32]) -> Vec<Option<u32>> {
    let mut d = vec![None; rings.len()];
    let mut queue = VecDeque::new();
    for &c in core {
        d[c as usize] = Some(0);
        queue.push_back(c);
    }
    while let Some(v) = queue.pop_front() {
        let dv = d[v as usize].expect("queued vertices have a distance");
        for &n in &rings[v as usize] {
            if d[n as usize].is_none() {
                d[n as usize] = Some(dv + 1);
                queue.push_back(n);
            }
        }
    }
    d
}

/// Eq. 7.2 as a mean, computed directly (in f64).
fn mean_laplacian_distance(positions: &[Vec3], rings: &[BTreeSet<u32>], region: &[u32]) -> f64 {
    let sum: f64 = region
        .iter()
        .map(|&v| {
            let ring = &rings[v as usize];
            let mut mean = [0.0f64; 3];
            for &n in ring {
                let p = positions[n as usize];
                mean[0] += p.x as f64;
                mean[1] += p.y as f64;
                mean[2] += p.z as f64;
            }
            let p = positions[v as usize];
            let k = ring.len() as f64;
            let d = [
                mean[0] / k - p.x as f64,
                mean[1] / k - p.y as f64,
                mean[2] / k - p.z as f64,
            ];
            (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
        })
        .sum();
    sum / region.len() as f64
}

// ---------------------------------------------------------------------------------------------
// Propagation weights

#[test]
fn decay_formulas_match_figure_4_8() {
    for decay in Decay::ALL {
        for depth in 0..10 {
            assert_eq!(decay.weight(0, depth), 1.0, "{decay} core weight");
            assert_eq!(
                decay.weight(depth + 1, depth),
                0.0,
                "{decay} past depth {depth}"
            );
        }
    }
    // p = d + 1 = 3.
    assert!((Decay::Linear.weight(1, 2) - 2.0 / 3.0).abs() < 1e-6);
    assert!((Decay::Linear.weight(2, 2) - 1.0 / 3.0).abs() < 1e-6);
    assert!((Decay::Square.weight(1, 2) - (1.0 - 1.0 / 9.0)).abs() < 1e-6);
    assert!((Decay::Square.weight(2, 2) - (1.0 - 4.0 / 9.0)).abs() < 1e-6);
    // σ = p / 3 = 3 at d = 8: k = 3 is one σ out.
    assert!((Decay::Gaussian.weight(3, 8) - (-0.5f32).exp()).abs() < 1e-6);
    assert_eq!("gaussian".parse::<Decay>(), Ok(Decay::Gaussian));
}

#[test]
fn propagation_weights_on_the_body() {
    let m = model();
    let seg = segmentation();
    let body = m.body_vertex_count as usize;
    let rings = rings(body, &m.triangles);
    let core = seg.core(BodySegment::Waist);
    let dist = distances(&rings, &core);
    for depth in [3u32, 6] {
        for decay in Decay::ALL {
            let w: SegmentWeights = seg
                .weights(BodySegment::Waist, Propagation::new(depth, decay))
                .expect("waist weights");
            // Exactly the vertices within `depth` hops, at their independent distance.
            let expected: Vec<u32> = (0..body as u32)
                .filter(|&v| dist[v as usize].is_some_and(|d| d <= depth))
                .collect();
            assert_eq!(w.vertices, expected, "{decay} depth {depth}: reached set");
            let mut by_hops = vec![None; depth as usize + 1];
            for ((&v, &k), &wt) in w.vertices.iter().zip(&w.hops).zip(&w.weights) {
                assert_eq!(Some(k), dist[v as usize], "vertex {v} hops");
                if k == 0 {
                    assert_eq!(wt, 1.0, "core vertex {v}");
                }
                assert!(wt > 0.0, "vertex {v} at {k} hops has weight {wt}");
                // One weight per ring.
                let slot: &mut Option<f32> = &mut by_hops[k as usize];
                assert!(slot.is_none_or(|s| s == wt), "ring {k} weights differ");
                *slot = Some(wt);
            }
            let ring_weights: Vec<f32> = by_hops
                .iter()
                .map(|w| w.expect("every ring up to the depth is reached"))
                .collect();
            assert!(
                ring_weights.windows(2).all(|p| p[1] < p[0]),
                "{decay} depth {depth}: weights {ring_weights:?} do not decrease"
            );
            // Zero beyond the depth.
            let beyond: Vec<u32> = (0..body as u32)
                .filter(|&v| dist[v as usize] == Some(depth + 1))
                .collect();
            assert!(!beyond.is_empty());
            assert!(beyond.iter().all(|&v| w.weight_of(v) == 0.0));
            if decay == Decay::Gaussian && depth == 6 {
                println!("gaussian depth 6, weight per ring: {ring_weights:.3?}");
            }
        }
    }
    // Depth 0 is the hard segment: the core alone.
    let hard = seg
        .weights(BodySegment::Waist, Propagation::HARD)
        .expect("hard waist");
    assert_eq!(hard.vertices, core);
    assert!(hard.weights.iter().all(|&w| w == 1.0));
}

// ---------------------------------------------------------------------------------------------
// Eq. 4.6

#[test]
fn weighted_mean_of_eq_4_6_on_a_strip() {
    // Six columns; area A = columns 0-2, area B = columns 3-5, both propagated 2 hops with the
    // linear decay: weights 1, 2/3, 1/3 at 0, 1, 2 hops. u_A = 1, u_B = 0.25. Per column,
    // Σ u w / Σ w by hand:
    //   0: A only                          = 1
    //   1: (1 + 0.25/3) / (1 + 1/3)        = 13/16
    //   2: (1 + 0.25·2/3) / (1 + 2/3)      = 7/10
    //   3: (2/3 + 0.25) / (2/3 + 1)        = 11/20
    //   4: (1/3 + 0.25) / (1/3 + 1)        = 7/16
    //   5: B only                          = 0.25
    let expected = [1.0, 13.0 / 16.0, 0.7, 11.0 / 20.0, 7.0 / 16.0, 0.25];
    let (source, triangles) = strip(6);
    let graph = MeshGraph::new(source.len(), &triangles).expect("strip graph");
    let propagation = Propagation::new(2, Decay::Linear);
    let a = graph
        .propagate(&[0, 1, 2, 3, 4, 5], propagation)
        .expect("area A");
    let b = graph
        .propagate(&[6, 7, 8, 9, 10, 11], propagation)
        .expect("area B");
    assert!((a.weight_of(6) - 2.0 / 3.0).abs() < 1e-6);
    assert_eq!(a.weight_of(10), 0.0);
    let blend = AreaBlend::new(source.len(), &[a, b]).expect("blend");
    let amounts = [1.0, 0.25];
    let multipliers = blend.multipliers(&amounts).expect("multipliers");
    // The target: every vertex 1 m up (plus a sideways part, to check the whole vector).
    let target: Vec<Vec3> = source
        .iter()
        .map(|p| *p + Vec3::new(0.5, 1.0, 0.0))
        .collect();
    let morphed = blend
        .morph_towards(&source, &target, &amounts)
        .expect("morph");
    let with = blend
        .morph_with(&source, &amounts, |_, k| target[k] - source[k])
        .expect("morph_with");
    for (v, (&m, p)) in multipliers.iter().zip(&morphed).enumerate() {
        let e = expected[v / 2];
        assert!(
            (m - e).abs() < 1e-6,
            "vertex {v}: multiplier {m}, by hand {e}"
        );
        let want = source[v] + Vec3::new(0.5, 1.0, 0.0) * e;
        assert!(p.distance(want) < 1e-6, "vertex {v}: {p} vs {want}");
        assert!(with[v].distance(want) < 1e-6, "morph_with vertex {v}");
    }
    // All amounts 1: a complete morph everywhere (the seed's requirement).
    let full = blend.morph_towards(&source, &target, &[1.0, 1.0]).unwrap();
    assert!(full.iter().zip(&target).all(|(p, t)| p.distance(*t) < 1e-6));
    // Wrong number of amounts.
    assert!(matches!(
        blend.multipliers(&[1.0]),
        Err(SegmentError::Length {
            field: "amounts",
            got: 1,
            expected: 2,
            ..
        })
    ));
}

// ---------------------------------------------------------------------------------------------
// Roughness (§7.1)

#[test]
fn roughness_of_flat_and_noisy_grids() {
    let n = 12u32;
    let (flat, triangles) = grid(n);
    let graph = MeshGraph::new(flat.len(), &triangles).expect("grid graph");
    let interior: Vec<u32> = (0..n * n)
        .filter(|v| (1..n - 1).contains(&(v % n)) && (1..n - 1).contains(&(v / n)))
        .collect();
    let r_flat = graph.roughness_m(&flat, &interior).expect("flat roughness");
    assert_eq!(r_flat, 0.0, "flat grid interior roughness");
    // Deterministic noise of ±0.2 m (a fifth of the spacing) out of the plane.
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let noisy: Vec<Vec3> = flat
        .iter()
        .map(|p| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            let u = (state >> 11) as f32 / (1u64 << 53) as f32;
            *p + Vec3::Z * (u - 0.5) * 0.4
        })
        .collect();
    let rings = rings(flat.len(), &triangles);
    for region in [interior.clone(), (0..n * n).collect::<Vec<u32>>()] {
        let r = graph.roughness_m(&noisy, &region).expect("noisy roughness") as f64;
        let independent = mean_laplacian_distance(&noisy, &rings, &region);
        println!(
            "noisy grid, {} vertices: roughness {:.5} m (independent {:.5} m)",
            region.len(),
            r,
            independent
        );
        assert!(r > 0.01, "noisy grid roughness {r}");
        assert!((r - independent).abs() < 1e-6 * independent);
    }
    let whole = graph.mesh_roughness_m(&noisy).unwrap() as f64;
    let all: Vec<u32> = (0..n * n).collect();
    assert!((whole - mean_laplacian_distance(&noisy, &rings, &all)).abs() < 1e-6 * whole);
    assert!(matches!(
        MeshGraph::new(3, &[[0, 1, 3]]),
        Err(SegmentError::TriangleIndex {
            triangle: 0,
            vertex: 3,
            ..
        })
    ));
}

// ---------------------------------------------------------------------------------------------
// The body's segments

#[test]
fn segments_partition_the_body() {
    let m = model();
    let seg = segmentation();
    let body = m.body_vertex_count as usize;
    assert_eq!(seg.labels().len(), body);
    let floor = m.positions[..body]
        .iter()
        .map(|p| p.y)
        .fold(f32::INFINITY, f32::min);
    println!("torso cuts: {:?}", seg.cuts);
    let mut total = 0;
    for s in BodySegment::ALL {
        let core = seg.core(s);
        assert!(!core.is_empty(), "{s} is empty");
        total += core.len();
        let centroid =
            core.iter().map(|&v| m.positions[v as usize]).sum::<Vec3>() / core.len() as f32;
        println!(
            "{:>16}: {:>5} vertices, centroid ({:+.3}, {:.3} above the sole, {:+.3}) m",
            s.name(),
            core.len(),
            centroid.x,
            centroid.y - floor,
            centroid.z
        );
        if s.name().ends_with("-left") {
            assert!(centroid.x > 0.05, "{s} centroid x {}", centroid.x);
        } else if s.name().ends_with("-right") {
            assert!(centroid.x < -0.05, "{s} centroid x {}", centroid.x);
        }
        assert_eq!(s.name().parse::<BodySegment>(), Ok(s));
    }
    assert_eq!(total, body, "cores partition the body");
    // Band heights follow the cuts; the waist band holds the waist line.
    let waist_line = m.measure(&m.positions).unwrap().landmarks.waist_cm;
    assert!(seg.cuts.waist_hip_cm < waist_line && waist_line < seg.cuts.chest_waist_cm);
    for v in seg.core(BodySegment::Waist) {
        let h = (m.positions[v as usize].y - floor) * 100.0;
        assert!((seg.cuts.waist_hip_cm..seg.cuts.chest_waist_cm).contains(&h));
    }
    // Top to bottom: head, chest, waist, hip, thigh, shank, foot.
    let height = |s| {
        let c = seg.core(s);
        c.iter().map(|&v| m.positions[v as usize].y).sum::<f32>() / c.len() as f32
    };
    use BodySegment::*;
    let column = [HeadNeck, Chest, Waist, Hip, ThighLeft, ShankLeft, FootLeft];
    assert!(column.windows(2).all(|p| height(p[0]) > height(p[1])));
    let arm = [UpperArmLeft, ForearmLeft, HandLeft];
    assert!(arm.windows(2).all(|p| height(p[0]) > height(p[1])));
}

#[test]
fn complete_morph_reaches_the_target() {
    let m = model();
    let seg = segmentation();
    let target = m
        .shaped(&fitroom_body::Shape {
            weight: 1.0,
            ..Default::default()
        })
        .unwrap()
        .positions;
    let blend = seg.blend(Propagation::new(4, Decay::Gaussian)).unwrap();
    let edits: Vec<SegmentEdit> = BodySegment::ALL
        .into_iter()
        .map(|segment| SegmentEdit {
            segment,
            target: SegmentTarget::Positions(target.clone()),
            amount: 1.0,
        })
        .collect();
    let out = seg.morph(&blend, &m.positions, &edits).unwrap();
    let body = m.body_vertex_count as usize;
    let worst = (0..body)
        .map(|k| out[k].distance(target[k]))
        .fold(0.0f32, f32::max);
    assert!(worst < 1e-6, "worst distance from the target {worst} m");
    // Helpers are carried unchanged.
    assert_eq!(out[body..], m.positions[body..]);
    // One edit per segment.
    let twice = [edits[2].clone(), edits[2].clone()];
    assert_eq!(
        seg.morph(&blend, &m.positions, &twice),
        Err(SegmentError::DuplicateEdit(BodySegment::Waist))
    );
}

// ---------------------------------------------------------------------------------------------
// The designer's waist-only edit

#[test]
fn waist_only_edit_moves_the_waist_and_nothing_far() {
    let m = model();
    let base = &m.positions;
    let propagation = Propagation::new(4, Decay::Gaussian);
    let edit = edit_waist_girth(m, base, -5.0, propagation).expect("waist edit");
    let before = m.measure(base).unwrap();
    let after = m.measure(&edit.positions).unwrap();
    println!(
        "waist edit -5 cm ({} depth {}): waist {:.2} -> {:.2} cm (requested {:.2}), scale {:.4}, \
         {} steps; hip {:.2} -> {:.2}, bust {:.2} -> {:.2}",
        propagation.decay,
        propagation.depth,
        before.waist_cm,
        after.waist_cm,
        edit.requested_cm,
        edit.scale_factor,
        edit.steps,
        before.hip_cm,
        after.hip_cm,
        before.bust_cm,
        after.bust_cm
    );
    assert!((edit.requested_cm - (before.waist_cm - 5.0)).abs() < 1e-4);
    assert!((after.waist_cm - (before.waist_cm - 5.0)).abs() <= GIRTH_TOLERANCE_CM + 1e-4);
    assert_eq!(after.waist_cm, edit.achieved_cm);
    // Far from the waist: exactly unmoved.
    let seg = segmentation();
    for s in [
        BodySegment::HeadNeck,
        BodySegment::FootLeft,
        BodySegment::FootRight,
        BodySegment::ShankLeft,
        BodySegment::ShankRight,
        BodySegment::HandLeft,
        BodySegment::HandRight,
    ] {
        for v in seg.core(s) {
            assert_eq!(
                edit.positions[v as usize], base[v as usize],
                "{s} vertex {v}"
            );
        }
    }
    // Exactly the vertices the waist's propagation reaches may move.
    let reach = seg.weights(BodySegment::Waist, propagation).unwrap();
    let moved: Vec<u32> = (0..m.body_vertex_count)
        .filter(|&v| edit.positions[v as usize] != base[v as usize])
        .collect();
    assert!(moved.iter().all(|&v| reach.weight_of(v) > 0.0));
    assert_eq!(
        edit.positions[m.body_vertex_count as usize..],
        base[m.body_vertex_count as usize..]
    );
    println!(
        "moved {} of {} body vertices (waist core {}, reach {})",
        moved.len(),
        m.body_vertex_count,
        seg.core(BodySegment::Waist).len(),
        reach.len()
    );
    // The same edit through SegmentMorph, from the edited body back to the original girth.
    let morph =
        SegmentMorph::with_segmentation(seg.clone(), BodySegment::Waist, propagation).unwrap();
    let back = morph
        .edit_girth(m, &edit.positions, before.waist_cm)
        .expect("edit back");
    assert!((back.achieved_cm - before.waist_cm).abs() <= GIRTH_TOLERANCE_CM);
    // A hand has no girth to edit; a girth three times as large is refused.
    let hand =
        SegmentMorph::with_segmentation(seg.clone(), BodySegment::HandLeft, propagation).unwrap();
    assert_eq!(
        hand.edit_girth(m, base, 20.0).map(|e| e.achieved_cm),
        Err(SegmentError::NoGirth(BodySegment::HandLeft))
    );
    assert!(matches!(
        morph.edit_girth(m, base, 3.0 * before.waist_cm),
        Err(SegmentError::GirthOutOfReach { .. })
    ));
    assert!(matches!(
        morph.apply(base, &SegmentTarget::RadialScale { factor: 0.0 }, 1.0),
        Err(SegmentError::BadValue { .. })
    ));
}

// ---------------------------------------------------------------------------------------------
// Figures 7.3-7.5

#[test]
fn gaussian_propagation_lowers_roughness_as_depth_grows() {
    let s = study();
    println!("{}", s.table());
    let last = s.amounts.len() - 1;
    assert_eq!(s.amounts[0], 0.0);
    assert_eq!(s.amounts[last], 1.0);
    let [a, b] = s.segments;
    for case in [vec![a], vec![b], vec![a, b]] {
        let at_one: Vec<f32> = s
            .depths
            .iter()
            .map(|&d| {
                let c = s
                    .curve(&case, Decay::Gaussian, d)
                    .expect("every case, decay and depth has a curve");
                assert_eq!(c.roughness_mm[0], s.source_roughness_mm);
                c.roughness_mm[last]
            })
            .collect();
        println!(
            "gaussian, {case:?}, roughness at u = 1 by depth {:?}: {at_one:.4?}",
            s.depths
        );
        assert!(
            at_one.windows(2).all(|p| p[1] < p[0]),
            "{case:?}: roughness at u = 1 {at_one:?} does not fall as depth {:?} grows",
            s.depths
        );
    }
    // Serialises with plain field names for the plot.
    let json = serde_json::to_value(s).unwrap();
    for field in [
        "segments",
        "target",
        "amounts",
        "depths",
        "decays",
        "source_roughness_mm",
        "curves",
    ] {
        assert!(json.get(field).is_some(), "no `{field}` in the JSON");
    }
    assert_eq!(json["segments"][0], "waist");
    assert_eq!(json["curves"][0]["decay"], "linear");
    assert!(json["curves"][0]["roughness_mm"].is_array());
    // A study of one segment with itself is refused.
    let bad = RoughnessStudyConfig {
        segments: [BodySegment::Waist, BodySegment::Waist],
        target: StudyTarget::RadialScale { factor: 1.1 },
        ..Default::default()
    };
    assert!(matches!(
        roughness_study_with(model(), segmentation(), &bad),
        Err(SegmentError::StudyConfig(_))
    ));
}
