//! The `fitroom` command line: the parser ([`Cli`]), one module per area with its clap
//! definitions and its implementation, and [`run`], which dispatches a parsed command.
//!
//! * [`app`]: the commands that build an App (`kiosk`, `design`, `run --headless`).
//! * [`sensor`], [`import`], [`body`], [`cloth`], [`motion`]: the data tools.

use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::{Parser, Subcommand};
use serde::Serialize;

pub mod app;
pub mod body;
pub mod cloth;
pub mod gesture;
pub mod gesture_depth;
pub mod gesture_run;
pub mod gesture_sheet;
pub mod import;
pub mod measure;
pub mod measure_dump;
pub mod measure_plot;
pub mod motion;
pub mod sensor;
pub mod track;

/// The `fitroom` command.
#[derive(Parser)]
#[command(
    name = "fitroom",
    version,
    about = "A virtual fitting room: a measured avatar mirrors you and wears simulated garments."
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Option<Command>,
}

#[derive(Subcommand)]
pub enum Command {
    /// The mirror kiosk (the default when no command is given).
    Kiosk(app::KioskArgs),
    /// The garment designer: the garment on the avatar in a window (orbit camera, poses,
    /// sizes, bodies, fit map); saving the garment or its fabric dresses the avatar again.
    Design(app::DesignArgs),
    /// Run the pipeline without a display server.
    Run(app::RunArgs),
    /// Sensor tools.
    Sensor {
        #[command(subcommand)]
        command: sensor::SensorCommand,
    },
    /// Convert source data into the product's assets.
    Import {
        #[command(subcommand)]
        command: import::ImportCommand,
    },
    /// Garments on the avatar without a window: simulation, fit map, speed.
    Cloth {
        #[command(subcommand)]
        command: cloth::ClothCommand,
    },
    /// Body tools.
    Body {
        #[command(subcommand)]
        command: body::BodyCommand,
    },
    /// Motion pipeline tools.
    Motion {
        #[command(subcommand)]
        command: motion::MotionCommand,
    },
    /// Seeing the person in depth recordings.
    Track {
        #[command(subcommand)]
        command: track::TrackCommand,
    },
    /// Measuring the person from depth.
    Measure {
        #[command(subcommand)]
        command: measure::MeasureCommand,
    },
    /// Hand gestures: the hand-state classifiers on synthetic hands.
    Gesture {
        #[command(subcommand)]
        command: gesture::GestureCommand,
    },
}

/// Runs a parsed command line (the kiosk when it names no command).
pub fn run(cli: Cli) -> Result<()> {
    let command = match cli.command {
        Some(command) => command,
        None => Cli::parse_from(["fitroom", "kiosk"])
            .command
            .context("the default command")?,
    };
    match command {
        Command::Kiosk(args) => app::kiosk(args),
        Command::Design(args) => app::design(args),
        Command::Run(args) => app::run_headless(args),
        Command::Sensor { command } => sensor::run(command),
        Command::Import { command } => import::run(command),
        Command::Cloth { command } => cloth::run(command),
        Command::Body { command } => body::run(command),
        Command::Motion { command } => motion::run(command),
        Command::Track { command } => track::run(command),
        Command::Measure { command } => measure::run(command),
        Command::Gesture { command } => gesture::run(command),
    }
}

/// `--body`: the converted body file.
#[derive(clap::Args, Clone, Debug, Default)]
pub struct BodyArg {
    /// Converted body file (default: assets/bodies/makehuman.fitbody).
    #[arg(long)]
    pub body: Option<PathBuf>,
}

impl BodyArg {
    /// The body file: `--body`, or the default body of the assets folder.
    pub fn path(&self) -> Result<PathBuf> {
        match &self.body {
            Some(path) => Ok(path.clone()),
            None => Ok(crate::assets::assets_dir()?.join(crate::assets::DEFAULT_BODY)),
        }
    }

    /// Reads the body model, with a hint on how to create it.
    pub fn load(&self) -> Result<fitroom_body::BodyModel> {
        let path = self.path()?;
        fitroom_body::BodyModel::read(&path).with_context(|| {
            format!(
                "cannot load the body '{}'; run `fitroom import makehuman DIR` (DIR: the \
                 MakeHuman data, e.g. MakeHuman's MPFB2 asset folder) to create it",
                path.display()
            )
        })
    }
}

/// `--json`: the report as JSON instead of text.
#[derive(clap::Args, Clone, Copy, Debug, Default)]
pub struct OutputArgs {
    /// Print the report as JSON.
    #[arg(long)]
    pub json: bool,
}

impl OutputArgs {
    /// Prints `report` as pretty JSON with `--json`, else as `text` prints it.
    pub fn print<T: Serialize>(&self, report: &T, text: impl FnOnce(&T)) -> Result<()> {
        if self.json {
            println!("{}", serde_json::to_string_pretty(report)?);
        } else {
            text(report);
        }
        Ok(())
    }

    /// [`Self::print`] with the JSON on one line.
    pub fn print_compact<T: Serialize>(&self, report: &T, text: impl FnOnce(&T)) -> Result<()> {
        if self.json {
            println!("{}", serde_json::to_string(report)?);
        } else {
            text(report);
        }
        Ok(())
    }
}

/// `--noise`: the recording as it is, or replayed through the Kinect v1 noise model.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Noise {
    /// The clean recording.
    None,
    /// The Kinect v1 noise model.
    Kinect,
}

/// Registers the plots' font (egui's Ubuntu Light, already a dependency) as "sans-serif";
/// every `--plot` calls it first.
pub fn plot_font() -> anyhow::Result<()> {
    plotters::style::register_font(
        "sans-serif",
        plotters::style::FontStyle::Normal,
        epaint_default_fonts::UBUNTU_LIGHT,
    )
    .map_err(|_| anyhow::anyhow!("cannot load the plot font"))
}

#[cfg(test)]
mod tests {
    use clap::CommandFactory;

    /// clap checks every subcommand's arguments (unique names, valid defaults) only when a
    /// command is parsed; this checks them all at once (a clash of the designer's garment
    /// with `--garment` once slipped through).
    #[test]
    fn every_command_line_is_well_formed() {
        super::Cli::command().debug_assert();
    }
}
