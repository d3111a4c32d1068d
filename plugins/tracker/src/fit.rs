//! Articulated ICP: the [`TrackBody`] fitted to one depth frame by damped Gauss-Newton
//! (Levenberg-Marquardt with a fixed damping) over the root's translation, rotation and scale
//! and the tracked bones' rotations, after Ganapathi, Plagemann, Koller & Thrun 2012
//! ("Real-time human pose tracking from range data", ECCV). Three terms:
//!
//! * **data to model**: each sampled point of the person lies on the nearest capsule's
//!   surface (point-to-surface distance, Huber-weighted; far points are outliers: a skirt, a
//!   bag);
//! * **model to data (free space)**: the front of each capsule, sampled along its axis and
//!   projected, must land on the person's silhouette, not where the camera sees past the
//!   body (pulled towards the nearest person pixel), and must not float in front of the
//!   surface the camera sees there (an arm's pull back bounded: seen end-on, a forearm is a
//!   small patch easily missed sideways);
//! * **detections**: optional targets for Kinect joints (geodesic extrema of head, hands and
//!   feet), to start and recover without a prior pose.
//!
//! Each step's damping is the temporal prior (the fit starts from the last frame's pose);
//! joint ranges and hinges are enforced after each step ([`TrackBody::clamp`]).

use fitroom_depth::DepthFrame;
use glam::{Quat, Vec3};
use serde::Serialize;

use crate::model::{JointKind, Pose, Posed, TrackBody};
use crate::silhouette::Silhouette;
use crate::skirt::SkirtZone;
use fitroom_sensor::KinectJoint;

/// Weights and thresholds of the fit.
#[derive(Clone, Copy, Debug)]
pub struct FitSettings {
    /// Data residuals beyond this are down-weighted (Huber), metres.
    pub huber_m: f32,
    /// Data points farther than this from every capsule are ignored, metres.
    pub outlier_m: f32,
    /// Weight of one free-space sample relative to one data point.
    pub free_space_weight: f32,
    /// Weight of one detection target relative to one data point.
    pub target_weight: f32,
    /// Damping per step, in data points' worth, for a rotation (per radian²) and for a
    /// translation (per metre², relative to the rotation's by the body's size).
    pub damping: f32,
    /// Damping of the scale relative to a rotation's. Very stiff by default: the person's
    /// height sets the scale at the start, and a capsule body left free to grow does (by 4 %
    /// on the rest body, where the right answer is known to be 1).
    pub scale_stiffness: f32,
    /// A point of an arm's front lying on the person but in front of the surface seen there
    /// is pulled back by at most this much, metres (Huber). Seen end-on, a forearm raised
    /// towards the sensor is a small patch: a little off sideways, its front projects onto
    /// the body 20-30 cm behind, and the unbounded pull (the trunk's and legs' still is)
    /// took the arm back down to the side.
    pub arm_front_cap_m: f32,
    /// On a body wearing the clothing layer ([`TrackBody::clothe`]), the weight of a point
    /// lying outside a clothed bone's skin relative to one inside it: a loose shirt touches
    /// the body where it is widest (shoulders, chest) and hangs clear of it below, so its
    /// points lie at or outside the skin, and those inside it are the firm evidence. (With
    /// the body under the shirt from `fitroom_measure`'s fit and all 45 T-shirt recordings
    /// of the acceptance set taken as clothed: mean / trunk 61.1 / 43.3 mm at 1, 53.9 / 37.5
    /// at 0.3; docs/STATUS.md, session 45. The tracker's own macro search, without a
    /// `BuildFit`, fits its clothed candidates with it too: not measured there.)
    pub cloth_gap_weight: f32,
    /// The weight of a point outside the body in a skirt worn but not found in the frame
    /// ([`crate::skirt::SkirtMemory`]) relative to one inside it.
    pub skirt_worn_weight: f32,
    /// Weight of one contact sample (a point on a forearm's or a hand's axis) sunk into the
    /// trunk's skin, relative to one data point. An arm hanging against a heavy trunk or a
    /// shirt shows no gap in the depth, and its points are explained as well by a forearm
    /// folded into the belly as by one beside it; the body cannot pass through itself.
    pub contact_weight: f32,
    /// How deep an arm may sink into the trunk's skin before the contact term pushes it out,
    /// metres (flesh gives, and the capsules and the skin only approximate the person), on top
    /// of the clothing layer (an arm against the body lies inside the layer).
    pub contact_tolerance_m: f32,
}

