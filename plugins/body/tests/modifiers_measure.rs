//! MakeHuman modifiers (macro and measure sliders) and anthropometric measurement: girths on
//! analytic solids, the base mesh against MakeHuman's own values, sliders moving measurements
//! the expected way, shape errors, and the time to shape a body.

mod common;

use std::collections::BTreeMap;
use std::f32::consts::PI;
use std::time::Instant;

use fitroom_body::measure::{Plane, convex_hull, cross_section, hull_perimeter};
use fitroom_body::{BodyModel, Measurements, Shape, ShapeError};
use glam::{Vec2, Vec3};

fn model() -> &'static BodyModel {
    common::asset_model()
}

fn measure_shape(shape: &Shape) -> Measurements {
    let m = model();
    let body = m.shaped(shape).unwrap();
    m.measure(&body.positions).unwrap()
}

// ---------------------------------------------------------------------------------------------
// Analytic solids

/// A closed prism: `outline` (x, z) extruded from y = 0 to y = 1, capped by fans from the
/// outline's centroid (fine for star-shaped outlines).
fn prism(outline: &[Vec2]) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let n = outline.len() as u32;
    let mut pos: Vec<Vec3> = Vec::new();
    for y in [0.0, 1.0] {
        pos.extend(outline.iter().map(|p| Vec3::new(p.x, y, p.y)));
    }
    let c = outline.iter().copied().sum::<Vec2>() / n as f32;
    pos.push(Vec3::new(c.x, 0.0, c.y));
    pos.push(Vec3::new(c.x, 1.0, c.y));
    let mut tris = Vec::new();
    for i in 0..n {
        let j = (i + 1) % n;
        tris.push([i, j, n + j]);
        tris.push([i, n + j, n + i]);
        tris.push([2 * n, j, i]);
        tris.push([2 * n + 1, n + i, n + j]);
    }
    (pos, tris)
}

fn ellipse(a: f32, b: f32, n: usize) -> Vec<Vec2> {
    (0..n)
        .map(|i| {
            let t = 2.0 * PI * i as f32 / n as f32;
            Vec2::new(a * t.cos(), b * t.sin())
        })
        .collect()
}

/// A UV sphere of radius `r`.
fn sphere(r: f32, rings: u32, segments: u32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let mut pos = vec![Vec3::new(0.0, -r, 0.0)];
    for i in 1..rings {
        let phi = PI * i as f32 / rings as f32;
        for j in 0..segments {
            let th = 2.0 * PI * j as f32 / segments as f32;
            pos.push(Vec3::new(
                r * phi.sin() * th.cos(),
                -r * phi.cos(),
                r * phi.sin() * th.sin(),
            ));
        }
    }
    pos.push(Vec3::new(0.0, r, 0.0));
    let top = pos.len() as u32 - 1;
    let at = |i: u32, j: u32| 1 + (i - 1) * segments + j % segments;
    let mut tris = Vec::new();
    for j in 0..segments {
        tris.push([0, at(1, j + 1), at(1, j)]);
        tris.push([top, at(rings - 1, j), at(rings - 1, j + 1)]);
        for i in 1..rings - 1 {
            tris.push([at(i, j), at(i, j + 1), at(i + 1, j + 1)]);
            tris.push([at(i, j), at(i + 1, j + 1), at(i + 1, j)]);
        }
    }
    (pos, tris)
}

fn polygon_perimeter(p: &[Vec2]) -> f32 {
    (0..p.len())
        .map(|i| p[i].distance(p[(i + 1) % p.len()]))
        .sum()
}

