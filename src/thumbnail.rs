//! Garment thumbnails for the try-on screen's carousel: the garment draped on the avatar at
//! rest (a second of cloth under gravity), seen from the front through the synthetic depth
//! camera's rasteriser ([`fitroom_depth::synthetic::raster`]: one z-buffer for the whole
//! product) with a focal length that frames the garment, each pixel shaded by how squarely
//! its surface faces the camera, then averaged down to the thumbnail's size (anti-aliased,
//! transparent around the figure). Bevy-free: the kiosk draws them on a task.

use fitroom_body::MODEL_TO_SENSOR;
use fitroom_body::plugin::{AvatarBody, visible_skin_indices};
use fitroom_depth::camera::{DepthCamera, HEIGHT, WIDTH};
use fitroom_depth::synthetic::Label;
use fitroom_depth::synthetic::raster::DepthBuffer;
use fitroom_garment::plugin::{ClothSettings, build_garment};
use fitroom_garment::source::GarmentSource;
use glam::{Affine3A, Vec3};

/// Cloth steps (120 Hz) the garment drapes before its picture is taken.
const DRAPE_STEPS: usize = 120;

/// The garment's larger side fills this share of the picture.
const FILL: f32 = 0.8;

/// The colours of the kiosk's avatar and garments (sRGB), as drawn.
const SKIN: [f32; 3] = [0.80, 0.62, 0.52];
const CLOTH: [f32; 3] = [0.35, 0.45, 0.75];

/// A square RGBA picture (sRGB, straight alpha), row-major from the top left.
#[derive(Clone, Debug)]
pub struct Thumbnail {
    pub side: usize,
    pub rgba: Vec<u8>,
}

impl Thumbnail {
    /// What pixel `(i, j)` shows: the body, the garment, or nothing (by its colour's nearer
    /// hue; a transparent pixel is nothing).
    pub fn label_at(&self, i: usize, j: usize) -> Option<Label> {
        let k = 4 * (j * self.side + i);
        let [r, _, b, a] = [0, 1, 2, 3].map(|c| self.rgba[k + c]);
        (a >= 128).then_some(if b > r { Label::Garment } else { Label::Body })
    }
}

/// The thumbnail (`side` pixels square) of `source` in `size` (`None`: its middle size) on
/// `body`.
pub fn garment_thumbnail(
    source: &GarmentSource,
    body: &AvatarBody,
    size: Option<&str>,
    side: usize,
) -> Result<Thumbnail, String> {
    // The skin the garment covers is left out, as the kiosk draws it: the cloth collides with
    // the body's spheres and capsules, not its mesh, and the skin would show through.
    let settings = ClothSettings {
        hide_covered_skin: true,
        ..ClothSettings::default()
    };
    let (_, mut sim, covered) = build_garment(source, body, size, &settings)?;
    // Identity skinning: the body in its rest pose, in model space.
    let rest = vec![Affine3A::IDENTITY; body.model.bones.len()];
    sim.set_measuring(false);
    sim.reset(&rest).map_err(|e| e.to_string())?;
    for _ in 0..DRAPE_STEPS {
        sim.step(&rest, 1.0 / 120.0).map_err(|e| e.to_string())?;
    }
    let (cloth, _) = sim.render_surface();
    // Sensor space (facing the camera), the garment's middle `DISTANCE` in front of it.
    let cloth: Vec<Vec3> = cloth.iter().map(|&p| MODEL_TO_SENSOR * p).collect();
    let (lo, hi) = cloth.iter().fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(lo, hi), &p| (lo.min(p), hi.max(p)),
    );
    if !(lo.is_finite() && hi.is_finite()) {
        return Err(format!(
            "{}: the draped garment has no finite surface to draw",
            source.path().display()
        ));
    }
    const DISTANCE: f32 = 2.0;
    let centre = 0.5 * (lo + hi);
    let shift = Vec3::new(-centre.x, -centre.y, DISTANCE - centre.z);
    let extent = (hi.x - lo.x).max(hi.y - lo.y).max(0.05);
    let focal = FILL * HEIGHT as f32 * DISTANCE / extent;
    let camera = DepthCamera {
        fx: focal,
        fy: focal,
        cx: WIDTH as f32 / 2.0,
        cy: HEIGHT as f32 / 2.0,
        ..DepthCamera::default()
    };
    let n = (body.model.body_vertex_count as usize).min(body.positions.len());
    let skin: Vec<Vec3> = body.positions[..n]
        .iter()
        .map(|&p| MODEL_TO_SENSOR * p + shift)
        .collect();
    let cloth: Vec<Vec3> = cloth.iter().map(|&p| p + shift).collect();
    let mut buffer = DepthBuffer::default();
    buffer.clear();
    let skin_triangles: Vec<[u32; 3]> = visible_skin_indices(&body.model, covered.as_deref())
        .chunks_exact(3)
        .map(|t| [t[0], t[1], t[2]])
        .collect();
    buffer.draw(&camera, &skin, &skin_triangles, Label::Body as u8, true);
    buffer.draw(
        &camera,
        &cloth,
        sim.triangles(),
        Label::Garment as u8,
        false,
    );
    Ok(downsample(&buffer, &camera, side.max(1)))
}

