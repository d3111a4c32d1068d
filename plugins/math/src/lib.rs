//! Small Bevy-free numerics shared by fitroom's crates and its CLI: summary statistics, the
//! rigid transform, the round-cone distance, the spatial grid, the small dense Cholesky solve and the parallel map. Each is defined here once.

#![forbid(unsafe_code)]

pub mod geometry;
pub mod grid;
pub mod linear;
pub mod parallel;
pub mod rigid;
pub mod stats;

pub use geometry::round_cone_distance;
pub use grid::CellGrid;
pub use linear::{Cholesky, cholesky_solve};
pub use parallel::parallel_map;
pub use rigid::RigidTransform;
