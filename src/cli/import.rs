//! `fitroom import`: source data converted into the product's assets.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use clap::Subcommand;

#[derive(Subcommand)]
pub enum ImportCommand {
    /// MakeHuman data folder (the MPFB2 asset layout: `3dobjs/`, `targets/`, `rigs/`) to a
    /// .fitbody asset.
    Makehuman {
        dir: PathBuf,
        #[arg(long, default_value = "assets/bodies/makehuman.fitbody")]
        out: PathBuf,
    },
}

pub fn run(command: ImportCommand) -> Result<()> {
    match command {
        ImportCommand::Makehuman { dir, out } => import_makehuman(&dir, &out),
    }
}

/// `fitroom import makehuman`: imports, writes, and checks that the file reads back the same.
pub fn import_makehuman(dir: &Path, out: &Path) -> Result<()> {
    let bar = indicatif::ProgressBar::new(1);
    bar.set_style(
        indicatif::ProgressStyle::with_template("{msg:24} [{bar:40}] {pos}/{len}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    let start = std::time::Instant::now();
    let (model, report) =
        fitroom_body::import_makehuman_with_report(dir, &mut |stage, done, total| {
            bar.set_message(stage.to_string());
            bar.set_length(total as u64);
            bar.set_position(done as u64);
        })?;
    bar.finish_and_clear();
    let import_s = start.elapsed().as_secs_f64();
    if let Some(parent) = out.parent() {
        std::fs::create_dir_all(parent)
            .with_context(|| format!("cannot create '{}'", parent.display()))?;
    }
    model.write(out)?;
    let size = std::fs::metadata(out).map(|m| m.len()).unwrap_or(0);
    let start = std::time::Instant::now();
    let back = fitroom_body::BodyModel::read(out)?;
    if back != model {
        anyhow::bail!(
            "{}: the body read back differs from the one written",
            out.display()
        );
    }
    println!("{report:#?}");
    println!(
        "wrote {} ({:.1} MB): {} vertices ({} body), {} triangles, {} bones, {} morph targets; \
         import {import_s:.1} s, reads back identical in {:.2} s",
        out.display(),
        size as f64 / 1e6,
        model.positions.len(),
        model.body_vertex_count,
        model.triangles.len(),
        model.bones.len(),
        model.targets.len(),
        start.elapsed().as_secs_f64()
    );
    Ok(())
}
