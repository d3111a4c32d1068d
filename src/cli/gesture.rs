//! `fitroom gesture`: training and evaluating the hand-state classifiers on synthetic hands.

use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use clap::Subcommand;
use fitroom_gesture::eval::swipes::{ClipFalseSwipes, SwipeRecall, false_swipes, swipe_recall};
use fitroom_gesture::eval::{BandScore, Sample, Sampling, TEST_SEEDS, film_samples, pooled, score};
use fitroom_gesture::hand::classify::{HandModel, train};
use fitroom_gesture::swipe::SwipeSettings;
use serde::Serialize;

use super::{BodyArg, OutputArgs};

#[derive(Subcommand)]
pub enum GestureCommand {
    /// Any depth recording (a fakenect dump) through the tracker and the hand reader: per
    /// frame, each hand's pixel, depth and state (open, closed, unknown).
    Run {
        #[arg(long)]
        dump: PathBuf,
        #[command(flatten)]
        body: BodyArg,
        #[command(flatten)]
        output: OutputArgs,
    },
    /// A picture of synthetic hands at 1-3.5 m, open and closed, with each method's call.
    Sheet {
        /// The PNG to write.
        #[arg(long)]
        out: PathBuf,
        /// Which held-out poses.
        #[arg(long, default_value_t = 0)]
        seed: u64,
        #[command(flatten)]
        body: BodyArg,
    },
    /// Train both hand-state methods (ours and the seed's threshold) on synthetic hands and
    /// write the model (the product's is assets/gesture/hands.ron).
    Train {
        #[command(flatten)]
        sampling: SamplingArgs,
        /// Where to write the model (RON).
        #[arg(long)]
        out: PathBuf,
        #[command(flatten)]
        body: BodyArg,
    },
    /// Hand-state accuracy per 0.5 m of distance, ours and the seed's, on held-out
    /// synthetic hands (seeds from 2^32 on; training uses seeds below).
    /// False actions through the whole chain: each clip drives the avatar the synthetic
    /// Kinect films (on a treadmill), the recording goes through the tracker and the kiosk's
    /// gesture reader; every swipe and grip is counted (nobody in the clips is clicking).
    DepthActions {
        /// Motion clips (BVH, .bvh.gz read as is).
        #[arg(long, default_value = "data/mocap/cmu")]
        clips: PathBuf,
        /// The avatar's distance from the sensor, metres.
        #[arg(long, default_value_t = 2.5)]
        distance_m: f32,
        #[command(flatten)]
        inputs: super::app::Inputs,
        #[command(flatten)]
        output: OutputArgs,
    },
    Eval {
        #[command(flatten)]
        sampling: SamplingArgs,
        /// The model to evaluate (default: the shipped one); with `--train`, train one on
        /// `--examples` training seeds first and evaluate that.
        #[arg(long)]
        model: Option<PathBuf>,
        #[arg(long)]
        train: bool,
        /// Scripted swipes for the swipe recall (held-out seeds).
        #[arg(long, default_value_t = 200)]
        swipes: usize,
        /// Motion clips where nobody swipes (BVH, .bvh.gz read as is), played
        /// `--repeats` times each with their own noise (every second one mirrored).
        #[arg(long, default_value = "data/mocap/cmu")]
        clips: PathBuf,
        #[arg(long, default_value_t = 7)]
        repeats: usize,
        #[command(flatten)]
        body: BodyArg,
        #[command(flatten)]
        output: OutputArgs,
    },
}

/// What to film.
#[derive(clap::Args, Clone, Copy, Debug)]
pub struct SamplingArgs {
    /// Synthetic hands filmed (1-3.5 m, either hand, open or closed, turned, tilted, any
    /// body).
    #[arg(long, default_value_t = 1000)]
    pub examples: usize,
    /// The error of the skeleton's hand, wrist and elbow joints, per axis, metres (the
    /// tracker's hands are 4-7 cm off in 3D).
    #[arg(long, default_value_t = 0.025)]
    pub joint_error_m: f32,
    /// Threads filming.
    #[arg(long, default_value_t = 2)]
    pub threads: usize,
}

impl SamplingArgs {
    fn sampling(&self, first_seed: u64) -> Result<Sampling> {
        if self.examples < 20 {
            bail!("--examples {}: at least 20 are needed", self.examples);
        }
        if !(0.0..=0.2).contains(&self.joint_error_m) {
            bail!(
                "--joint-error-m {}: expected 0 to 0.2 metres",
                self.joint_error_m
            );
        }
        let mut s = Sampling::new(self.examples, first_seed);
        s.joint_error_m = self.joint_error_m;
        Ok(s)
    }
}

