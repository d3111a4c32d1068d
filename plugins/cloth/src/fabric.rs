//! Fabric materials in physical units, and their mapping to XPBD compliances.
//!
//! XPBD (Macklin et al. 2016) gives every constraint `C` a compliance `α` (inverse stiffness)
//! with potential energy `U = C² / (2α)`; a substep of length `h` uses `α̃ = α / h²`, which
//! makes the result independent of the substep count. The fabric is given as:
//!
//! - **areal density** `ρ_A`, kg/m²: particle masses are triangle areas × `ρ_A` (a third per
//!   corner);
//! - **stretch stiffness** `Y`, N/m: the membrane's in-plane stiffness (Young's modulus ×
//!   thickness). A stretch segment of rest length `L` standing for membrane area `A` (see
//!   [`crate::mesh`]) gets `α = L² / (Y·A)`. This reproduces `Y` exactly for a square grid of
//!   springs (area = two half quads) and for an equilateral triangle net (area = both
//!   triangles);
//! - **shear stiffness** `G`, N/m: each quad diagonal gets `α = L² / (G·2A_quad)`, which gives
//!   the square cell the shear energy `G·γ²·A/2` to first order;
//! - **bend stiffness** `k_b`, N·m (J): the isometric bending energy of Bergou et al. 2006,
//!   `E = k_b/2 · 3/(A₀+A₁) · |Σ Kᵢ xᵢ|²`, is the XPBD constraint
//!   `C = √(3/(A₀+A₁)) Σ Kᵢ xᵢ` (a 3-vector) with `α = 1 / k_b`;
//! - **damping**, 1/s: velocities decay as `exp(-damping·t)` (seed 000 Algorithm 5's
//!   `dampVelocities`);
//! - **friction**: the Coulomb coefficient against colliders (position-based friction of
//!   Macklin et al. 2014);
//! - **drag** and **lift** coefficients for the per-triangle aerodynamics.
//!
//! An infinite stiffness means a rigid (zero compliance) constraint.

use crate::error::{ClothError, non_negative, positive};

/// A fabric's physical parameters (see the module documentation for units and meaning).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fabric {
    /// Mass per area, kg/m².
    pub areal_density_kg_m2: f32,
    /// In-plane stretch stiffness, N/m (`f32::INFINITY`: inextensible).
    pub stretch_stiffness_n_m: f32,
    /// In-plane shear stiffness, N/m.
    pub shear_stiffness_n_m: f32,
    /// Bending stiffness, N·m.
    pub bend_stiffness_n_m: f32,
    /// Velocity damping rate, 1/s.
    pub damping_per_s: f32,
    /// Coulomb friction coefficient against colliders and the floor.
    pub friction: f32,
    /// Aerodynamic drag coefficient (0 disables drag).
    pub drag_coefficient: f32,
    /// Aerodynamic lift coefficient (0 disables lift).
    pub lift_coefficient: f32,
}

impl Fabric {
    /// A medium cotton (about 150 g/m²).
    pub fn cotton() -> Self {
        Self {
            areal_density_kg_m2: 0.15,
            stretch_stiffness_n_m: 2_000.0,
            shear_stiffness_n_m: 100.0,
            bend_stiffness_n_m: 2e-5,
            damping_per_s: 0.3,
            friction: 0.4,
            drag_coefficient: 1.0,
            lift_coefficient: 0.3,
        }
    }

    /// A light silk (about 60 g/m²), soft in bending.
    pub fn silk() -> Self {
        Self {
            areal_density_kg_m2: 0.06,
            stretch_stiffness_n_m: 1_000.0,
            shear_stiffness_n_m: 30.0,
            bend_stiffness_n_m: 2e-6,
            damping_per_s: 0.2,
            friction: 0.25,
            drag_coefficient: 1.2,
            lift_coefficient: 0.4,
        }
    }

    /// A heavy denim (about 400 g/m²), stiff in bending.
    pub fn denim() -> Self {
        Self {
            areal_density_kg_m2: 0.4,
            stretch_stiffness_n_m: 8_000.0,
            shear_stiffness_n_m: 500.0,
            bend_stiffness_n_m: 3e-4,
            damping_per_s: 0.5,
            friction: 0.5,
            drag_coefficient: 0.9,
            lift_coefficient: 0.2,
        }
    }

    /// Checks every parameter's range.
    pub fn validate(&self) -> Result<(), ClothError> {
        positive("fabric areal density (kg/m²)", self.areal_density_kg_m2)?;
        non_negative("fabric stretch stiffness (N/m)", self.stretch_stiffness_n_m)?;
        non_negative("fabric shear stiffness (N/m)", self.shear_stiffness_n_m)?;
        non_negative("fabric bend stiffness (N·m)", self.bend_stiffness_n_m)?;
        finite_non_negative("fabric damping (1/s)", self.damping_per_s)?;
        finite_non_negative("fabric friction", self.friction)?;
        finite_non_negative("fabric drag coefficient", self.drag_coefficient)?;
        finite_non_negative("fabric lift coefficient", self.lift_coefficient)?;
        Ok(())
    }
}

impl Default for Fabric {
    fn default() -> Self {
        Self::cotton()
    }
}

fn finite_non_negative(what: &'static str, value: f32) -> Result<(), ClothError> {
    if value.is_finite() && value >= 0.0 {
        Ok(())
    } else {
        Err(ClothError::InvalidParameter {
            what,
            requirement: "finite and >= 0",
            value: value as f64,
        })
    }
}

/// XPBD compliance (m/N) of a distance constraint of rest length `length_m` standing for
/// membrane area `area_m2` of a membrane with stiffness `stiffness_n_m`. Zero stiffness gives
/// `None` (no constraint); infinite stiffness gives 0 (rigid).
pub fn distance_compliance(stiffness_n_m: f32, length_m: f32, area_m2: f32) -> Option<f32> {
    if stiffness_n_m <= 0.0 {
        None
    } else if stiffness_n_m.is_infinite() {
        Some(0.0)
    } else {
        Some(length_m * length_m / (stiffness_n_m * area_m2.max(f32::MIN_POSITIVE)))
    }
}

/// XPBD compliance (1/(N·m)) of an isometric bending constraint with stiffness
/// `stiffness_n_m`; `None` for zero stiffness.
pub fn bend_compliance(stiffness_n_m: f32) -> Option<f32> {
    if stiffness_n_m <= 0.0 {
        None
    } else {
        Some(1.0 / stiffness_n_m)
    }
}
