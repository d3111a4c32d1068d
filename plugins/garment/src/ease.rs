//! Ease: how much a garment's girth exceeds the body's at the bust, waist and hip.

use fitroom_body::{
    Measurements,
    measure::{Plane, cross_section, hull_perimeter},
};
use glam::{Vec2, Vec3};
use serde::Serialize;

/// Ease of the garment at one landmark.
#[derive(Debug, Clone, Serialize)]
pub struct Ease {
    pub landmark: &'static str,
    /// Height above the sole, cm.
    pub height_cm: f32,
    pub body_girth_cm: f32,
    /// `None` where the garment does not go round the body at that height.
    pub garment_girth_cm: Option<f32>,
    /// Garment minus body girth, cm.
    pub ease_cm: Option<f32>,
}

/// Half-width of the trunk, m: a garment loop whose centre is farther from the body's midline
/// (`x = 0`) is a sleeve, not round the trunk.
const TRUNK_HALF_WIDTH_M: f32 = 0.12;

/// The girth (convex hull of its cross-section loops, cm) of a mesh at height `y`, over the
/// loops whose centre `keep` accepts; `None` with fewer than 3 points.
fn girth_at(
    points: &[Vec3],
    triangles: &[[u32; 3]],
    y: f32,
    keep: &dyn Fn(Vec2) -> bool,
) -> Option<f32> {
    let loops = cross_section(points, triangles, &Plane::horizontal(y));
    let pts: Vec<Vec2> = loops
        .iter()
        .filter(|l| keep(l.centroid()))
        .flat_map(|l| l.points.iter().copied())
        .collect();
    (pts.len() >= 3).then(|| hull_perimeter(&pts) * 100.0)
}

/// The ease of a garment (`positions`, `triangles`, on the body standing in its rest pose with
/// its soles at `floor_y`) at the bust, waist and hip of the body `measured`: the garment's
/// loops around the trunk at each landmark's height against the body's girth.
pub fn trunk_ease(
    positions: &[Vec3],
    triangles: &[[u32; 3]],
    measured: &Measurements,
    floor_y: f32,
) -> Vec<Ease> {
    let l = &measured.landmarks;
    let mut ease = Vec::new();
    for (name, h_cm, body_cm) in [
        ("bust", l.bust_cm, measured.bust_cm),
        ("waist", l.waist_cm, measured.waist_cm),
        ("hip", l.hip_cm, measured.hip_cm),
    ] {
        let h = floor_y + h_cm / 100.0;
        // The garment's loops around the trunk (not a sleeve).
        let g = girth_at(positions, triangles, h, &|c: Vec2| {
            c.x.abs() < TRUNK_HALF_WIDTH_M
        });
        ease.push(Ease {
            landmark: name,
            height_cm: h_cm,
            body_girth_cm: body_cm,
            garment_girth_cm: g,
            ease_cm: g.map(|g| g - body_cm),
        });
    }
    ease
}
