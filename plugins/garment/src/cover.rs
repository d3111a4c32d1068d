//! Which of the body's skin a garment covers, so that the renderer can leave it out.
//!
//! The body colliders lie inside the skin (by 1.5 cm on the trunk and up to 3 cm at the front
//! of the thighs, so that they never stick out of it; see `fitroom_body::colliders`), and the
//! cloth rests 3 mm over them. Drawn 2.5 cm farther out along its normals
//! ([`crate::sim::RENDER_OFFSET_M`]) a skirt still lets patches of thigh and hip show through
//! in a stride. Where a garment surely covers the body, the body need not be drawn at all (as
//! games and fitting rooms do): a body vertex is *covered* when, in the pose the garment was
//! placed in, a garment vertex lies over it (along its normal, at most [`COVER_GAP_M`] out
//! and [`COVER_REACH_M`] to the side), and that garment vertex is at least
//! [`COVER_MARGIN_M`] along the garment's surface from the garment's open edges where they
//! are free (a hem, a sleeve's end), or [`STATIC_MARGIN_M`] where they follow the body (a
//! skinned bodice's neckline). The margin keeps the skin near
//! an opening drawn, where a garment moving over the body uncovers it (a stride lifts a
//! skirt's hem, a raised arm pulls up a sleeve). And the garment vertex must move with that
//! skin: the body vertex nearest to it is driven by the same bone as the covered one, or by
//! its parent or a child (a hand hanging beside a skirt at rest is not covered by it, nor the
//! inside of an upper arm by a T-shirt's side).

use std::cmp::Ordering;
use std::collections::{BinaryHeap, HashMap};

use fitroom_body::{BodyModel, MeshGraph, SegmentError};
use fitroom_math::CellGrid;
use glam::Vec3;

/// Farthest a covering garment vertex lies out from the skin (along its normal), metres.
pub const COVER_GAP_M: f32 = 0.05;
/// Farthest a covering garment vertex lies to the side of the skin's normal, metres (more
/// than the distance from a point of a garment triangle to its nearest vertex at the shipped
/// garments' ~2 cm edges).
pub const COVER_REACH_M: f32 = 0.025;
/// Least distance along the garment from its free open edges of a covering garment vertex,
/// metres.
pub const COVER_MARGIN_M: f32 = 0.10;
/// The same from open edges whose vertices follow the body (attached or skinned), metres: the
/// skin is hidden from [`COVER_REACH_M`] less than that inside such an edge, so that no gap
/// opens between the edge, which stands off the skin, and the skin drawn.
pub const STATIC_MARGIN_M: f32 = 0.045;
/// How far behind the skin (along its normal) a covering garment vertex may lie, metres: a
/// skinned bodice is placed on the skin, within rounding.
const BEHIND_SKIN_M: f32 = 0.01;

/// Per body vertex of `model` (its body vertices only, at `body` with unit `normals`): whether
/// the garment (its rest positions `garment`, in the body's space, `triangles`, and the
/// vertices that follow the body, `attached`) covers it, as the module documentation says. An
/// error if a triangle names a vertex out of range.
pub fn covered_skin(
    model: &BodyModel,
    (body, normals): (&[Vec3], &[Vec3]),
    garment: &[Vec3],
    triangles: &[[u32; 3]],
    attached: &[u32],
) -> Result<Vec<bool>, SegmentError> {
    // The dominant bone: the model lists each vertex's bones largest weight first.
    let bone_of: Vec<usize> = (0..body.len())
        .map(|v| {
            model
                .skin_joints
                .get(v)
                .map_or(usize::MAX, |j| j[0] as usize)
        })
        .collect();
    let related = |a: usize, b: usize| {
        let parent = |x: usize| model.bones.get(x).and_then(|bone| bone.parent);
        a != usize::MAX && (a == b || parent(a) == Some(b) || parent(b) == Some(a))
    };
    covered_by(
        (body, normals, &bone_of),
        &related,
        (garment, triangles, attached),
    )
}

