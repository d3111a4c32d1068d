//! The still part of a scene (its first [`Scene::still`](super::Scene::still) meshes: the
//! room), kept rendered from frame to frame: its z-buffer, edge flags and per-pixel noise
//! coefficients ([`Layer`]). A frame then starts from a copy of it, draws only the moving
//! meshes and recomputes only the pixels they can affect; the result is, bit for bit, that
//! of drawing the whole scene (the still meshes come first in both, so the z-buffer sees
//! the same writes in the same order).
//!
//! The still meshes are compared with a copy each frame (a room is a few quads): a caller that
//! changes one is not served a stale image. A still part that changed is rendered with the
//! rest until it has stood still for a frame.

use super::edges::{self, EdgeFlags};
use super::readings::{Coefficients, NoiseTables};
use super::spans::Spans;
use super::{DepthBuffer, NoiseSettings, SceneMesh};
use crate::camera::{DepthCamera, WIDTH};

/// What the noise pass needs of a scene, frame-independent: the nearest surface per pixel,
/// its edge flags and its noise coefficients.
#[derive(Clone, Debug, Default)]
pub struct Layer {
    pub view: DepthBuffer,
    pub edges: EdgeFlags,
    pub coefficients: Coefficients,
}

impl Layer {
    /// Renders `meshes` and derives everything from them, over the whole image.
    pub fn render_all(
        &mut self,
        meshes: &[SceneMesh],
        camera: &DepthCamera,
        n: NoiseSettings,
        tables: &NoiseTables,
    ) {
        self.view.clear();
        for m in meshes {
            self.view
                .draw(camera, &m.positions, &m.triangles, m.label as u8, m.closed);
        }
        let iz = &self.view.inverse_z;
        self.edges.compute(iz, camera, n.shadow, n.dropouts);
        let images = (
            iz.as_slice(),
            self.view.normal_dot_ray.as_slice(),
            &*self.edges.flags,
        );
        tables.coefficients(n, images, None, &mut self.coefficients);
    }

    /// Draws `meshes` over this layer, the frame-independent images of [`Self::render_all`]
    /// of the meshes before them in `still`, and derives again the pixels they can affect:
    /// the pixels they were drawn into and their neighbours (the edge flags compare
    /// neighbours), and the projector's shadow they cast along their rows: those pixels go
    /// into `swept` (`scratch` is for the neighbours).
    pub fn render_over(
        &mut self,
        meshes: &[SceneMesh],
        still: &Layer,
        camera: &DepthCamera,
        n: NoiseSettings,
        tables: &NoiseTables,
        (scratch, swept): (&mut Spans, &mut Spans),
    ) {
        self.view.touched.clear();
        for m in meshes {
            self.view
                .draw(camera, &m.positions, &m.triangles, m.label as u8, m.closed);
        }
        let (iz, flags) = (&self.view.inverse_z, &mut self.edges.flags);
        self.view.touched.grown_into(scratch);
        swept.clear();
        if n.dropouts {
            edges::mark_edges_in(iz, scratch, flags);
        }
        if n.shadow {
            let run = &still.edges.run;
            edges::mark_shadow_in(iz, camera, &self.view.touched, run, flags, swept);
        }
        swept.union(scratch);
        let images = (iz.as_slice(), self.view.normal_dot_ray.as_slice(), &**flags);
        tables.coefficients(n, images, Some(swept), &mut self.coefficients);
    }

    /// Copies `from`'s pixels of `spans` (all of its images but the shadow sweep's state).
    pub fn copy_spans(&mut self, from: &Layer, spans: &Spans) {
        for (j, r) in spans.iter() {
            let r = j * WIDTH + r.start..j * WIDTH + r.end;
            let (to, fr) = (&mut self.view, &from.view);
            to.inverse_z[r.clone()].copy_from_slice(&fr.inverse_z[r.clone()]);
            to.label[r.clone()].copy_from_slice(&fr.label[r.clone()]);
            to.normal_dot_ray[r.clone()].copy_from_slice(&fr.normal_dot_ray[r.clone()]);
            self.edges.flags[r.clone()].copy_from_slice(&from.edges.flags[r]);
        }
        self.coefficients.copy_spans(&from.coefficients, spans);
    }
}

/// The still meshes of the last frames and, once they have stood still, their [`Layer`].
#[derive(Default)]
pub struct Still {
    meshes: Vec<SceneMesh>,
    /// The camera and settings the layer was made with.
    made_for: Option<(DepthCamera, NoiseSettings)>,
    layer: Option<Box<Layer>>,
    /// Whether `layer` is the image of `meshes` under `made_for`.
    ready: bool,
}

impl Still {
    /// The layer of `meshes`, and whether it was made anew (`None` when they changed since
    /// the last frame: they are remembered, and made into a layer if they stand still).
    pub fn layer(
        &mut self,
        meshes: &[SceneMesh],
        camera: &DepthCamera,
        n: NoiseSettings,
        tables: &NoiseTables,
    ) -> Option<(&Layer, bool)> {
        let first = self.made_for.is_none() && self.meshes.is_empty();
        let same = self.meshes.len() == meshes.len()
            && self.meshes.iter().zip(meshes).all(|(a, b)| same_mesh(a, b));
        if !same {
            self.meshes.resize_with(meshes.len(), SceneMesh::empty);
            for (to, from) in self.meshes.iter_mut().zip(meshes) {
                to.copy_from(from);
            }
            self.ready = false;
            // The first still part is taken at its word; a changed one must stand still
            // for a frame first (a caller moving it every frame gains nothing from a cache).
            if !first {
                return None;
            }
        }
        let made = !self.ready || self.made_for != Some((*camera, n));
        if made {
            let layer = self.layer.get_or_insert_with(Box::default);
            layer.render_all(&self.meshes, camera, n, tables);
            self.made_for = Some((*camera, n));
            self.ready = true;
        }
        self.layer.as_deref().map(|l| (l, made))
    }
}

/// Whether two meshes are the same, bit for bit.
fn same_mesh(a: &SceneMesh, b: &SceneMesh) -> bool {
    let bits = |p: &glam::Vec3| [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()];
    a.label == b.label
        && a.closed == b.closed
        && a.triangles == b.triangles
        && a.positions.len() == b.positions.len()
        && a.positions
            .iter()
            .zip(&b.positions)
            .all(|(p, q)| bits(p) == bits(q))
}

impl SceneMesh {
    fn empty() -> Self {
        Self {
            positions: Vec::new(),
            triangles: Vec::new(),
            label: super::Label::Nothing,
            closed: false,
        }
    }

    /// `from`'s contents, in this mesh's allocations.
    fn copy_from(&mut self, from: &SceneMesh) {
        self.positions.clone_from(&from.positions);
        self.triangles.clone_from(&from.triangles);
        self.label = from.label;
        self.closed = from.closed;
    }
}