/// The `gesture eval` report.
#[derive(Serialize)]
pub struct HandReport {
    pub sampling: Sampling,
    pub model_trained_on: String,
    pub bands: Vec<BandScore>,
    /// Share called right at 1.0-2.5 m (the acceptance range), ours and the seed's.
    pub ours_1_to_2_5_m: f32,
    pub seed_1_to_2_5_m: f32,
    pub seed_threshold: f32,
    pub swipe_recall: SwipeRecall,
    pub false_swipes: Vec<ClipFalseSwipes>,
    /// Swipes over the clips per 10 minutes (goal: at most 2).
    pub false_swipes_per_10_min: f64,
}

fn film(
    model: &fitroom_body::BodyModel,
    sampling: &Sampling,
    threads: usize,
    what: &str,
) -> Result<Vec<Sample>> {
    let bar = indicatif::ProgressBar::new(sampling.count as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template("{msg} [{bar:40}] {pos}/{len} ({eta})")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    bar.set_message(what.to_owned());
    let samples = film_samples(model, sampling, threads, &|n| bar.set_position(n as u64))
        .context("filming synthetic hands")?;
    bar.finish_and_clear();
    Ok(samples)
}

fn trained(model: &fitroom_body::BodyModel, args: &SamplingArgs) -> Result<HandModel> {
    let sampling = args.sampling(0)?;
    let samples = film(model, &sampling, args.threads, "training hands")?;
    let examples: Vec<_> = samples.iter().map(|s| s.example).collect();
    Ok(train(
        &examples,
        format!(
            "{} synthetic hands, seeds 0-{}, 1-3.5 m, joints off by {} m per axis",
            sampling.count,
            sampling.count - 1,
            sampling.joint_error_m
        ),
    ))
}

pub fn run(command: GestureCommand) -> Result<()> {
    match command {
        GestureCommand::DepthActions {
            clips,
            distance_m,
            inputs,
            output,
        } => {
            let files = clip_files(&clips)?;
            let body = inputs.body.clone();
            let report = super::gesture_depth::depth_actions(&files, &inputs, &body, distance_m)?;
            output.print(&report, |r| {
                for c in &r.clips {
                    println!(
                        "{:<14} {:>6.1} s  {} swipes  {} presses",
                        c.clip, c.seconds, c.swipes, c.presses
                    );
                }
                println!(
                    "{} swipes and {} presses in {:.1} min: {:.1} false actions per 10 min (goal: at most 2)",
                    r.swipes,
                    r.presses,
                    r.seconds / 60.0,
                    r.per_10_min
                );
            })
        }
        GestureCommand::Run { dump, body, output } => {
            let report = super::gesture_run::gesture_run(&dump, &body)?;
            output.print(&report, |r| {
                println!("{}: {} frames", r.dump, r.frames.len());
                for f in &r.frames {
                    let hands: Vec<String> = f
                        .hands
                        .iter()
                        .map(|h| format!("{:?} {:?} ({:.2})", h.hand, h.state, h.p_open))
                        .collect();
                    let event = match (f.swipe, f.click) {
                        (Some(s), _) => format!("  swipe {s:?}"),
                        (None, Some(c)) => format!("  {c:?}"),
                        (None, None) => String::new(),
                    };
                    println!(
                        "{:>5} {:>7.3} s  {}{event}",
                        f.frame,
                        f.time_s,
                        hands.join(", ")
                    );
                }
                println!(
                    "{:.1} s: {} swipes, {} presses",
                    r.seconds, r.swipes, r.presses
                );
            })
        }
        GestureCommand::Sheet { out, seed, body } => {
            let model = HandModel::embedded()?;
            super::gesture_sheet::hand_sheet(&body.load()?, &model, seed, &out)?;
            println!("wrote {}", out.display());
            Ok(())
        }
        GestureCommand::Train {
            sampling,
            out,
            body,
        } => {
            let model = trained(&body.load()?, &sampling)?;
            let text = ron::ser::to_string_pretty(&model, ron::ser::PrettyConfig::default())?;
            std::fs::write(&out, text + "\n")
                .with_context(|| format!("cannot write '{}'", out.display()))?;
            println!("wrote {} ({})", out.display(), model.trained_on);
            Ok(())
        }
        GestureCommand::Eval {
            sampling,
            model,
            train,
            swipes,
            clips,
            repeats,
            body,
            output,
        } => {
            let clip_files = clip_files(&clips)?;
            if repeats == 0 {
                bail!("--repeats 0: at least 1");
            }
            // The body, once: the hands, the training and the scripted swipes all film it.
            let body = body.load()?;
            let hand_model = match (model, train) {
                (Some(_), true) => bail!("--model and --train: give one"),
                (Some(path), false) => {
                    let text = std::fs::read_to_string(&path)
                        .with_context(|| format!("cannot read '{}'", path.display()))?;
                    HandModel::parse(&text, &path.display().to_string())?
                }
                (None, true) => trained(&body, &sampling)?,
                (None, false) => HandModel::embedded()?,
            };
            let test = sampling.sampling(TEST_SEEDS)?;
            let samples = film(&body, &test, sampling.threads, "held-out hands")?;
            let bands = score(&hand_model, &samples, &[1.0, 1.5, 2.0, 2.5, 3.0, 3.5]);
            let (ours, seed) = pooled(&bands, 1.0, 2.5);
            let settings = SwipeSettings::default();
            let recall =
                swipe_recall(&body, settings, swipes, TEST_SEEDS).context("scripting swipes")?;
            let mut per_clip = Vec::new();
            for file in &clip_files {
                per_clip.push(
                    false_swipes(file, settings, repeats, 11)
                        .with_context(|| format!("cannot play '{}'", file.display()))?,
                );
            }
            let seconds: f64 = per_clip.iter().map(|c| c.seconds).sum();
            let count: usize = per_clip.iter().map(|c| c.swipes).sum();
            let report = HandReport {
                sampling: test,
                model_trained_on: hand_model.trained_on.clone(),
                bands,
                ours_1_to_2_5_m: ours,
                seed_1_to_2_5_m: seed,
                seed_threshold: hand_model.seed_threshold,
                swipe_recall: recall,
                false_swipes: per_clip,
                false_swipes_per_10_min: count as f64 / seconds.max(1e-9) * 600.0,
            };
            output.print(&report, |r| {
                println!(
                    "hand state on {} held-out synthetic hands (joints off by {} m per axis)",
                    r.sampling.count, r.sampling.joint_error_m
                );
                println!(
                    "{:>10} {:>8} {:>8} {:>8} {:>8}",
                    "distance", "hands", "ours", "seed's", "unknown"
                );
                for b in &r.bands {
                    println!(
                        "{:>4.1}-{:<3.1} m {:>8} {:>7.1}% {:>7.1}% {:>7.1}%",
                        b.near_m,
                        b.far_m,
                        b.examples,
                        100.0 * b.ours,
                        100.0 * b.seed,
                        100.0 * b.ours_unknown
                    );
                }
                println!(
                    "1.0-2.5 m: ours {:.1} %, the seed's {:.1} % (goal: 95 %, ours better)",
                    100.0 * r.ours_1_to_2_5_m,
                    100.0 * r.seed_1_to_2_5_m
                );
                println!(
                    "swipes: {} of {} scripted found in their direction ({:.1} %; goal 95 %), \
                     {} the wrong way",
                    r.swipe_recall.found,
                    r.swipe_recall.scripted,
                    100.0 * r.swipe_recall.recall(),
                    r.swipe_recall.wrong_way
                );
                let minutes: f64 = r.false_swipes.iter().map(|c| c.seconds).sum::<f64>() / 60.0;
                println!(
                    "false swipes: {:.2} per 10 min over {} clips, {minutes:.1} min (goal: at most 2)",
                    r.false_swipes_per_10_min,
                    r.false_swipes.len()
                );
                for c in r.false_swipes.iter().filter(|c| c.swipes > 0) {
                    println!("  {}: {} in {:.0} s", c.clip, c.swipes, c.seconds);
                }
            })
        }
    }
}

/// The BVH clips in `dir` (`.bvh`, `.bvh.gz`), sorted.
fn clip_files(dir: &std::path::Path) -> Result<Vec<PathBuf>> {
    let entries = std::fs::read_dir(dir).with_context(|| {
        format!(
            "cannot read the clips folder '{}' (give one with --clips DIR)",
            dir.display()
        )
    })?;
    let mut files: Vec<PathBuf> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            let name = p.to_string_lossy();
            name.ends_with(".bvh") || name.ends_with(".bvh.gz")
        })
        .collect();
    files.sort();
    if files.is_empty() {
        bail!("no .bvh or .bvh.gz clip in '{}'", dir.display());
    }
    Ok(files)
}
