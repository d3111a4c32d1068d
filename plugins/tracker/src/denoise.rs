//! The sensor's depth noise averaged out before a fit to a single frame: a reading taken as
//! the mean of the person's readings about it on the same surface.
//!
//! Why: the Kinect v1's axial error grows with the square of the distance, 14 mm per reading
//! at 3 m ([`fitroom_depth::noise`]), as much as a forearm's curvature shows over its width,
//! and the fits of a body to single frames did not average it away: they came out small and
//! their joints in front. One recording (CMU 07_01, the small woman at 3 m) fitted by the
//! measurement's body fit from the tracker's frames, against her true girths (bust 81.0,
//! hip 87.6, thigh 53.1 cm): with the sensor's every error 78.8 / 81.2 / 46.8; without the
//! axial one 79.0 / 84.3 / 50.4; every reading the mean of a 5 x 5 window 80.8 / 85.2 / 51.4
//! (docs/STATUS.md, session 52). The tracker's own fit gained too: its trunk's joints,
//! tracked with the three acceptance bodies' true shapes, 10.4 / 15.1 / 13.4 -> 9.0 / 12.6 /
//! 11.3 mm.
//!
//! The window's mean leaves a smooth surface where it is: its slope averages out, and its
//! curvature moves the mean by under a millimetre (a 6 cm limb at 3 m: 0.45 mm forward over a
//! 5 x 5 window). Readings more than [`SAME_SURFACE_M`] from the centre's are another surface
//! (a hand before the chest, the wall past the body's edge) and are left out.

use fitroom_depth::{DepthFrame, HEIGHT, WIDTH};

/// A reading this far from the centre's is of another surface, metres.
pub const SAME_SURFACE_M: f32 = 0.04;

/// The mean depth of the person's readings in the square window `radius` pixels about pixel
/// (`x`, `y`) of `depth_mm` (row-major, [`WIDTH`] x [`HEIGHT`]) within [`SAME_SURFACE_M`] of
/// its own, metres; `None` where the pixel has no reading or lies outside the image. A
/// pixel is the person's where `mask` says so (a missing mask pixel: not the person's).
pub fn surface_depth_m(
    depth_mm: &[u16],
    mask: &[bool],
    x: usize,
    y: usize,
    radius: usize,
) -> Option<f32> {
    if x >= WIDTH || y >= HEIGHT {
        return None;
    }
    let centre = *depth_mm.get(y * WIDTH + x)?;
    if centre == 0 {
        return None;
    }
    let tolerance = (SAME_SURFACE_M * 1000.0) as u32;
    let (mut sum, mut count) = (0u32, 0u32);
    for yy in y.saturating_sub(radius)..=(y + radius).min(HEIGHT - 1) {
        let row = yy * WIDTH;
        for xx in x.saturating_sub(radius)..=(x + radius).min(WIDTH - 1) {
            let k = row + xx;
            let (Some(&mm), Some(true)) = (depth_mm.get(k), mask.get(k).copied()) else {
                continue;
            };
            if mm > 0 && u32::from(mm.abs_diff(centre)) <= tolerance {
                sum += u32::from(mm);
                count += 1;
            }
        }
    }
    // The centre counts even when the mask leaves it out (a caller asking about it).
    if count == 0 {
        return Some(f32::from(centre) / 1000.0);
    }
    Some(sum as f32 / count as f32 / 1000.0)
}

/// `frame` with each of the person's readings (`mask`) replaced by [`surface_depth_m`]
/// (rounded to the millimetre); the rest of the scene as it was, and no raw values. `radius`
/// 0: a copy.
pub fn denoised(frame: &DepthFrame, mask: &[bool], radius: usize) -> DepthFrame {
    if radius == 0 {
        return frame.clone();
    }
    let mut depth: Vec<u16> = frame.depth_mm.to_vec();
    for (i, out) in depth.iter_mut().enumerate() {
        if !mask.get(i).copied().unwrap_or(false) {
            continue;
        }
        if let Some(m) = surface_depth_m(&frame.depth_mm, mask, i % WIDTH, i / WIDTH, radius) {
            *out = (m * 1000.0).round() as u16;
        }
    }
    DepthFrame {
        depth_mm: depth.into(),
        // The device's raw values are what it read, not these.
        raw: None,
        ..frame.clone()
    }
}