#[test]
fn elliptic_cylinder_girth_is_the_ellipse_perimeter() {
    let (a, b) = (0.16, 0.11);
    let outline = ellipse(a, b, 720);
    let (pos, tris) = prism(&outline);
    let loops = cross_section(&pos, &tris, &Plane::horizontal(0.37));
    assert_eq!(loops.len(), 1);
    assert!(loops[0].closed);
    // Each side quad's two edges and its diagonal are cut.
    assert_eq!(loops[0].points.len(), 2 * 720);
    // Ramanujan's second approximation (relative error ~ h^5 / 10^4 here, negligible).
    let h = ((a - b) / (a + b)).powi(2);
    let exact = PI * (a + b) * (1.0 + 3.0 * h / (10.0 + (4.0 - 3.0 * h).sqrt()));
    let girth = hull_perimeter(&loops[0].points);
    assert!((girth - exact).abs() / exact < 1e-4, "{girth} vs {exact}");
    assert!(
        (loops[0].length() - girth).abs() < 1e-5,
        "convex: loop = hull"
    );
    // A tilted plane through the cylinder cuts a longer ellipse.
    let tilted = cross_section(
        &pos,
        &tris,
        &Plane::new(Vec3::new(0.0, 0.5, 0.0), Vec3::new(0.3, 1.0, 0.0)),
    );
    assert_eq!(tilted.len(), 1);
    assert!(hull_perimeter(&tilted[0].points) > girth);
}

#[test]
fn box_girth_is_twice_width_plus_depth() {
    let outline = [
        Vec2::new(-0.15, -0.1),
        Vec2::new(0.15, -0.1),
        Vec2::new(0.15, 0.1),
        Vec2::new(-0.15, 0.1),
    ];
    let (pos, tris) = prism(&outline);
    let loops = cross_section(&pos, &tris, &Plane::horizontal(0.5));
    assert_eq!(loops.len(), 1);
    assert!((hull_perimeter(&loops[0].points) - 1.0).abs() < 1e-5);
    // A plane exactly through the bottom ring's vertices still gives one closed loop.
    let at_vertices = cross_section(&pos, &tris, &Plane::horizontal(0.0));
    assert!(at_vertices.iter().all(|l| l.closed));
}

#[test]
fn sphere_sections_are_circles() {
    let r = 0.2;
    let (pos, tris) = sphere(r, 180, 360);
    for y in [-0.15f32, -0.05, 0.0013, 0.1, 0.18] {
        let loops = cross_section(&pos, &tris, &Plane::horizontal(y));
        assert_eq!(loops.len(), 1, "y = {y}");
        let exact = 2.0 * PI * (r * r - y * y).sqrt();
        let girth = hull_perimeter(&loops[0].points);
        // Chords of the tessellation cut inside the sphere: within 0.2 %.
        assert!(
            girth <= exact && (exact - girth) / exact < 2e-3,
            "y = {y}: {girth} vs {exact}"
        );
    }
}

#[test]
fn non_convex_sections_take_the_hull() {
    // A five-pointed star: the hull is the regular pentagon of its tips.
    let (outer, inner) = (0.2f32, 0.08f32);
    let star: Vec<Vec2> = (0..10)
        .map(|i| {
            let t = PI * i as f32 / 5.0;
            let r = if i % 2 == 0 { outer } else { inner };
            Vec2::new(r * t.cos(), r * t.sin())
        })
        .collect();
    let (pos, tris) = prism(&star);
    let loops = cross_section(&pos, &tris, &Plane::horizontal(0.5));
    assert_eq!(loops.len(), 1);
    let pentagon = 10.0 * outer * (PI / 5.0).sin();
    let girth = hull_perimeter(&loops[0].points);
    assert!((girth - pentagon).abs() < 1e-5, "{girth} vs {pentagon}");
    assert!((loops[0].length() - polygon_perimeter(&star)).abs() < 1e-5);
    assert!(loops[0].length() > girth);

    // Two legs: two circular cylinders of radius r, centres d apart; the hull is 2 pi r + 2 d.
    let (r, d) = (0.07f32, 0.2f32);
    let mut pos = Vec::new();
    let mut tris = Vec::new();
    for cx in [-d / 2.0, d / 2.0] {
        let circle: Vec<Vec2> = ellipse(r, r, 1440)
            .into_iter()
            .map(|p| p + Vec2::new(cx, 0.0))
            .collect();
        let (p, t) = prism(&circle);
        let base = pos.len() as u32;
        pos.extend(p);
        tris.extend(t.into_iter().map(|t| t.map(|i| i + base)));
    }
    let loops = cross_section(&pos, &tris, &Plane::horizontal(0.5));
    assert_eq!(loops.len(), 2);
    let all: Vec<Vec2> = loops.iter().flat_map(|l| l.points.clone()).collect();
    let exact = 2.0 * PI * r + 2.0 * d;
    assert!((hull_perimeter(&all) - exact).abs() / exact < 1e-4);
}

