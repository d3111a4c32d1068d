//! The cloth core of fitroom: a Bevy-free, substepped XPBD solver for garments on a moving,
//! measured body.
//!
//! The thesis this product starts from (seed 000 §3.2, §4.3, ch. 5) simulated the free part of
//! a dress with PhysX cloth: position-based dynamics (Müller et al. 2007, "Position based
//! dynamics"), stretch and shear fibres solved in independent sets, 16 spheres joined into 28
//! sphere and capsule colliders, continuous collision, fixed vertices on the skinned body, the
//! inertia of the root bone, 120 Hz. This crate rebuilds that on the CPU with today's methods:
//!
//! - **XPBD** (Macklin, Müller and Chentanez 2016, "XPBD: position-based simulation of
//!   compliant constrained dynamics"): compliance in physical units, many small substeps
//!   ([`solver`]);
//! - stretch, shear and **isometric bending** (Bergou, Wardetzky, Harmon, Zorin and Grinspun
//!   2006, "A quadratic bending model for inextensible surfaces") ([`constraints`],
//!   [`mesh`], [`fabric`]);
//! - **long-range attachments** (Kim, Chentanez and Müller 2012, "Long range attachments —
//!   a method to simulate inextensible clothing in computer games") ([`mesh`]);
//! - spheres and **tapered capsules** with swept, tunnelling-free particle collision and
//!   friction, and planes ([`collision`]); no self-collision;
//! - seeded **wind gusts**, per-triangle **drag and lift** ([`wind`]);
//! - simulation in the **moving body frame** with a chosen fraction of its inertia (seed 000
//!   §4.3) ([`frame`]);
//! - particles ordered by a **recursive bisection** of the rest shape into compact blocks,
//!   whose constraints are solved on worker threads block by block, then along the seams and
//!   corners between blocks, in **SIMD batches** of eight (SSE2, or AVX2 and FMA where the
//!   processor has them, with identical results), with results that do not depend on the
//!   thread count ([`constraints`], [`pool`]);
//! - a **blow-up guard** and [`ClothSolver::reset_to`].
//!
//! # Example
//!
//! ```
//! use fitroom_cloth::{ClothMesh, ClothSolver, Fabric, SolverSettings, Sphere};
//! use glam::Vec3;
//!
//! // A 1 m × 1 m cloth, 20 × 20 cells, hanging from its two top corners.
//! let mesh = ClothMesh::grid(Vec3::new(-0.5, 1.5, 0.0), Vec3::X, -Vec3::Y, 20, 20)?;
//! let mut cloth = ClothSolver::new(&mesh, Fabric::cotton(), &[0, 20], SolverSettings::default())?;
//! cloth.set_colliders(&[Sphere::new(Vec3::new(0.0, 0.8, 0.2), 0.15)], &[])?;
//! for _ in 0..60 {
//!     let report = cloth.step(1.0 / 120.0)?;
//!     if !report.is_healthy() {
//!         cloth.reset_to(mesh.positions())?;
//!     }
//! }
//! assert!(cloth.positions().iter().all(|p| p.is_finite()));
//! # Ok::<(), fitroom_cloth::ClothError>(())
//! ```
//!
//! # Units and frames
//!
//! Metres, seconds, kilograms, newtons. Positions are in the simulation frame: world space,
//! or the body frame's local space once [`ClothSolver::set_body_frame`] has been called.

#![deny(clippy::undocumented_unsafe_blocks)]

pub mod collision;
pub mod constraints;
pub mod error;
pub mod fabric;
pub mod frame;
pub mod mesh;
pub mod order;
pub mod pool;
pub mod simd;
pub mod solver;
pub mod wind;

pub use collision::{MAX_COLLIDERS, Plane, RoundCone, Sphere};
pub use error::ClothError;
pub use fabric::Fabric;
pub use frame::{FrameInertia, RigidTransform};
pub use mesh::{ClothMesh, DistanceStencil, MeshTopology, Tether};
pub use solver::{BlowUp, BlowUpGuard, ClothSolver, Health, SolverSettings, StepReport};
pub use wind::Wind;
