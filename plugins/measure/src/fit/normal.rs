//! The Gauss-Newton normal equations `Jᵀ W J` and `Jᵀ W r` of one view's rows.
//!
//! A row touches the sliders (all of them: every slider moves most of the skin), the turns
//! of the bones that carry its skin (a hand's row: the spine's, the shoulder's and the arm's;
//! a shin's: the leg's) and the view's placement. Each row's derivatives are made from the
//! vertex-major slider derivatives and the bones' carried weights of its three corners, and
//! added into a dense block of the view's own unknowns (sliders first), which is then added
//! into the whole system. (The row-by-row sum over scattered per-slider columns, found
//! through the whole system's index, was ~40 % of the measurement's time.)

use glam::{Quat, Vec3};

use super::residuals::Row;

/// One view's part of the derivatives: what its rows are differentiated with.
pub(super) struct ViewJacobian<'a> {
    /// Per body vertex, its motion per unit of each slider (`[vertex * sliders + k]`).
    pub(super) shape: &'a [Vec3],
    pub(super) sliders: usize,
    /// Per body vertex, its skin weight carried by each refined bone (`[vertex * bones + k]`).
    pub(super) carried: &'a [f32],
    /// The refined bones' heads, sensor space.
    pub(super) heads: &'a [Vec3],
    /// The body's placement: its rotation turns the bone turns' axes into sensor space, and
    /// the placement's own turn is about its pelvis.
    pub(super) rotation: Quat,
    pub(super) pelvis: Vec3,
}

