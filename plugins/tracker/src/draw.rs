//! Skeletons drawn on depth images: the kiosk's picture-in-picture and the evaluation's
//! pictures (the tracked skeleton beside the ground truth) use the same drawing.

use fitroom_depth::{DepthFrame, HEIGHT, WIDTH, colour};
use fitroom_sensor::KinectJoint;
use glam::Vec3;

use crate::tracker::{Confidence, Tracked};

/// Depth range of the pictures, mm (near warm, far cool).
pub const NEAR_MM: u16 = 800;
pub const FAR_MM: u16 = 4000;

/// Colours: tracked, inferred, ground truth.
pub const TRACKED: [u8; 3] = [40, 220, 60];
pub const INFERRED: [u8; 3] = [250, 210, 40];
pub const TRUTH: [u8; 3] = [230, 40, 230];

/// The colour of a joint by its confidence (`None`: not drawn).
pub fn confidence_colour(c: Confidence) -> Option<[u8; 3]> {
    match c {
        Confidence::Tracked => Some(TRACKED),
        Confidence::Inferred => Some(INFERRED),
        Confidence::NotTracked => None,
    }
}

/// Draws the 20 joints at `pixels` and the bones between them into a 640x480 image of
/// `channels` bytes per pixel (3: RGB, 4: RGBA, alpha left as is). `colour` gives each
/// joint's colour, `None` to leave it (and its bones) out; a bone takes its child's colour.
pub fn draw_skeleton(
    image: &mut [u8],
    channels: usize,
    pixels: &[[f32; 2]],
    colour: impl Fn(usize) -> Option<[u8; 3]>,
) {
    let mut dot = |x: f32, y: f32, c: [u8; 3], r: i32| {
        if !(x.is_finite() && y.is_finite()) {
            return;
        }
        for dy in -r..=r {
            for dx in -r..=r {
                let (px, py) = (
                    x.round() as i64 + i64::from(dx),
                    y.round() as i64 + i64::from(dy),
                );
                if (0..WIDTH as i64).contains(&px) && (0..HEIGHT as i64).contains(&py) {
                    let k = (py as usize * WIDTH + px as usize) * channels;
                    if let Some(p) = image.get_mut(k..k + 3) {
                        p.copy_from_slice(&c);
                    }
                }
            }
        }
    };
    for joint in KinectJoint::ALL {
        let (Some(parent), Some(&b)) = (joint.parent(), pixels.get(joint.index())) else {
            continue;
        };
        let Some(&a) = pixels.get(parent.index()) else {
            continue;
        };
        let (Some(c), Some(_)) = (colour(joint.index()), colour(parent.index())) else {
            continue;
        };
        let steps = ((b[0] - a[0]).abs().max((b[1] - a[1]).abs()).ceil()).clamp(1.0, 2000.0);
        for s in 0..=steps as usize {
            let t = s as f32 / steps;
            dot(a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t, c, 1);
        }
    }
    for (k, p) in pixels.iter().enumerate() {
        if let Some(c) = colour(k) {
            dot(p[0], p[1], c, 3);
        }
    }
}

/// A frame as the evaluation shows it: depth colour-mapped, the person tinted pale (the rest
/// dimmed), the ground truth's skeleton (magenta, where given) and the tracked one (green: tracked,
/// yellow: inferred) drawn on it. RGB, 640x480.
pub fn picture(frame: &DepthFrame, tracked: Option<&Tracked>, truth: &[Vec3]) -> Vec<u8> {
    let mut rgb = Vec::new();
    colour::colourise(&frame.depth_mm, NEAR_MM, FAR_MM, &mut rgb);
    // The person pale; the rest dimmed and in coarse steps of colour (the room's noise is of
    // no interest here, and a picture of it compresses badly).
    let mask = tracked.map(|t| &t.person.mask);
    for (k, p) in rgb.chunks_exact_mut(3).enumerate() {
        let on_person = mask.is_some_and(|m| m.get(k).copied().unwrap_or(false));
        for c in p {
            *c = if on_person {
                ((u16::from(*c) + 255) / 2) as u8
            } else {
                (*c & 0xC0) / 2
            };
        }
    }
    let truth_pixels: Vec<[f32; 2]> = truth
        .iter()
        .map(|p| {
            frame
                .camera
                .project(*p)
                .map_or([f32::NAN; 2], |v| [v.x, v.y])
        })
        .collect();
    draw_skeleton(&mut rgb, 3, &truth_pixels, |_| Some(TRUTH));
    if let Some(t) = tracked {
        let pixels: Vec<[f32; 2]> = t.joints.iter().map(|j| j.pixel).collect();
        draw_skeleton(&mut rgb, 3, &pixels, |k| {
            confidence_colour(t.joints[k].confidence)
        });
    }
    rgb
}
