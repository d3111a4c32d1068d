//! A garment simulated on a posed body (Bevy-free): the cloth solver driven by the body's
//! skinning transforms each step.
//!
//! * The garment's rest mesh is in the body's model space (where it was placed and sewn).
//!   Every garment vertex gets the skin weights of its nearest body vertex, so it can be skinned
//!   like the body (seed 000 §3.2.1: the static part of a garment is skinned); a reset puts the
//!   garment in that skinned pose.
//! * Attached vertices (waistband, shoulder straps, a skinned bodice) follow their skinned
//!   position each step; the solver moves them there linearly over the substeps.
//! * The solver steps only the garment's simulated part ([`simulated_part`]): the free vertices
//!   and the attached ones that share a constraint with them. The rest of the static part (the
//!   inside of a skinned bodice or of a wide band) cannot move the cloth; it is skinned when the
//!   garment is read or drawn, not in every 120 Hz step.
//! * The body collides as [`BodyColliders`] posed by the same transforms; the floor is a plane.
//!   The forearms and hands yield to the trunk and thighs and are frictionless
//!   (`yield_to_body`), so that an arm pushes a skirt aside without pinching it.
//! * A blow-up (non-finite positions, absurd speed or stretch, reported by the solver's guard)
//!   resets the garment to its skinned pose instead of crashing, and is counted.
//!
//! Fit figures: per-vertex strain (the largest stretch of its edges against their rest length,
//! in %) and the gap between the garment and the body.

use std::ops::Range;
use std::sync::Mutex;
use std::sync::atomic::{AtomicU32, AtomicU64, Ordering};

use glam::{Affine3A, Vec3};
use serde::Serialize;

use fitroom_body::colliders::{BodyColliders, ColliderOptions, round_cone_distance};
use fitroom_body::{BodyModel, MeshGraph, RestPose, SegmentError};
use fitroom_cloth::{
    ClothError, ClothMesh, ClothSolver, Fabric, Health, Plane, SolverSettings, Sphere, StepReport,
};

/// What the simulation needs of a garment.
#[derive(Clone, Debug)]
pub struct SimGarment {
    /// Rest positions, body model space, metres.
    pub positions: Vec<Vec3>,
    pub triangles: Vec<[u32; 3]>,
    /// Vertices that follow the body.
    pub attached: Vec<u32>,
    pub fabric: Fabric,
    /// Body colliders (by name) the garment does not collide with.
    pub ignore_colliders: Vec<String>,
}

impl SimGarment {
    /// The simulation's view of a garment: its attached vertices and its static, skinned part
    /// (seed 000 §3.2.1) follow the body; the rest is simulated.
    pub fn from_mesh(mesh: &crate::GarmentMesh) -> Self {
        let mut attached: Vec<u32> = mesh.attached.clone();
        attached.extend(
            mesh.skinned
                .iter()
                .enumerate()
                .filter(|(_, s)| **s)
                .map(|(i, _)| i as u32),
        );
        attached.sort_unstable();
        attached.dedup();
        Self {
            positions: mesh.positions.clone(),
            triangles: mesh.triangles.clone(),
            attached,
            fabric: mesh.fabric,
            ignore_colliders: mesh.ignore_colliders.clone(),
        }
    }
}

