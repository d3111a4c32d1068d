//! Each step's posing of a garment on the body: the attachment targets skinned like the body
//! (seed 000 §3.2.1) and the body colliders posed and fitted to them ([`super::colliders`]),
//! the work shared out to the solver's threads.

use std::sync::Mutex;
use std::sync::atomic::{AtomicU32, AtomicU64, Ordering};

use glam::{Affine3A, Vec3};

use fitroom_cloth::Sphere;

use super::colliders::{
    ANCHOR_RUN, BODY_SKIN_OFFSET_M, YIELD_CLEARANCE_M, anchor_runs_into, apply_cuts, collider_cuts,
    fit_to_anchors, yield_to_body,
};
use super::{GarmentSim, SimError};

/// Pieces that skinning the attachment targets is cut into: the solver's threads claim them
/// one after another ([`ClothSolver::share_out`]), so a thread that wakes late finds the
/// others have done its share.
pub(super) const POSE_PIECES: usize = 8;

/// The fewest attached particles whose posing [`GarmentSim::step`] shares out to the solver's
/// threads. Handing a job to the workers costs about as much as posing a few hundred: the
/// 4,000-particle dress's 79 posed on one thread in 4.9 µs, shared out in 8.3 (session 15).
pub(super) const SHARED_POSING_MIN: usize = 512;

/// One piece of the attachment targets: the targets, and their runs' bounds
/// ([`anchor_runs_into`]).
#[derive(Default)]
pub(super) struct PosePiece {
    targets: Vec<Vec3>,
    runs: Vec<(Vec3, Vec3)>,
}

/// What the solver's threads share out when [`GarmentSim::step`] poses the attachment targets
/// and fits the colliders to them (from [`SHARED_POSING_MIN`] attached particles: when the
/// 4,000-particle dress attached all 766 of its bodice's, this took ~45 µs serial, a 15th of
/// its step while the second thread waited; it attaches 79 since the solver steps only the
/// part that moves), and when it measures the step.
#[derive(Default)]
pub(super) struct Posing {
    pub(super) pieces: Vec<Mutex<PosePiece>>,
    /// Per posed collider: its two cuts ([`collider_cuts`]) as `f32` bits.
    pub(super) cuts: Vec<AtomicU64>,
    /// What [`GarmentSim::measure_on_threads`] found so far, as `f32` bits.
    pub(super) deepest: AtomicU32,
    pub(super) strain: AtomicU32,
    /// Attached particles from which the posing is shared out ([`SHARED_POSING_MIN`]; a
    /// test lowers it).
    pub(super) shared_from: usize,
}
impl GarmentSim {
    /// The body colliders posed by `skinning`, each shrunk where the garment's attached
    /// (skinned) vertices `anchors` lie inside it (see [`fit_to_anchors`]), and the forearms
    /// and hands then yielding to the trunk and thighs ([`yield_to_body`]). Also returns the
    /// largest radius taken away for the anchors, metres.
    pub(super) fn posed_colliders(
        &self,
        skinning: &[Affine3A],
        anchors: &[Vec3],
    ) -> (Vec<(Vec3, Vec3, f32, f32)>, f32) {
        let mut posed = self.colliders.posed(skinning);
        let shrink = fit_to_anchors(&mut posed, anchors, BODY_SKIN_OFFSET_M);
        yield_to_body(&mut posed, &self.yielding, &self.firm, YIELD_CLEARANCE_M);
        (posed, shrink)
    }

    /// Gives the solver `posed` colliders as spheres and the capsules joining them.
    pub(super) fn set_solver_colliders(
        &mut self,
        posed: &[(Vec3, Vec3, f32, f32)],
    ) -> Result<(), SimError> {
        let (spheres, capsules) = (&mut self.spheres, &mut self.capsules);
        spheres.clear();
        capsules.clear();
        for (c, &(a, b, ra, rb)) in posed.iter().enumerate() {
            let friction = if self.yielding.contains(&c) { 0.0 } else { 1.0 };
            let i = spheres.len() as u32;
            spheres.push(Sphere::new(a, ra).with_friction(friction));
            if a.distance(b) > 1e-6 {
                spheres.push(Sphere::new(b, rb).with_friction(friction));
                capsules.push([i, i + 1]);
            }
        }
        self.solver.set_colliders(spheres, capsules)?;
        Ok(())
    }

    pub(super) fn anchors(&self, skinning: &[Affine3A]) -> Vec<Vec3> {
        self.attached
            .iter()
            .map(|&v| self.skin_point(v as usize, skinning))
            .collect()
    }

