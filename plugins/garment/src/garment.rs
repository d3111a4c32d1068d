//! From a pattern to a garment mesh on the body: grading, meshing, placement, sewing,
//! attachment and binding; and the [`GarmentMesh`] every garment source produces.

use std::collections::{BTreeSet, HashMap};

use fitroom_cloth::{ClothMesh, Fabric};
use glam::{Vec2, Vec3};

use crate::binding::{Binding, skin_weights_for};
use crate::body::{BodySurface, Region};
use crate::error::GarmentError;
use crate::mesher::{mesh_polygon, polyline_length, resample_polyline};
use crate::pattern::{Pattern, SeamDirection, edge_polyline};
use crate::placement::{RowReport, place_wrap, push_outside};

/// A garment ready to simulate on a body.
///
/// All vertices form one cloth mesh: the **attached** ones (the static, skinned part and the
/// pinned bands) are driven by the body through [`GarmentMesh::binding`]
/// (`binding.positions(skinned body positions, normals)` gives their targets, in the order of
/// `attached`); the others are simulated. A pattern garment's panels are separate pieces
/// joined by `seams`: either weld them ([`GarmentMesh::welded`]) or give the solver the
/// vertex pairs as zero-rest-length constraints.
#[derive(Clone, Debug, PartialEq)]
pub struct GarmentMesh {
    pub name: String,
    /// The size label.
    pub size: String,
    /// Model space, metres, placed around the body.
    pub positions: Vec<Vec3>,
    /// Counter-clockwise seen from outside the garment.
    pub triangles: Vec<[u32; 3]>,
    /// Vertices driven by the body, sorted.
    pub attached: Vec<u32>,
    /// Binding of the attached vertices (same order as `attached`).
    pub binding: Binding,
    /// Vertex pairs to sew (zero rest length), each pair once.
    pub seams: Vec<[u32; 2]>,
    /// The vertex lists of each seam's two edges, in pairing order (equal lengths).
    pub seam_lines: Vec<SeamLine>,
    /// Per vertex: part of the static, skinned part (seed 000 §3.2.1).
    pub skinned: Vec<bool>,
    pub fabric: Fabric,
    pub fabric_name: String,
    /// Panel (or OBJ material / glTF mesh) names.
    pub panels: Vec<String>,
    /// Index into `panels` of each vertex.
    pub panel_of_vertex: Vec<u16>,
    /// Flat rest coordinates of each vertex in its panel, cm (pattern garments); for mesh
    /// garments the texture coordinates when the file has them, else empty.
    pub rest_2d: Vec<Vec2>,
    /// The tube rows where all panels of a wrap were present (girths, offsets).
    pub rows: Vec<RowReport>,
    /// Body colliders the garment does not collide with.
    pub ignore_colliders: Vec<String>,
}

/// The two edges of one seam, as garment vertex lists in pairing order.
#[derive(Clone, Debug, PartialEq)]
pub struct SeamLine {
    /// `"panel.edge"` of each side.
    pub names: [String; 2],
    pub a: Vec<u32>,
    pub b: Vec<u32>,
}

/// How a pattern garment is built.
#[derive(Clone, Debug, PartialEq)]
pub struct BuildOptions {
    /// Smallest distance from the body surface after placement, cm.
    pub clearance_cm: f32,
    /// Run the sewing pre-simulation ([`GarmentMesh::sew`]) before binding.
    pub sew: bool,
    pub sew_iterations: usize,
}

impl Default for BuildOptions {
    fn default() -> Self {
        Self {
            clearance_cm: 0.4,
            sew: true,
            sew_iterations: 200,
        }
    }
}

/// What the sewing pre-simulation did.
#[derive(Clone, Debug, PartialEq)]
pub struct SewReport {
    /// Largest seam gap before and after, metres.
    pub max_gap_before: f32,
    pub max_gap_after: f32,
    pub iterations: usize,
}

