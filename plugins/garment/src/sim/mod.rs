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
//!
//! The code is split along the simulation's seams:
//! - `part`: the part of the garment the solver steps, and each vertex's share of the work.
//! - `skin`: the garment's skin weights, taken from the nearest body vertices and smoothed.
//! - `colliders`: the posed body colliders fitted to the skinned garment, the forearms and
//!   hands yielding to the trunk and thighs.
//! - `posing`: each step's attachment targets and colliders, shared out to the solver's
//!   threads.
//! - `step`: reset (dressing the body) and the step, with its teleport and blow-up handling.
//! - `report`: what is read out: the drawn surface, positions, strain and gap.

mod colliders;
mod part;
mod posing;
mod report;
mod skin;
mod step;

use std::sync::Mutex;

use glam::{Affine3A, Vec3};
use serde::Serialize;

use fitroom_body::colliders::{BodyColliders, ColliderOptions};
use fitroom_body::{BodyModel, MeshGraph, RestPose, SegmentError};
use fitroom_cloth::{ClothError, ClothMesh, ClothSolver, Fabric, Plane, SolverSettings, Sphere};

pub use colliders::{BODY_SKIN_OFFSET_M, fit_to_anchors};
pub use part::simulated_part;
pub use report::{RENDER_OFFSET_M, RENDER_RAMP_EDGES};
#[cfg(feature = "plugin")]
pub(crate) use skin::lerp_affine;

use colliders::{FIRM, YIELDING};
use part::{NOT_SIMULATED, work_hints};
use posing::{POSE_PIECES, Posing, SHARED_POSING_MIN};
use report::render_weights;
use skin::{SKIN_SMOOTHING, nearest, smooth_skin};

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
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The sun dress (size 38) on the default body, simulated on `threads` threads: the body
    /// model, the garment, its simulation and the solver settings.
    pub(super) fn sun_dress(threads: usize) -> (BodyModel, SimGarment, GarmentSim, SolverSettings) {
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
}
