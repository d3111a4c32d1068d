//! Development loop for the body-part forest:
//!
//! * `parts train OUT.forest [IMAGES] [SEED]`: grows the forest on IMAGES synthetic images;
//! * `parts test FOREST [IMAGES] [SEED]`: per-pixel accuracy and joint proposals' errors on
//!   other synthetic images (another seed);
//! * `parts dump FOREST DIR...`: joint proposals' errors on recordings with ground truth.
//!
//! `cargo run -p fitroom_tracker --no-default-features --release --example parts -- ...`

use std::path::Path;

use fitroom_body::BodyModel;
use fitroom_depth::fakenect::Recording;
use fitroom_depth::truth::read_truth;
use fitroom_depth::{DepthCamera, DepthFrame, HEIGHT, WIDTH};
use fitroom_tracker::Segmenter;
use fitroom_tracker::bodyparts::forest::DepthImage;
use fitroom_tracker::bodyparts::synth::{LabelledImage, Synth};
use fitroom_tracker::bodyparts::train::{TrainSettings, train};
use fitroom_tracker::bodyparts::{Forest, PARTS, PartScratch, Proposal, ProposalSettings, propose};
use glam::Vec3;

type Error = Box<dyn std::error::Error>;

fn model() -> Result<BodyModel, Error> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/bodies/makehuman.fitbody");
    Ok(BodyModel::read(&path)?)
}

fn images(model: &BodyModel, n: usize, seed: u64) -> Vec<LabelledImage> {
    let mut synth = Synth::new(model, 24, seed);
    let mut out = Vec::with_capacity(n);
    while out.len() < n {
        if let Some(i) = synth.next_image() {
            out.push(i);
            if out.len() % 100 == 0 {
                eprintln!("{} images", out.len());
            }
        }
    }
    out
}

