//! Segmentation against a recording's per-pixel ground truth: per frame, the precision and
//! recall of the person's mask (the body's and the garment's pixels with a reading) and the
//! count of the person's pixels missed; `AUDIT_FRAME=N`: frame N as a picture
//! (`/tmp/audit.ppm`: found grey, missed red, taken wrongly blue). The floor band takes the
//! soles, so a recall of about 0.99 is the most a standing person gives.
//!
//! `cargo run -p fitroom_tracker --no-default-features --release --example seg_audit -- DIR`
use std::path::PathBuf;

use fitroom_depth::DepthCamera;
use fitroom_depth::fakenect::Recording;
use fitroom_depth::truth::{FrameTruth, read_truth};
use fitroom_tracker::{SegmentSettings, Segmenter};

type Error = Box<dyn std::error::Error>;

fn main() -> Result<(), Error> {
    let dir = PathBuf::from(std::env::args().nth(1).ok_or("usage: seg_audit DIR")?);
    let recording = Recording::open(&dir)?;
    let truth = read_truth(&dir)?.ok_or("no ground truth")?;
    let mut segmenter = Segmenter::new(SegmentSettings::default());
    for (entry, line) in recording.depth_entries().zip(&truth) {
        let frame = recording.read_depth(entry, DepthCamera::default())?;
        let body = FrameTruth::mask(&line.body_runs);
        let garment = FrameTruth::mask(&line.garment_runs);
        let person: Vec<bool> = (0..body.len())
            .map(|k| (body[k] || garment.get(k).copied().unwrap_or(false)) && frame.depth_mm[k] > 0)
            .collect();
        let found = segmenter.segment(&frame);
        let mask = found
            .map(|s| s.mask)
            .unwrap_or_else(|| vec![false; person.len()]);
        let both = (0..person.len()).filter(|&k| mask[k] && person[k]).count() as f32;
        let ours = mask.iter().filter(|&&m| m).count() as f32;
        let theirs = person.iter().filter(|&&t| t).count() as f32;
        if std::env::var("AUDIT_FRAME")
            .ok()
            .and_then(|v| v.parse::<usize>().ok())
            == Some(line.frame)
        {
            let mut bytes = b"P6 640 480 255\n".to_vec();
            for k in 0..person.len() {
                let g = (f32::from(frame.depth_mm[k]) / 4000.0 * 120.0) as u8;
                bytes.extend(match (person[k], mask[k]) {
                    (true, true) => [200, 200, 200],
                    (true, false) => [255, 0, 0],
                    (false, true) => [0, 80, 255],
                    (false, false) => [g, g, g],
                });
            }
            std::fs::write("/tmp/audit.ppm", bytes)?;
        }
        println!(
            "{} {:.4} {:.4} {}",
            line.frame,
            both / ours.max(1.0),
            both / theirs.max(1.0),
            theirs - both
        );
    }
    Ok(())
}
