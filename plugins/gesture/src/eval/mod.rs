//! Evaluations on files and synthetic data: hand state on synthetic hands ([`hands`]),
//! swipes on scripted swipes and on the CMU clips, where nobody swipes ([`swipes`]).

pub mod hands;
pub mod swipes;

pub use hands::*;
