//! `fitroom sensor`: sensor tools.

use std::path::PathBuf;

use anyhow::Result;
use clap::Subcommand;

use super::OutputArgs;

#[derive(Subcommand)]
pub enum SensorCommand {
    /// Print a BVH clip's frame count, rate, duration, joints and skeleton kind.
    Inspect {
        file: PathBuf,
        #[command(flatten)]
        output: OutputArgs,
    },
}

pub fn run(command: SensorCommand) -> Result<()> {
    match command {
        SensorCommand::Inspect { file, output } => {
            let info = fitroom_sensor::bvh_source::inspect(&file)?;
            output.print_compact(&info, |info| {
                println!(
                    "{}: {} frames at {:.1} fps ({:.2} s), {} joints, skeleton {}",
                    file.display(),
                    info.frames,
                    info.fps,
                    info.duration_s,
                    info.joints,
                    info.skeleton
                );
            })
        }
    }
}
