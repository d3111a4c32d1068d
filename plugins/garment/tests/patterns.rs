//! Every shipped pattern garment, in every size, meshes, grades, sews and sits outside the
//! real MakeHuman body, in its default shape and in a fitted (female) shape.

mod common;

use std::sync::OnceLock;

use common::{TestBody, bodies, build, default_body, pattern};
use fitroom_garment::mesher::triangle_min_angle_deg;
use fitroom_garment::{BuildOptions, GarmentMesh, Landmark};

struct Built {
    garment: &'static str,
    size: String,
    body: &'static TestBody,
    mesh: GarmentMesh,
}

/// Every garment, size and body, built once per test binary.
fn all() -> &'static [Built] {
    static ALL: OnceLock<Vec<Built>> = OnceLock::new();
    ALL.get_or_init(|| {
        let mut out = Vec::new();
        for garment in common::GARMENTS {
            let p = pattern(garment);
            assert!(p.sizes.len() >= 3, "{garment}: at least three sizes");
            for body in bodies() {
                for size in p.size_labels() {
                    out.push(Built {
                        garment,
                        size: size.to_owned(),
                        body,
                        mesh: build(garment, size, body),
                    });
                }
            }
        }
        out
    })
}

#[test]
fn triangles_are_well_shaped_at_the_target_edge_length() {
    let mut worst_2d = f32::INFINITY;
    let mut worst_3d = f32::INFINITY;
    let mut edge_ratio = (f32::INFINITY, 0.0f32);
    for b in all() {
        let h = pattern(b.garment).target_edge_cm;
        let m = &b.mesh;
        let mut sheared = 0;
        assert_eq!(m.rest_2d.len(), m.positions.len());
        for t in &m.triangles {
            let [p, q, r] = t.map(|v| m.rest_2d[v as usize]);
            worst_2d = worst_2d.min(triangle_min_angle_deg(p, q, r));
            for (a, c) in [(p, q), (q, r), (r, p)] {
                let l = a.distance(c) / h;
                edge_ratio = (edge_ratio.0.min(l), edge_ratio.1.max(l));
            }
            let [p, q, r] = t.map(|v| m.positions[v as usize]);
            let angle = |o: glam::Vec3, a: glam::Vec3, c: glam::Vec3| {
                (a - o).angle_between(c - o).to_degrees()
            };
            let w = angle(p, q, r).min(angle(q, r, p)).min(angle(r, p, q));
            worst_3d = worst_3d.min(w);
            if b.garment != "tshirt" {
                assert!(
                    w >= 15.0,
                    "{} {}: placed triangle with a {w}° angle",
                    b.garment,
                    b.size
                );
            }
            if w < 15.0 {
                sheared += 1;
            }
        }
        assert!(
            sheared * 200 <= m.triangles.len(),
            "{} {} on {}: {sheared} of {} triangles have an angle below 15°",
            b.garment,
            b.size,
            b.body.name,
            m.triangles.len()
        );
    }
    println!(
        "min angle {worst_2d:.1}° flat, {worst_3d:.1}° placed and sewn; edges {:.2}..{:.2} × target",
        edge_ratio.0, edge_ratio.1
    );
    // The mesher refines to a 30° angle limit; boundary vertices are fixed by the seams.
    assert!(worst_2d >= 25.0, "flat min angle {worst_2d}°");
    // Placed on the body and sewn, triangles shear a little; the T-shirt's armholes are pulled
    // onto the sleeve caps by the sewing pre-simulation and a few triangles there (at most
    // 0.5%, checked above) shear more.
    assert!(worst_3d >= 5.0, "placed min angle {worst_3d}°");
    assert!(
        edge_ratio.0 >= 0.4 && edge_ratio.1 <= 1.6,
        "edge length ratio {edge_ratio:?}"
    );
}

