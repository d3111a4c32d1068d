//! The robustness acceptance on the avatar: garments through 10,000 frames of the
//! committed walking clips (their 120 Hz frames, one cloth step each, the clips looping, which
//! teleports the body back to its start): no NaN, no simulated particle more than 5 mm inside
//! a body collider after a step, no tether past 110 %, no blow-up reset. The figures are
//! printed per clip. The dress and the T-shirt walk all six clips (10,000 frames each), the
//! skirt two.

mod common;

use std::path::PathBuf;

fn walking_clips() -> Vec<(PathBuf, usize)> {
    fitroom_testdata::cmu_index()
        .into_iter()
        .filter(|c| c.description.starts_with("walk") || c.description.starts_with("slow walk"))
        .map(|c| (c.path(), c.frames))
        .collect()
}

#[test]
fn garments_survive_ten_thousand_frames_of_walking() {
    let model = fitroom_body::BodyModel::read(
        &fitroom::assets::assets_dir()
            .expect("assets")
            .join(fitroom::assets::DEFAULT_BODY),
    )
    .expect("body");
    let garments = fitroom::assets::assets_dir()
        .expect("assets")
        .join("garments");
    let clips = walking_clips();
    assert!(clips.len() >= 5, "{clips:?}");
    let total: usize = clips.iter().map(|c| c.1).sum();
    // Loop the clips until 10,000 of their frames (120 Hz) have been stepped: a 30 Hz video
    // frame is four cloth steps.
    let loops = 10_000usize.div_ceil(total);
    let mut steps = 0;
    let mut tshirt_steps = 0;
    for (garment, clips_for) in [
        ("sundress.ron", clips.clone()),
        ("tshirt.ron", clips.clone()),
        ("skirt.ron", clips[..2].to_vec()),
    ] {
        for (clip, frames_120) in &clips_for {
            let frames = (frames_120 * loops).div_ceil(4) + 1;
            let (r, _, _) = fitroom::cli::cloth::sim(
                &model,
                &fitroom_body::Shape::default(),
                &garments.join(garment),
                None,
                clip,
                frames,
                None,
            )
            .unwrap_or_else(|e| panic!("{garment} on {}: {e:#}", clip.display()));
            println!(
                "{garment} on {}: {} steps, penetration {:.2} mm, tether {:.3}, strain at the end p95 {:.1}% max {:.1}%, resets {}, step {:.2} ms",
                clip.display(),
                r.steps,
                r.max_penetration_mm,
                r.max_tether_ratio,
                r.final_strain_pct.p95,
                r.final_strain_pct.max,
                r.resets,
                r.step_ms.mean
            );
            if garment == "sundress.ron" {
                steps += r.steps;
            }
            if garment == "tshirt.ron" {
                tshirt_steps += r.steps;
            }
            assert!(r.all_finite, "{garment} {}: NaN", clip.display());
            assert!(
                r.max_penetration_mm <= 5.0,
                "{garment} {}: {} mm inside",
                clip.display(),
                r.max_penetration_mm
            );
            assert!(
                r.max_tether_ratio <= 1.1,
                "{garment} {}: tether at {}",
                clip.display(),
                r.max_tether_ratio
            );
            assert!(
                r.resets == 0,
                "{garment} {}: {} resets, first {:?}",
                clip.display(),
                r.resets,
                r.first_blow_up
            );
        }
    }
    assert!(steps >= 10_000, "only {steps} steps of the dress");
    assert!(
        tshirt_steps >= 10_000,
        "only {tshirt_steps} steps of the T-shirt"
    );
}