impl Pattern {
    /// Builds size `size` (a label of [`Pattern::sizes`]) on `body`.
    pub fn build(
        &self,
        body: &BodySurface,
        size: &str,
        options: &BuildOptions,
    ) -> Result<GarmentMesh, GarmentError> {
        let index = self.size_index(size).ok_or_else(|| GarmentError::Invalid {
            file: self.file.clone(),
            line: crate::error::line_of(&self.source_text, &["sizes"]),
            field: "sizes".into(),
            problem: format!(
                "no size \"{size}\"; the sizes are: {}",
                self.size_labels().join(", ")
            ),
        })?;
        let panels = self.graded_panels(index);
        let h = self.target_edge_cm;
        let invalid = |panel: &str, problem: String| GarmentError::Invalid {
            file: self.file.clone(),
            line: crate::error::line_of(&self.source_text, &["panels", &format!("\"{panel}\"")]),
            field: format!("panels ({panel})"),
            problem,
        };

        // Segment count of every edge; sewn edges share the larger count.
        let mut counts: Vec<Vec<usize>> = panels
            .iter()
            .map(|p| {
                p.edges
                    .iter()
                    .map(|e| {
                        ((polyline_length(&edge_polyline(&p.outline, e)) / h).round() as usize)
                            .max(1)
                    })
                    .collect()
            })
            .collect();
        for s in &self.seams {
            let n = counts[s.a.panel][s.a.edge].max(counts[s.b.panel][s.b.edge]);
            counts[s.a.panel][s.a.edge] = n;
            counts[s.b.panel][s.b.edge] = n;
        }

        // Mesh each panel; remember each edge's vertex list.
        let mut positions_2d: Vec<Vec2> = Vec::new();
        let mut triangles: Vec<[u32; 3]> = Vec::new();
        let mut panel_of_vertex: Vec<u16> = Vec::new();
        let mut edge_vertices: Vec<Vec<Vec<u32>>> = Vec::with_capacity(panels.len());
        let mut panel_range: Vec<std::ops::Range<usize>> = Vec::with_capacity(panels.len());
        for (p, panel) in panels.iter().enumerate() {
            let mut boundary: Vec<Vec2> = Vec::new();
            let mut local_edges: Vec<Vec<u32>> = Vec::with_capacity(panel.edges.len());
            for (e, edge) in panel.edges.iter().enumerate() {
                let line = resample_polyline(&edge_polyline(&panel.outline, edge), counts[p][e]);
                let start = boundary.len() as u32;
                let n = line.len() - 1;
                boundary.extend_from_slice(&line[..n]);
                local_edges.push((0..=n as u32).map(|k| start + k).collect());
            }
            let total = boundary.len() as u32;
            for list in &mut local_edges {
                if let Some(last) = list.last_mut()
                    && *last == total
                {
                    *last = 0;
                }
            }
            let mesh = mesh_polygon(&boundary, h).map_err(|e| {
                invalid(&panel.name, format!("cannot be meshed in size {size}: {e}"))
            })?;
            let offset = positions_2d.len() as u32;
            positions_2d.extend_from_slice(&mesh.vertices);
            triangles.extend(mesh.triangles.iter().map(|t| t.map(|v| v + offset)));
            panel_of_vertex.extend(std::iter::repeat_n(p as u16, mesh.vertices.len()));
            edge_vertices.push(
                local_edges
                    .into_iter()
                    .map(|l| l.into_iter().map(|v| v + offset).collect())
                    .collect(),
            );
            panel_range.push(offset as usize..positions_2d.len());
        }

        // Place each wrap.
        let mut positions = vec![Vec3::ZERO; positions_2d.len()];
        let mut rows = Vec::new();
        for wrap in &self.wraps {
            let verts: Vec<&[Vec2]> = wrap
                .panels
                .iter()
                .map(|&(p, _)| &positions_2d[panel_range[p].clone()])
                .collect();
            let placed = place_wrap(body, wrap, &panels, &verts, &self.name, &mut rows)?;
            for (&(p, _), list) in wrap.panels.iter().zip(placed) {
                positions[panel_range[p].clone()].copy_from_slice(&list);
            }
        }
        let clearance = options.clearance_cm / 100.0;
        push_outside(body, &mut positions, clearance);

        // Seams.
        let mut seam_lines = Vec::with_capacity(self.seams.len());
        let mut pairs: BTreeSet<[u32; 2]> = BTreeSet::new();
        for s in &self.seams {
            let a = edge_vertices[s.a.panel][s.a.edge].clone();
            let mut b = edge_vertices[s.b.panel][s.b.edge].clone();
            if s.direction == SeamDirection::Opposite {
                b.reverse();
            }
            for (&u, &v) in a.iter().zip(&b) {
                if u != v {
                    pairs.insert([u.min(v), u.max(v)]);
                }
            }
            let name = |r: crate::pattern::EdgeRef| {
                format!(
                    "{}.{}",
                    panels[r.panel].name, panels[r.panel].edges[r.edge].name
                )
            };
            seam_lines.push(SeamLine {
                names: [name(s.a), name(s.b)],
                a,
                b,
            });
        }

        // The static part and the attached bands, with the region each vertex follows.
        let mut skinned = vec![false; positions.len()];
        let mut follows: HashMap<u32, Option<Region>> = HashMap::new();
        let wrap_of = |p: usize| {
            self.wraps
                .iter()
                .find(|w| w.panels.iter().any(|&(q, _)| q == p))
        };
        for &p in &self.skinned {
            let region = wrap_of(p).map(|w| w.around);
            for v in panel_range[p].clone() {
                skinned[v] = true;
                follows.insert(v as u32, region);
            }
        }
        for a in &self.attach {
            let list: Vec<u32> = match a.edge {
                Some(e) => edge_vertices[a.panel][e].clone(),
                None => panel_range[a.panel].clone().map(|v| v as u32).collect(),
            };
            for v in list {
                follows.insert(v, Some(a.follows));
            }
        }
        let mut attached: Vec<u32> = follows.keys().copied().collect();
        attached.sort_unstable();

        let mut garment = GarmentMesh {
            name: self.name.clone(),
            size: size.to_owned(),
            positions,
            triangles,
            attached,
            binding: Binding::default(),
            seams: pairs.into_iter().collect(),
            seam_lines,
            skinned,
            fabric: self.fabric.fabric,
            fabric_name: self.fabric_name.clone(),
            panels: panels.iter().map(|p| p.name.clone()).collect(),
            panel_of_vertex,
            rest_2d: positions_2d,
            rows,
            ignore_colliders: self.ignore_colliders.clone(),
        };
        if options.sew {
            garment.sew(body, options.sew_iterations, clearance);
        }
        let regions: Vec<Option<Region>> = garment
            .attached
            .iter()
            .map(|v| follows.get(v).copied().flatten())
            .collect();
        let points: Vec<Vec3> = garment
            .attached
            .iter()
            .map(|&v| garment.positions[v as usize])
            .collect();
        garment.binding = Binding::bind(body, &garment.attached, &points, &regions)?;
        Ok(garment)
    }
}

