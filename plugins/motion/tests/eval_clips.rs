//! Issue acceptance over all 15 shared CMU clips, with the Kinect v1 noise model (seed 1):
//! our filter against the Kinect SDK's Holt filter (default set) and the One Euro filter tuned
//! with its authors' procedure; foot skating and joint limits of the corrected output.

mod common;

use std::path::{Path, PathBuf};

use fitroom_motion::{
    AvatarSkeleton,
    eval::{EvalOptions, EvalReport, FilterChoice, evaluate_clip},
};

fn clips() -> Vec<PathBuf> {
    fitroom_testdata::cmu_index()
        .iter()
        .map(|c| c.path())
        .collect()
}

fn run(path: &Path, skeleton: &AvatarSkeleton, filter: &str) -> EvalReport {
    let options = EvalOptions {
        filter: filter.parse::<FilterChoice>().expect("filter name"),
        ..EvalOptions::default()
    };
    evaluate_clip(path, skeleton, &options)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .report
}

#[test]
fn our_filter_beats_holt_and_one_euro_and_the_output_is_clean() {
    let skeleton = common::skeleton();
    let mut wins = 0;
    let (mut skate_in, mut skate_out) = (0.0f32, 0.0f32);
    // The noisy Kinect skeleton's own foot points (before retargeting), for comparison.
    let mut skate_sensor = 0.0f32;
    let mut violations = 0;
    // Mean over the clips whose noisy input skates at all of output / input, and the skating
    // of the clean clip itself (retargeted without noise or correction).
    let (mut ratio_sum, mut ratio_clips, mut skate_clean) = (0.0f32, 0usize, 0.0f32);
    println!(
        "| clip | raw RMSE mm | holt RMSE / lag | 1€ tuned RMSE / lag | ours RMSE / lag | ours jitter m/s² (clean) | avatar skate in → out (clean clip) | foot correction mean / max mm | limit violations | µs/frame |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|");
    for path in clips() {
        let holt = run(&path, &skeleton, "holt");
        let euro = run(&path, &skeleton, "oneeuro-tuned");
        let ours = run(&path, &skeleton, "kalman");
        let clean = evaluate_clip(
            &path,
            &skeleton,
            &EvalOptions {
                noise: None,
                ..EvalOptions::default()
            },
        )
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .report;
        skate_clean += clean.avatar_foot_skate_input;
        if ours.avatar_foot_skate_input > 0.0 {
            ratio_sum += ours.avatar_foot_skate_output / ours.avatar_foot_skate_input;
            ratio_clips += 1;
        }
        let win = ours.output.rmse_mm < holt.output.rmse_mm
            && ours.output.rmse_mm < euro.output.rmse_mm
            && ours.output.lag_ms <= holt.output.lag_ms.max(euro.output.lag_ms) + 33.0;
        wins += usize::from(win);
        skate_in += ours.avatar_foot_skate_input;
        skate_sensor += ours.input.foot_skate_ratio as f32;
        skate_out += ours.avatar_foot_skate_output;
        violations += ours.joint_limit_violations;
        println!(
            "| {} | {:.1} | {:.1} / {:.0} | {:.1} / {:.0} | {:.1} / {:.0} | {:.1} ({:.1}) | {:.3} → {:.3} ({:.3}) | {:.0} / {:.0} | {} | {:.1} |{}",
            ours.clip,
            ours.input.rmse_mm,
            holt.output.rmse_mm,
            holt.output.lag_ms,
            euro.output.rmse_mm,
            euro.output.lag_ms,
            ours.output.rmse_mm,
            ours.output.lag_ms,
            ours.output.jitter_m_s2,
            ours.output.clean_jitter_m_s2,
            ours.avatar_foot_skate_input,
            ours.avatar_foot_skate_output,
            clean.avatar_foot_skate_input,
            ours.foot_correction_mean_mm,
            ours.foot_correction_max_mm,
            ours.joint_limit_violations,
            ours.pipeline_us_per_frame,
            if win { "" } else { " not better" }
        );
        assert!(ours.output.rmse_mm.is_finite() && ours.output.rmse_mm > 0.0);
    }
    println!(
        "ours better on {wins}/15 clips; avatar foot skating (mean over clips) {:.3} → {:.3} ({:.0}%); joint-limit violations {violations}",
        skate_in / 15.0,
        skate_out / 15.0,
        100.0 * skate_out / skate_in.max(1e-6)
    );
    println!(
        "output / input per clip, mean over the {ratio_clips} clips whose input skates: {:.0}%; \
         the clean clips themselves (retargeted, no noise, no correction) skate {:.3} ({:.0}% of \
         the noisy input's)",
        100.0 * ratio_sum / ratio_clips.max(1) as f32,
        skate_clean / 15.0,
        100.0 * skate_clean / skate_in.max(1e-6)
    );
    println!(
        "the noisy Kinect skeleton's own foot points skate {:.3}; the output is {:.0}% of that",
        skate_sensor / 15.0,
        100.0 * skate_out / skate_sensor.max(1e-6)
    );
    assert!(wins >= 12, "our filter is better on only {wins}/15 clips");
    // The line: the corrected output skates at most 20% as much as the noisy input
    // (mean ratio over the clips).
    assert!(
        skate_out <= 0.2 * skate_in,
        "foot skating {skate_in} -> {skate_out}: more than 20% of the input's remains"
    );
    assert_eq!(violations, 0, "joint-limit violations in the output");
}