impl Default for FitSettings {
    fn default() -> Self {
        Self {
            huber_m: 0.02,
            outlier_m: 0.12,
            free_space_weight: 4.0,
            target_weight: 200.0,
            damping: 2.0,
            scale_stiffness: 1.0e6,
            arm_front_cap_m: 0.05,
            cloth_gap_weight: 0.3,
            skirt_worn_weight: 0.3,
            contact_weight: 20.0,
            contact_tolerance_m: 0.02,
        }
    }
}

/// What one frame offers the fit.
pub struct Observation<'a> {
    pub frame: &'a DepthFrame,
    /// The person's pixels, full resolution.
    pub mask: &'a [bool],
    pub silhouette: &'a Silhouette,
    /// Sampled points of the person, sensor space.
    pub points: &'a [Vec3],
    /// Detections: (Kinect joint index, where it is, weight multiplier).
    pub targets: &'a [(usize, Vec3, f32)],
    /// Where a skirt hides the legs ([`crate::skirt`]): its points, unless on an arm, are
    /// left out of the data term if it was found in this frame ([`SkirtZone::seen`]), and
    /// pull weakly from outside the body if it is only worn
    /// ([`FitSettings::skirt_worn_weight`]); the silhouette and free space still hold the legs
    /// inside it.
    pub skirt: Option<&'a SkirtZone>,
}

/// How well a fit matches its frame.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct FitStats {
    /// Share of the data points within 3 cm of the model's surface.
    pub inliers: f32,
    /// Mean absolute data residual of the non-outliers, metres.
    pub mean_residual_m: f32,
    /// Share of the data points farther than [`FitSettings::outlier_m`] from the model: what
    /// the fit leaves unexplained.
    pub outliers: f32,
    /// Share of the capsules' front samples in the image that fall where the camera sees
    /// past the person.
    pub outside: f32,
    /// Iterations run.
    pub iterations: usize,
}

/// Per capsule, the points that lie on it within 3 cm (the evidence for its bone).
pub type Support = Vec<u32>;

/// Parameters: root translation (3), root rotation (3), scale (1), then each tracked
/// joint's (3 for a ball, 1 for a hinge).
struct Layout {
    offsets: Vec<usize>,
    count: usize,
    /// Per bone, whether it is an arm's: moved by an upper arm.
    arm: Vec<bool>,
    /// Per bone, whether it wears the body's clothing layer (none on a bare body).
    loose: Vec<bool>,
    /// Per bone, whether it is a forearm's or a hand's: an arm's but not an upper arm.
    forearm: Vec<bool>,
}

const ROOT: usize = 7;

impl Layout {
    fn new(body: &TrackBody) -> Self {
        let mut offsets = Vec::with_capacity(body.joints.len());
        let mut at = ROOT;
        for j in &body.joints {
            offsets.push(at);
            at += match j.kind {
                JointKind::Ball => 3,
                JointKind::Hinge { .. } => 1,
            };
        }
        // The bones an upper arm moves (the upper arm, the forearm, the hand).
        let shoulders = [
            body.drivers[KinectJoint::ElbowLeft.index()],
            body.drivers[KinectJoint::ElbowRight.index()],
        ];
        let arm: Vec<bool> = (0..body.parents.len())
            .map(|b| {
                body.chains[b]
                    .iter()
                    .any(|&j| shoulders.contains(&body.joints[j].bone))
            })
            .collect();
        let forearm = (0..body.parents.len())
            .map(|b| arm[b] && !shoulders.contains(&b))
            .collect();
        let loose = (0..body.parents.len())
            .map(|b| body.layer_m > 0.0 && body.clothed.contains(&b))
            .collect();
        Self {
            offsets,
            count: at,
            arm,
            loose,
            forearm,
        }
    }
}

