//! A garment's reset and step on the body: dressing it (the rest pose carried by the pelvis,
//! then swept into the body's pose), each step's attachment targets and colliders handed to
//! the cloth solver, a teleported body carried along, and a blow-up reset to the skinned pose
//! (seed 000 §3.2.1: the static part is skinned, the rest simulated).

use glam::{Affine3A, Vec3};

use fitroom_cloth::{Health, StepReport};

use super::skin::lerp_affine;
use super::{GarmentSim, SimError, SimStep};

/// An attached vertex moving farther than this in one step means the body was teleported
/// (a clip looping, a tracked person replaced): the garment moves with it instead of being
/// dragged (30 m/s at 120 Hz).
const TELEPORT_M: f32 = 0.25;

/// Steps a reset takes to move the garment from the rest pose into the body's pose.
const DRESS_STEPS: usize = 8;
/// Their length, seconds.
const DRESS_DT: f32 = 1.0 / 120.0;
impl GarmentSim {
    /// Puts the garment on the body posed by `skinning`, at rest.
    ///
    /// The garment is put on as it was placed: in the body's rest pose carried rigidly by the
    /// pelvis, then the limbs move into `skinning` over [`DRESS_STEPS`] simulated steps, so
    /// the cloth is pushed along by the colliders. Skinned straight into a pose, a garment can
    /// start across a collider (a T-shirt's armhole, whose vertices blend arm and trunk
    /// weights, lies across the upper arm's capsule when the arm swings back), and the first
    /// step tears it. If the sweep blows up, the plain skinned pose is used.
    pub fn reset(&mut self, skinning: &[Affine3A]) -> Result<(), SimError> {
        self.check(skinning)?;
        if let Some(pelvis) = self.pelvis {
            let start = vec![skinning[pelvis]; skinning.len()];
            self.place(&start)?;
            let mut healthy = true;
            for k in 1..=DRESS_STEPS {
                let t = k as f32 / DRESS_STEPS as f32;
                let pose: Vec<Affine3A> = start
                    .iter()
                    .zip(skinning)
                    .map(|(a, b)| lerp_affine(a, b, t))
                    .collect();
                let anchors = self.anchors(&pose);
                self.solver.set_attachment_targets(&anchors)?;
                let (posed, _) = self.posed_colliders(&pose, &anchors);
                self.set_solver_colliders(&posed)?;
                if !self.solver.step(DRESS_DT)?.is_healthy() {
                    healthy = false;
                    break;
                }
            }
            if healthy {
                self.keep_skinning(skinning);
                self.last_targets = Some(self.anchors(skinning));
                return Ok(());
            }
        }
        self.place(skinning)
    }

    /// The garment in its skinned pose, at rest, with the colliders where they are.
    fn place(&mut self, skinning: &[Affine3A]) -> Result<(), SimError> {
        let skinned: Vec<Vec3> = self
            .particle_vertex
            .iter()
            .map(|&v| self.skin_point(v as usize, skinning))
            .collect();
        self.keep_skinning(skinning);
        self.solver.reset_to(&skinned)?;
        let anchors = self.anchors(skinning);
        let (posed, _) = self.posed_colliders(skinning, &anchors);
        self.set_solver_colliders(&posed)?;
        self.solver.teleport_colliders();
        // The next step's teleport check starts from here: a body that has moved far since
        // (an app that loaded the garment on the last frame's pose) carries it along.
        self.last_targets = Some(anchors);
        Ok(())
    }

    /// One step of `dt` seconds towards the body posed by `skinning` (rest model space to the
    /// simulation's space, one per bone).
    pub fn step(&mut self, skinning: &[Affine3A], dt: f32) -> Result<SimStep, SimError> {
        self.check(skinning)?;
        let start = std::time::Instant::now();
        // The solver's workers wake while the targets and colliders are posed.
        self.solver.prewake();
        let mut targets = std::mem::take(&mut self.spare_targets);
        let mut posed = std::mem::take(&mut self.posed);
        self.colliders.posed_into(skinning, &mut posed);
        let (collider_shrink_m, _) = self.pose_on_threads(skinning, &mut targets, &mut posed);
        let jumped = self.last_targets.as_ref().is_some_and(|last| {
            last.iter()
                .zip(&targets)
                .any(|(a, b)| a.distance(*b) > TELEPORT_M)
        });
        if jumped {
            // The body jumped: carry the garment along (its skinned pose, colliders teleported)
            // and simulate from there.
            self.teleports += 1;
            self.reset(skinning)?;
        }
        self.solver.set_attachment_targets(&targets)?;
        if let Some(old) = self.last_targets.replace(targets) {
            self.spare_targets = old;
        }
        self.set_solver_colliders(&posed)?;
        self.keep_skinning(skinning);
        let report: StepReport = self.solver.step(dt)?;
        let mut reset = false;
        let mut blow_up = None;
        if let Health::BlownUp(why) = &report.health {
            blow_up = Some(format!("{why:?}"));
            self.resets += 1;
            reset = true;
            self.reset(skinning)?;
        }
        let solve_ms = start.elapsed().as_secs_f64() * 1e3;
        let (max_penetration_m, max_strain_pct) = if self.measuring {
            let mut measured = std::mem::take(&mut self.measured);
            self.positions_into(&mut measured);
            let figures = self.measure_on_threads(&posed, &measured);
            self.measured = measured;
            figures
        } else {
            (0.0, 0.0)
        };
        self.posed = posed;
        Ok(SimStep {
            collider_shrink_m,
            blow_up,
            solve_ms,
            max_penetration_m,
            max_strain_pct,
            reset,
            max_speed_m_s: report.max_speed_m_s,
        })
    }
}