    /// [`Self::anchors`] into `targets` and the `posed` colliders fitted to them
    /// ([`Self::posed_colliders`]: fitted to the anchors, the arms yielding; the same results),
    /// the work shared out to the solver's threads (from [`SHARED_POSING_MIN`] attached
    /// particles on): first the targets, in pieces, then the colliders, one at a time.
    /// Returns the largest radius taken away and the number of threads that skinned the
    /// targets.
    pub(super) fn pose_on_threads(
        &mut self,
        skinning: &[Affine3A],
        targets: &mut Vec<Vec3>,
        posed: &mut [(Vec3, Vec3, f32, f32)],
    ) -> (f32, usize) {
        let count = self.attached.len();
        // Whole runs of anchors per piece, so that the pieces' runs are the runs of all.
        let piece = count.div_ceil(POSE_PIECES).next_multiple_of(ANCHOR_RUN);
        let pieces = &self.posing.pieces;
        let pose_piece = |k: usize| {
            let mut guard = pieces[k].lock().unwrap_or_else(|e| e.into_inner());
            let PosePiece {
                targets: piece_targets,
                runs: piece_runs,
            } = &mut *guard;
            piece_targets.clear();
            piece_targets.extend(
                self.attached[(k * piece).min(count)..((k + 1) * piece).min(count)]
                    .iter()
                    .map(|&v| self.skin_point(v as usize, skinning)),
            );
            piece_runs.clear();
            anchor_runs_into(piece_targets, piece_runs);
        };
        let shared = count >= self.posing.shared_from;
        let threads = if shared {
            self.solver.share_out(pieces.len(), &pose_piece)
        } else {
            (0..pieces.len()).for_each(pose_piece);
            1
        };
        targets.clear();
        let runs = &mut self.anchor_runs;
        runs.clear();
        for slot in &self.posing.pieces {
            let guard = slot.lock().unwrap_or_else(|e| e.into_inner());
            targets.extend_from_slice(&guard.targets);
            runs.extend_from_slice(&guard.runs);
        }
        let cuts = &mut self.posing.cuts;
        if cuts.len() < posed.len() {
            cuts.resize_with(posed.len(), AtomicU64::default);
        }
        let (cuts, runs, anchors) = (&self.posing.cuts, &self.anchor_runs, &targets[..]);
        let colliders = &*posed;
        let cut = |c: usize| {
            let (a, b) = collider_cuts(&colliders[c], anchors, runs, BODY_SKIN_OFFSET_M);
            let bits = (u64::from(a.to_bits()) << 32) | u64::from(b.to_bits());
            cuts[c].store(bits, Ordering::Relaxed);
        };
        if shared {
            self.solver.share_out(colliders.len(), &cut);
        } else {
            (0..colliders.len()).for_each(cut);
        }
        let mut largest = 0.0f32;
        for (collider, bits) in posed.iter_mut().zip(&self.posing.cuts) {
            let bits = bits.load(Ordering::Relaxed);
            let cuts = (
                f32::from_bits((bits >> 32) as u32),
                f32::from_bits(bits as u32),
            );
            largest = largest.max(apply_cuts(collider, cuts));
        }
        yield_to_body(posed, &self.yielding, &self.firm, YIELD_CLEARANCE_M);
        (largest, threads)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::tests::sun_dress;

    /// The attachment targets and fitted colliders that the solver's threads pose together
    /// ([`GarmentSim::pose_on_threads`]) are, to the bit, those that skinning every anchor and
    /// fitting every collider one after another give.
    #[test]
    fn posing_on_the_solvers_threads_gives_the_serial_targets_and_colliders() {
        let (model, _, mut sim, _) = sun_dress(2);
        // The dress has fewer attached particles than are shared out in the app.
        assert!(sim.attached.len() < SHARED_POSING_MIN);
        sim.posing.shared_from = 0;
        let bones = model.bones.len();
        let still = vec![Affine3A::IDENTITY; bones];
        // Every bone a little differently turned and moved: the anchors blend them.
        let bent: Vec<Affine3A> = (0..bones)
            .map(|b| {
                Affine3A::from_rotation_translation(
                    glam::Quat::from_rotation_y(0.02 * (b % 7) as f32),
                    Vec3::new(0.0, 0.01 * (b % 3) as f32, 0.0),
                )
            })
            .collect();
        sim.reset(&still).expect("a reset");
        let (mut on_two, mut cut) = (0, 0.0f32);
        // 40 steps, and more until the two threads have posed together: a sleeping worker is
        // not used, nor any while the steps run on one thread after a stall (a busy machine),
        // and the results must agree either way.
        let deadline = std::time::Instant::now() + std::time::Duration::from_secs(60);
        let mut k = 0;
        while k < 40 || (on_two == 0 && std::time::Instant::now() < deadline) {
            let pose = if k % 2 == 0 { &bent } else { &still };
            sim.step(pose, 1.0 / 120.0).expect("a step");
            for _ in 0..20 {
                sim.solver.prewake();
                let (mut targets, mut posed) = (Vec::new(), Vec::new());
                sim.colliders.posed_into(pose, &mut posed);
                let (largest, threads) = sim.pose_on_threads(pose, &mut targets, &mut posed);
                let serial_targets = sim.anchors(pose);
                let (serial_posed, serial_largest) = sim.posed_colliders(pose, &serial_targets);
                let bits = |v: &Vec3| v.to_array().map(f32::to_bits);
                assert_eq!(targets.len(), serial_targets.len());
                for (a, b) in targets.iter().zip(&serial_targets) {
                    assert_eq!(bits(a), bits(b), "step {k}: a target differs");
                }
                assert_eq!(posed.len(), serial_posed.len());
                for (a, b) in posed.iter().zip(&serial_posed) {
                    assert_eq!(
                        (bits(&a.0), bits(&a.1), a.2.to_bits(), a.3.to_bits()),
                        (bits(&b.0), bits(&b.1), b.2.to_bits(), b.3.to_bits()),
                        "step {k}: a fitted collider differs"
                    );
                }
                assert_eq!(largest.to_bits(), serial_largest.to_bits());
                cut = cut.max(largest);
                if threads == 2 {
                    on_two += 1;
                    break;
                }
            }
            k += 1;
        }
        assert!(on_two > 0, "the two threads never posed together");
        assert!(cut > 0.0, "no collider was fitted: the test shows nothing");
        eprintln!("posed on two threads after {on_two} of {k} steps; largest cut {cut} m");
    }
}