#[test]
fn hull_handles_degenerate_input() {
    assert!(convex_hull(&[]).is_empty());
    assert_eq!(hull_perimeter(&[Vec2::ONE]), 0.0);
    // Collinear points: the segment, counted both ways.
    let line: Vec<Vec2> = (0..5)
        .map(|i| Vec2::new(i as f32, 2.0 * i as f32))
        .collect();
    assert!((hull_perimeter(&line) - 2.0 * 20f32.sqrt() * 2.0).abs() < 1e-4);
    // Duplicates and interior points.
    let mut sq = vec![
        Vec2::ZERO,
        Vec2::X,
        Vec2::ONE,
        Vec2::Y,
        Vec2::splat(0.5),
        Vec2::X,
        Vec2::new(0.5, 0.0),
    ];
    sq.push(Vec2::splat(0.25));
    let h = convex_hull(&sq);
    assert_eq!(h.len(), 4);
    assert!((hull_perimeter(&sq) - 4.0).abs() < 1e-6);
}

// ---------------------------------------------------------------------------------------------
// The base mesh

#[test]
fn base_mesh_against_makehuman() {
    let m = model();
    let start = Instant::now();
    let r = m.measure(&m.positions).unwrap();
    println!(
        "measuring took {:.1?} (release/debug as built)\n{}",
        start.elapsed(),
        serde_json::to_string_pretty(&r).unwrap()
    );
    assert!((r.stature_cm - 166.6).abs() < 0.2, "{}", r.stature_cm);
    // MakeHuman measures girths along fixed vertex loops on the skin (its "measure" ruler):
    // bust 80.4, waist 75.1, hips 97.4 cm on this mesh. A convex hull bridges the concavities
    // (between the breasts, the spine's groove, the buttocks' cleft) like a tape measure, so it
    // is a little shorter than the loop along the skin, and our landmarks are searched rather
    // than fixed, so the heights differ a little too.
    // Our chest girth is EN 13402's (the largest girth under the armpits): on this flat-chested
    // neutral body that is just under the armpits, above MakeHuman's loop, which runs over the
    // bust points. At the bust points (our `bust_point` landmark) our hull agrees with it.
    let floor0 = m.positions[..m.body_vertex_count as usize]
        .iter()
        .map(|p| p.y)
        .fold(f32::INFINITY, f32::min);
    let at_bust_point: Vec<Vec2> = cross_section(
        &m.positions[..m.body_vertex_count as usize],
        &m.triangles,
        &Plane::horizontal(floor0 + r.landmarks.bust_point_cm / 100.0),
    )
    .iter()
    .filter(|l| l.centroid().x.abs() < 0.2)
    .flat_map(|l| l.points.clone())
    .collect();
    let bust_point_girth = hull_perimeter(&at_bust_point) * 100.0;
    assert!(
        bust_point_girth > 80.4 - 3.0 && bust_point_girth < 80.4 + 0.5,
        "{bust_point_girth}"
    );
    assert!(r.bust_cm >= bust_point_girth - 0.01, "{}", r.bust_cm);
    assert!(
        r.hip_cm > 97.4 - 3.0 && r.hip_cm < 97.4 + 0.5,
        "{}",
        r.hip_cm
    );
    // MakeHuman's waist loop runs at the navel (omphalion, ~101 cm above the floor here, ANSUR's
    // waist level); ours is the natural waist, the narrowest trunk girth (~108 cm), about 8 cm
    // smaller on this body. At MakeHuman's level our hull agrees with MakeHuman.
    assert!(
        r.waist_cm > 62.0 && r.waist_cm < 75.1 - 4.0,
        "{}",
        r.waist_cm
    );
    let floor = m.positions[..m.body_vertex_count as usize]
        .iter()
        .map(|p| p.y)
        .fold(f32::INFINITY, f32::min);
    let body = &m.positions[..m.body_vertex_count as usize];
    let navel: Vec<Vec2> = cross_section(body, &m.triangles, &Plane::horizontal(floor + 1.015))
        .iter()
        .filter(|l| l.centroid().x.abs() < 0.2) // not the forearms
        .flat_map(|l| l.points.clone())
        .collect();
    let navel_girth = hull_perimeter(&navel) * 100.0;
    assert!((navel_girth - 75.1).abs() < 1.5, "{navel_girth}");

    let l = &r.landmarks;
    let order = [
        l.calf_cm,
        l.thigh_cm,
        l.crotch_cm,
        l.hip_cm,
        l.waist_cm,
        l.underbust_cm,
        l.bust_cm,
        l.axilla_cm,
        l.acromion_left_cm,
        l.neck_base_cm,
    ];
    assert!(order.windows(2).all(|w| w[0] < w[1]), "{l:?}");
    assert!((l.acromion_left_cm - l.acromion_right_cm).abs() < 0.5);
    // Plausible for an adult of 166 cm (ANSUR II / ISO 8559 ranges, generous).
    for (name, v, lo, hi) in [
        ("crotch height", r.crotch_height_cm, 70.0, 85.0),
        ("shoulder width", r.shoulder_width_cm, 33.0, 43.0),
        ("neck", r.neck_cm, 30.0, 42.0),
        ("arm length", r.arm_length_cm, 42.0, 62.0),
        ("thigh", r.thigh_cm, 48.0, 65.0),
        ("calf", r.calf_cm, 30.0, 42.0),
        ("underbust", r.underbust_cm, 65.0, r.bust_cm),
    ] {
        assert!(v > lo && v < hi, "{name} {v} outside {lo}..{hi}");
    }
}

