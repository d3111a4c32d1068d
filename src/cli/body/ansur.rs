//! `fitroom body ansur`: the fit evaluated on ANSUR II subjects.

use std::{
    fmt::Write as _,
    path::{Path, PathBuf},
};

use anyhow::{Context, Result};
use fitroom_body::{BodyModel, FitOptions, ansur::AnsurReport};

use crate::cli::BodyArg;

/// `fitroom body ansur`.
#[derive(clap::Args)]
pub struct AnsurArgs {
    /// The folder with ANSUR_II_FEMALE_Public.csv and ANSUR_II_MALE_Public.csv (or their
    /// `.csv.gz`); by default the copy committed in the repository's `data/ansur2`.
    #[arg(long, default_value = concat!(env!("CARGO_MANIFEST_DIR"), "/data/ansur2"))]
    pub data: PathBuf,
    /// Subjects per sex (a seeded random sample); all 6,068 when absent.
    #[arg(long)]
    pub per_sex: Option<usize>,
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    #[arg(long, default_value_t = 2)]
    pub threads: usize,
    /// Write the whole report (every subject) as JSON here.
    #[arg(long)]
    pub report: Option<PathBuf>,
    /// Write the summary (Markdown) here.
    #[arg(long)]
    pub summary: Option<PathBuf>,
    #[command(flatten)]
    pub body: BodyArg,
}

/// Fits, writes the report and summary if asked, and prints the summary.
pub fn run(args: AnsurArgs) -> Result<()> {
    let AnsurArgs {
        data,
        per_sex,
        seed,
        threads,
        report,
        summary,
        body,
    } = args;
    let model = body.load()?;
    let r = ansur(&model, &data, per_sex, seed, threads)?;
    let title = match per_sex {
        Some(n) => format!("ANSUR II, {n} random subjects per sex (seed {seed})"),
        None => "ANSUR II, all subjects".to_owned(),
    };
    let md = ansur_markdown(&r, &title);
    if let Some(path) = report {
        std::fs::write(&path, serde_json::to_string_pretty(&r)?)
            .with_context(|| format!("cannot write the report '{}'", path.display()))?;
    }
    if let Some(path) = summary {
        std::fs::write(&path, &md)
            .with_context(|| format!("cannot write the summary '{}'", path.display()))?;
    }
    print!("{md}");
    Ok(())
}

/// `fitroom body ansur`: fits ANSUR II subjects and summarises the errors.
pub fn ansur(
    model: &BodyModel,
    data: &Path,
    per_sex: Option<usize>,
    seed: u64,
    threads: usize,
) -> Result<AnsurReport> {
    let mut subjects = Vec::new();
    for all in fitroom_body::ansur::read_survey(data)? {
        subjects.extend(match per_sex {
            Some(n) => fitroom_body::ansur::sample(&all, n, seed),
            None => all,
        });
    }
    let bar = indicatif::ProgressBar::new(subjects.len() as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "fitting {pos}/{len} [{bar:40}] {per_sec} eta {eta}",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    let report = fitroom_body::ansur::evaluate(
        model,
        &subjects,
        &FitOptions::default(),
        threads,
        &|done, _| bar.set_position(done as u64),
    );
    bar.finish_and_clear();
    Ok(report)
}

/// The report of `fitroom body ansur` as Markdown (without the per-subject list).
pub fn ansur_markdown(r: &AnsurReport, title: &str) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "### {title}\n\n{} subjects, {} (subject, measurement) pairs: **{:.1}%** within ±{} cm; \
         {} subjects with every measurement within; {} failed fits; fit time mean {:.0} ms, \
         max {:.0} ms.\n",
        r.subjects,
        r.pairs,
        100.0 * r.pairs_within_tolerance,
        r.tolerance_cm,
        r.subjects_reachable,
        r.failed_fits,
        r.mean_fit_ms,
        r.max_fit_ms
    );
    let _ = writeln!(
        s,
        "| measure | within ±{} cm | median abs cm | p90 | p95 | max | bias cm |\n|---|---|---|---|---|---|---|",
        r.tolerance_cm
    );
    for m in &r.per_measure {
        let _ = writeln!(
            s,
            "| {} | {:.1}% | {:.2} | {:.2} | {:.2} | {:.1} | {:+.2} |",
            m.measure.name(),
            100.0 * m.within_tolerance,
            m.median_abs_cm,
            m.p90_abs_cm,
            m.p95_abs_cm,
            m.max_abs_cm,
            m.bias_cm
        );
    }
    let _ = writeln!(s, "\n|abs error| histogram (cm: pairs): {}", {
        r.histogram_abs_cm
            .iter()
            .map(|(b, c)| {
                if *b >= 2.0 {
                    format!(">2.0: {c}")
                } else {
                    format!("{b:.1}: {c}")
                }
            })
            .collect::<Vec<_>>()
            .join(", ")
    });
    s
}
