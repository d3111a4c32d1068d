//! Shared helpers of the garment tests: the shipped assets, the MakeHuman body (read once per
//! test binary) in its default shape and in a fitted (female) shape, and the built garments.

#![allow(dead_code)]

use std::path::PathBuf;
use std::sync::OnceLock;

use fitroom_body::{BodyModel, Shape, ShapedBody};
use fitroom_garment::{BodySurface, BuildOptions, GarmentMesh, Pattern};

/// The shipped garments (pattern files in `assets/garments/`).
pub const GARMENTS: [&str; 3] = ["sundress", "tshirt", "skirt"];

/// The shipped fabrics (`assets/fabrics/`).
pub const FABRICS: [&str; 5] = ["cotton", "denim", "silk", "jersey", "leather"];

pub fn assets() -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../assets"))
}

pub fn garment_path(name: &str) -> PathBuf {
    assets().join("garments").join(format!("{name}.ron"))
}

pub fn model() -> &'static BodyModel {
    static MODEL: OnceLock<BodyModel> = OnceLock::new();
    MODEL.get_or_init(|| {
        let path = assets().join("bodies/makehuman.fitbody");
        BodyModel::read(&path).unwrap_or_else(|e| panic!("reading {}: {e}", path.display()))
    })
}

/// A body and the shaped mesh it was made from.
pub struct TestBody {
    pub name: &'static str,
    pub shaped: ShapedBody,
    pub surface: BodySurface,
}

fn make(name: &'static str, shape: Shape) -> TestBody {
    let shaped = model().shaped(&shape).expect("valid shape");
    let surface = BodySurface::new(model(), &shaped).expect("the body measures");
    TestBody {
        name,
        shaped,
        surface,
    }
}

/// MakeHuman's default body (gender 0.5, every slider at its middle).
pub fn default_body() -> &'static TestBody {
    static BODY: OnceLock<TestBody> = OnceLock::new();
    BODY.get_or_init(|| make("default", Shape::default()))
}

/// A fitted female body: smaller bust and waist than the default one, shorter.
pub fn female_body() -> &'static TestBody {
    static BODY: OnceLock<TestBody> = OnceLock::new();
    BODY.get_or_init(|| {
        make(
            "female",
            Shape {
                gender: 0.0,
                weight: 0.55,
                ..Shape::default()
            },
        )
    })
}

pub fn bodies() -> [&'static TestBody; 2] {
    [default_body(), female_body()]
}

pub fn pattern(name: &str) -> Pattern {
    Pattern::load(garment_path(name)).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// Builds `garment` in `size` on `body` with the default options (sewn).
pub fn build(garment: &str, size: &str, body: &TestBody) -> GarmentMesh {
    pattern(garment)
        .build(&body.surface, size, &BuildOptions::default())
        .unwrap_or_else(|e| panic!("{garment} {size} on the {} body: {e}", body.name))
}

/// Length of the closed loop where a horizontal plane cuts the garment's triangles, metres
/// (the girth a tape laid on the garment would read, concavities followed): the sum of the
/// segment lengths.
pub fn girth_at(garment: &GarmentMesh, y: f32) -> f32 {
    girth_of_panels_at(garment, &garment.panels, y)
}

/// [`girth_at`] counting only the triangles of the named panels.
pub fn girth_of_panels_at(garment: &GarmentMesh, panels: &[String], y: f32) -> f32 {
    let mut total = 0.0;
    for t in &garment.triangles {
        let panel = &garment.panels[garment.panel_of_vertex[t[0] as usize] as usize];
        if !panels.contains(panel) {
            continue;
        }
        let p = t.map(|v| garment.positions[v as usize]);
        let mut cut = Vec::new();
        for k in 0..3 {
            let (a, b) = (p[k], p[(k + 1) % 3]);
            if (a.y >= y) != (b.y >= y) {
                let s = (y - a.y) / (b.y - a.y);
                cut.push(a.lerp(b, s));
            }
        }
        if cut.len() == 2 {
            total += cut[0].distance(cut[1]);
        }
    }
    total
}