/// Adds the rows of one view into `h` (lower triangle, row-major, `size` unknowns) and `g`:
/// the sliders are unknowns `0..sliders`, the view's bone turns (three per bone) and then
/// its placement (turn, shift) begin at `at`.
#[allow(clippy::too_many_arguments)]
pub(super) fn add_view(
    h: &mut [f64],
    g: &mut [f64],
    size: usize,
    at: usize,
    jac: &ViewJacobian,
    rows: &[Row],
    vertices: &[Vec3],
) {
    let n = jac.sliders;
    let nb = jac.heads.len();
    let m = n + 3 * nb + 6;
    let (turn_at, shift_at) = (n + 3 * nb, n + 3 * nb + 3);
    let inverse = jac.rotation.inverse();
    // The view's block, lower triangle, local indices.
    let mut block = vec![0.0f64; m * m];
    let mut grad = vec![0.0f64; m];
    let mut val = vec![0.0f64; m];
    // The local indices past the sliders this row touches, ascending.
    let mut extra: Vec<usize> = Vec::with_capacity(3 * nb + 6);
    let mut lever = vec![Vec3::ZERO; nb];
    let mut weight = vec![0.0f32; nb];
    for rw in rows {
        let dir = rw.dir;
        // The sliders: the blend of the corners' motions along the row.
        val[..n].iter_mut().for_each(|v| *v = 0.0);
        for (&c, &b) in rw.vertices.iter().zip(&rw.blend) {
            if b == 0.0 {
                continue;
            }
            let Some(d) = jac.shape.get(c as usize * n..(c as usize + 1) * n) else {
                continue;
            };
            for (v, d) in val[..n].iter_mut().zip(d) {
                *v += f64::from(b * dir.dot(*d));
            }
        }
        // The bones: a turn `a` of bone k moves a corner by `w (a × (v - head))`, so the
        // row by `a · (Σ b w (v - head) × dir)` (the turn's axes in model space).
        lever.iter_mut().for_each(|l| *l = Vec3::ZERO);
        weight.iter_mut().for_each(|w| *w = 0.0);
        for (&c, &b) in rw.vertices.iter().zip(&rw.blend) {
            let (Some(w), Some(v)) = (
                jac.carried.get(c as usize * nb..(c as usize + 1) * nb),
                vertices.get(c as usize),
            ) else {
                continue;
            };
            for k in 0..nb {
                if w[k] != 0.0 {
                    lever[k] += b * w[k] * *v;
                    weight[k] += b * w[k];
                }
            }
        }
        extra.clear();
        for k in 0..nb {
            if weight[k] == 0.0 {
                continue;
            }
            let turn = inverse * (lever[k] - weight[k] * jac.heads[k]).cross(dir);
            for a in 0..3 {
                val[n + 3 * k + a] = f64::from(turn[a]);
                extra.push(n + 3 * k + a);
            }
        }
        // The placement: a turn about the pelvis and a shift.
        let p = rw.at(vertices);
        let turn = (p - jac.pelvis).cross(dir);
        for a in 0..3 {
            val[turn_at + a] = f64::from(turn[a]);
            val[shift_at + a] = f64::from(dir[a]);
            extra.push(turn_at + a);
        }
        extra.extend(shift_at..shift_at + 3);
        let (w, r) = (f64::from(rw.w), f64::from(rw.r));
        for i in 0..n {
            let wi = w * val[i];
            grad[i] += wi * r;
            let line = &mut block[i * m..i * m + i + 1];
            for (b, v) in line.iter_mut().zip(&val[..=i]) {
                *b += wi * v;
            }
        }
        for (a, &e) in extra.iter().enumerate() {
            let we = w * val[e];
            grad[e] += we * r;
            let line = &mut block[e * m..(e + 1) * m];
            for (b, v) in line[..n].iter_mut().zip(&val[..n]) {
                *b += we * v;
            }
            for &f in &extra[..=a] {
                line[f] += we * val[f];
            }
        }
    }
    // Local to global: the sliders stay, the rest moves to `at`.
    let global = |l: usize| if l < n { l } else { at + (l - n) };
    for i in 0..m {
        let gi = global(i);
        g[gi] += grad[i];
        for j in 0..=i {
            h[gi * size + global(j)] += block[i * m + j];
        }
    }
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use fitroom_body::{BodyModel, Shape};
    use glam::{Quat, Vec3};

    use super::{ViewJacobian, add_view};
    use crate::fit::REFINED;
    use crate::fit::residuals::Row;
    use crate::posed::{Placement, Posing, ShapeSpace, carried_weights, shape_jacobians};

    /// Each row derivative the normal equations are made of, against the row's skin point
    /// moved by the unknown (a bone turned, the body turned or shifted, a slider stepped) and
    /// the body posed again: the same within the step's curvature.
    #[test]
    fn row_derivatives_match_the_posed_skin_moved() {
        let path =
            Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/bodies/makehuman.fitbody");
        let model = BodyModel::read(&path).expect("the shipped body");
        let bones: Vec<usize> = REFINED.iter().filter_map(|b| model.bone_index(b)).collect();
        // A posed, turned body: the forearm bent and the body turned, so no axis is special.
        let mut locals = vec![Quat::IDENTITY; model.bones.len()];
        let elbow = model.bone_index("lowerarm_l").expect("a left forearm");
        locals[elbow] = Quat::from_rotation_x(0.6) * Quat::from_rotation_z(0.3);
        let posing = Posing::new(&model, locals);
        let place = Placement {
            rotation: Quat::from_rotation_y(0.7) * Quat::from_rotation_x(0.1),
            pelvis: Vec3::new(0.1, -0.2, 2.4),
        };
        let shape = Shape {
            weight: 0.7,
            ..Shape::default()
        };
        let body = posing.body(&shape, &place).expect("posed");
        let space = ShapeSpace::full();
        let x = space.values(&shape);
        let n = space.len();
        let poses = [(&posing, &place, body.vertices.as_slice())];
        let shape_columns = shape_jacobians(&space, &x, &body, &poses, 2).expect("slider motions");
        let carried = carried_weights(&model, &bones, body.vertices.len());
        let heads = posing.bone_heads(&body.rest, &place, &bones);
        let jac = ViewJacobian {
            shape: &shape_columns[0],
            sliders: n,
            carried: &carried,
            heads: &heads,
            rotation: place.rotation,
            pelvis: place.pelvis,
        };
        // Rows on triangles of the bent forearm, the thigh and the chest.
        let on = |bone: &str| {
            let b = model.bone_index(bone).expect("a bone") as u16;
            let t = model
                .triangles
                .iter()
                .find(|t| t.iter().all(|&v| model.skin_joints[v as usize][0] == b))
                .expect("a triangle on the bone");
            Row {
                surface: true,
                r: 1.0,
                w: 1.0,
                vertices: *t,
                blend: [0.2, 0.3, 0.5],
                dir: Vec3::new(0.3, -0.5, 0.8).normalize(),
            }
        };
        let size = n + 3 * bones.len() + 6;
        let at_of = |vertices: &[Vec3], row: &Row| row.dir.dot(row.at(vertices));
        for bone in ["lowerarm_l", "thigh_r", "spine_03"] {
            let row = on(bone);
            let (mut h, mut g) = (vec![0.0; size * size], vec![0.0; size]);
            add_view(
                &mut h,
                &mut g,
                size,
                n,
                &jac,
                std::slice::from_ref(&row),
                &body.vertices,
            );
            let here = at_of(&body.vertices, &row);
            let eps = 1e-3f32;
            let mut checked = 0;
            for (k, &b) in bones.iter().enumerate() {
                for a in 0..3 {
                    let turn = Vec3::AXES[a] * eps;
                    let mut turned = posing.clone();
                    turned.locals = posing.turned(&body.rest, b, turn);
                    let moved = turned.repose(&body, &place);
                    let fd = (at_of(&moved.vertices, &row) - here) / eps;
                    let got = g[n + 3 * k + a] as f32;
                    assert!(
                        (fd - got).abs() < 2e-3 + 0.02 * fd.abs(),
                        "{bone} row, bone {} axis {a}: {got} vs {fd} by turning",
                        REFINED[k]
                    );
                    checked += usize::from(fd.abs() > 1e-3);
                }
            }
            assert!(
                checked >= 2,
                "{bone} row: only {checked} bone turns move it"
            );
            for a in 0..3 {
                let e = Vec3::AXES[a] * eps;
                for (moved, at) in [
                    (place.moved(e, Vec3::ZERO), n + 3 * bones.len() + a),
                    (place.moved(Vec3::ZERO, e), n + 3 * bones.len() + 3 + a),
                ] {
                    let fd = (at_of(&posing.repose(&body, &moved).vertices, &row) - here) / eps;
                    let got = g[at] as f32;
                    assert!(
                        (fd - got).abs() < 2e-3 + 0.02 * fd.abs(),
                        "{bone} row, placement {at}: {got} vs {fd}"
                    );
                }
            }
            // A slider: the body morphed anew one step along it.
            let k = 2;
            let mut tx = x.clone();
            tx[k] += 0.02;
            let stepped = posing.body(&space.shape(&tx), &place).expect("stepped");
            let fd = (at_of(&stepped.vertices, &row) - here) / 0.02;
            assert!(
                (fd - g[k] as f32).abs() < 2e-3 + 0.02 * fd.abs(),
                "{bone} row, slider {k}: {} vs {fd}",
                g[k]
            );
        }
    }
}
