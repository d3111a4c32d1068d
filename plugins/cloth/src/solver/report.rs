//! What a step reports ([`StepReport`]): the blow-up guard's verdict ([`Health`],
//! [`BlowUp`]), gathered after the last substep from the particle groups' finish (speeds,
//! non-finite values) and the constraint items' stretch check.

use super::ClothSolver;
use super::step::StepContext;
use crate::constraints::max_stretch_squared;

/// What the blow-up guard found.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum BlowUp {
    /// A position or velocity is NaN or infinite.
    NonFinite {
        /// The first such particle.
        particle: usize,
    },
    /// A particle moves faster than the guard allows.
    Speed {
        /// The fastest particle.
        particle: usize,
        /// Its speed, m/s.
        speed_m_s: f32,
    },
    /// A constraint is stretched beyond the guard's ratio.
    Stretch {
        /// Its two particles.
        vertices: [u32; 2],
        /// Current length over rest length.
        ratio: f32,
    },
}

/// The state of the simulation after a step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Health {
    /// Finite and within the guard's bounds.
    Ok,
    /// The simulation has blown up: reset it (e.g. to the skinned pose) with
    /// [`ClothSolver::reset_to`].
    BlownUp(BlowUp),
}

/// What a step reports.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepReport {
    /// Blow-up guard verdict.
    pub health: Health,
    /// Fastest particle speed, m/s (NaN if a velocity is not finite).
    pub max_speed_m_s: f32,
    /// Largest length / rest length over stretch and shear constraints.
    pub max_stretch_ratio: f32,
}

impl StepReport {
    /// Whether the guard found nothing wrong.
    pub fn is_healthy(&self) -> bool {
        self.health == Health::Ok
    }
}

#[derive(Debug, Clone, Copy, Default)]
pub(super) struct ItemHealth {
    pub(super) max_speed2: f32,
    /// Mesh index.
    pub(super) fastest: u32,
    /// Smallest mesh index.
    pub(super) first_non_finite: u32,
}

impl ClothSolver {
    pub(super) fn report(&self) -> StepReport {
        let mut max_speed2 = 0.0f32;
        let mut fastest = 0u32;
        let mut non_finite = u32::MAX;
        for h in &self.group_health {
            non_finite = non_finite.min(h.first_non_finite);
            if h.max_speed2 > max_speed2 {
                max_speed2 = h.max_speed2;
                fastest = h.fastest;
            }
        }
        let mut max_ratio2 = 0.0f32;
        let mut worst = u32::MAX;
        for &(ratio2, lane) in &self.stretch_health {
            if ratio2.is_nan() || ratio2 > max_ratio2 {
                max_ratio2 = ratio2;
                worst = lane;
                if ratio2.is_nan() {
                    break;
                }
            }
        }
        let max_ratio = max_ratio2.sqrt();
        let guard = self.model.settings.guard;
        let max_speed = max_speed2.sqrt();
        let health = if non_finite != u32::MAX {
            Health::BlownUp(BlowUp::NonFinite {
                particle: non_finite as usize,
            })
        } else if max_speed > guard.max_speed_m_s {
            Health::BlownUp(BlowUp::Speed {
                particle: fastest as usize,
                speed_m_s: max_speed,
            })
        } else if (max_ratio.is_nan() || max_ratio > guard.max_stretch_ratio) && worst != u32::MAX {
            let to_mesh = &self.model.order.to_mesh;
            let vertices = self
                .model
                .constraints
                .distance_vertices(worst)
                .map(|v| to_mesh[v as usize]);
            Health::BlownUp(BlowUp::Stretch {
                vertices,
                ratio: max_ratio,
            })
        } else {
            Health::Ok
        };
        StepReport {
            health,
            max_speed_m_s: if non_finite != u32::MAX {
                f32::NAN
            } else {
                max_speed
            },
            max_stretch_ratio: max_ratio,
        }
    }
}

impl StepContext<'_> {
    /// The stretch check of item `item`'s distance constraints.
    #[inline(always)]
    pub(super) fn stretch(&self, item: usize) {
        let c = &self.model.constraints;
        let (d0, d1) = c.items[item].check;
        // SAFETY: positions are only read in this phase; slot `item` belongs to this item.
        unsafe {
            let worst = max_stretch_squared(
                self.k.isa,
                &c.check[d0 as usize..d1 as usize],
                d0 as usize,
                self.xs.as_ptr(),
            );
            self.stretch_health.set(item, worst);
        }
    }
}
