//! Small Bevy-free numerics shared by fitroom's crates and its CLI.

#![forbid(unsafe_code)]

pub mod stats;
