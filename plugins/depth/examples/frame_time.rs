//! The synthetic frame's time on this noisy host: the shipped body at 2.5 m in the room (the
//! criterion bench's scene), rendered `N` times (default 600) on the calling thread; prints
//! the fastest, the 10th percentile and the median. Other work on the machine only ever adds
//! time, so the fastest frames compare two builds better than a mean does.
//!
//! Run: `taskset -c 0 cargo run --release -p fitroom_depth --no-default-features --example
//! frame_time [N]`.

#[path = "../benches/common/mod.rs"]
mod common;

use std::time::Instant;

use fitroom_depth::DepthCamera;
use fitroom_depth::synthetic::{NoiseSettings, SyntheticCamera};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let frames: usize = match std::env::args().nth(1) {
        Some(n) => n.parse()?,
        None => 600,
    };
    let scene = common::avatar_scene()?;
    let mut camera = SyntheticCamera::new(DepthCamera::default(), NoiseSettings::default(), 1);
    let mut times: Vec<f64> = (0..frames.max(1))
        .map(|_| {
            let start = Instant::now();
            std::hint::black_box(camera.render(&scene, 0.0));
            start.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    times.sort_by(f64::total_cmp);
    let at = |q: f64| times[((times.len() - 1) as f64 * q) as usize];
    println!(
        "{} frames: fastest {:.3} ms, p10 {:.3} ms, median {:.3} ms",
        times.len(),
        at(0.0),
        at(0.1),
        at(0.5)
    );
    Ok(())
}
