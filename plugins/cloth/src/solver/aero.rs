//! Aerodynamic drag and lift per triangle in the seeded wind ([`crate::wind`]), computed
//! eight triangles at a time once per step from the current velocities, and gathered into
//! the particles' external forces.

use glam::{Vec3, Vec3A};

use super::step::StepContext;
use crate::frame::RigidTransform;
use crate::simd::{Isa, LANES, Lanes, V3, dispatch_lanes, offset};
use crate::wind::triangle_force_lanes;

/// Triangles per aerodynamics work item.
pub(super) const TRIANGLE_ITEM: usize = 1024;

impl StepContext<'_> {
    /// Gathers the aerodynamic forces of the particles of `range` from their triangles'.
    #[inline(always)]
    pub(super) fn load(&self, range: std::ops::Range<usize>) {
        if !self.k.aero {
            return;
        }
        let m = self.model;
        for i in range {
            let w = m.inverse_mass[i];
            let mut sum = Vec3A::ZERO;
            if w > 0.0 {
                // SAFETY: the triangle forces are only read in this phase (written by the
                // `AeroTriangles` phase, which this one waits for), and every index in the
                // particle's triangle lists is below `triangle_force`'s length (its triangles, or
                // the zero padding slot).
                let f = |t: u32| unsafe { self.triangle_force.get(t as usize) };
                // A tree of eight (short dependency chains, no branch on the count).
                let t = &m.vertex_triangles8[i];
                sum = ((f(t[0]) + f(t[1])) + (f(t[2]) + f(t[3])))
                    + ((f(t[4]) + f(t[5])) + (f(t[6]) + f(t[7])));
                let (start, end) = (m.vertex_triangles_start[i], m.vertex_triangles_start[i + 1]);
                for &t in
                    &m.vertex_triangles[(start as usize + LANES).min(end as usize)..end as usize]
                {
                    sum += f(t);
                }
            }
            // SAFETY: particle `i` belongs to this item.
            unsafe { self.external.set(i, sum * (w / 3.0)) };
        }
    }

    #[inline(always)]
    pub(super) fn aero_triangles(&self, item: usize) {
        let tris = &self.model.triangles;
        let lo = item * TRIANGLE_ITEM;
        let hi = (lo + TRIANGLE_ITEM).min(tris.len());
        // Eight triangles at a time; a last, shorter group repeats its last triangle in the
        // spare lanes.
        for t in (lo..hi).step_by(LANES) {
            // SAFETY: positions and velocities are only read in this phase; the force slots
            // of triangles `t..hi` belong to this item.
            unsafe { aero8(self.k.isa, self, t, (hi - t).min(LANES)) };
        }
    }
}

/// The aerodynamic forces of the `count` (1 to 8) triangles from `t` on
/// ([`StepContext::aero_triangles`]).
///
/// # Safety
/// Positions and velocities are only read in this phase, and the force slots of these
/// triangles belong to the calling item.
pub(super) unsafe fn aero8(isa: Isa, context: &StepContext<'_>, t: usize, count: usize) {
    dispatch_lanes!(isa, aero_with(context: &StepContext<'_>, t: usize, count: usize))
}

#[inline(always)]
pub(super) unsafe fn aero_with<L: Lanes>(context: &StepContext<'_>, t: usize, count: usize) {
    let k = &context.k;
    // Spare lanes repeat the last triangle: the same force is stored to its slot again.
    let mut slots = [0u32; LANES];
    let mut corners = [[0u32; LANES]; 3];
    for l in 0..LANES {
        let triangle = t + l.min(count - 1);
        slots[l] = offset(triangle as u32);
        for (corner, &v) in corners.iter_mut().zip(&context.model.triangles[triangle]) {
            corner[l] = offset(v);
        }
    }
    let (xs, vs) = (context.xs.as_ptr(), context.vs.as_ptr());
    // SAFETY: the caller's contract. (No closures here: they would not inherit the caller's
    // target features.)
    unsafe {
        let p = [
            L::gather(xs, &corners[0]),
            L::gather(xs, &corners[1]),
            L::gather(xs, &corners[2]),
        ];
        let third = L::splat(1.0 / 3.0);
        let mut relative =
            (L::gather(vs, &corners[0]) + L::gather(vs, &corners[1]) + L::gather(vs, &corners[2]))
                .scale(third);
        let centroid = (p[0] + p[1] + p[2]).scale(third);
        if let Some(f) = &k.frame {
            relative =
                relative + V3::splat(f.air_velocity) + V3::splat(f.air_omega).cross(centroid);
        }
        if let Some(wind) = context.wind {
            let (pose, to_local) = match &k.frame {
                Some(f) => (f.motion.pose, f.motion.to_local),
                None => (RigidTransform::IDENTITY, glam::Quat::IDENTITY),
            };
            let c = centroid.to_arrays();
            let mut air = [[0.0f32; LANES]; 3];
            for l in 0..LANES {
                let world = pose.transform_point(Vec3::new(c[0][l], c[1][l], c[2][l]));
                let a = to_local * wind.velocity(world, k.time);
                (air[0][l], air[1][l], air[2][l]) = (a.x, a.y, a.z);
            }
            relative = relative - V3::load(&air);
        }
        let force = triangle_force_lanes(p, relative, k.air_density, k.drag, k.lift);
        L::scatter(context.triangle_force.as_ptr(), &slots, force);
    }
}