#[test]
fn seams_pair_equal_vertex_counts_and_are_closed_after_sewing() {
    for b in all() {
        let p = pattern(b.garment);
        assert_eq!(b.mesh.seam_lines.len(), p.seams.len());
        for line in &b.mesh.seam_lines {
            assert_eq!(
                line.a.len(),
                line.b.len(),
                "{} {}: {:?}",
                b.garment,
                b.size,
                line.names
            );
            assert!(line.a.len() >= 2);
        }
        let gap = b.mesh.max_seam_gap();
        assert!(
            gap < 1e-4,
            "{} {} on {}: seam gap {gap} m after sewing",
            b.garment,
            b.size,
            b.body.name
        );
        // Welding joins the panels into one mesh the cloth core accepts.
        let welded = b.mesh.welded(&b.body.surface).expect("welds");
        let classes: std::collections::HashSet<u32> = b.mesh.seam_classes().into_iter().collect();
        assert_eq!(welded.positions.len(), classes.len());
        assert!(welded.seams.is_empty());
        welded
            .cloth_mesh()
            .expect("the cloth core accepts the welded garment");
        assert_eq!(welded.binding.len(), welded.attached.len());
    }
}

#[test]
fn the_placed_garment_is_outside_the_body() {
    for b in all() {
        let mut closest = f32::INFINITY;
        for (v, &p) in b.mesh.positions.iter().enumerate() {
            let d = b.body.surface.signed_distance(p);
            assert!(
                d > 0.0,
                "{} {} on {}: vertex {v} is {d} m inside the body",
                b.garment,
                b.size,
                b.body.name
            );
            closest = closest.min(d);
        }
        assert!(
            closest > 0.001,
            "{} {}: closest {closest}",
            b.garment,
            b.size
        );
    }
}

#[test]
fn unsewn_placement_already_closes_side_seams_and_is_outside() {
    // Without the sewing pre-simulation, the closed rows of a wrap put both sides of a side
    // seam at the same place: the skirt comes out of placement sewn.
    let body = default_body();
    let options = BuildOptions {
        sew: false,
        ..BuildOptions::default()
    };
    let skirt = pattern("skirt")
        .build(&body.surface, "M", &options)
        .expect("builds");
    assert!(
        skirt.max_seam_gap() < 0.003,
        "skirt side seams {} m apart",
        skirt.max_seam_gap()
    );
    for &p in &skirt.positions {
        assert!(body.surface.signed_distance(p) > 0.0);
    }
    // The T-shirt's shoulders and armholes are placed apart and closed by sewing.
    let tshirt = pattern("tshirt")
        .build(&body.surface, "M", &options)
        .expect("builds");
    assert!(tshirt.max_seam_gap() > 0.03);
    let mut sewn = tshirt.clone();
    let report = sewn.sew(&body.surface, 200, 0.004);
    assert!(report.max_gap_after < 1e-4, "{report:?}");
}

/// The sewn garment's girth at a landmark's height plus an offset, cm (the T-shirt's body
/// panels only: its sleeves hang at those heights).
fn girth_cm(b: &Built, landmark: Landmark, offset_cm: f32) -> f32 {
    let y = b.body.surface.landmark_y(landmark) + offset_cm / 100.0;
    let panels = if b.garment == "tshirt" {
        wrap_panels("tshirt", "body")
    } else {
        b.mesh.panels.clone()
    };
    100.0 * common::girth_of_panels_at(&b.mesh, &panels, y)
}