/// The centred `HEIGHT`-pixel square of `buffer`, shaded, averaged into `side` x `side`.
fn downsample(buffer: &DepthBuffer, camera: &DepthCamera, side: usize) -> Thumbnail {
    let left = (WIDTH - HEIGHT) / 2;
    let mut rgba = Vec::with_capacity(side * side * 4);
    for tj in 0..side {
        let (j0, j1) = (
            tj * HEIGHT / side,
            ((tj + 1) * HEIGHT / side).max(tj * HEIGHT / side + 1),
        );
        for ti in 0..side {
            let (i0, i1) = (
                ti * HEIGHT / side,
                ((ti + 1) * HEIGHT / side).max(ti * HEIGHT / side + 1),
            );
            let (mut sum, mut covered, mut count) = ([0.0f32; 3], 0usize, 0usize);
            for j in j0..j1 {
                for i in (left + i0)..(left + i1) {
                    count += 1;
                    let colour = match buffer.label[j * WIDTH + i] {
                        l if l == Label::Body as u8 => SKIN,
                        l if l == Label::Garment as u8 => CLOTH,
                        _ => continue,
                    };
                    // Lit from the camera: squarely facing surfaces brightest.
                    let shade = 0.35 + 0.65 * buffer.facing(camera, i, j);
                    for c in 0..3 {
                        sum[c] += colour[c] * shade;
                    }
                    covered += 1;
                }
            }
            let byte = |v: f32| (v * 255.0).round().clamp(0.0, 255.0) as u8;
            if covered == 0 {
                rgba.extend_from_slice(&[0, 0, 0, 0]);
            } else {
                let k = covered as f32;
                rgba.extend_from_slice(&[
                    byte(sum[0] / k),
                    byte(sum[1] / k),
                    byte(sum[2] / k),
                    byte(covered as f32 / count.max(1) as f32),
                ]);
            }
        }
    }
    Thumbnail { side, rgba }
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use super::*;

    fn body() -> AvatarBody {
        let assets = crate::assets::assets_dir().expect("assets");
        let model = fitroom_body::BodyModel::read(&assets.join(crate::assets::DEFAULT_BODY))
            .expect("the shipped body");
        AvatarBody::unshaped(Arc::new(model))
    }

    fn thumbnail(garment: &str) -> Thumbnail {
        let path = crate::assets::assets_dir()
            .expect("assets")
            .join("garments")
            .join(garment);
        let source = GarmentSource::load(&path).expect("the shipped garment");
        garment_thumbnail(&source, &body(), None, 64).expect("it draws")
    }

    /// Rows (top first) in which `label` shows.
    fn rows_with(t: &Thumbnail, label: Label) -> Vec<usize> {
        (0..t.side)
            .filter(|&j| (0..t.side).any(|i| t.label_at(i, j) == Some(label)))
            .collect()
    }

    #[test]
    fn a_skirt_is_framed_between_the_torso_above_and_the_legs_below() {
        let t = thumbnail("skirt.ron");
        assert_eq!(t.rgba.len(), 64 * 64 * 4);
        let cloth = rows_with(&t, Label::Garment);
        let (top, bottom) = (cloth[0], cloth[cloth.len() - 1]);
        // Framed: the garment spans most of the picture, with a margin.
        assert!(
            bottom - top >= 40 && top >= 2 && bottom <= 61,
            "{top}..{bottom}"
        );
        assert_eq!(t.label_at(32, 32), Some(Label::Garment));
        // The body shows above the waistband and below the hem, not in the corners.
        let skin = rows_with(&t, Label::Body);
        assert!(skin[0] < top && skin[skin.len() - 1] > bottom, "{skin:?}");
        assert_eq!(t.label_at(0, 63), None);
    }

    #[test]
    fn a_t_shirt_covers_the_chest_with_the_head_and_hands_out() {
        let t = thumbnail("tshirt.ron");
        assert_eq!(t.label_at(32, 32), Some(Label::Garment));
        // Sleeves: the garment is wider than at the middle column alone.
        let middle_row = 24;
        let wide = (0..t.side)
            .filter(|&i| t.label_at(i, middle_row) == Some(Label::Garment))
            .count();
        assert!(wide > 30, "{wide} garment pixels across row {middle_row}");
        // The neck and head above the collar are skin.
        let skin = rows_with(&t, Label::Body);
        let cloth = rows_with(&t, Label::Garment);
        assert!(
            skin[0] < cloth[0],
            "skin from {} cloth from {}",
            skin[0],
            cloth[0]
        );
    }
}
