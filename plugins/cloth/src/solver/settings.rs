//! The solver's settings ([`SolverSettings`]) and the blow-up guard's thresholds
//! ([`BlowUpGuard`]), with the check of their ranges.

use glam::Vec3;

use crate::error::{ClothError, non_negative, positive};
use crate::frame::FrameInertia;

/// Thresholds of the blow-up guard.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BlowUpGuard {
    /// A particle faster than this (m/s) counts as a blow-up.
    pub max_speed_m_s: f32,
    /// A stretch or shear constraint longer than this multiple of its rest length counts as a
    /// blow-up. The default, 6, lies above what a pinch reaches and recovers from: a T-shirt
    /// caught between an upper arm swept into the chest and the trunk stretches 4.0-4.1 times
    /// for a few steps and is back under 1.4 once the arm withdraws, while a reset there put
    /// the shirt's skinned pose 41 mm inside the arm (`tests/garment_robust.rs`; with 4 it
    /// fired or not depending on the order the solver visits particles in).
    pub max_stretch_ratio: f32,
}

impl Default for BlowUpGuard {
    fn default() -> Self {
        Self {
            max_speed_m_s: 100.0,
            max_stretch_ratio: 6.0,
        }
    }
}

/// Solver settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SolverSettings {
    /// Substeps per step (10 at 120 Hz gives 1,200 substeps per second).
    pub substeps: u32,
    /// Constraint iterations per substep (1 is the small-steps choice).
    pub iterations: u32,
    /// Threads that solve a step, the caller's included. Results do not depend on it.
    pub threads: usize,
    /// Gravity in world coordinates, m/s².
    pub gravity: Vec3,
    /// Skin distance kept between particles and colliders, metres.
    pub collision_thickness: f32,
    /// Tether length as a multiple of the rest geodesic distance, in `[1.0, 1.1]`.
    pub tether_scale: f32,
    /// Attachments each free particle is tethered to (0 disables tethers).
    pub tethers_per_particle: usize,
    /// Air density for drag and lift, kg/m³ (0 disables aerodynamics).
    pub air_density_kg_m3: f32,
    /// Optional cap on particle speed, m/s, applied after each substep.
    pub max_velocity_m_s: Option<f32>,
    /// How much of the body frame's inertia the cloth feels ([`crate::frame`]).
    pub frame_inertia: FrameInertia,
    /// Blow-up thresholds.
    pub guard: BlowUpGuard,
}

impl Default for SolverSettings {
    fn default() -> Self {
        Self {
            substeps: 10,
            iterations: 1,
            threads: std::thread::available_parallelism()
                .map(|n| n.get().min(4))
                .unwrap_or(1),
            gravity: Vec3::new(0.0, -9.81, 0.0),
            collision_thickness: 0.003,
            tether_scale: 1.0,
            tethers_per_particle: 2,
            air_density_kg_m3: 1.2,
            max_velocity_m_s: None,
            frame_inertia: FrameInertia::FULL,
            guard: BlowUpGuard::default(),
        }
    }
}

impl SolverSettings {
    /// Checks every setting's range.
    pub fn validate(&self) -> Result<(), ClothError> {
        let range = |what, value: u64, lo: u64, hi: u64, requirement| {
            if value < lo || value > hi {
                Err(ClothError::InvalidParameter {
                    what,
                    requirement,
                    value: value as f64,
                })
            } else {
                Ok(())
            }
        };
        range(
            "substeps",
            self.substeps as u64,
            1,
            1000,
            "between 1 and 1000",
        )?;
        range(
            "iterations",
            self.iterations as u64,
            1,
            100,
            "between 1 and 100",
        )?;
        range("threads", self.threads as u64, 1, 64, "between 1 and 64")?;
        range(
            "tethers per particle",
            self.tethers_per_particle as u64,
            0,
            8,
            "between 0 and 8",
        )?;
        if !self.gravity.is_finite() {
            return Err(ClothError::NonFiniteInput {
                what: "gravity",
                index: 0,
            });
        }
        non_negative("collision thickness (m)", self.collision_thickness)?;
        if !self.collision_thickness.is_finite() {
            return Err(ClothError::InvalidParameter {
                what: "collision thickness (m)",
                requirement: "finite",
                value: self.collision_thickness as f64,
            });
        }
        if !(1.0..=1.1).contains(&self.tether_scale) {
            return Err(ClothError::InvalidParameter {
                what: "tether scale",
                requirement: "between 1.0 and 1.1",
                value: self.tether_scale as f64,
            });
        }
        non_negative("air density (kg/m³)", self.air_density_kg_m3)?;
        if let Some(v) = self.max_velocity_m_s {
            positive("maximum velocity (m/s)", v)?;
        }
        for (what, s) in [
            ("linear frame inertia", self.frame_inertia.linear),
            ("angular frame inertia", self.frame_inertia.angular),
            ("centrifugal frame inertia", self.frame_inertia.centrifugal),
        ] {
            if !(0.0..=1.0).contains(&s) {
                return Err(ClothError::InvalidParameter {
                    what,
                    requirement: "between 0 and 1",
                    value: s as f64,
                });
            }
        }
        positive("guard maximum speed (m/s)", self.guard.max_speed_m_s)?;
        positive("guard maximum stretch ratio", self.guard.max_stretch_ratio)?;
        Ok(())
    }
}
