//! The body colliders a garment collides with, fitted to it each step: shrunk where the
//! garment's skinned attached vertices lie inside them ([`fit_to_anchors`]: colliders are
//! rigid with their bones, the skin and the skinned garment are not), and the forearms and
//! hands yielding to the trunk and thighs (`yield_to_body`: an arm pushes a skirt aside
//! without pinching it). The body's capsules themselves are `fitroom_body::colliders`; the
//! skinned static part of a garment follows seed 000 §3.2.1.

use glam::Vec3;

use fitroom_body::colliders::round_cone_distance;

/// The skin offset kept over the body colliders, metres (the 3 mm). The colliders
/// lie up to 1.5 cm inside the skin (up to 3 cm at the front of the thighs) so that they never
/// stick out of it (see [`fitroom_body::colliders`]); drawn as simulated, the skin would show
/// through a tight skirt in places ([`RENDER_OFFSET_M`](super::RENDER_OFFSET_M) and
/// [`crate::cover`] hide it). A larger offset hides that but stretches the skirt against the
/// skinned bodice until the stretch guard fires (tried: 8 and 20 mm).
pub const BODY_SKIN_OFFSET_M: f32 = 0.003;

/// Largest share of a collider's radius that [`fit_to_anchors`] takes away.
const MAX_COLLIDER_SHRINK: f32 = 0.6;

/// Anchors [`fit_to_anchors`] bounds together.
pub(super) const ANCHOR_RUN: usize = 8;

/// Shrinks posed colliders `(a, b, radius_a, radius_b)` so that no point of `anchors` is
/// inside one by more than `-skin` (i.e. each stays at least `skin` outside).
///
/// The garment's attached vertices are skinned like the body's skin, but the colliders are
/// rigid with their bones: in a stride the top of a thigh's capsule comes out through the
/// skinned hip crease (by up to 1.7 cm on the walking clips), so the free cloth next to the
/// waistband could satisfy neither its tethers (a few centimetres to an anchor that is inside
/// the capsule) nor the collision, and was stretched until the blow-up guard fired. The
/// skinned garment shows where the body's surface is there; the capsule yields to it. An
/// anchor at axis parameter `t` (0 at `a`, 1 at `b`) shrinks the nearer end's radius by
/// `depth / (1 - t)` or `depth / t`, so the radius at `t` (linear along the axis) loses at
/// least `depth`; at most [`MAX_COLLIDER_SHRINK`] of a radius goes. Returns the largest radius
/// taken away.
///
/// The deepest case is a T-shirt's neckline over the trapezius, up to 4 cm inside the upper
/// chest's capsules (whose radius is half the chest's depth); with 40 % at most, the neckline
/// stayed inside and tethers reached 111 %. The cost: where an end shrinks, the garment can
/// sink into the body nearby (the upper chest shows through a T-shirt in places).
pub fn fit_to_anchors(
    colliders: &mut [(Vec3, Vec3, f32, f32)],
    anchors: &[Vec3],
    skin: f32,
) -> f32 {
    let mut runs = Vec::new();
    anchor_runs_into(anchors, &mut runs);
    let mut largest = 0.0f32;
    for collider in colliders.iter_mut() {
        let cuts = collider_cuts(collider, anchors, &runs, skin);
        largest = largest.max(apply_cuts(collider, cuts));
    }
    largest
}