/// The fit's scratch space, kept between frames.
#[derive(Default)]
pub struct Fitter {
    posed: Posed,
    h: Vec<f64>,
    g: Vec<f64>,
    row: Vec<(usize, f32)>,
    pub support: Support,
    /// Per data point, the capsules worth testing: all in a fit's first step, then the
    /// [`CANDIDATES`] nearest found then (a point does not change limbs within a frame).
    candidates: Vec<[u8; CANDIDATES]>,
    gathered: Vec<Gathered>,
    /// Per data point, the capsule it was matched on and its bone's skin vertex (`u32::MAX`: none),
    /// found again every [`MATCH_EVERY`] steps and followed in between.
    matches: Vec<(u32, u32)>,
    refresh_matches: bool,
    /// Per bone, sensor space to the bone's rest frame, this step.
    to_bone: Vec<glam::Affine3A>,
}

/// Steps between two searches for each point's nearest skin vertex.
const MATCH_EVERY: usize = 3;
const NO_MATCH: u32 = u32::MAX;

/// One capsule's data residuals gathered in one step: `M = Σ w ψ ψᵀ` (upper triangle) and
/// `v = Σ w r ψ` over its points, with `ψ = (dir, p × dir, p · dir)`: every parameter's row
/// entry for a point is a fixed combination of ψ's seven numbers.
#[derive(Clone, Copy, Default)]
struct Gathered {
    m: [[f64; 7]; 7],
    v: [f64; 7],
}

const CANDIDATES: usize = 4;