/// Why a garment cannot be simulated.
#[derive(Debug, thiserror::Error)]
pub enum SimError {
    #[error("cloth: {0}")]
    Cloth(#[from] ClothError),
    #[error("body colliders: {0}")]
    Colliders(#[from] fitroom_body::colliders::ColliderError),
    #[error("{got} skinning transforms, the body has {expected} bones")]
    Bones { got: usize, expected: usize },
    #[error("the garment ignores a body collider \"{0}\" that the body does not have")]
    UnknownCollider(String),
    #[error("garment mesh: {0}")]
    Mesh(#[from] SegmentError),
}

/// Per-step figures.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct SimStep {
    /// Deepest particle inside a body collider after the step, metres (0 if none).
    pub max_penetration_m: f32,
    /// Largest edge stretch, % over rest length.
    pub max_strain_pct: f32,
    /// Largest radius a body collider gave up to the skinned garment this step
    /// ([`fit_to_anchors`]), metres.
    pub collider_shrink_m: f32,
    /// Whether the step blew up and the garment was reset to its skinned pose.
    pub reset: bool,
    /// What the blow-up guard saw, if it fired.
    pub blow_up: Option<String>,
    pub max_speed_m_s: f32,
    /// CPU time of the step's simulation (attachment targets, colliders, the solver), ms; the
    /// figures above are measured after it and not counted.
    pub solve_ms: f64,
}

/// A garment on a body.
pub struct GarmentSim {
    solver: ClothSolver,
    rest: Vec<Vec3>,
    triangles: Vec<[u32; 3]>,
    /// The garment vertices of the solver's attached particles (`solver.attached()`), in the
    /// solver's order (both increasing).
    attached: Vec<u32>,
    /// Per solver particle: its garment vertex (increasing).
    particle_vertex: Vec<u32>,
    /// Per garment vertex: its solver particle, or [`NOT_SIMULATED`].
    vertex_particle: Vec<u32>,
    /// The skinning of the last step or reset (empty before the first): where the vertices the
    /// solver does not step are.
    skinning: Vec<Affine3A>,
    /// Buffer of the garment's positions for [`GarmentSim::step`]'s measurements.
    measured: Vec<Vec3>,
    /// Indices into `colliders` of the forearms and hands and of the trunk and thighs they
    /// yield to ([`yield_to_body`]).
    yielding: Vec<usize>,
    firm: Vec<usize>,
    /// Per garment vertex: bone indices and weights (from the nearest body vertex).
    skin: Vec<([u16; 4], [f32; 4])>,
    colliders: BodyColliders,
    bones: usize,
    edges: Vec<(u32, u32, f32)>,
    floor_y: Option<f32>,
    resets: u32,
    measuring: bool,
    /// Attachment targets of the last step or reset, to notice a teleported body.
    last_targets: Option<Vec<Vec3>>,
    /// Per vertex: the share of [`RENDER_OFFSET_M`] it is drawn out along its normal.
    render_weight: Vec<f32>,
    /// The pelvis bone (a reset starts from the rest pose it carries).
    pelvis: Option<usize>,
    teleports: u32,
    /// Buffers of [`GarmentSim::set_solver_colliders`], kept between steps.
    spheres: Vec<Sphere>,
    capsules: Vec<[u32; 2]>,
    /// Buffers of [`GarmentSim::step`]: the posed colliders, and the attachment targets of the
    /// step before the last one.
    posed: Vec<(Vec3, Vec3, f32, f32)>,
    spare_targets: Vec<Vec3>,
    /// Room for [`GarmentSim::pose_on_threads`]' anchor run bounds.
    anchor_runs: Vec<(Vec3, Vec3)>,
    /// [`GarmentSim::step`]'s posing work, shared out to the solver's threads.
    posing: Posing,
}

/// Pieces that skinning the attachment targets is cut into: the solver's threads claim them
/// one after another ([`ClothSolver::share_out`]), so a thread that wakes late finds the
/// others have done its share.
const POSE_PIECES: usize = 8;

/// The fewest attached particles whose posing [`GarmentSim::step`] shares out to the solver's
/// threads. Handing a job to the workers costs about as much as posing a few hundred: the
/// 4,000-particle dress's 79 posed on one thread in 4.9 µs, shared out in 8.3 (session 15).
const SHARED_POSING_MIN: usize = 512;

/// One piece of the attachment targets: the targets, and their runs' bounds
/// ([`anchor_runs_into`]).
#[derive(Default)]
struct PosePiece {
    targets: Vec<Vec3>,
    runs: Vec<(Vec3, Vec3)>,
}

/// What the solver's threads share out when [`GarmentSim::step`] poses the attachment targets
/// and fits the colliders to them (from [`SHARED_POSING_MIN`] attached particles: when the
/// 4,000-particle dress attached all 766 of its bodice's, this took ~45 µs serial, a 15th of
/// its step while the second thread waited; it attaches 79 since the solver steps only the
/// part that moves), and when it measures the step.
#[derive(Default)]
struct Posing {
    pieces: Vec<Mutex<PosePiece>>,
    /// Per posed collider: its two cuts ([`collider_cuts`]) as `f32` bits.
    cuts: Vec<AtomicU64>,
    /// What [`GarmentSim::measure_on_threads`] found so far, as `f32` bits.
    deepest: AtomicU32,
    strain: AtomicU32,
    /// Attached particles from which the posing is shared out ([`SHARED_POSING_MIN`]; a
    /// test lowers it).
    shared_from: usize,
}

/// An attached vertex moving farther than this in one step means the body was teleported
/// (a clip looping, a tracked person replaced): the garment moves with it instead of being
/// dragged (30 m/s at 120 Hz).
const TELEPORT_M: f32 = 0.25;

/// The skin offset kept over the body colliders, metres (the 3 mm). The colliders
/// lie up to 1.5 cm inside the skin (up to 3 cm at the front of the thighs) so that they never
/// stick out of it (see [`fitroom_body::colliders`]); drawn as simulated, the skin would show
/// through a tight skirt in places ([`RENDER_OFFSET_M`] and [`crate::cover`] hide it). A larger
/// offset hides that but stretches the skirt against the skinned bodice until the stretch
/// guard fires (tried: 8 and 20 mm).
pub const BODY_SKIN_OFFSET_M: f32 = 0.003;

/// How far out along its normals the simulated part of a garment is drawn, metres. The body
/// colliders sit inside the skin (by 1.5 cm on the trunk and up to 3 cm at the front of the
/// thighs, so that they never stick out of it) and the cloth rests 3 mm over them, so drawn
/// where it is simulated a skirt lets the thighs and belly show through in a stride. Colliders
/// on the skin, or a larger collision offset, stretch the skirt against its skinned waistband
/// instead (tried: a 10-15 mm offset took tethers to 1.7-2.4 on 16_11). Drawing the free
/// cloth a little farther out hides most of it (15 mm left large patches of thigh, 25 mm a
/// few small ones in a long stride) and changes no simulated figure; the app also leaves out
/// the skin the garment surely covers ([`crate::cover`]), which hides the rest.
pub const RENDER_OFFSET_M: f32 = 0.025;

/// Edges over which that offset blends in from the attached part.
pub const RENDER_RAMP_EDGES: u32 = 4;

/// Per vertex of `graph`: `min(1, edges to the nearest attached vertex / RENDER_RAMP_EDGES)`
/// (1 without attached vertices).
fn render_weights(graph: &MeshGraph, attached: &[u32]) -> Result<Vec<f32>, SegmentError> {
    let mut weights = vec![1.0f32; graph.vertex_count()];
    for (v, hops) in graph.hops_from(attached, RENDER_RAMP_EDGES)? {
        weights[v as usize] = hops as f32 / RENDER_RAMP_EDGES as f32;
    }
    Ok(weights)
}

/// Steps a reset takes to move the garment from the rest pose into the body's pose.
const DRESS_STEPS: usize = 8;
/// Their length, seconds.
const DRESS_DT: f32 = 1.0 / 120.0;

/// Blends two bone transforms by `t`: scale and translation linearly, rotation by slerp.
pub(crate) fn lerp_affine(a: &Affine3A, b: &Affine3A, t: f32) -> Affine3A {
    let (sa, ra, ta) = a.to_scale_rotation_translation();
    let (sb, rb, tb) = b.to_scale_rotation_translation();
    Affine3A::from_scale_rotation_translation(sa.lerp(sb, t), ra.slerp(rb, t), ta.lerp(tb, t))
}

/// Smoothing passes of the garment's skin weights over its mesh.
const SKIN_SMOOTHING: usize = 12;

/// Largest share of a collider's radius that [`fit_to_anchors`] takes away.
const MAX_COLLIDER_SHRINK: f32 = 0.6;

/// Anchors [`fit_to_anchors`] bounds together.
const ANCHOR_RUN: usize = 8;

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
fn anchor_runs_into(anchors: &[Vec3], runs: &mut Vec<(Vec3, Vec3)>) {
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
fn collider_cuts(
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
fn apply_cuts(collider: &mut (Vec3, Vec3, f32, f32), (cut_a, cut_b): (f32, f32)) -> f32 {
    collider.2 -= cut_a;
    collider.3 -= cut_b;
    cut_a.max(cut_b)
}

/// Skin weights averaged with the mesh neighbours' `passes` times (Jacobi), then cut to the
/// four largest and renormalised.
fn smooth_skin(
    skin: Vec<([u16; 4], [f32; 4])>,
    graph: &MeshGraph,
    bones: usize,
    passes: usize,
) -> Vec<([u16; 4], [f32; 4])> {
    let n = skin.len();
    let mut dense = vec![0.0f32; n * bones];
    for (v, (j, w)) in skin.iter().enumerate() {
        for k in 0..4 {
            if let Some(slot) = dense.get_mut(v * bones + j[k] as usize) {
                *slot += w[k];
            }
        }
    }
    let mut next = dense.clone();
    for _ in 0..passes {
        for v in 0..n {
            let neighbours = graph.neighbours(v);
            let count = (neighbours.len() + 1) as f32;
            for b in 0..bones {
                let mut sum = dense[v * bones + b];
                for &u in neighbours {
                    sum += dense[u as usize * bones + b];
                }
                next[v * bones + b] = sum / count;
            }
        }
        std::mem::swap(&mut dense, &mut next);
    }
    (0..n)
        .map(|v| {
            let row = &dense[v * bones..(v + 1) * bones];
            let mut idx: Vec<usize> = (0..bones).collect();
            idx.sort_by(|&a, &b| row[b].total_cmp(&row[a]));
            let mut j = [0u16; 4];
            let mut w = [0.0f32; 4];
            for k in 0..4.min(bones) {
                j[k] = idx[k] as u16;
                w[k] = row[idx[k]];
            }
            let total: f32 = w.iter().sum();
            if total > 0.0 {
                for x in &mut w {
                    *x /= total;
                }
            }
            (j, w)
        })
        .collect()
}

/// Index of the nearest point of `points` for each of `queries` (a uniform grid of 3 cm cells;
/// falls back to a full search where the neighbourhood is empty).
fn nearest(points: &[Vec3], queries: &[Vec3]) -> Vec<usize> {
    use std::collections::HashMap;
    let cell = 0.03f32;
    let key = |p: Vec3| {
        (
            (p.x / cell).floor() as i32,
            (p.y / cell).floor() as i32,
            (p.z / cell).floor() as i32,
        )
    };
    let mut grid: HashMap<(i32, i32, i32), Vec<usize>> = HashMap::new();
    for (i, &p) in points.iter().enumerate() {
        grid.entry(key(p)).or_default().push(i);
    }
    queries
        .iter()
        .map(|&q| {
            let (x, y, z) = key(q);
            let mut best: Option<(f32, usize)> = None;
            for r in 1..=4 {
                for dx in -r..=r {
                    for dy in -r..=r {
                        for dz in -r..=r {
                            if let Some(list) = grid.get(&(x + dx, y + dy, z + dz)) {
                                for &i in list {
                                    let d = points[i].distance_squared(q);
                                    if best.is_none_or(|b| d < b.0) {
                                        best = Some((d, i));
                                    }
                                }
                            }
                        }
                    }
                }
                // Anything found within r cells is exact once r cells cover its distance.
                if let Some((d, _)) = best
                    && d.sqrt() <= (r as f32 - 1.0) * cell
                {
                    break;
                }
            }
            best.map(|b| b.1).unwrap_or_else(|| {
                points
                    .iter()
                    .enumerate()
                    .min_by(|a, b| a.1.distance_squared(q).total_cmp(&b.1.distance_squared(q)))
                    .map_or(0, |(i, _)| i)
            })
        })
        .collect()
}

/// The colliders that yield to the trunk and thighs ([`yield_to_body`]) and that the cloth
/// slides off without friction: the forearms and hands.
const YIELDING: [&str; 4] = ["lowerarm_l", "lowerarm_r", "hand_l", "hand_r"];
/// Name prefixes of the colliders they yield to.
const FIRM: [&str; 3] = ["pelvis", "spine_", "thigh_"];
/// The room a yielding collider leaves the firm ones, metres: room for the cloth between a
/// hand and a hip (with 2 cm the dress still stretched 108 % on 16_11, with 3.5 cm 27 %).
const YIELD_CLEARANCE_M: f32 = 0.035;
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
fn yield_to_body(
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

/// [`GarmentSim`]'s mark of a garment vertex the solver does not step.
const NOT_SIMULATED: u32 = u32::MAX;

/// The part of a garment (`vertex_count` vertices, `triangles`, `attached` ones following the
/// body) that the solver steps: its vertices (increasing) and its triangles in their numbering.
///
/// That is every triangle with a free vertex, and every triangle that shares an edge with one
/// (so that each bending stencil, which spans the two triangles of an edge, and each distance
/// constraint with a free particle is whole), with their vertices and any free vertex in no
/// triangle. The attached vertices left out (the inside of a skinned bodice) share no
/// constraint with a free particle, and tethers run to the nearest attached vertices along the
/// mesh, which border the free ones: leaving them out changes no constraint and no tether of
/// the free cloth. A garment without free vertices keeps them all.
pub fn simulated_part(
    vertex_count: usize,
    triangles: &[[u32; 3]],
    attached: &[u32],
) -> (Vec<u32>, Vec<[u32; 3]>) {
    let mut is_attached = vec![false; vertex_count];
    for &v in attached {
        if let Some(a) = is_attached.get_mut(v as usize) {
            *a = true;
        }
    }
    let free = |v: u32| !is_attached.get(v as usize).copied().unwrap_or(true);
    if !(0..vertex_count as u32).any(free) {
        return ((0..vertex_count as u32).collect(), triangles.to_vec());
    }
    let edge = |t: &[u32; 3], k: usize| {
        let (a, b) = (t[k], t[(k + 1) % 3]);
        (a.min(b), a.max(b))
    };
    let with_free = |t: &[u32; 3]| t.iter().any(|&v| free(v));
    let free_edges: std::collections::HashSet<(u32, u32)> = triangles
        .iter()
        .filter(|t| with_free(t))
        .flat_map(|t| (0..3).map(move |k| edge(t, k)))
        .collect();
    let kept: Vec<&[u32; 3]> = triangles
        .iter()
        .filter(|t| with_free(t) || (0..3).any(|k| free_edges.contains(&edge(t, k))))
        .collect();
    let mut keep: Vec<bool> = (0..vertex_count as u32).map(free).collect();
    for t in &kept {
        for &v in t.iter() {
            if let Some(k) = keep.get_mut(v as usize) {
                *k = true;
            }
        }
    }
    let vertices: Vec<u32> = (0..vertex_count as u32)
        .filter(|&v| keep[v as usize])
        .collect();
    let mut number = vec![NOT_SIMULATED; vertex_count];
    for (i, &v) in vertices.iter().enumerate() {
        number[v as usize] = i as u32;
    }
    let triangles = kept
        .into_iter()
        .map(|t| t.map(|v| number[v as usize]))
        .collect();
    (vertices, triangles)
}

/// Free vertices nearer than this to a collider in the rest pose are "near" for [`work_hints`].
const NEAR_BODY_M: f32 = 0.03;
/// The extra work of a near vertex, in units of a free vertex's.
const NEAR_EXTRA_WORK: f32 = 0.8;
/// The work of an attached vertex (it follows its target in every substep), in units of a
/// free vertex's.
const ATTACHED_WORK: f32 = 0.1;

/// Each vertex's share of a step's work, for the solver's split of the garment between its
/// threads ([`ClothSolver::new_balanced`]): [`ATTACHED_WORK`] for an attached vertex, 1 for a
/// free one, and more for a free one lying against the body at rest, which will be tested
/// against colliders and pushed out in most substeps. The weights are fitted to the
/// 4,000-particle dress's measured work per thread (session 13, one thread: a free vertex
/// ~0.23 µs a step, 0.13 for its constraints and 0.10 for its own work; a near one ~0.20
/// more; an attached one ~0.02).
fn work_hints(positions: &[Vec3], attached: &[u32], colliders: &BodyColliders) -> Vec<f32> {
    let mut work: Vec<f32> = positions
        .iter()
        .map(|&p| {
            if colliders.signed_distance(p) < NEAR_BODY_M {
                1.0 + NEAR_EXTRA_WORK
            } else {
                1.0
            }
        })
        .collect();
    for &v in attached {
        if let Some(w) = work.get_mut(v as usize) {
            *w = ATTACHED_WORK;
        }
    }
    work
}

impl GarmentSim {
    /// A garment on the body with these (shaped) positions and rest pose.
    pub fn new(
        model: &BodyModel,
        body_positions: &[Vec3],
        rest: &RestPose,
        garment: &SimGarment,
        settings: SolverSettings,
    ) -> Result<Self, SimError> {
        let vertex_count = garment.positions.len();
        let (particle_vertex, part_triangles) =
            simulated_part(vertex_count, &garment.triangles, &garment.attached);
        let mut vertex_particle = vec![NOT_SIMULATED; vertex_count];
        for (p, &v) in particle_vertex.iter().enumerate() {
            vertex_particle[v as usize] = p as u32;
        }
        let mut attached: Vec<u32> = garment
            .attached
            .iter()
            .copied()
            .filter(|&v| {
                vertex_particle
                    .get(v as usize)
                    .is_some_and(|&p| p != NOT_SIMULATED)
            })
            .collect();
        attached.sort_unstable();
        attached.dedup();
        let attached_particles: Vec<u32> = attached
            .iter()
            .map(|&v| vertex_particle[v as usize])
            .collect();
        let part_positions: Vec<Vec3> = particle_vertex
            .iter()
            .map(|&v| garment.positions[v as usize])
            .collect();
        let mesh = ClothMesh::new(part_positions.clone(), part_triangles)?;
        let settings = SolverSettings {
            collision_thickness: settings.collision_thickness.max(BODY_SKIN_OFFSET_M),
            ..settings
        };
        let mut colliders =
            BodyColliders::fit(model, body_positions, rest, &ColliderOptions::default())?;
        for name in &garment.ignore_colliders {
            if !colliders.capsules.iter().any(|c| c.name == name) {
                return Err(SimError::UnknownCollider(name.clone()));
            }
        }
        colliders
            .capsules
            .retain(|c| !garment.ignore_colliders.iter().any(|n| n == c.name));
        let work = work_hints(&part_positions, &attached_particles, &colliders);
        let solver =
            ClothSolver::new_balanced(&mesh, garment.fabric, &attached_particles, settings, &work)?;
        // Every vertex takes the skin of its nearest body vertex, smoothed over the garment's
        // mesh (a sleeve's armpit edge would otherwise be torn between the arm and the chest in
        // a pose): the attached ones follow the body with it, and a reset puts the whole garment
        // where the skinned body is, outside it as it was placed.
        let body = &body_positions[..model.body_vertex_count as usize];
        let graph = MeshGraph::new(garment.positions.len(), &garment.triangles)?;
        let skin = smooth_skin(
            nearest(body, &garment.positions)
                .into_iter()
                .map(|v| (model.skin_joints[v], model.skin_weights[v]))
                .collect(),
            &graph,
            model.bones.len(),
            SKIN_SMOOTHING,
        );
        // Each edge once, as (lower vertex, higher vertex, rest length), in that order.
        let edges: Vec<(u32, u32, f32)> = (0..graph.vertex_count())
            .flat_map(|a| {
                graph
                    .neighbours(a)
                    .iter()
                    .filter(move |&&b| b as usize > a)
                    .map(move |&b| (a as u32, b))
            })
            .map(|(a, b)| {
                let rest = garment.positions[a as usize].distance(garment.positions[b as usize]);
                (a, b, rest)
            })
            .collect();
        let named = |names: &dyn Fn(&str) -> bool| -> Vec<usize> {
            colliders
                .capsules
                .iter()
                .enumerate()
                .filter(|(_, c)| names(c.name))
                .map(|(i, _)| i)
                .collect()
        };
        let yielding = named(&|n| YIELDING.contains(&n));
        let firm = named(&|n| FIRM.iter().any(|f| n.starts_with(f)));
        Ok(Self {
            yielding,
            firm,
            solver,
            rest: garment.positions.clone(),
            triangles: garment.triangles.clone(),
            attached,
            particle_vertex,
            vertex_particle,
            skinning: Vec::new(),
            measured: Vec::new(),
            skin,
            colliders,
            bones: model.bones.len(),
            edges,
            floor_y: None,
            resets: 0,
            measuring: true,
            last_targets: None,
            pelvis: model.bone_index("pelvis"),
            render_weight: render_weights(&graph, &garment.attached)?,
            teleports: 0,
            spheres: Vec::new(),
            capsules: Vec::new(),
            posed: Vec::new(),
            spare_targets: Vec::new(),
            anchor_runs: Vec::new(),
            posing: Posing {
                pieces: (0..POSE_PIECES).map(|_| Mutex::default()).collect(),
                shared_from: SHARED_POSING_MIN,
                ..Posing::default()
            },
        })
    }

    /// Whether [`GarmentSim::step`] measures penetration and strain after each step (on by
    /// default; the app turns it off and asks for the strain only when it draws the fit map).
    pub fn set_measuring(&mut self, on: bool) {
        self.measuring = on;
    }

    /// A floor (horizontal plane at height `y` in the simulation's space), or none.
    pub fn set_floor(&mut self, y: Option<f32>) -> Result<(), SimError> {
        self.floor_y = y;
        let planes: Vec<Plane> = y.map(Plane::floor).into_iter().collect();
        self.solver.set_planes(&planes)?;
        Ok(())
    }

    fn skin_point(&self, v: usize, skinning: &[Affine3A]) -> Vec3 {
        let (j, w) = self.skin[v];
        let p = self.rest[v];
        let mut out = Vec3::ZERO;
        for k in 0..4 {
            if w[k] > 0.0
                && let Some(m) = skinning.get(j[k] as usize)
            {
                out += m.transform_point3(p) * w[k];
            }
        }
        out
    }

    /// The garment skinned like the body (its pose without simulation).
    pub fn skinned(&self, skinning: &[Affine3A]) -> Vec<Vec3> {
        (0..self.rest.len())
            .map(|v| self.skin_point(v, skinning))
            .collect()
    }

    /// Where garment vertex `v`, which the solver does not step, is: skinned by the last
    /// step's or reset's skinning (at rest before the first).
    fn static_point(&self, v: usize) -> Vec3 {
        if self.skinning.is_empty() {
            self.rest[v]
        } else {
            self.skin_point(v, &self.skinning)
        }
    }

    /// The garment's positions into `out` (cleared first): the solver's particles, and the
    /// static vertices it does not step where the last skinning puts them.
    fn positions_into(&self, out: &mut Vec<Vec3>) {
        let particles = self.solver.positions();
        out.clear();
        out.extend(self.vertex_particle.iter().enumerate().map(|(v, &p)| {
            match particles.get(p as usize) {
                Some(&q) => Vec3::from(q),
                None => self.static_point(v),
            }
        }));
    }

    /// Keeps `skinning` for the static vertices (without allocating after the first time).
    fn keep_skinning(&mut self, skinning: &[Affine3A]) {
        self.skinning.clear();
        self.skinning.extend_from_slice(skinning);
    }

    fn check(&self, skinning: &[Affine3A]) -> Result<(), SimError> {
        if skinning.len() != self.bones {
            return Err(SimError::Bones {
                got: skinning.len(),
                expected: self.bones,
            });
        }
        Ok(())
    }

    /// The body colliders posed by `skinning`, each shrunk where the garment's attached
    /// (skinned) vertices `anchors` lie inside it (see [`fit_to_anchors`]), and the forearms
    /// and hands then yielding to the trunk and thighs ([`yield_to_body`]). Also returns the
    /// largest radius taken away for the anchors, metres.
    fn posed_colliders(
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
    fn set_solver_colliders(&mut self, posed: &[(Vec3, Vec3, f32, f32)]) -> Result<(), SimError> {
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

    fn anchors(&self, skinning: &[Affine3A]) -> Vec<Vec3> {
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
    fn pose_on_threads(
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

    /// Where to draw the garment, and its normals: its positions, the simulated part drawn
    /// [`RENDER_OFFSET_M`] out along its normals (see there), blending in over
    /// [`RENDER_RAMP_EDGES`] edges from the attached part, which is drawn where it is. The
    /// normals are those of the simulated surface (the offset one is parallel to it).
    pub fn render_surface(&self) -> (Vec<Vec3>, Vec<Vec3>) {
        let (mut positions, mut normals) = (Vec::new(), Vec::new());
        self.render_surface_into(&mut positions, &mut normals);
        (positions, normals)
    }

    /// [`Self::render_surface`] into `positions` and `normals` (cleared first), to reuse their
    /// storage frame after frame.
    pub fn render_surface_into(&self, positions: &mut Vec<Vec3>, normals: &mut Vec<Vec3>) {
        self.positions_into(positions);
        fitroom_body::rig::compute_normals_into(positions, &self.triangles, normals);
        for ((p, &n), &w) in positions
            .iter_mut()
            .zip(normals.iter())
            .zip(&self.render_weight)
        {
            if n.is_finite() {
                *p += n * (w * RENDER_OFFSET_M);
            }
        }
    }

    /// The garment's current positions.
    pub fn positions(&self) -> Vec<Vec3> {
        let mut out = Vec::new();
        self.positions_into(&mut out);
        out
    }

    /// Particles the solver steps (the garment's vertices less the static ones that share no
    /// constraint with a free one, see [`simulated_part`]).
    pub fn simulated_particles(&self) -> usize {
        self.solver.particle_count()
    }

    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    /// Longest tether over its allowed length (1.0 = at the limit).
    pub fn max_tether_ratio(&self) -> f32 {
        self.solver.max_tether_ratio()
    }

    /// Body colliders the garment collides with.
    pub fn collider_count(&self) -> usize {
        self.colliders.capsules.len()
    }

    /// Body teleports the garment followed so far.
    pub fn teleports(&self) -> u32 {
        self.teleports
    }

    /// Blow-ups that were reset so far.
    pub fn resets(&self) -> u32 {
        self.resets
    }

    /// Per vertex: the largest stretch of its edges over their rest length, % (negative when
    /// all its edges are compressed).
    pub fn strain_pct(&self) -> Vec<f32> {
        let p = self.positions();
        let mut out = vec![f32::NEG_INFINITY; p.len()];
        for &(a, b, rest) in &self.edges {
            if rest <= 0.0 {
                continue;
            }
            let s = (p[a as usize].distance(p[b as usize]) / rest - 1.0) * 100.0;
            for v in [a, b] {
                let o = &mut out[v as usize];
                *o = o.max(s);
            }
        }
        for o in &mut out {
            if !o.is_finite() {
                *o = 0.0;
            }
        }
        out
    }

    /// Per vertex: distance to the posed body colliders' surface, metres (negative inside).
    pub fn gap_m(&self, skinning: &[Affine3A]) -> Vec<f32> {
        self.gaps(&self.posed_colliders(skinning, &self.anchors(skinning)).0)
    }

    /// Deepest simulated (free) particle inside a collider, metres (0 if none). Attached
    /// particles are where the skinned body puts them, not the solver.
    pub fn max_penetration(&self, skinning: &[Affine3A]) -> f32 {
        self.deepest(&self.posed_colliders(skinning, &self.anchors(skinning)).0)
    }

    fn gaps(&self, posed: &[(Vec3, Vec3, f32, f32)]) -> Vec<f32> {
        self.positions().iter().map(|&q| gap(q, posed)).collect()
    }

    fn deepest(&self, posed: &[(Vec3, Vec3, f32, f32)]) -> f32 {
        self.deepest_of(posed, 0..self.solver.particle_count())
    }

    /// [`Self::deepest`] over the particles of `range` (never negative, never NaN; possibly
    /// -0.0).
    fn deepest_of(&self, posed: &[(Vec3, Vec3, f32, f32)], range: Range<usize>) -> f32 {
        let start = range.start;
        self.solver.positions()[range]
            .iter()
            .enumerate()
            .filter(|(i, _)| {
                self.solver
                    .attached()
                    .binary_search(&((start + i) as u32))
                    .is_err()
            })
            .fold(0.0f32, |m, (_, &q)| m.max(-gap(q.into(), posed)))
    }

    /// The largest stretch over its rest length of the edges of `range`, the garment at `p`,
    /// % (0 if none is stretched; never NaN): the largest of [`Self::strain_pct`] over them.
    fn max_strain_pct_of(&self, p: &[Vec3], range: Range<usize>) -> f32 {
        self.edges[range]
            .iter()
            .filter(|e| e.2 > 0.0)
            .map(|&(a, b, rest)| (p[a as usize].distance(p[b as usize]) / rest - 1.0) * 100.0)
            .fold(0.0, f32::max)
    }

    /// [`Self::deepest`] and the largest edge stretch ([`Self::max_strain_pct_of`] of every
    /// edge), the work shared out to the solver's threads in pieces (the same results: each
    /// is the largest of its pieces'). Besides taking half the time, this keeps the workers
    /// awake for the next step, as the steps of a frame find them when nothing is measured
    /// between them.
    fn measure_on_threads(&self, posed: &[(Vec3, Vec3, f32, f32)], p: &[Vec3]) -> (f32, f32) {
        const PIECES: usize = 16;
        let posing = &self.posing;
        posing.deepest.store(0, Ordering::Relaxed);
        posing.strain.store(0, Ordering::Relaxed);
        let (particles, edges) = (self.solver.particle_count(), self.edges.len());
        let piece = |count: usize, k: usize| {
            let size = count.div_ceil(PIECES);
            (k * size).min(count)..((k + 1) * size).min(count)
        };
        self.solver.share_out(PIECES, &|k| {
            // Both maxima are at least zero and never NaN, and the bits of such floats order
            // as they do; `+ 0.0` turns a maximum of -0.0 (whose bits would beat every
            // positive float's) into +0.0.
            let deepest = self.deepest_of(posed, piece(particles, k)) + 0.0;
            posing
                .deepest
                .fetch_max(deepest.to_bits(), Ordering::Relaxed);
            let strain = self.max_strain_pct_of(p, piece(edges, k)) + 0.0;
            posing.strain.fetch_max(strain.to_bits(), Ordering::Relaxed);
        });
        (
            f32::from_bits(posing.deepest.load(Ordering::Relaxed)),
            f32::from_bits(posing.strain.load(Ordering::Relaxed)),
        )
    }
}

/// Signed distance from `q` to the nearest of the `posed` colliders (negative inside).
fn gap(q: Vec3, posed: &[(Vec3, Vec3, f32, f32)]) -> f32 {
    posed
        .iter()
        .map(|&(a, b, ra, rb)| round_cone_distance(q, a, b, ra, rb))
        .fold(f32::INFINITY, f32::min)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The sun dress (size 38) on the default body, simulated on `threads` threads: the body
    /// model, the garment, its simulation and the solver settings.
    fn sun_dress(threads: usize) -> (BodyModel, SimGarment, GarmentSim, SolverSettings) {
        let assets = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets");
        let model = BodyModel::read(&assets.join("bodies/makehuman.fitbody")).expect("the body");
        let shaped = model
            .shaped(&fitroom_body::Shape::default())
            .expect("the default shape");
        let surface = crate::BodySurface::new(&model, &shaped).expect("the body measures");
        let dress = crate::Pattern::load(assets.join("garments/sundress.ron"))
            .expect("the sun dress")
            .build(&surface, "38", &crate::BuildOptions::default())
            .expect("the dress on the body");
        let settings = SolverSettings {
            threads,
            ..SolverSettings::default()
        };
        let garment = SimGarment::from_mesh(&dress);
        let sim = GarmentSim::new(
            &model,
            &shaped.positions,
            &shaped.rest_pose,
            &garment,
            settings,
        )
        .expect("a valid garment");
        (model, garment, sim, settings)
    }

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

    /// A strip of 2 × 8 vertices attached at its first four columns: the solver steps the
    /// free columns, the attached column next to them and the one vertex of the column before
    /// that a triangle sharing an edge with a free triangle brings in.
    #[test]
    fn the_simulated_part_is_the_free_cloth_and_the_triangles_around_it() {
        let mut triangles = Vec::new();
        for i in 0..7u32 {
            let (a, b, c, d) = (i, i + 1, i + 8, i + 9);
            triangles.push([a, b, d]);
            triangles.push([a, d, c]);
        }
        let attached: Vec<u32> = (0..4).chain(8..12).collect();
        let (vertices, part) = simulated_part(16, &triangles, &attached);
        // [3, 4, 12] and [3, 12, 11] hold free vertices; [2, 3, 11] shares their edge 3-11
        // (the bending stencil across it reaches the free vertex 12), so vertex 2 comes in;
        // [2, 11, 10] shares no edge with a free triangle, so vertex 10 stays out.
        let expected: Vec<u32> = (2..8).chain(11..16).collect();
        assert_eq!(vertices, expected);
        assert_eq!(
            part.len(),
            2 * 4 + 1,
            "four free quads and one triangle around them"
        );
        for t in &part {
            for &v in t {
                assert!((v as usize) < vertices.len());
            }
        }
        // Nothing free: everything is kept.
        let all: Vec<u32> = (0..16).collect();
        let (vertices, part) = simulated_part(16, &triangles, &all);
        assert_eq!(vertices, all);
        assert_eq!(part, triangles);
    }

    /// On the sun dress (a skinned bodice over a simulated skirt), the solver's part holds
    /// every constraint and tether the whole garment's solver has, and the same particle
    /// masses; the static vertices left out are drawn where the skinning puts them.
    #[test]
    fn the_dress_solver_part_keeps_every_constraint_of_the_whole_dress() {
        let (model, garment, mut sim, settings) = sun_dress(1);
        let whole = ClothSolver::new(
            &ClothMesh::new(garment.positions.clone(), garment.triangles.clone())
                .expect("the dress's mesh"),
            garment.fabric,
            &garment.attached,
            settings,
        )
        .expect("the whole dress's solver");
        let n = garment.positions.len();
        let part = sim.simulated_particles();
        assert!(part < n, "the bodice's inside is left out: {part} of {n}");
        assert!(part > n - garment.attached.len(), "every free vertex is in");
        assert_eq!(sim.solver.constraint_counts(), whole.constraint_counts());
        assert_eq!(sim.solver.tether_count(), whole.tether_count());
        for (p, &v) in sim.particle_vertex.iter().enumerate() {
            if sim.solver.attached().binary_search(&(p as u32)).is_err() {
                assert_eq!(
                    sim.solver.masses()[p],
                    whole.masses()[v as usize],
                    "vertex {v}"
                );
            }
        }
        // A turned pose: the static vertices are where skinning puts them, the others where
        // the solver has them.
        let pose: Vec<Affine3A> = (0..model.bones.len())
            .map(|b| Affine3A::from_rotation_y(0.01 * (b % 5) as f32))
            .collect();
        sim.reset(&pose).expect("a reset");
        sim.step(&pose, 1.0 / 120.0).expect("a step");
        let positions = sim.positions();
        assert_eq!(positions.len(), n);
        for (v, &p) in positions.iter().enumerate() {
            match sim.vertex_particle[v] {
                NOT_SIMULATED => assert_eq!(p, sim.skin_point(v, &pose), "static vertex {v}"),
                q => assert_eq!(p, Vec3::from(sim.solver.positions()[q as usize])),
            }
        }
        let (drawn, normals) = sim.render_surface();
        assert_eq!((drawn.len(), normals.len()), (n, n));
    }

    #[test]
    fn the_render_offset_blends_in_from_the_attached_part() {
        // A strip of 2 x 8 vertices, attached at its first column.
        let mut triangles = Vec::new();
        for i in 0..7u32 {
            let (a, b, c, d) = (i, i + 1, i + 8, i + 9);
            triangles.push([a, b, d]);
            triangles.push([a, d, c]);
        }
        // One more vertex in no triangle.
        let graph = MeshGraph::new(17, &triangles).expect("a valid mesh");
        let w = render_weights(&graph, &[0, 8]).expect("valid attachments");
        let expected = |i: u32| (i as f32 / RENDER_RAMP_EDGES as f32).min(1.0);
        for i in 0..8u32 {
            assert_eq!(w[i as usize], expected(i), "top {i}");
            assert_eq!(w[i as usize + 8], expected(i), "bottom {i}");
        }
        assert_eq!(w[16], 1.0, "the isolated vertex");
        // Nothing attached: drawn out everywhere.
        assert!(
            render_weights(&graph, &[])
                .expect("no attachments")
                .iter()
                .all(|&x| x == 1.0)
        );
    }

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