/// Appends the bounds of runs of [`ANCHOR_RUN`] consecutive anchors to `runs`: a garment's
/// attached vertices come in mesh order, where neighbours stay together, so a collider skips
/// most anchors far from it a run at a time. A run with an anchor that is not finite is
/// unbounded: its anchors are tested (and that one skipped) one by one.
pub(super) fn anchor_runs_into(anchors: &[Vec3], runs: &mut Vec<(Vec3, Vec3)>) {
    runs.extend(anchors.chunks(ANCHOR_RUN).map(|run| {
        if run.iter().all(|p| p.is_finite()) {
            run.iter().fold(
                (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
                |(lo, hi), &p| (lo.min(p), hi.max(p)),
            )
        } else {
            (Vec3::splat(f32::NEG_INFINITY), Vec3::splat(f32::INFINITY))
        }
    }));
}

/// How much [`fit_to_anchors`] takes from the radii at the two ends of `collider`, given
/// `runs`, the bounds of the anchors' runs ([`anchor_runs_into`]).
pub(super) fn collider_cuts(
    &(a, b, ra, rb): &(Vec3, Vec3, f32, f32),
    anchors: &[Vec3],
    runs: &[(Vec3, Vec3)],
    skin: f32,
) -> (f32, f32) {
    let reach = ra.max(rb) + skin;
    let lo = a.min(b) - Vec3::splat(reach);
    let hi = a.max(b) + Vec3::splat(reach);
    let axis = b - a;
    let len2 = axis.length_squared();
    let (mut cut_a, mut cut_b) = (0.0f32, 0.0f32);
    let near = runs
        .iter()
        .zip(anchors.chunks(ANCHOR_RUN))
        .filter(|((run_lo, run_hi), _)| !(run_hi.cmplt(lo).any() || run_lo.cmpgt(hi).any()))
        .flat_map(|(_, run)| run);
    // A cheaper test before the exact distance: the round cone is the union of spheres
    // centred on its axis whose radius changes by `slope` per metre along it, so a point
    // at distance `d` from the axis point nearest to it (parameter `t`) is at least
    // `d·√(1 − slope²) − r(t)` from its surface (Pythagoras along the axis, then the
    // smallest of `√(d² + x²) − slope·x`).
    let slope2 = if len2 > 1e-12 {
        (ra - rb) * (ra - rb) / len2
    } else {
        0.0
    };
    let keep = (1.0 - slope2).max(0.0);
    for &p in near {
        if p.cmplt(lo).any() || p.cmpgt(hi).any() {
            continue;
        }
        let t = if len2 > 1e-12 {
            ((p - a).dot(axis) / len2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        // (A degenerate cone is a ball of the larger radius; a millimetre's tenth for
        // rounding.)
        let radius = if len2 > 1e-12 {
            ra + (rb - ra) * t
        } else {
            ra.max(rb)
        };
        let within = radius + skin + 1e-4;
        if (p - (a + axis * t)).length_squared() * keep > within * within {
            continue;
        }
        let depth = skin - round_cone_distance(p, a, b, ra, rb);
        if depth.is_nan() || depth <= 0.0 {
            continue;
        }
        if t < 0.5 {
            cut_a = cut_a.max(depth / (1.0 - t));
        } else {
            cut_b = cut_b.max(depth / t);
        }
    }
    if len2 <= 1e-12 {
        let cut = cut_a.max(cut_b).min(MAX_COLLIDER_SHRINK * ra);
        (cut, cut)
    } else {
        (
            cut_a.min(MAX_COLLIDER_SHRINK * ra),
            cut_b.min(MAX_COLLIDER_SHRINK * rb),
        )
    }
}

/// Takes [`collider_cuts`]' `(cut_a, cut_b)` from the radii of `collider`; returns the larger.
pub(super) fn apply_cuts(collider: &mut (Vec3, Vec3, f32, f32), (cut_a, cut_b): (f32, f32)) -> f32 {
    collider.2 -= cut_a;
    collider.3 -= cut_b;
    cut_a.max(cut_b)
}

/// The colliders that yield to the trunk and thighs ([`yield_to_body`]) and that the cloth
/// slides off without friction: the forearms and hands.
pub(super) const YIELDING: [&str; 4] = ["lowerarm_l", "lowerarm_r", "hand_l", "hand_r"];
/// Name prefixes of the colliders they yield to.
pub(super) const FIRM: [&str; 3] = ["pelvis", "spine_", "thigh_"];
/// The room a yielding collider leaves the firm ones, metres: room for the cloth between a
/// hand and a hip (with 2 cm the dress still stretched 108 % on 16_11, with 3.5 cm 27 %).
pub(super) const YIELD_CLEARANCE_M: f32 = 0.035;
/// Points along a yielding collider's axis where its clearance is measured (5 cm apart on a
/// forearm: between them its axis comes at most ~2 mm nearer a hip).
const YIELD_SAMPLES: usize = 9;

/// Shrinks the `yielding` posed colliders (forearms, hands) so that each keeps `clearance`
/// from every `firm` one (the trunk, the thighs), both radii by the same amount (never below
/// zero), measured at [`YIELD_SAMPLES`] points along its axis.
///
/// On the recorded walks the forearms and hands swing past the hips and often dip into them.
/// As rigid colliders that overlap the hip's, they pinched the skirt against it and, with the
/// fabric's friction, carried it along: the sun dress stretched 184 % on the embedded walk,
/// the skirt 143-257 % (07_01). So the garments ignored them, and an arm passed through a
/// skirt. Yielding and frictionless (the cloth slides off a hand, as off a real one brushing
/// past), they push the dress aside without pinching it: on the embedded walk and 12 of the
/// 15 CMU clips its largest stretch is within 2 points of what it is with the arms ignored,
/// or lower (21-104 %, the largest on the clips whose arms swing hardest); on 02_01, 02_04
/// and 14_19 it is 97, 89 and 85 % against 26, 58 and 34 % (single edges for a frame, where
/// the tracked hand jumps); no penetration, tethers within 1.6 %, no reset (session 14,
/// `fitroom cloth sim`, 400 frames each). The short skirt and the T-shirt, whose hems hang
/// where the hands swing, still stretch two to three fold with them and ignore them.
pub(super) fn yield_to_body(
    posed: &mut [(Vec3, Vec3, f32, f32)],
    yielding: &[usize],
    firm: &[usize],
    clearance: f32,
) {
    // Each collider's bounding ball: the middle of its axis, and a radius that reaches its
    // ends' balls.
    let ball = |&(a, b, ra, rb): &(Vec3, Vec3, f32, f32)| {
        ((a + b) * 0.5, 0.5 * a.distance(b) + ra.max(rb))
    };
    for &i in yielding {
        let (a, b, ra, rb) = posed[i];
        let (centre, reach) = ball(&posed[i]);
        let mut shrink = 0.0f32;
        for &j in firm {
            let (ja, jb, jra, jrb) = posed[j];
            let (firm_centre, firm_reach) = ball(&posed[j]);
            // (NaN passes on to the exact test.)
            if centre.distance(firm_centre) > reach + firm_reach + clearance {
                continue;
            }
            for k in 0..YIELD_SAMPLES {
                let t = k as f32 / (YIELD_SAMPLES - 1) as f32;
                let d = round_cone_distance(a.lerp(b, t), ja, jb, jra, jrb);
                // (A NaN distance shrinks nothing; the solver's input check sees the NaN.)
                shrink = shrink.max(ra + (rb - ra) * t + clearance - d);
            }
        }
        posed[i] = (a, b, (ra - shrink).max(0.0), (rb - shrink).max(0.0));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A hand (a sphere) and a forearm (a tapered capsule) beside a hip (a sphere): the hand
    /// keeps its radius while clear of the hip by the clearance, shrinks to keep it when
    /// nearer (closed form), vanishes with its centre inside; the forearm crossing the hip's
    /// side shrinks until every sampled point of it keeps the clearance.
    #[test]
    fn yielding_colliders_keep_their_clearance_from_the_firm_ones() {
        let c = YIELD_CLEARANCE_M;
        let hip = (Vec3::ZERO, Vec3::ZERO, 0.1, 0.1);
        let hand = |x: f32| (Vec3::new(x, 0.0, 0.0), Vec3::new(x, 0.0, 0.0), 0.04, 0.04);
        let shrunk = |x: f32| {
            let mut posed = [hip, hand(x)];
            yield_to_body(&mut posed, &[1], &[0], c);
            assert_eq!(posed[0], hip, "the firm collider does not change");
            posed[1].2
        };
        assert_eq!(shrunk(0.1 + c + 0.05), 0.04, "clear: unchanged");
        let near = 0.1 + c + 0.02;
        assert!((shrunk(near) - 0.02).abs() < 1e-6, "{}", shrunk(near));
        assert_eq!(shrunk(0.05), 0.0, "the centre inside the hip");
        // A forearm passing the hip's side.
        let forearm = (
            Vec3::new(0.15, 0.2, 0.0),
            Vec3::new(0.15, -0.2, 0.0),
            0.035,
            0.025,
        );
        let mut posed = [hip, forearm];
        yield_to_body(&mut posed, &[1], &[0], c);
        let (a, b, ra, rb) = posed[1];
        assert!(ra < 0.035 && rb < 0.025 && ra - rb > 0.0099, "{ra} {rb}");
        for k in 0..=20 {
            let t = k as f32 / 20.0;
            let d = round_cone_distance(a.lerp(b, t), hip.0, hip.1, hip.2, hip.3);
            let r = ra + (rb - ra) * t;
            // Between the sampled points the axis may come a little nearer.
            assert!(d >= r + c - 0.0025, "t = {t}: {d} against {}", r + c);
        }
    }

    #[test]
    fn fit_to_anchors_leaves_every_anchor_a_skin_outside() {
        let skin = 0.003;
        let capsule = (Vec3::ZERO, Vec3::new(0.0, -0.4, 0.0), 0.07, 0.05);
        // Anchors inside near each end and in the middle, one outside.
        let anchors = [
            Vec3::new(0.06, -0.02, 0.0),
            Vec3::new(0.0, -0.38, 0.045),
            Vec3::new(-0.055, -0.2, 0.0),
            Vec3::new(0.2, -0.2, 0.0),
        ];
        let mut colliders = [capsule];
        let largest = fit_to_anchors(&mut colliders, &anchors, skin);
        let (a, b, ra, rb) = colliders[0];
        for p in anchors {
            let d = round_cone_distance(p, a, b, ra, rb);
            assert!(d >= skin - 1e-5, "{p}: {d}");
        }
        assert!(largest > 0.0 && ra < capsule.2 && rb < capsule.3);
        assert!((capsule.2 - ra).max(capsule.3 - rb) <= largest + 1e-6);
        // Nothing inside: nothing changes.
        let mut untouched = [capsule];
        assert_eq!(fit_to_anchors(&mut untouched, &anchors[3..], skin), 0.0);
        assert_eq!(untouched[0], capsule);
        // A deep anchor takes at most MAX_COLLIDER_SHRINK of a radius.
        let mut deep = [capsule];
        fit_to_anchors(&mut deep, &[Vec3::new(0.0, -0.01, 0.0)], skin);
        assert!((deep[0].2 - (1.0 - MAX_COLLIDER_SHRINK) * capsule.2).abs() < 1e-6);
    }

    /// Every anchor against every collider, as `fit_to_anchors` did before it bounded runs of
    /// anchors: the cuts only.
    fn cuts_one_by_one(
        colliders: &[(Vec3, Vec3, f32, f32)],
        anchors: &[Vec3],
        skin: f32,
    ) -> Vec<(f32, f32)> {
        colliders
            .iter()
            .map(|&(a, b, ra, rb)| {
                let (mut cut_a, mut cut_b) = (0.0f32, 0.0f32);
                // A ball (both ends at one point) shrinks as one, by the deepest anchor.
                let ball = a == b;
                for &p in anchors {
                    let depth = skin - round_cone_distance(p, a, b, ra, rb);
                    if depth.is_nan() || depth <= 0.0 {
                        continue;
                    }
                    let axis = b - a;
                    let t = if ball {
                        0.0
                    } else {
                        ((p - a).dot(axis) / axis.length_squared()).clamp(0.0, 1.0)
                    };
                    if t < 0.5 {
                        cut_a = cut_a.max(depth / (1.0 - t));
                    } else {
                        cut_b = cut_b.max(depth / t);
                    }
                }
                if ball {
                    let cut = cut_a.max(cut_b).min(MAX_COLLIDER_SHRINK * ra);
                    return (cut, cut);
                }
                (
                    cut_a.min(MAX_COLLIDER_SHRINK * ra),
                    cut_b.min(MAX_COLLIDER_SHRINK * rb),
                )
            })
            .collect()
    }

    #[test]
    fn runs_of_anchors_shrink_colliders_as_every_anchor_alone_does() {
        let mut seed = 7u32;
        let mut r = |scale: f32| {
            seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            ((seed >> 8) as f32 / (1u32 << 24) as f32 - 0.5) * 2.0 * scale
        };
        let skin = 0.003;
        let axes = [
            Vec3::X,
            Vec3::NEG_X,
            Vec3::Y,
            Vec3::NEG_Y,
            Vec3::Z,
            Vec3::NEG_Z,
        ];
        let mut cut_cases = 0;
        for case in 0..300 {
            let a = Vec3::new(r(0.3), r(0.6), r(0.3));
            let b = a + Vec3::new(r(0.1), r(0.3), r(0.1));
            let (ra, rb) = (0.03 + r(0.02).abs(), 0.03 + r(0.02).abs());
            // Every fourth collider short and steeply tapered (radii 6 and 2 cm, 8 cm apart),
            // every tenth a ball (both ends at one point) of unequal radii.
            let (b, rb, ra) = match case % 20 {
                3 | 7 | 11 | 15 | 19 => (a + (b - a).normalize_or(Vec3::Y) * 0.08, 0.02, 0.06),
                0 | 10 => (a, 0.06, 0.03),
                _ => (b, rb, ra),
            };
            let colliders = [(a, b, ra, rb), (b, a, rb, ra)];
            // A few anchors anywhere (so runs start at different places), then neighbours a
            // fraction of a millimetre apart (as in a mesh) at the collider's extreme along
            // an axis, where a run only just meets the collider's bounds, or anywhere on its
            // surface; one NaN now and then.
            let mut anchors: Vec<Vec3> = (0..case % 8)
                .map(|_| Vec3::new(r(0.35), r(0.7), r(0.35)))
                .collect();
            let u = axes[case % 6];
            let on_surface = if case % 3 < 2 {
                let (end, r_end) = if (a - b).dot(u) > 0.0 {
                    (a, ra)
                } else {
                    (b, rb)
                };
                end + u * r_end
            } else {
                let t = r(0.5) + 0.5;
                let u = Vec3::new(r(1.0), r(1.0), r(1.0)).normalize_or(Vec3::X);
                a.lerp(b, t) + u * (ra + (rb - ra) * t)
            };
            let mut p = on_surface + Vec3::new(r(0.004), r(0.004), r(0.004));
            for _ in 0..12 {
                anchors.push(p);
                p += Vec3::new(r(0.0005), r(0.0005), r(0.0005));
            }
            // Now and then a NaN amid the run, after anchors that cut.
            if case % 10 == 0 {
                let at = anchors.len() - 4;
                anchors.insert(at, Vec3::NAN);
            }
            let expected = cuts_one_by_one(&colliders, &anchors, skin);
            let mut fitted = colliders;
            let largest = fit_to_anchors(&mut fitted, &anchors, skin);
            for ((before, after), (cut_a, cut_b)) in colliders.iter().zip(&fitted).zip(&expected) {
                assert_eq!(
                    after.2.to_bits(),
                    (before.2 - cut_a).to_bits(),
                    "case {case}"
                );
                assert_eq!(
                    after.3.to_bits(),
                    (before.3 - cut_b).to_bits(),
                    "case {case}"
                );
            }
            let most = expected.iter().fold(0.0f32, |m, c| m.max(c.0).max(c.1));
            assert_eq!(largest, most, "case {case}");
            cut_cases += usize::from(most > 0.0);
        }
        assert!(
            cut_cases >= 100,
            "only {cut_cases} of 300 cases cut a collider"
        );
    }
}