// ---------------------------------------------------------------------------------------------
// Modifiers

#[test]
fn default_shape_is_a_sensible_body() {
    let m = model();
    let shape = Shape::default();
    let w = shape.target_weights(m).unwrap();
    let names: Vec<&str> = w.iter().map(|&(i, _)| m.targets[i].name.as_str()).collect();
    println!("default shape targets: {names:?}");
    // Six ethnic targets at 1/6 and the two (empty) universal young average targets at 1/2.
    assert_eq!(w.len(), 8);
    let total: f32 = w.iter().map(|p| p.1).sum();
    assert!((total - 2.0).abs() < 1e-5);
    let r = measure_shape(&shape);
    println!("default: {r:?}");
    assert!(
        (r.stature_cm - 166.6).abs() < 2.0,
        "stature {}",
        r.stature_cm
    );
    assert!(r.bust_cm > 80.0 && r.bust_cm < 100.0);
    assert!(r.waist_cm > 60.0 && r.waist_cm < r.bust_cm);
    assert!(r.hip_cm > r.waist_cm + 10.0 && r.hip_cm < 110.0);
}

#[test]
fn macro_weights_are_a_partition_of_unity() {
    let m = model();
    for (g, a, mu, we, h, p) in [
        (0.3, 0.4, 0.7, 0.2, 0.8, 0.1),
        (1.0, 0.05, 0.0, 1.0, 0.0, 1.0),
        (0.0, 0.9, 0.5, 0.6, 0.5, 0.5),
    ] {
        let shape = Shape {
            gender: g,
            age: a,
            muscle: mu,
            weight: we,
            height: h,
            proportions: p,
            african: 0.2,
            asian: 0.0,
            caucasian: 0.6,
            ..Default::default()
        };
        let w = shape.target_weights(m).unwrap();
        let sum = |pred: &dyn Fn(&str) -> bool| -> f32 {
            w.iter()
                .filter(|&&(i, _)| pred(&m.targets[i].name))
                .map(|p| p.1)
                .sum()
        };
        let ethnic = sum(&|n| {
            n.starts_with("macrodetails/") && n.split('/').count() == 2 && !n.contains("universal")
        });
        let universal = sum(&|n| n.contains("universal"));
        let height = sum(&|n| n.contains("/height/"));
        let prop = sum(&|n| n.contains("/proportions/"));
        // Age factors sum to 1 up to MakeHuman's 5.333 ~ 16/3 rounding.
        assert!((ethnic - 1.0).abs() < 2e-3, "{ethnic}");
        assert!((universal - 1.0).abs() < 2e-3, "{universal}");
        let expected_h = (1.0f32 - 2.0 * h).abs();
        assert!(
            (height - expected_h).abs() < 2e-3,
            "{height} vs {expected_h}"
        );
        // Proportions: no baby targets.
        assert!(prop <= (1.0f32 - 2.0 * p).abs() + 2e-3);
        assert!(w.iter().all(|p| p.1 > 0.0 && p.1 <= 1.0 + 1e-6));
    }
}