/// [`covered_skin`] with each body vertex's bone given (`bone_of`) and which bones move
/// together (`related`).
fn covered_by(
    (body, normals, bone_of): (&[Vec3], &[Vec3], &[usize]),
    related: &dyn Fn(usize, usize) -> bool,
    (garment, triangles, attached): (&[Vec3], &[[u32; 3]], &[u32]),
) -> Result<Vec<bool>, SegmentError> {
    let graph = MeshGraph::new(garment.len(), triangles)?;
    let inland = distance_from_edges(garment, triangles, &graph, attached);
    let body_grid = CellGrid::of_points(body, COVER_GAP_M);
    // Garment vertices far enough from the edges, with the bone of their nearest body vertex
    // (within the grid's reach), in a grid of COVER_GAP_M cells.
    let mut grid = CellGrid::new(COVER_GAP_M);
    let mut garment_bone = vec![usize::MAX; garment.len()];
    for (g, &q) in garment.iter().enumerate() {
        if inland[g] < COVER_MARGIN_M || !q.is_finite() {
            continue;
        }
        let nearest = body_grid.around(q, 1).min_by(|&a, &b| {
            body[a as usize]
                .distance_squared(q)
                .total_cmp(&body[b as usize].distance_squared(q))
                .then(a.cmp(&b))
        });
        if let Some(b) = nearest {
            garment_bone[g] = bone_of[b as usize];
            grid.insert(g as u32, q);
        }
    }
    Ok(body
        .iter()
        .zip(normals)
        .enumerate()
        .map(|(v, (&p, &n))| {
            p.is_finite()
                && grid.around(p, 1).any(|g| {
                    let d = garment[g as usize] - p;
                    let out = d.dot(n);
                    (-BEHIND_SKIN_M..=COVER_GAP_M).contains(&out)
                        && d.length_squared() - out * out <= COVER_REACH_M * COVER_REACH_M
                        && related(bone_of[v], garment_bone[g as usize])
                })
        })
        .collect())
}

/// Per garment vertex: its distance along the mesh's edges from the nearest vertex on an open
/// edge (an edge of one triangle), metres, counting an `attached` vertex there as
/// [`COVER_MARGIN_M`] − [`STATIC_MARGIN_M`] away already; infinite on a closed mesh.
fn distance_from_edges(
    positions: &[Vec3],
    triangles: &[[u32; 3]],
    graph: &MeshGraph,
    attached: &[u32],
) -> Vec<f32> {
    let mut follows = vec![false; positions.len()];
    for &a in attached {
        if let Some(f) = follows.get_mut(a as usize) {
            *f = true;
        }
    }
    let mut uses: HashMap<(u32, u32), u32> = HashMap::new();
    for t in triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            *uses.entry((a.min(b), a.max(b))).or_default() += 1;
        }
    }
    let mut distance = vec![f32::INFINITY; positions.len()];
    let mut queue = BinaryHeap::new();
    for (&(a, b), &n) in &uses {
        if n == 1 {
            for v in [a, b] {
                let start = if follows[v as usize] {
                    COVER_MARGIN_M - STATIC_MARGIN_M
                } else {
                    0.0
                };
                if start < distance[v as usize] {
                    distance[v as usize] = start;
                    queue.push(Nearest(start, v));
                }
            }
        }
    }
    // Dijkstra from the open edges' vertices.
    while let Some(Nearest(d, v)) = queue.pop() {
        if d > distance[v as usize] {
            continue;
        }
        for &u in graph.neighbours(v as usize) {
            let step = positions[v as usize].distance(positions[u as usize]);
            let next = d + step;
            if next < distance[u as usize] {
                distance[u as usize] = next;
                queue.push(Nearest(next, u));
            }
        }
    }
    distance
}

/// A queue entry: the nearest first.
struct Nearest(f32, u32);

impl PartialEq for Nearest {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}

impl Eq for Nearest {}

