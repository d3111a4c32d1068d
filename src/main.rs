//! The `fitroom` command: the kiosk by default, headless runs, and the data tools
//! ([`fitroom::cli`]).

#![forbid(unsafe_code)]

use clap::Parser;

fn main() -> std::process::ExitCode {
    match fitroom::cli::run(fitroom::cli::Cli::parse()) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(error) => {
            eprintln!("error: {error:#}");
            std::process::ExitCode::FAILURE
        }
    }
}