#[test]
fn gender_makes_female_and_male_bodies() {
    let female = measure_shape(&Shape {
        gender: 0.0,
        ..Default::default()
    });
    let male = measure_shape(&Shape {
        gender: 1.0,
        ..Default::default()
    });
    println!("female: {female:?}\nmale: {male:?}");
    assert!(male.stature_cm > female.stature_cm + 8.0);
    assert!(male.shoulder_width_cm > female.shoulder_width_cm + 2.0);
    assert!(male.neck_cm > female.neck_cm + 2.0);
    assert!(male.waist_cm > female.waist_cm);
    // Hips relative to the chest: wider for the female body.
    let (rf, rm) = (female.hip_cm / female.bust_cm, male.hip_cm / male.bust_cm);
    assert!(rf > rm + 0.05, "hip/bust female {rf} male {rm}");
    // Waist-to-hip: smaller for the female body.
    assert!(female.waist_cm / female.hip_cm < male.waist_cm / male.hip_cm - 0.05);
    // The female chest girth is largest over the bust points; the male one just under the
    // armpits, well above his bust point.
    let (lf, lm) = (&female.landmarks, &male.landmarks);
    assert!(
        (lf.bust_cm - lf.bust_point_cm).abs() < 2.0,
        "female bust girth at {} cm, bust point at {} cm",
        lf.bust_cm,
        lf.bust_point_cm
    );
    assert!(
        lm.bust_cm > lm.bust_point_cm + 2.0 && lm.axilla_cm - lm.bust_cm < 2.0,
        "male chest girth at {} cm, bust point {} cm, armpits {} cm",
        lm.bust_cm,
        lm.bust_point_cm,
        lm.axilla_cm
    );
    assert!(female.bust_cm - female.underbust_cm > 5.0);
}