impl PartialOrd for Nearest {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Nearest {
    fn cmp(&self, other: &Self) -> Ordering {
        other.0.total_cmp(&self.0).then(other.1.cmp(&self.1))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 1 m × 1 m sheet of 2 cm squares at z = 0.02 over a grid of "skin" points at z = 0
    /// facing +z: the points under the sheet's inside are covered, those within the margin of
    /// its edges or beyond it are not, nor any facing away from the sheet with it behind.
    #[test]
    fn a_sheet_covers_the_skin_under_its_inside_only() {
        // A 1 m square sheet of 2 cm cells, 2 cm over the skin.
        let step = 0.02f32;
        let sheet =
            fitroom_cloth::ClothMesh::grid(Vec3::new(0.0, 0.0, 0.02), Vec3::X, Vec3::Y, 50, 50)
                .expect("a valid grid");
        let (garment, triangles) = (sheet.positions(), sheet.triangles());
        let mut body = Vec::new();
        for j in -4..30 {
            for i in -4..30 {
                body.push(Vec3::new(i as f32 * 0.04, j as f32 * 0.04, 0.0));
            }
        }
        let up = vec![Vec3::Z; body.len()];
        let bones = vec![0; body.len()];
        let same = |a: usize, b: usize| a == b;
        let sheet = (garment, triangles, &[][..]);
        let covered = covered_by((&body, &up, &bones), &same, sheet).expect("a valid sheet");
        // Distance along the sheet from its edges is at least the distance in the plane from
        // its border square (edges run along the grid and its diagonals).
        let inside = |p: Vec3| p.x.min(p.y).min(1.0 - p.x).min(1.0 - p.y);
        let mut hidden = 0;
        for (p, &c) in body.iter().zip(&covered) {
            let d = inside(*p);
            if d >= COVER_MARGIN_M + step {
                assert!(c, "{p} is well inside the sheet");
                hidden += 1;
            }
            if d < COVER_MARGIN_M - COVER_REACH_M {
                assert!(!c, "{p} is near the sheet's edge or beyond it");
            }
        }
        assert!(hidden > 200, "{hidden}");
        // Facing away from the sheet, which then lies 2 cm behind the skin: not covered.
        let down = vec![-Vec3::Z; body.len()];
        let away = covered_by((&body, &down, &bones), &same, sheet).expect("a valid sheet");
        assert!(away.iter().all(|&c| !c));
        // The skin of bones that do not move together: not covered.
        let never = |_: usize, _: usize| false;
        let apart = covered_by((&body, &up, &bones), &never, sheet).expect("a valid sheet");
        assert!(apart.iter().all(|&c| !c));
        // Two bones, split at x = 0.5: the sheet over each side covers it; across the split, a
        // point is covered only by sheet vertices nearest to its own side.
        let halves: Vec<usize> = body.iter().map(|p| usize::from(p.x >= 0.5)).collect();
        let split = covered_by((&body, &up, &halves), &same, sheet).expect("a valid sheet");
        for ((p, &c), &whole) in body.iter().zip(&split).zip(&covered) {
            assert!(!c || whole, "{p}: covered only when split");
            if whole && (p.x - 0.5).abs() > COVER_REACH_M + step {
                assert!(c, "{p} is far from the split");
            }
        }
    }

    /// The shipped garments on the default body, their seams welded as the app wears them:
    /// the sun dress covers most of the hips and upper thighs and none of the head, the
    /// forearms, the hands or the feet; the T-shirt covers most of the chest and back and none
    /// of the legs, forearms, hands or head.
    #[test]
    fn the_shipped_garments_cover_what_they_should() {
        use fitroom_body::BodyModel;
        let assets = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets");
        let model = BodyModel::read(&assets.join("bodies/makehuman.fitbody")).expect("the body");
        let shaped = model
            .shaped(&fitroom_body::Shape::default())
            .expect("the default shape");
        let n = model.body_vertex_count as usize;
        let surface = crate::BodySurface::new(&model, &shaped).expect("the body measures");
        // Per body vertex, the name of its dominant bone.
        let bone_of: Vec<&str> = (0..n)
            .map(|v| model.bones[model.skin_joints[v][0] as usize].name.as_str())
            .collect();
        let share = |covered: &[bool], prefix: &[&str]| {
            let of: Vec<usize> = (0..n)
                .filter(|&v| prefix.iter().any(|p| bone_of[v].starts_with(p)))
                .collect();
            of.iter().filter(|&&v| covered[v]).count() as f32 / of.len().max(1) as f32
        };
        for (file, size, covers, spares) in [
            (
                "sundress.ron",
                "38",
                &["pelvis", "thigh_"][..],
                &["head", "lowerarm", "hand", "foot", "ball"][..],
            ),
            (
                "tshirt.ron",
                "M",
                &["spine_02", "spine_03"][..],
                &["head", "lowerarm", "hand", "thigh", "calf", "foot"][..],
            ),
        ] {
            let garment = crate::Pattern::load(assets.join("garments").join(file))
                .expect("the garment")
                .build(&surface, size, &crate::BuildOptions::default())
                .and_then(|m| m.welded(&surface))
                .expect("the garment on the body, its seams welded");
            let follows = crate::sim::SimGarment::from_mesh(&garment).attached;
            let covered = covered_skin(
                &model,
                (&shaped.positions[..n], &shaped.normals[..n]),
                &garment.positions,
                &garment.triangles,
                &follows,
            )
            .expect("a valid garment");
            let hidden = share(&covered, covers);
            let spared = share(&covered, spares);
            eprintln!(
                "{file}: covers {:.1} % of {covers:?}, {:.2} % of {spares:?}",
                100.0 * hidden,
                100.0 * spared
            );
            assert!(hidden > 0.3, "{file}: {hidden}");
            assert!(spared == 0.0, "{file}: {spared}");
        }
    }
}