impl GarmentMesh {
    /// The whole garment as a cloth mesh (vertices and triangles as they are: weld first with
    /// [`GarmentMesh::welded`] to join the panels).
    pub fn cloth_mesh(&self) -> Result<ClothMesh, GarmentError> {
        Ok(ClothMesh::new(
            self.positions.clone(),
            self.triangles.clone(),
        )?)
    }

    /// The largest distance between two vertices of a seam pair, metres (0 without seams).
    pub fn max_seam_gap(&self) -> f32 {
        self.seams
            .iter()
            .map(|&[a, b]| self.positions[a as usize].distance(self.positions[b as usize]))
            .fold(0.0, f32::max)
    }

    /// The sewing pre-simulation: position-based dynamics (Müller et al. 2007) without
    /// inertia. Each iteration pulls seam pairs together (stiffness ramped up over the first
    /// half), keeps every triangle edge at its flat pattern length, and every fourth
    /// iteration pushes the garment out of the body to `clearance` metres. Finally the pairs
    /// are moved onto their midpoints.
    pub fn sew(&mut self, body: &BodySurface, iterations: usize, clearance: f32) -> SewReport {
        let before = self.max_seam_gap();
        if before < 0.002 {
            // Nothing to sew: the placement already closed the seams (to 2 mm).
            self.snap_seams();
            return SewReport {
                max_gap_before: before,
                max_gap_after: self.max_seam_gap(),
                iterations: 0,
            };
        }
        let mut edges: BTreeSet<(u32, u32)> = BTreeSet::new();
        for t in &self.triangles {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                edges.insert((a.min(b), a.max(b)));
            }
        }
        let rest = |a: u32, b: u32| -> f32 {
            match (self.rest_2d.get(a as usize), self.rest_2d.get(b as usize)) {
                (Some(p), Some(q)) => p.distance(*q) / 100.0,
                _ => self.positions[a as usize].distance(self.positions[b as usize]),
            }
        };
        let edges: Vec<(u32, u32, f32)> =
            edges.into_iter().map(|(a, b)| (a, b, rest(a, b))).collect();
        let p = &mut self.positions;
        let ramp = (iterations / 2).max(1);
        for it in 0..iterations {
            let stiffness = ((it + 1) as f32 / ramp as f32).min(1.0);
            for &[a, b] in &self.seams {
                let (pa, pb) = (p[a as usize], p[b as usize]);
                let mid = 0.5 * (pa + pb);
                p[a as usize] = pa + (mid - pa) * stiffness;
                p[b as usize] = pb + (mid - pb) * stiffness;
            }
            for &(a, b, l) in &edges {
                let (pa, pb) = (p[a as usize], p[b as usize]);
                let d = pb - pa;
                let len = d.length();
                if len < 1e-9 {
                    continue;
                }
                let corr = d * (0.5 * (len - l) / len);
                p[a as usize] = pa + corr;
                p[b as usize] = pb - corr;
            }
            if it % 4 == 3 || it + 1 == iterations {
                push_outside(body, p, clearance);
            }
        }
        self.snap_seams();
        push_outside(body, &mut self.positions, clearance);
        self.snap_seams();
        SewReport {
            max_gap_before: before,
            max_gap_after: self.max_seam_gap(),
            iterations,
        }
    }

    /// Moves the vertices sewn together (seam pairs, and chains of pairs through shared
    /// corners) onto their common mean.
    pub fn snap_seams(&mut self) {
        let class = self.seam_classes();
        let mut sums: HashMap<u32, (Vec3, u32)> = HashMap::new();
        for (v, &c) in class.iter().enumerate() {
            let e = sums.entry(c).or_insert((Vec3::ZERO, 0));
            e.0 += self.positions[v];
            e.1 += 1;
        }
        for (v, c) in class.iter().enumerate() {
            if let Some(&(sum, count)) = sums.get(c)
                && count > 1
            {
                self.positions[v] = sum / count as f32;
            }
        }
    }

    /// For every vertex, the smallest vertex sewn to it (directly or through other pairs).
    pub fn seam_classes(&self) -> Vec<u32> {
        let n = self.positions.len();
        let mut parent: Vec<u32> = (0..n as u32).collect();
        fn find(parent: &mut [u32], mut v: u32) -> u32 {
            while parent[v as usize] != v {
                parent[v as usize] = parent[parent[v as usize] as usize];
                v = parent[v as usize];
            }
            v
        }
        for &[a, b] in &self.seams {
            let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
            if ra != rb {
                parent[ra.max(rb) as usize] = ra.min(rb);
            }
        }
        (0..n as u32).map(|v| find(&mut parent, v)).collect()
    }

    /// The garment with every seam pair welded into one vertex (at the pair's midpoint):
    /// the panels become one connected mesh. Attached vertices are re-bound on `body`.
    pub fn welded(&self, body: &BodySurface) -> Result<GarmentMesh, GarmentError> {
        let n = self.positions.len();
        let class = self.seam_classes();
        let mut new_index = vec![u32::MAX; n];
        let mut sums: Vec<(Vec3, u32)> = Vec::new();
        let mut first_of: Vec<u32> = Vec::new();
        for v in 0..n as u32 {
            let r = class[v as usize];
            if new_index[r as usize] == u32::MAX {
                new_index[r as usize] = sums.len() as u32;
                sums.push((Vec3::ZERO, 0));
                first_of.push(v);
            }
            let k = new_index[r as usize];
            new_index[v as usize] = k;
            sums[k as usize].0 += self.positions[v as usize];
            sums[k as usize].1 += 1;
        }
        let positions: Vec<Vec3> = sums.iter().map(|(s, c)| *s / *c as f32).collect();
        let triangles: Vec<[u32; 3]> = self
            .triangles
            .iter()
            .map(|t| t.map(|v| new_index[v as usize]))
            .filter(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
            .collect();
        let m = positions.len();
        let mut skinned = vec![false; m];
        for v in 0..n {
            if self.skinned[v] {
                skinned[new_index[v] as usize] = true;
            }
        }
        let attached: BTreeSet<u32> = self
            .attached
            .iter()
            .map(|&v| new_index[v as usize])
            .collect();
        let attached: Vec<u32> = attached.into_iter().collect();
        let points: Vec<Vec3> = attached.iter().map(|&v| positions[v as usize]).collect();
        let binding = Binding::bind(body, &attached, &points, &vec![None; attached.len()])?;
        let pick = |list: &[u32]| {
            list.iter()
                .map(|&v| new_index[v as usize])
                .collect::<Vec<u32>>()
        };
        Ok(GarmentMesh {
            name: self.name.clone(),
            size: self.size.clone(),
            positions,
            triangles,
            attached,
            binding,
            seams: Vec::new(),
            seam_lines: self
                .seam_lines
                .iter()
                .map(|s| SeamLine {
                    names: s.names.clone(),
                    a: pick(&s.a),
                    b: pick(&s.b),
                })
                .collect(),
            skinned,
            fabric: self.fabric,
            fabric_name: self.fabric_name.clone(),
            panels: self.panels.clone(),
            panel_of_vertex: first_of
                .iter()
                .map(|&v| self.panel_of_vertex[v as usize])
                .collect(),
            rest_2d: if self.rest_2d.len() == n {
                first_of.iter().map(|&v| self.rest_2d[v as usize]).collect()
            } else {
                Vec::new()
            },
            rows: self.rows.clone(),
            ignore_colliders: self.ignore_colliders.clone(),
        })
    }

    /// Skin joints and weights of every vertex from the nearest body point (for the static,
    /// skinned part; see [`skin_weights_for`]).
    pub fn skin_weights(&self, body: &BodySurface) -> (Vec<[u16; 4]>, Vec<[f32; 4]>) {
        skin_weights_for(body, &self.positions)
    }

    /// The vertices of the simulated (free) part: everything not attached.
    pub fn free_vertices(&self) -> Vec<u32> {
        let attached: BTreeSet<u32> = self.attached.iter().copied().collect();
        (0..self.positions.len() as u32)
            .filter(|v| !attached.contains(v))
            .collect()
    }
}