#[test]
fn sliders_move_measurements_the_expected_way() {
    let at = |f: &dyn Fn(&mut Shape)| {
        let mut s = Shape::default();
        f(&mut s);
        measure_shape(&s)
    };
    let thin = at(&|s| s.weight = 0.0);
    let heavy = at(&|s| s.weight = 1.0);
    println!("thin: {thin:?}\nheavy: {heavy:?}");
    for (name, a, b) in [
        ("waist", thin.waist_cm, heavy.waist_cm),
        ("hip", thin.hip_cm, heavy.hip_cm),
        ("bust", thin.bust_cm, heavy.bust_cm),
        ("thigh", thin.thigh_cm, heavy.thigh_cm),
        ("calf", thin.calf_cm, heavy.calf_cm),
    ] {
        assert!(b > a + 2.0, "{name}: thin {a}, heavy {b}");
    }
    assert!((thin.stature_cm - heavy.stature_cm).abs() < 2.0);

    let short = at(&|s| s.height = 0.0);
    let tall = at(&|s| s.height = 1.0);
    println!("short: {short:?}\ntall: {tall:?}");
    assert!(tall.stature_cm > short.stature_cm + 20.0);
    assert!(tall.crotch_height_cm > short.crotch_height_cm + 8.0);
    assert!(tall.arm_length_cm > short.arm_length_cm + 4.0);

    let baby = at(&|s| s.age = 0.0);
    let child = at(&|s| s.age = 0.1875);
    let adult = Measurements { ..at(&|_| {}) };
    let old = at(&|s| s.age = 1.0);
    println!("baby: {baby:?}\nchild: {child:?}\nold: {old:?}");
    assert!(baby.stature_cm < 90.0, "{}", baby.stature_cm);
    assert!(baby.stature_cm < child.stature_cm && child.stature_cm < adult.stature_cm);
    assert!(old.stature_cm < adult.stature_cm);

    let weak = at(&|s| s.muscle = 0.0);
    let strong = at(&|s| s.muscle = 1.0);
    println!("weak: {weak:?}\nstrong: {strong:?}");
    // At a fixed weight the muscle slider trades fat for muscle (MakeHuman's manual): the
    // muscular body has the slimmer waist and hips.
    assert!(strong.waist_cm < weak.waist_cm - 2.0);
    assert!(strong.hip_cm < weak.hip_cm);

    // Proportions and ethnicity apply without error and change the body a little.
    let ideal = at(&|s| s.proportions = 1.0);
    let uncommon = at(&|s| s.proportions = 0.0);
    assert!(ideal != uncommon);
    let asian = at(&|s| {
        s.african = 0.0;
        s.asian = 1.0;
        s.caucasian = 0.0;
    });
    assert!(asian.stature_cm != adult.stature_cm);
}

#[test]
fn measure_modifiers_change_mostly_their_own_girth() {
    let base = measure_shape(&Shape::default());
    let with = |name: &str, v: f32| {
        measure_shape(&Shape {
            measures: BTreeMap::from([(name.to_owned(), v)]),
            ..Default::default()
        })
    };
    let wider = with("waist-circ", 1.0);
    let narrower = with("waist-circ", -1.0);
    println!("waist-circ -1/0/+1: {narrower:?}\n{base:?}\n{wider:?}");
    let dw = wider.waist_cm - base.waist_cm;
    assert!(dw > 2.0, "waist +{dw}");
    assert!(narrower.waist_cm < base.waist_cm - 2.0);
    for (name, a, b) in [
        ("bust", base.bust_cm, wider.bust_cm),
        ("hip", base.hip_cm, wider.hip_cm),
        ("thigh", base.thigh_cm, wider.thigh_cm),
        ("neck", base.neck_cm, wider.neck_cm),
    ] {
        assert!(
            (b - a).abs() < 0.3 * dw,
            "{name} moved {} for waist {dw}",
            b - a
        );
    }
    assert!((wider.stature_cm - base.stature_cm).abs() < 0.1);

    let hips = with("hips-circ", 1.0);
    let dh = hips.hip_cm - base.hip_cm;
    assert!(dh > 2.0, "hips +{dh}");
    assert!((hips.bust_cm - base.bust_cm).abs() < 0.3 * dh);

    let bust = with("bust-circ", 1.0);
    let db = bust.bust_cm - base.bust_cm;
    assert!(db > 2.0, "bust +{db}");
    assert!((bust.hip_cm - base.hip_cm).abs() < 0.3 * db);
}

