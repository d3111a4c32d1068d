//! The tracker tells a shirt from skin: `fitroom track eval` renders a person moving (a build
//! and seeds the acceptance set does not have) in the shipped T-shirt, simulated as it moves,
//! and bare; the build the tracker finds wears its clothing layer in the shirt and not on bare
//! skin. The sleeves' ends tell (`fitroom_tracker::sleeve`: a step of 20 mm or more in the
//! hanging upper arms' outline, against under 10 mm on bare arms); the body fit's own cost
//! decides only when they do not (`fitroom_tracker::shape::estimate_with`).

mod common;

use std::process::Command;

/// `fitroom track eval` of `clip` rendered on the fly (`frames` frames, noise seed `seed`) on
/// a build of its own, wearing `garment` if given: the recording's report.
fn tracked(clip: &str, frames: u32, seed: u64, garment: Option<&str>) -> serde_json::Value {
    let shape = std::env::temp_dir().join(format!(
        "fitroom-track-clothing-{}-{clip}-{seed}-{}.ron",
        std::process::id(),
        garment.is_some()
    ));
    // Neither of the acceptance set's men: a little lighter, more muscular.
    std::fs::write(
        &shape,
        "(gender: 0.9, weight: 0.6, muscle: 0.55, height: 0.5)",
    )
    .expect("a shape file");
    let mut run = Command::new(env!("CARGO_BIN_EXE_fitroom"));
    run.args(["track", "eval", "--json", "--motion"])
        .arg(fitroom_testdata::clip_path(clip))
        .args(["--frames", &frames.to_string(), "--seed", &seed.to_string()])
        .arg("--shape")
        .arg(&shape)
        .current_dir(env!("CARGO_MANIFEST_DIR"));
    if let Some(g) = garment {
        run.args(["--garment", g]);
    }
    let out = run.output().expect("fitroom runs");
    let _ = std::fs::remove_file(&shape);
    common::assert_succeeded(&out, format!("track eval {clip} {garment:?}"));
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).expect("a JSON report");
    report["recordings"][0].clone()
}

#[test]
fn the_build_wears_the_clothing_layer_in_a_shirt_and_not_bare() {
    const SHIRT: &str = "assets/garments/tshirt.ron";
    let runs = [
        ("07_01.bvh", 5, Some(SHIRT)),
        ("14_19.bvh", 11, Some(SHIRT)),
        ("08_04.bvh", 7, Some(SHIRT)),
        ("02_01.bvh", 3, Some(SHIRT)),
        ("07_01.bvh", 5, None),
        ("08_04.bvh", 7, None),
    ];
    // Two at a time (each run is one process).
    let reports: Vec<serde_json::Value> = runs
        .chunks(2)
        .flat_map(|pair| {
            std::thread::scope(|scope| {
                let handles: Vec<_> = pair
                    .iter()
                    .map(|&(clip, seed, garment)| {
                        scope.spawn(move || tracked(clip, 60, seed, garment))
                    })
                    .collect();
                handles
                    .into_iter()
                    .map(|h| h.join().expect("a run"))
                    .collect::<Vec<_>>()
            })
        })
        .collect();
    let (mut told, mut shirts) = (0, 0);
    for (&(clip, _, garment), r) in runs.iter().zip(&reports) {
        let layer_cm = r["clothing_cm"]
            .as_f64()
            .unwrap_or_else(|| panic!("{clip}: no build found: {r}"));
        let step_mm = r["sleeve_step_mm"].as_f64();
        let step = step_mm.map_or("none".to_string(), |s| format!("{s:.0} mm"));
        println!(
            "{clip} {}: sleeve step {step}, layer {layer_cm:.1} cm, trunk {:.1} mm",
            if garment.is_some() {
                "in the T-shirt"
            } else {
                "bare"
            },
            r["trunk_mean_mm"].as_f64().unwrap_or(f64::NAN)
        );
        if garment.is_some() {
            shirts += 1;
            told += usize::from(layer_cm > 0.0);
            assert!(
                step_mm.is_some_and(|s| s >= 20.0),
                "{clip}: the sleeves' ends not seen: {r}"
            );
        } else {
            assert!(
                step_mm.is_some_and(|s| s < 10.0),
                "{clip}: bare arms taken for sleeves: {r}"
            );
            assert_eq!(layer_cm, 0.0, "{clip}: bare skin taken for a shirt: {r}");
        }
    }
    assert_eq!(told, shirts, "the shirt told in {told} of {shirts} runs");
}
