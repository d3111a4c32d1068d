//! `fitroom gesture`: training and evaluating the hand-state classifiers on synthetic hands.

use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use clap::Subcommand;
use fitroom_gesture::eval::{BandScore, Sample, Sampling, TEST_SEEDS, film_samples, pooled, score};
use fitroom_gesture::hand::classify::{HandModel, train};
use serde::Serialize;

use super::{BodyArg, OutputArgs};

#[derive(Subcommand)]
pub enum GestureCommand {
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
    Eval {
        #[command(flatten)]
        sampling: SamplingArgs,
        /// The model to evaluate (default: the shipped one); with `--train`, train one on
        /// `--examples` training seeds first and evaluate that.
        #[arg(long)]
        model: Option<PathBuf>,
        #[arg(long)]
        train: bool,
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
}

fn film(body: &BodyArg, sampling: &Sampling, threads: usize, what: &str) -> Result<Vec<Sample>> {
    let model = body.load()?;
    let bar = indicatif::ProgressBar::new(sampling.count as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template("{msg} [{bar:40}] {pos}/{len} ({eta})")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    bar.set_message(what.to_owned());
    let samples = film_samples(&model, sampling, threads, &|n| bar.set_position(n as u64))
        .context("filming synthetic hands")?;
    bar.finish_and_clear();
    Ok(samples)
}

fn trained(body: &BodyArg, args: &SamplingArgs) -> Result<HandModel> {
    let sampling = args.sampling(0)?;
    let samples = film(body, &sampling, args.threads, "training hands")?;
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
        GestureCommand::Train {
            sampling,
            out,
            body,
        } => {
            let model = trained(&body, &sampling)?;
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
            body,
            output,
        } => {
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
            let report = HandReport {
                sampling: test,
                model_trained_on: hand_model.trained_on.clone(),
                bands,
                ours_1_to_2_5_m: ours,
                seed_1_to_2_5_m: seed,
                seed_threshold: hand_model.seed_threshold,
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
            })
        }
    }
}