fn arg<T: std::str::FromStr>(k: usize, default: T) -> T {
    std::env::args()
        .nth(k)
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

fn env(key: &str) -> Option<f32> {
    std::env::var(key).ok().and_then(|v| v.parse().ok())
}

fn main() -> Result<(), Error> {
    let cmd = std::env::args()
        .nth(1)
        .ok_or("usage: parts train|test|dump ...")?;
    let path = std::env::args().nth(2).ok_or("a forest path")?;
    let mut ps = ProposalSettings::default();
    if let Some(v) = env("STEP") {
        ps.step = v as usize;
    }
    if let Some(v) = env("MINP") {
        ps.min_probability = v;
    }
    if let Some(v) = env("BAND") {
        ps.bandwidth_m = v;
    }
    if let Some(v) = env("PUSH") {
        ps.push_m = v;
    }
    match cmd.as_str() {
        "train" => {
            let model = model()?;
            let t0 = std::time::Instant::now();
            let imgs = images(&model, arg(3, 1000), arg(4, 1));
            eprintln!("images: {:.1} s", t0.elapsed().as_secs_f64());
            let mut s = TrainSettings::default();
            if let Some(v) = env("DEPTH") {
                s.max_depth = v as usize;
            }
            if let Some(v) = env("TREES") {
                s.trees = v as usize;
            }
            if let Some(v) = env("PPI") {
                s.pixels_per_image = v as usize;
            }
            if let Some(v) = env("FEATS") {
                s.features = v as usize;
            }
            if let Some(v) = env("MINPIX") {
                s.min_pixels = v as usize;
            }
            let t1 = std::time::Instant::now();
            let forest = train(&imgs, PARTS, s);
            eprintln!(
                "trained: {:.1} s, nodes {:?}",
                t1.elapsed().as_secs_f64(),
                forest
                    .trees
                    .iter()
                    .map(|t| t.nodes.len())
                    .collect::<Vec<_>>()
            );
            let mut f = std::fs::File::create(&path)?;
            forest.write(&mut f)?;
        }
        "test" => {
            let forest = Forest::read(&mut std::fs::File::open(&path)?)?;
            let model = model()?;
            let imgs = images(&model, arg(3, 200), arg(4, 99));
            let (mut right, mut all) = (0usize, 0usize);
            let mut confusion = vec![[0usize; PARTS]; PARTS];
            let mut errs: Vec<Vec<f32>> = vec![Vec::new(); PARTS];
            let mut scratch = PartScratch::default();
            for img in &imgs {
                let view = DepthImage {
                    metres: &img.metres,
                    width: img.width,
                    height: img.height,
                };
                let mut probs = vec![0f32; PARTS];
                for &(x, y, part) in &img.pixels {
                    probs.fill(0.0);
                    let d = view.at(i32::from(x), i32::from(y));
                    forest.classify_into(&view, i32::from(x), i32::from(y), d, &mut probs);
                    let best = (0..PARTS)
                        .max_by(|&a, &b| probs[a].total_cmp(&probs[b]))
                        .unwrap_or(0);
                    right += usize::from(best == usize::from(part));
                    all += 1;
                    confusion[usize::from(part)][best] += 1;
                }
                // The full frame for proposals.
                let (frame, mask) = full_frame(img);
                for p in propose(&forest, &frame, &mask, ps, &mut scratch) {
                    errs[p.joint].push(p.position.distance(img.joints[p.joint]));
                }
            }
            println!(
                "per-pixel accuracy {:.3} ({all} pixels)",
                right as f64 / all as f64
            );
            for (part, row) in confusion.iter().enumerate() {
                let n: usize = row.iter().sum();
                let e = &mut errs[part];
                e.sort_by(f32::total_cmp);
                println!(
                    "part {part:>2}: recall {:.2}  proposals {:>4} median {:>4.0} mm, within 10 cm {:.2}",
                    row[part] as f64 / n.max(1) as f64,
                    e.len(),
                    e.get(e.len() / 2).copied().unwrap_or(f32::NAN) * 1000.0,
                    e.iter().filter(|&&v| v < 0.1).count() as f64 / e.len().max(1) as f64
                );
            }
        }
        "dump" => {
            let forest = Forest::read(&mut std::fs::File::open(&path)?)?;
            let mut errs: Vec<Vec<f32>> = vec![Vec::new(); PARTS];
            let mut scratch = PartScratch::default();
            let mut frames = 0usize;
            for dir in std::env::args().skip(3) {
                let dir = Path::new(&dir);
                let recording = Recording::open(dir)?;
                let truth = read_truth(dir)?.ok_or("no ground truth")?;
                let mut seg = Segmenter::new(fitroom_tracker::SegmentSettings::default());
                for (entry, line) in recording.depth_entries().zip(&truth) {
                    let frame = recording.read_depth(entry, DepthCamera::default())?;
                    let Some(s) = seg.segment(&frame) else {
                        continue;
                    };
                    frames += 1;
                    let props: Vec<Proposal> = propose(&forest, &frame, &s.mask, ps, &mut scratch);
                    for p in props {
                        let g = Vec3::from_array(line.joints[p.joint]);
                        errs[p.joint].push(p.position.distance(g));
                    }
                }
            }
            println!("{frames} frames");
            let mut all: Vec<f32> = Vec::new();
            for (part, e) in errs.iter_mut().enumerate() {
                e.sort_by(f32::total_cmp);
                all.extend(e.iter());
                println!(
                    "joint {part:>2}: proposals {:>5} median {:>4.0} mm, within 10 cm {:.2}, within 20 cm {:.2}",
                    e.len(),
                    e.get(e.len() / 2).copied().unwrap_or(f32::NAN) * 1000.0,
                    e.iter().filter(|&&v| v < 0.1).count() as f64 / e.len().max(1) as f64,
                    e.iter().filter(|&&v| v < 0.2).count() as f64 / e.len().max(1) as f64
                );
            }
            all.sort_by(f32::total_cmp);
            println!(
                "all: median {:.0} mm, within 10 cm {:.2}",
                all.get(all.len() / 2).copied().unwrap_or(f32::NAN) * 1000.0,
                all.iter().filter(|&&v| v < 0.1).count() as f64 / all.len().max(1) as f64
            );
        }
        _ => return Err("usage: parts train|test|dump ...".into()),
    }
    Ok(())
}

/// A labelled image back in a full frame (its readings, the rest no reading) and its mask.
fn full_frame(img: &LabelledImage) -> (DepthFrame, Vec<bool>) {
    let mut mm = vec![0u16; WIDTH * HEIGHT];
    let mut mask = vec![false; WIDTH * HEIGHT];
    for y in 0..img.height {
        for x in 0..img.width {
            let m = img.metres[y * img.width + x];
            if m < fitroom_tracker::bodyparts::forest::BACKGROUND_M {
                let k = (y + img.y0) * WIDTH + x + img.x0;
                mm[k] = (m * 1000.0).round() as u16;
                mask[k] = true;
            }
        }
    }
    let frame = DepthFrame {
        depth_mm: mm.into(),
        raw: None,
        rgb: None,
        time_s: 0.0,
        timestamp: 0,
        camera: DepthCamera::default(),
    };
    (frame, mask)
}