/// The closest point's distance and outward normal of a tapered capsule (the sphere swept
/// along the axis, its radius interpolated at the point's projection on the axis).
pub(crate) fn capsule_distance(p: Vec3, a: Vec3, b: Vec3, ra: f32, rb: f32) -> (f32, Vec3) {
    let ab = b - a;
    let l2 = ab.length_squared();
    let t = if l2 > 1e-12 {
        ((p - a).dot(ab) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let c = a + ab * t;
    let v = p - c;
    let len = v.length();
    let n = if len > 1e-9 { v / len } else { Vec3::NEG_Z };
    (len - (ra + (rb - ra) * t), n)
}

impl Fitter {
    /// Runs `iterations` steps of the fit from `pose`, in place.
    pub fn fit(
        &mut self,
        body: &TrackBody,
        pose: &mut Pose,
        obs: &Observation,
        settings: &FitSettings,
        iterations: usize,
    ) -> FitStats {
        let layout = Layout::new(body);
        let n = layout.count;
        let mut stats = FitStats::default();
        self.candidates.clear();
        self.matches.clear();
        for iteration in 0..iterations {
            self.refresh_matches = iteration % MATCH_EVERY == 0;
            body.pose_into(pose, &mut self.posed);
            self.h.clear();
            self.h.resize(n * n, 0.0);
            self.g.clear();
            self.g.resize(n, 0.0);
            let pivot = self.posed.head(body.root);
            stats = self.accumulate(body, &layout, pivot, obs, settings);
            stats.iterations += 1;
            // The temporal prior as damping: rotations per radian², translations scaled to
            // the body's size (a 1 m lever), the scale stiffer.
            let base = f64::from(settings.damping);
            for i in 0..3 {
                self.h[i * n + i] += base;
                self.h[(3 + i) * n + 3 + i] += base;
            }
            self.h[6 * n + 6] += base * f64::from(settings.scale_stiffness);
            for (j, joint) in body.joints.iter().enumerate() {
                let dofs = match joint.kind {
                    JointKind::Ball => 3,
                    JointKind::Hinge { .. } => 1,
                };
                for d in 0..dofs {
                    let i = layout.offsets[j] + d;
                    self.h[i * n + i] += base * f64::from(joint.stiffness);
                }
            }
            let Some(step) = solve(&mut self.h, &self.g, n) else {
                break;
            };
            apply(body, &layout, pose, &self.posed, pivot, &step);
            body.clamp(pose);
        }
        stats
    }

    /// Adds every residual's row to the normal equations; returns the frame's statistics.
    // Index loops over the small fixed matrices read as the formulas they implement.
    #[allow(clippy::needless_range_loop)]
    fn accumulate(
        &mut self,
        body: &TrackBody,
        layout: &Layout,
        pivot: Vec3,
        obs: &Observation,
        settings: &FitSettings,
    ) -> FitStats {
        let posed = std::mem::take(&mut self.posed);
        let mut stats = FitStats::default();
        self.support.clear();
        self.support.resize(posed.capsules.len(), 0);
        self.gathered.clear();
        self.gathered
            .resize(posed.capsules.len(), Gathered::default());
        if self.refresh_matches {
            self.to_bone.clear();
            self.to_bone
                .extend(posed.frames.iter().map(|f| f.inverse()));
            self.matches.clear();
        }
        // Data to model.
        let (mut inliers, mut used, mut sum, mut outliers) = (0usize, 0usize, 0.0f32, 0usize);
        // Points a skirt hides: out of the data term and of its shares.
        let mut hidden = 0usize;
        let first = self.candidates.len() != obs.points.len();
        if first {
            self.candidates.clear();
        }
        for (i, &p) in obs.points.iter().enumerate() {
            let mut best = (f32::INFINITY, 0usize);
            if first {
                // Every capsule; keep the nearest few for the next steps.
                let mut near = [(f32::INFINITY, 0u8); CANDIDATES];
                for (k, &(a, b, ra, rb)) in posed.capsules.iter().enumerate() {
                    let (d, _) = capsule_distance(p, a, b, ra, rb);
                    if d.abs() < near[CANDIDATES - 1].0 {
                        near[CANDIDATES - 1] = (d.abs(), k as u8);
                        near.sort_by(|x, y| x.0.total_cmp(&y.0));
                    }
                    if d.abs() < best.0.abs() {
                        best = (d, k);
                    }
                }
                self.candidates.push(near.map(|(_, k)| k));
            } else {
                for &k in &self.candidates[i] {
                    let (a, b, ra, rb) = posed.capsules[usize::from(k)];
                    let (d, _) = capsule_distance(p, a, b, ra, rb);
                    if d.abs() < best.0.abs() {
                        best = (d, usize::from(k));
                    }
                }
            }
            let (capsule_d, k) = best;
            // The skin of the capsule's bone: the distance to the nearest vertex's tangent
            // plane (the capsule's own surface where the skin has no vertex within reach).
            let bone = body.capsules[k].bone;
            if self.refresh_matches {
                let local = self.to_bone[bone].transform_point3(p);
                let v = body.surfaces[bone].nearest(local).unwrap_or(NO_MATCH);
                self.matches.push((k as u32, v));
            }
            // Between two searches the point stays with the capsule it was matched on: its
            // residual and its rows are that bone's (the nearest capsule may change between
            // steps, the vertex followed is not the new one's).
            let (k, v) = match self.matches.get(i) {
                Some(&(matched, v)) if v != NO_MATCH => (matched as usize, v),
                _ => (k, NO_MATCH),
            };
            let matched_bone = body.capsules[k].bone;
            let (d, normal, far) = match body.surfaces[matched_bone].points.get(v as usize) {
                Some(&at) if v != NO_MATCH => {
                    let b = matched_bone;
                    let at = posed.frames[b].transform_point3(at);
                    let n = (posed.rotations[b] * body.surfaces[b].normals[v as usize])
                        .normalize_or_zero();
                    (n.dot(p - at), n, p.distance(at))
                }
                _ => {
                    let (a, b, ra, rb) = posed.capsules[k];
                    let (_, n) = capsule_distance(p, a, b, ra, rb);
                    (capsule_d, n, capsule_d.abs())
                }
            };
            // A skirt's point pulls no leg or pelvis (as skin, the skirt drew the thighs
            // forward and the calves down, and the knees bent: the person sank into it).
            // One worn but not seen in this frame pulls weakly: hidden, a leg lost there had
            // nothing to find it by.
            let mut worn = false;
            if let Some(skirt) = obs.skirt
                && !layout.arm[matched_bone]
                && skirt.hides(p)
            {
                if skirt.seen {
                    hidden += 1;
                    continue;
                }
                worn = true;
            }
            if far < 0.03 {
                inliers += 1;
                self.support[k] += 1;
            }
            if far > settings.outlier_m {
                outliers += 1;
                continue;
            }
            used += 1;
            sum += d.abs();
            let mut w = if d.abs() > settings.huber_m {
                settings.huber_m / d.abs()
            } else {
                1.0
            };
            if d > 0.0 && layout.loose[matched_bone] {
                w *= settings.cloth_gap_weight;
            }
            if d > 0.0 && worn {
                w *= settings.skirt_worn_weight;
            }
            // The capsule moving by δ at p changes d by -n·δ: gathered per capsule as
            // ψ = (dir, p × dir, p · dir) with dir = -n (see `Gathered`).
            let dir = -normal;
            let psi = [dir, p.cross(dir)];
            let psi = [
                psi[0].x,
                psi[0].y,
                psi[0].z,
                psi[1].x,
                psi[1].y,
                psi[1].z,
                p.dot(dir),
            ]
            .map(f64::from);
            let acc = &mut self.gathered[k];
            let (w, r) = (f64::from(w), f64::from(d));
            for i in 0..7 {
                let wi = w * psi[i];
                acc.v[i] += wi * r;
                for j in i..7 {
                    acc.m[i][j] += wi * psi[j];
                }
            }
        }
        self.spread_gathered(body, layout, &posed, pivot);
        let fitted = (obs.points.len() - hidden).max(1) as f32;
        stats.inliers = inliers as f32 / fitted;
        stats.mean_residual_m = sum / used.max(1) as f32;
        stats.outliers = outliers as f32 / fitted;
        // Model to data: the front of each capsule, along its axis.
        let camera = obs.frame.camera;
        let (mut seen, mut outside) = (0usize, 0usize);
        for (k, &(a, b, ra, rb)) in posed.capsules.iter().enumerate() {
            let samples: &[f32] = if a.distance_squared(b) < 1e-8 {
                &[0.0]
            } else {
                &[0.1, 0.5, 0.9]
            };
            for &t in samples {
                let c = a.lerp(b, t);
                let s = c - c.normalize_or_zero() * (ra + (rb - ra) * t);
                let Some(px) = camera.project(s) else {
                    continue;
                };
                let (u, v) = (px.x.round(), px.y.round());
                if !(0.0..(fitroom_depth::WIDTH as f32)).contains(&u)
                    || !(0.0..(fitroom_depth::HEIGHT as f32)).contains(&v)
                {
                    continue;
                }
                seen += 1;
                let i = v as usize * fitroom_depth::WIDTH + u as usize;
                let z = f32::from(obs.frame.depth_mm[i]) / 1000.0;
                let bone = body.capsules[k].bone;
                if obs.mask[i] {
                    // On the person: the model must not float in front of the surface seen.
                    if z > 0.0 && z - s.z > 0.04 {
                        let r = s.z - z + 0.04;
                        let cap = settings.arm_front_cap_m;
                        let w = if layout.arm[bone] && r.abs() > cap {
                            cap / r.abs()
                        } else {
                            1.0
                        };
                        self.row.clear();
                        self.point_row(body, layout, &posed, pivot, bone, s, Vec3::Z);
                        self.add_row(r, settings.free_space_weight * w, layout.count);
                    }
                    continue;
                }
                if z > 0.0 && z < s.z - 0.1 {
                    continue; // something in front hides this part: no evidence
                }
                let Some(target) = obs.silhouette.nearest(u, v) else {
                    continue;
                };
                outside += 1;
                let to = camera.unproject(target[0], target[1], s.z);
                let e = s - to;
                let w = settings.free_space_weight;
                for (axis, r) in [(Vec3::X, e.x), (Vec3::Y, e.y)] {
                    let wr = if r.abs() > 0.05 { 0.05 / r.abs() } else { 1.0 };
                    self.row.clear();
                    self.point_row(body, layout, &posed, pivot, bone, s, axis);
                    self.add_row(r, w * wr, layout.count);
                }
            }
        }
        stats.outside = outside as f32 / seen.max(1) as f32;
        self.contact(body, layout, &posed, pivot, settings);
        // Detections.
        for &(joint, target, weight) in obs.targets {
            let (bone, local) = body.kinect[joint];
            let q = posed.frames[bone].transform_point3(local);
            let e = q - target;
            for (axis, r) in [(Vec3::X, e.x), (Vec3::Y, e.y), (Vec3::Z, e.z)] {
                self.row.clear();
                self.point_row(body, layout, &posed, pivot, bone, q, axis);
                self.add_row(r, settings.target_weight * weight, layout.count);
            }
        }
        self.posed = posed;
        stats
    }

    /// The contact term: each forearm's and hand's axis, sampled, kept out of the trunk's
    /// skin (beyond [`FitSettings::contact_tolerance_m`] and the clothing layer). The sample's
    /// sphere against the skin of the nearest trunk capsule's bone (its nearest vertex's
    /// tangent plane); the row moves the arm out and the trunk away, so a contact never moves
    /// the body as a whole.
    fn contact(
        &mut self,
        body: &TrackBody,
        layout: &Layout,
        posed: &Posed,
        pivot: Vec3,
        settings: &FitSettings,
    ) {
        if settings.contact_weight <= 0.0 || body.trunk.is_empty() {
            return;
        }
        let tolerance = settings.contact_tolerance_m + body.layer_m;
        for (k, &(a, b, ra, rb)) in posed.capsules.iter().enumerate() {
            let bone = body.capsules[k].bone;
            if !layout.forearm[bone] {
                continue;
            }
            for t in [0.1, 0.5, 0.9] {
                let c = a.lerp(b, t);
                let r = ra + (rb - ra) * t;
                // The nearest trunk capsule picks the bone whose skin is asked.
                let mut nearest = (f32::INFINITY, Vec3::ZERO, usize::MAX);
                for (q, &(qa, qb, qra, qrb)) in posed.capsules.iter().enumerate() {
                    if body.trunk.contains(&body.capsules[q].bone) {
                        let (d, n) = capsule_distance(c, qa, qb, qra, qrb);
                        if d < nearest.0 {
                            nearest = (d, n, q);
                        }
                    }
                }
                let (d, capsule_n, q) = nearest;
                // Far from every trunk capsule: no contact to test.
                if q == usize::MAX || d > r + 0.05 {
                    continue;
                }
                let trunk = body.capsules[q].bone;
                let surface = &body.surfaces[trunk];
                let local = posed.frames[trunk].inverse().transform_point3(c);
                // The skin's nearest vertex within reach (a few cm); deeper in, the capsule.
                let (at, n) = match surface.nearest(local) {
                    Some(v) => (
                        posed.frames[trunk].transform_point3(surface.points[v as usize]),
                        (posed.rotations[trunk] * surface.normals[v as usize]).normalize_or_zero(),
                    ),
                    None if d < 0.0 => (c - capsule_n * d, capsule_n),
                    None => continue,
                };
                let overlap = r - n.dot(c - at);
                if overlap <= tolerance {
                    continue;
                }
                // d(overlap) = -n·δ(arm) + n·δ(trunk).
                self.row.clear();
                self.point_row(body, layout, posed, pivot, bone, c, -n);
                self.point_row(body, layout, posed, pivot, trunk, at, n);
                self.add_row(overlap - tolerance, settings.contact_weight, layout.count);
            }
        }
    }

    /// Adds each capsule's gathered data residuals to the normal equations: with the row of
    /// a point `c · ψ` per parameter (`c` from [`Self::coefficients`]), `H += Cᵀ M C` and
    /// `g += Cᵀ v`: one small product per capsule instead of one outer product per point.
    #[allow(clippy::needless_range_loop)]
    fn spread_gathered(&mut self, body: &TrackBody, layout: &Layout, posed: &Posed, pivot: Vec3) {
        let n = layout.count;
        let mut coefficients: Vec<(usize, [f64; 7])> = Vec::new();
        for (k, acc) in self.gathered.iter().enumerate() {
            if acc.m[0][0] == 0.0 && acc.m[1][1] == 0.0 && acc.m[2][2] == 0.0 {
                continue;
            }
            let mut m = acc.m;
            for i in 0..7 {
                for j in 0..i {
                    m[i][j] = m[j][i];
                }
            }
            coefficients.clear();
            Self::coefficients(
                body,
                layout,
                posed,
                pivot,
                body.capsules[k].bone,
                &mut coefficients,
            );
            // M C, column by column.
            let mc: Vec<[f64; 7]> = coefficients
                .iter()
                .map(|(_, c)| {
                    let mut out = [0.0; 7];
                    for (i, o) in out.iter_mut().enumerate() {
                        *o = (0..7).map(|j| m[i][j] * c[j]).sum();
                    }
                    out
                })
                .collect();
            for (i, ci) in &coefficients {
                self.g[*i] += (0..7).map(|t| ci[t] * acc.v[t]).sum::<f64>();
                for ((j, _), mcj) in coefficients.iter().zip(&mc) {
                    if j >= i {
                        self.h[i * n + j] += (0..7).map(|t| ci[t] * mcj[t]).sum::<f64>();
                    }
                }
            }
        }
    }

    /// Per parameter moving `bone`, the coefficients `c` with which its row entry for a point
    /// `p` and direction `dir` is `c · (dir, p × dir, p · dir)`: a turn `ω` about a centre `o`
    /// moves `p` along `dir` by `ω · ((p - o) × dir)`, and `(o × dir)_i` is linear in `dir`.
    #[allow(clippy::needless_range_loop)]
    fn coefficients(
        body: &TrackBody,
        layout: &Layout,
        posed: &Posed,
        pivot: Vec3,
        bone: usize,
        out: &mut Vec<(usize, [f64; 7])>,
    ) {
        let f = |v: Vec3, w: Vec3, last: f32| [v.x, v.y, v.z, w.x, w.y, w.z, last].map(f64::from);
        // Row i of the cross-product matrix [o]×: (o × dir)_i = row_i · dir.
        let cross_row = |o: Vec3, i: usize| match i {
            0 => Vec3::new(0.0, -o.z, o.y),
            1 => Vec3::new(o.z, 0.0, -o.x),
            _ => Vec3::new(-o.y, o.x, 0.0),
        };
        let axes = [Vec3::X, Vec3::Y, Vec3::Z];
        for i in 0..3 {
            out.push((i, f(axes[i], Vec3::ZERO, 0.0)));
        }
        for i in 0..3 {
            out.push((3 + i, f(-cross_row(pivot, i), axes[i], 0.0)));
        }
        out.push((6, f(-pivot, Vec3::ZERO, 1.0)));
        for &j in &body.chains[bone] {
            let joint = &body.joints[j];
            let centre = posed.head(joint.bone);
            let at = layout.offsets[j];
            match joint.kind {
                JointKind::Ball => {
                    for i in 0..3 {
                        out.push((at + i, f(-cross_row(centre, i), axes[i], 0.0)));
                    }
                }
                JointKind::Hinge { axis, .. } => {
                    let w = posed.rotations[joint.bone] * axis;
                    out.push((at, f(-w.cross(centre), w, 0.0)));
                }
            }
        }
    }

    /// The row of `dir · δp` for a point `p` moving with `bone`: how each parameter moves it
    /// along `dir`.
    #[allow(clippy::too_many_arguments)]
    fn point_row(
        &mut self,
        body: &TrackBody,
        layout: &Layout,
        posed: &Posed,
        pivot: Vec3,
        bone: usize,
        p: Vec3,
        dir: Vec3,
    ) {
        // Translation: δp = τ; rotation about the pivot: δp = ω × (p - pivot), so
        // dir·δp = ω · ((p - pivot) × dir); scale about the pivot: δp = σ (p - pivot).
        for i in 0..3 {
            self.row.push((i, dir[i]));
        }
        let m = (p - pivot).cross(dir);
        for i in 0..3 {
            self.row.push((3 + i, m[i]));
        }
        self.row.push((6, (p - pivot).dot(dir)));
        for &j in &body.chains[bone] {
            let joint = &body.joints[j];
            let centre = posed.head(joint.bone);
            let m = (p - centre).cross(dir);
            let at = layout.offsets[j];
            match joint.kind {
                JointKind::Ball => {
                    for i in 0..3 {
                        self.row.push((at + i, m[i]));
                    }
                }
                JointKind::Hinge { axis, .. } => {
                    let world = posed.rotations[joint.bone] * axis;
                    self.row.push((at, world.dot(m)));
                }
            }
        }
    }

    /// Adds `w (r + row·δ)²` to the normal equations.
    fn add_row(&mut self, r: f32, w: f32, n: usize) {
        let (r, w) = (f64::from(r), f64::from(w));
        for &(i, a) in &self.row {
            let a = f64::from(a) * w;
            self.g[i] += a * r;
            for &(j, b) in &self.row {
                if j >= i {
                    self.h[i * n + j] += a * f64::from(b);
                }
            }
        }
    }
}

/// Solves `H δ = -g` for the symmetric positive definite `H` (upper triangle filled) by
/// Cholesky; `None` if it is not positive definite. Hand-written: the system is small
/// (about 50 unknowns) and a linear-algebra crate would add more than it saves.
fn solve(h: &mut [f64], g: &[f64], n: usize) -> Option<Vec<f64>> {
    for i in 0..n {
        for j in 0..i {
            h[i * n + j] = h[j * n + i];
        }
    }
    // In place: the lower triangle becomes L with H = L Lᵀ.
    for j in 0..n {
        let mut d = h[j * n + j];
        for k in 0..j {
            d -= h[j * n + k] * h[j * n + k];
        }
        if d.is_nan() || d <= 1e-12 {
            return None;
        }
        let d = d.sqrt();
        h[j * n + j] = d;
        for i in j + 1..n {
            let mut s = h[i * n + j];
            for k in 0..j {
                s -= h[i * n + k] * h[j * n + k];
            }
            h[i * n + j] = s / d;
        }
    }
    let mut y = vec![0.0; n];
    for i in 0..n {
        let mut s = -g[i];
        for k in 0..i {
            s -= h[i * n + k] * y[k];
        }
        y[i] = s / h[i * n + i];
    }
    for i in (0..n).rev() {
        let mut s = y[i];
        for k in i + 1..n {
            s -= h[k * n + i] * y[k];
        }
        y[i] = s / h[i * n + i];
    }
    y.iter().all(|v| v.is_finite()).then_some(y)
}

/// A rotation vector as a quaternion.
fn exp(w: Vec3) -> Quat {
    let angle = w.length();
    if angle < 1e-9 {
        Quat::IDENTITY
    } else {
        Quat::from_axis_angle(w / angle, angle)
    }
}

/// Applies a step: world-frame increments turned into the pose's parameters.
fn apply(
    body: &TrackBody,
    layout: &Layout,
    pose: &mut Pose,
    posed: &Posed,
    pivot: Vec3,
    d: &[f64],
) {
    let v = |i: usize| Vec3::new(d[i] as f32, d[i + 1] as f32, d[i + 2] as f32);
    let (tau, omega, sigma) = (v(0), v(3), (d[6] as f32).clamp(-0.05, 0.05));
    let turn = exp(omega);
    pose.rotation = (turn * pose.rotation).normalize();
    let about = pose.translation - pivot;
    pose.translation = pivot + turn * about * (1.0 + sigma) + tau;
    pose.scale *= 1.0 + sigma;
    for (j, joint) in body.joints.iter().enumerate() {
        let at = layout.offsets[j];
        let Some(local) = pose.local.get_mut(joint.bone) else {
            continue;
        };
        match joint.kind {
            JointKind::Ball => {
                // A world turn ω of the bone: local' = local · exp(W⁻¹ ω), W its world rotation.
                let w = posed.rotations[joint.bone].inverse() * v(at);
                *local = (*local * exp(w)).normalize();
            }
            JointKind::Hinge { axis, .. } => {
                *local = (*local * exp(axis * d[at] as f32)).normalize();
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cholesky_solves_a_known_system() {
        // H = A Aᵀ + I for a fixed A; check H x = -g by multiplying back.
        let n = 6;
        let a: Vec<f64> = (0..n * n)
            .map(|k| ((k * 7 % 11) as f64 - 5.0) / 3.0)
            .collect();
        let mut h = vec![0.0; n * n];
        for i in 0..n {
            for j in 0..n {
                h[i * n + j] = (0..n).map(|k| a[i * n + k] * a[j * n + k]).sum::<f64>()
                    + if i == j { 1.0 } else { 0.0 };
            }
        }
        let original = h.clone();
        let g: Vec<f64> = (0..n).map(|i| i as f64 - 2.5).collect();
        let x = solve(&mut h, &g, n).expect("positive definite");
        for i in 0..n {
            let hx: f64 = (0..n).map(|j| original[i * n + j] * x[j]).sum();
            assert!((hx + g[i]).abs() < 1e-9, "row {i}: {hx} vs {}", -g[i]);
        }
    }

    #[test]
    fn capsule_distance_is_exact_for_a_cylinder() {
        let (d, n) = capsule_distance(Vec3::new(0.3, 0.5, 0.0), Vec3::ZERO, Vec3::Y, 0.1, 0.1);
        assert!((d - 0.2).abs() < 1e-6);
        assert!(n.distance(Vec3::X) < 1e-6);
        let (d, _) = capsule_distance(Vec3::new(0.0, 1.5, 0.0), Vec3::ZERO, Vec3::Y, 0.1, 0.1);
        assert!((d - 0.4).abs() < 1e-6);
    }
}