#[test]
fn bad_shapes_name_the_field_and_range() {
    let m = model();
    let err = |s: Shape| s.target_weights(m).unwrap_err();

    let e = err(Shape {
        gender: f32::NAN,
        ..Default::default()
    });
    assert!(matches!(e, ShapeError::NotFinite { ref field, .. } if field == "gender"));
    let msg = e.to_string();
    assert!(msg.contains("`gender`") && msg.contains("0..=1"), "{msg}");

    let e = err(Shape {
        weight: 2.0,
        ..Default::default()
    });
    let msg = e.to_string();
    assert!(
        msg.contains("`weight`") && msg.contains("2") && msg.contains("0..=1"),
        "{msg}"
    );

    let e = err(Shape {
        age: -0.1,
        ..Default::default()
    });
    assert!(e.to_string().contains("`age`"), "{e}");

    let e = err(Shape {
        measures: BTreeMap::from([("waist-circ".to_owned(), 1.5)]),
        ..Default::default()
    });
    let msg = e.to_string();
    assert!(
        msg.contains("measures[\"waist-circ\"]") && msg.contains("-1..=1"),
        "{msg}"
    );

    let e = err(Shape {
        measures: BTreeMap::from([("belly-circ".to_owned(), 0.5)]),
        ..Default::default()
    });
    let msg = e.to_string();
    assert!(
        msg.contains("belly-circ") && msg.contains("waist-circ") && msg.contains("`measures`"),
        "{msg}"
    );

    let e = err(Shape {
        african: 0.0,
        asian: 0.0,
        caucasian: 0.0,
        ..Default::default()
    });
    assert_eq!(e, ShapeError::NoEthnicity);
    println!("{e}");

    assert!(
        m.shaped(&Shape {
            height: f32::INFINITY,
            ..Default::default()
        })
        .is_err()
    );
}

#[test]
fn shapes_read_from_partial_text() {
    let m = model();
    let s: Shape =
        serde_json::from_str(r#"{"gender": 1.0, "measures": {"waist-circ": -0.25}}"#).unwrap();
    assert_eq!(s.gender, 1.0);
    assert_eq!(s.weight, 0.5);
    assert_eq!(s.caucasian, 1.0 / 3.0);
    assert!(s.target_weights(m).is_ok());
    let back: Shape = serde_json::from_str(&serde_json::to_string(&s).unwrap()).unwrap();
    assert_eq!(back, s);
    assert!(serde_json::from_str::<Shape>(r#"{"gendre": 1.0}"#).is_err());
    let names = Shape::measure_names(m);
    assert_eq!(names.len(), 20, "{names:?}");
}

#[test]
fn shaping_time() {
    let m = model();
    let shape = Shape {
        gender: 0.3,
        age: 0.4,
        muscle: 0.7,
        weight: 0.3,
        height: 0.8,
        proportions: 0.7,
        african: 0.2,
        asian: 0.3,
        caucasian: 0.5,
        measures: BTreeMap::from([
            ("waist-circ".to_owned(), 0.3),
            ("bust-circ".to_owned(), -0.2),
            ("upperarm-length".to_owned(), 0.4),
        ]),
        regions: BTreeMap::new(),
    };
    // Warm up, then average.
    let body = m.shaped(&shape).unwrap();
    let runs = 20;
    let start = Instant::now();
    for _ in 0..runs {
        std::hint::black_box(m.shaped(std::hint::black_box(&shape)).unwrap());
    }
    let per = start.elapsed() / runs;
    let t = Instant::now();
    for _ in 0..runs {
        std::hint::black_box(shape.target_weights(m).unwrap());
    }
    println!("target_weights(): {:.2?}", t.elapsed() / runs);
    let t = Instant::now();
    for _ in 0..runs {
        std::hint::black_box(m.apply_targets(&body.weights));
    }
    println!("apply_targets(): {:.2?}", t.elapsed() / runs);
    let t = Instant::now();
    for _ in 0..runs {
        std::hint::black_box(m.body_normals(&body.positions));
    }
    println!("body_normals(): {:.2?}", t.elapsed() / runs);
    println!(
        "shaped(): {per:.2?} per body ({} targets, {} vertices; positions + normals + rest \
         pose; goal <= 2 ms in release)",
        body.weights.len(),
        body.positions.len()
    );
    assert_eq!(body.normals.len(), m.body_vertex_count as usize);
    assert_eq!(body.rest_pose.heads.len(), m.bones.len());
    assert!(body.positions.iter().all(|p| p.is_finite()));
    let start = Instant::now();
    let r = m.measure(&body.positions).unwrap();
    println!("measure(): {:.1?}; {r:?}", start.elapsed());
}