#[test]
fn graded_sizes_are_ordered_at_bust_waist_and_hip() {
    // The rows each garment is graded at: (name, landmark, offset cm) inside the garment.
    type Row = (&'static str, Landmark, f32);
    let rows: [(&str, &[Row]); 3] = [
        (
            "sundress",
            &[
                ("bust", Landmark::Waist, 13.0),
                ("waist", Landmark::Waist, -2.0),
                ("hip", Landmark::Hip, 0.0),
            ],
        ),
        (
            "tshirt",
            &[
                ("bust", Landmark::Axilla, -5.0),
                ("waist", Landmark::Axilla, -30.0),
            ],
        ),
        (
            "skirt",
            &[
                ("waist", Landmark::Waist, -2.0),
                ("hip", Landmark::Hip, 0.0),
            ],
        ),
    ];
    for body in bodies() {
        for (garment, rows) in rows {
            let sizes: Vec<&Built> = all()
                .iter()
                .filter(|b| b.garment == garment && std::ptr::eq(b.body, body))
                .collect();
            for &(name, landmark, offset) in rows {
                let girths: Vec<f32> = sizes
                    .iter()
                    .map(|b| girth_cm(b, landmark, offset))
                    .collect();
                let labels: Vec<&str> = sizes.iter().map(|b| b.size.as_str()).collect();
                println!(
                    "{garment} on {}: {name} girths {labels:?} {girths:.1?} cm",
                    body.name
                );
                assert!(girths[0] > 40.0, "{garment}: the cut meets the garment");
                for w in girths.windows(2) {
                    assert!(w[0] < w[1], "{garment} {name} on {}: {girths:?}", body.name);
                }
            }
        }
    }
}

/// The panel names of a pattern's wrap.
fn wrap_panels(garment: &str, wrap: &str) -> Vec<String> {
    let p = pattern(garment);
    p.wraps
        .iter()
        .filter(|w| w.name == wrap)
        .flat_map(|w| w.panels.iter().map(|&(i, _)| p.panels[i].name.clone()))
        .collect()
}

#[test]
fn closed_rows_have_the_pattern_girth_and_the_intended_ease() {
    let unsewn = BuildOptions {
        sew: false,
        ..BuildOptions::default()
    };
    for b in all() {
        let s = &b.body.surface;
        // Placement alone (before the sewing pre-simulation moves panels about): exact.
        let placed = pattern(b.garment)
            .build(s, &b.size, &unsewn)
            .expect("builds");
        let waist = s.landmark_y(Landmark::Waist);
        let mut checked = 0;
        for row in &placed.rows {
            // Vertical wraps only (straps and sleeves run along other axes), away from the
            // waist seam, the hem and the top edge.
            if !matches!(row.wrap.as_str(), "skirt" | "bodice" | "body") || !row.closed {
                continue;
            }
            if (row.h - waist).abs() < 0.03 {
                continue;
            }
            // Above the armpits a cut of the T-shirt also meets the sleeves.
            if row.wrap == "body" && row.h > s.landmark_y(Landmark::Axilla) - 0.04 {
                continue;
            }
            let heights: Vec<f32> = placed
                .rows
                .iter()
                .filter(|r| r.wrap == row.wrap)
                .map(|r| r.h)
                .collect();
            let (lo, hi) = heights
                .iter()
                .fold((f32::INFINITY, f32::NEG_INFINITY), |(l, h), &y| {
                    (l.min(y), h.max(y))
                });
            if row.h < lo + 0.04 || row.h > hi - 0.04 {
                continue;
            }
            // The intended ease: garment girth − body girth = 2π × the tube's offset.
            let ease = row.garment_girth_cm - row.body_girth_cm;
            assert!(ease >= 0.0);
            assert!(
                (ease - std::f32::consts::TAU * row.offset_cm).abs() < 0.05,
                "{row:?}"
            );
            // The placed mesh has the pattern's girth (chords of the tube: a little less).
            let panels = wrap_panels(b.garment, &row.wrap);
            let placed_girth = 100.0 * common::girth_of_panels_at(&placed, &panels, row.h);
            let rel = (placed_girth - row.garment_girth_cm) / row.garment_girth_cm;
            assert!(
                (-0.015..0.01).contains(&rel),
                "{} {} on {}: row at {:.3}: placed girth {placed_girth:.1} cm, pattern {:.1} cm",
                b.garment,
                b.size,
                b.body.name,
                row.h,
                row.garment_girth_cm
            );
            // Sewing moves panels by a centimetre or so, not more (the cut counts only this
            // wrap's panels: a sleeve may hang at the same height).
            let sewn = 100.0
                * common::girth_of_panels_at(&b.mesh, &wrap_panels(b.garment, &row.wrap), row.h);
            let rel = (sewn - row.garment_girth_cm) / row.garment_girth_cm;
            assert!(
                (-0.06..0.06).contains(&rel),
                "{} {}: sewn girth {sewn:.1} vs {row:?}",
                b.garment,
                b.size
            );
            checked += 1;
        }
        assert!(
            checked >= 10,
            "{} {}: {checked} rows checked",
            b.garment,
            b.size
        );
    }
    // The base size's ease at the waist on the fitted body, as drafted: skirt waist 72 cm
    // (size M, 2 cm over the chart's 70 cm waist) around a smaller body waist.
    let skirt = all()
        .iter()
        .find(|b| b.garment == "skirt" && b.size == "M" && b.body.name == "female")
        .expect("built");
    let body_waist = skirt.body.surface.measurements.waist_cm;
    let at_waist = girth_cm(skirt, Landmark::Waist, -0.5);
    assert!(
        (at_waist - 72.0).abs() < 2.0 && at_waist > body_waist,
        "{at_waist} vs body {body_waist}"
    );
}

#[test]
fn static_part_and_attachments_follow_the_pattern() {
    for b in all() {
        let m = &b.mesh;
        assert!(!m.attached.is_empty());
        assert!(m.attached.windows(2).all(|w| w[0] < w[1]));
        assert_eq!(m.binding.vertices, m.attached);
        let skinned: Vec<u32> = (0..m.positions.len() as u32)
            .filter(|&v| m.skinned[v as usize])
            .collect();
        for v in &skinned {
            assert!(
                m.attached.binary_search(v).is_ok(),
                "static vertices are attached"
            );
        }
        let panel = |v: u32| m.panels[m.panel_of_vertex[v as usize] as usize].as_str();
        match b.garment {
            "sundress" => {
                // Seed 000 §3.2.1: bodice and straps static, skirt simulated from the waist.
                for v in 0..m.positions.len() as u32 {
                    let p = panel(v);
                    assert_eq!(
                        m.skinned[v as usize],
                        p.contains("bodice") || p.starts_with("strap"),
                        "{p}"
                    );
                }
                let free = m.free_vertices();
                assert!(free.iter().all(|&v| panel(v).ends_with("skirt")));
                assert!(free.len() > m.positions.len() / 2);
            }
            _ => {
                assert!(skinned.is_empty());
                assert!(
                    m.attached.len() < m.positions.len() / 10,
                    "only a band is pinned"
                );
            }
        }
        assert_eq!(m.fabric, pattern(b.garment).fabric.fabric);
    }
}

#[test]
fn a_sewn_garment_simulates_in_the_cloth_core() {
    use fitroom_cloth::{ClothSolver, SolverSettings};
    let body = default_body();
    let skirt = all()
        .iter()
        .find(|b| b.garment == "skirt" && b.size == "M" && b.body.name == "default")
        .expect("built")
        .mesh
        .welded(&body.surface)
        .expect("welds");
    let mesh = skirt.cloth_mesh().expect("valid");
    let settings = SolverSettings {
        threads: 1,
        ..SolverSettings::default()
    };
    let mut solver =
        ClothSolver::new(&mesh, skirt.fabric, &skirt.attached, settings).expect("solver");
    let targets = skirt
        .binding
        .positions(&body.shaped.positions, &body.shaped.normals);
    solver
        .set_attachment_targets(&targets)
        .expect("one target per attached vertex");
    for _ in 0..24 {
        let report = solver.step(1.0 / 120.0).expect("steps");
        assert!(report.is_healthy());
    }
    assert!(solver.positions().iter().all(|p| p.is_finite()));
}
