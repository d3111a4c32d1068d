//! `fitroom gesture sheet`: a picture of synthetic hands, open above and closed below, at
//! 1-3.5 m as the Kinect v1 sees them (depth, near is bright), the region our method reads
//! tinted, and each method's call.

use std::path::Path;

use anyhow::{Context, Result};
use fitroom_body::BodyModel;
use fitroom_depth::synthetic::NoiseSettings;
use fitroom_depth::{HEIGHT, WIDTH};
use fitroom_gesture::eval::{TEST_SEEDS, hand_joints};
use fitroom_gesture::hand::classify::{HandModel, look};
use fitroom_gesture::hand::region::hand_region;
use fitroom_gesture::hand::seed::seed_score;
use fitroom_gesture::synth::{HandPose, HandStudio};
use fitroom_gesture::{HandSide, HandState};

const TILE: u32 = 200;
const LABEL: u32 = 44;
const DISTANCES: [f32; 6] = [1.0, 1.5, 2.0, 2.5, 3.0, 3.5];

/// Draws the sheet to `out` (PNG) with `model`'s classifier; the poses from held-out seeds.
pub fn hand_sheet(body: &BodyModel, model: &HandModel, seed: u64, out: &Path) -> Result<()> {
    use plotters::prelude::*;
    let studio = HandStudio::new(body, NoiseSettings::default());
    let (w, h) = (TILE * DISTANCES.len() as u32, 2 * (TILE + LABEL) + 40);
    let mut buf = vec![30u8; (w * h * 3) as usize];
    let mut labels = Vec::new();
    for (col, &d) in DISTANCES.iter().enumerate() {
        for (row, state) in [HandState::Open, HandState::Closed].into_iter().enumerate() {
            let mut pose = HandPose::drawn(TEST_SEEDS + seed + col as u64, d);
            pose.state = state;
            pose.curl = if state == HandState::Open { 0.05 } else { 0.95 };
            let shot = studio
                .film(&pose, seed + col as u64)
                .context("filming a hand")?;
            let mut rng = 1;
            let joints = hand_joints(&shot.joints, pose.side, 0.0, &mut rng);
            let region = hand_region(&shot.frame, &joints);
            let ours = look(&shot.frame, &joints, model);
            let seed_call = seed_score(&shot.frame, &joints).map(|s| s > model.seed_threshold);
            let inside: std::collections::HashSet<(u16, u16)> = region
                .map(|r| r.pixels.into_iter().collect())
                .unwrap_or_default();
            let Some(centre) = shot.frame.camera.project(joints.hand) else {
                continue;
            };
            // 0.4 m of the scene across the tile.
            let span_px = 0.4 * shot.frame.camera.fx / joints.hand.z;
            let (x0, y0) = (col as u32 * TILE, 40 + row as u32 * (TILE + LABEL));
            for ty in 0..TILE {
                for tx in 0..TILE {
                    let u = (centre.x + (tx as f32 / TILE as f32 - 0.5) * span_px).round();
                    let v = (centre.y + (ty as f32 / TILE as f32 - 0.5) * span_px).round();
                    let mut rgb = [0u8, 0, 0];
                    if u >= 0.0 && v >= 0.0 && (u as usize) < WIDTH && (v as usize) < HEIGHT {
                        let (u, v) = (u as usize, v as usize);
                        let mm = shot.frame.depth_mm[v * WIDTH + u];
                        if mm > 0 {
                            let z = f32::from(mm) * 1e-3;
                            let g = (230.0 - (z - joints.hand.z + 0.1) / 0.6 * 200.0)
                                .clamp(30.0, 230.0) as u8;
                            rgb = [g, g, g];
                            if inside.contains(&(u as u16, v as u16)) {
                                rgb = [g / 2, (g as f32 * 0.75) as u8, g];
                            }
                        }
                    }
                    let k = (((y0 + ty) * w + x0 + tx) * 3) as usize;
                    buf[k..k + 3].copy_from_slice(&rgb);
                }
            }
            let call = |s: HandState| match s {
                HandState::Open => "open",
                HandState::Closed => "closed",
                HandState::Unknown => "unknown",
            };
            let seed_text = match seed_call {
                Some(true) => "open",
                Some(false) => "closed",
                None => "unknown",
            };
            let side = match pose.side {
                HandSide::Left => "left",
                HandSide::Right => "right",
            };
            labels.push((
                x0 + 6,
                y0 + TILE + 4,
                format!("ours: {} ({:.2})", call(ours.state), ours.p_open),
                ours.state == state,
            ));
            labels.push((
                x0 + 6,
                y0 + TILE + 22,
                format!("seed's: {seed_text} · {side}, {d:.1} m"),
                seed_call == Some(state == HandState::Open),
            ));
        }
    }
    crate::cli::plot_font()?;
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        let draw = |e: DrawingAreaErrorKind<_>| anyhow::anyhow!("cannot draw the sheet: {e:?}");
        root.draw(&Text::new(
            "Synthetic hands through the Kinect v1 model (held-out seeds): open above, closed below; ours reads the tinted region",
            (8, 10),
            ("sans-serif", 18).into_font().color(&WHITE),
        ))
        .map_err(draw)?;
        for (x, y, text, right) in labels {
            let colour = if right {
                RGBColor(150, 220, 150)
            } else {
                RGBColor(240, 120, 100)
            };
            root.draw(&Text::new(
                text,
                (x as i32, y as i32),
                ("sans-serif", 15).into_font().color(&colour),
            ))
            .map_err(draw)?;
        }
        root.present().map_err(draw)?;
    }
    image::RgbImage::from_raw(w, h, buf)
        .context("the sheet's pixels")?
        .save(out)
        .with_context(|| format!("cannot write '{}'", out.display()))?;
    Ok(())
}
