//! Meshes bent as they play: skins (glTF 2.0 §3.7.3) and morph targets (§3.7.2.2), on the
//! CPU. [`Bending`] is what bends them at one time (every node's world transform and the
//! morph weights the clips drive); [`bend_meshes`] bends every deformed mesh from it.
//! The renderer bends the same meshes on the GPU from the same [`Bending`] (its `deform`
//! pass); this is the path the CPU references and `Renderer::set_mesh_vertices` take.

use glam::{Mat4, Vec3};

/// What bends the deformed meshes at one time.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Bending {
    /// Every node's world transform.
    pub worlds: Vec<Mat4>,
    /// `(node, weights)`: the morph weights a clip drives (a node missing here keeps its
    /// mesh's default weights).
    pub weights: Vec<(usize, Vec<f32>)>,
}

/// A mesh its joints bend (glTF 2.0 §3.7.3): each vertex is placed by the weighted sum of its
/// joints' matrices, `Σ wᵢ · W(jointᵢ) · IBMᵢ`, its normal by the same sum's upper 3×3 (as
/// three.js does), normalized. The mesh's node transform plays no part; its instance stands at
/// the identity.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Skin {
    /// The scene mesh it bends.
    pub mesh: usize,
    /// The node of each joint.
    pub joints: Vec<usize>,
    /// Each joint's inverse bind matrix (the identity where the file gives none).
    pub inverse_bind: Vec<Mat4>,
    /// Per vertex, four indices into `joints`.
    pub vertex_joints: Vec<[u16; 4]>,
    /// Per vertex, the four joints' weights (summing to 1 with `extra_weights`).
    pub vertex_weights: Vec<[f32; 4]>,
    /// Per vertex, four more joints (glTF's `JOINTS_1`), or empty.
    pub extra_joints: Vec<[u16; 4]>,
    /// Their weights (glTF's `WEIGHTS_1`), or empty.
    pub extra_weights: Vec<[f32; 4]>,
    /// The mesh's vertices and normals as the file gives them, before any joint moves them.
    pub bind_positions: Vec<Vec3>,
    /// Normals in the same coordinates.
    pub bind_normals: Vec<Vec3>,
}

impl Skin {
    /// Why this skin cannot bend its mesh, if it cannot (`None`: it can): joints outside the
    /// tree, a vertex naming a joint the skin lacks, counts that disagree, matrices not
    /// finite.
    pub fn problem(&self, nodes: usize) -> Option<String> {
        if self.joints.is_empty() {
            return Some("it has no joints".into());
        }
        if let Some(j) = self.joints.iter().find(|&&j| j >= nodes) {
            return Some(format!("joint node {j} is not in the file's tree"));
        }
        if self.inverse_bind.len() != self.joints.len() {
            return Some(format!(
                "{} inverse bind matrices for {} joints",
                self.inverse_bind.len(),
                self.joints.len()
            ));
        }
        if self.inverse_bind.iter().any(|m| !m.is_finite()) {
            return Some("an inverse bind matrix is not finite".into());
        }
        let n = self.bind_positions.len();
        if self.vertex_joints.len() != n
            || self.vertex_weights.len() != n
            || self.bind_normals.len() != n
            || self.extra_joints.len() != self.extra_weights.len()
            || !(self.extra_joints.is_empty() || self.extra_joints.len() == n)
        {
            return Some("joints, weights and vertices differ in number".into());
        }
        let count = self.joints.len();
        let extra = self.extra_joints.iter().zip(&self.extra_weights);
        for (v, (j, w)) in self
            .vertex_joints
            .iter()
            .zip(&self.vertex_weights)
            .enumerate()
            .chain(extra.enumerate())
        {
            if let Some(k) = (0..4).find(|&k| w[k] > 0.0 && usize::from(j[k]) >= count) {
                return Some(format!(
                    "vertex {v} names joint {} of a skin of {count} joints",
                    j[k]
                ));
            }
        }
        None
    }

    /// Each joint's skinning matrix with the nodes at `worlds` (every node's world
    /// transform): `W(joint) · IBM`.
    pub fn matrices(&self, worlds: &[Mat4]) -> Vec<Mat4> {
        self.joints
            .iter()
            .zip(&self.inverse_bind)
            .map(|(&j, ibm)| worlds.get(j).copied().unwrap_or(Mat4::IDENTITY) * *ibm)
            .collect()
    }

    /// Every vertex's weights are 0 or more and sum to 1 (the loader normalizes a file's so):
    /// a bent vertex then lies among its joints' images of it, which is what bounds drawn
    /// from the joints assume.
    pub fn is_convex(&self) -> bool {
        let extra = |v: usize| self.extra_weights.get(v).map_or(0.0, |w| w.iter().sum());
        self.vertex_weights.iter().enumerate().all(|(v, w)| {
            let all = w
                .iter()
                .chain(self.extra_weights.get(v).into_iter().flatten());
            all.clone().all(|&x| x >= 0.0) && (w.iter().sum::<f32>() + extra(v) - 1.0).abs() < 1e-3
        })
    }

    /// The mesh's vertices and normals with its joints at `worlds` (every node's world
    /// transform), from its bind vertices.
    pub fn bend(&self, worlds: &[Mat4]) -> (Vec<Vec3>, Vec<Vec3>) {
        self.bend_from(worlds, &self.bind_positions, &self.bind_normals)
    }

    /// [`Skin::bend`] from other vertices of the same mesh (its morph targets applied first).
    pub fn bend_from(
        &self,
        worlds: &[Mat4],
        bind_positions: &[Vec3],
        bind_normals: &[Vec3],
    ) -> (Vec<Vec3>, Vec<Vec3>) {
        let matrices = self.matrices(worlds);
        let at = |j: u16| {
            matrices
                .get(usize::from(j))
                .copied()
                .unwrap_or(Mat4::IDENTITY)
        };
        let mut positions = Vec::with_capacity(self.bind_positions.len());
        let mut normals = Vec::with_capacity(self.bind_positions.len());
        for (v, (((p, n), j), w)) in bind_positions
            .iter()
            .zip(bind_normals)
            .zip(&self.vertex_joints)
            .zip(&self.vertex_weights)
            .enumerate()
        {
            let mut m = Mat4::ZERO;
            let extra = self.extra_joints.get(v).zip(self.extra_weights.get(v));
            for (j, w) in std::iter::once((j, w)).chain(extra) {
                for k in 0..4 {
                    if w[k] != 0.0 {
                        m += at(j[k]) * w[k];
                    }
                }
            }
            positions.push(m.transform_point3(*p));
            normals.push(m.transform_vector3(*n).try_normalize().unwrap_or(*n));
        }
        (positions, normals)
    }
}

/// A mesh's morph targets (glTF 2.0 §3.7.2.2): its vertices are its base plus each target's
/// displacement times that target's weight, its normals likewise, normalized. The weights are
/// its node's, animated by `weights` channels, else the node's or mesh's default.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Morph {
    /// The scene mesh it shapes.
    pub mesh: usize,
    /// The node whose weights it takes.
    pub node: usize,
    /// The vertices and normals without any target (in the mesh's coordinates as loaded).
    pub base_positions: Vec<Vec3>,
    /// Normals without any target.
    pub base_normals: Vec<Vec3>,
    /// Per target, a displacement per vertex.
    pub position_deltas: Vec<Vec<Vec3>>,
    /// Per target, a normal displacement per vertex (zeros where the file gives none).
    pub normal_deltas: Vec<Vec<Vec3>>,
    /// The weights where no channel drives them.
    pub default_weights: Vec<f32>,
}

impl Morph {
    /// Its weights in `bending`: those a clip drives for its node, else its defaults.
    pub fn weights_in<'a>(&'a self, bending: &'a Bending) -> &'a [f32] {
        bending
            .weights
            .iter()
            .find(|(n, _)| *n == self.node)
            .map_or(&self.default_weights, |(_, w)| w)
    }

    /// The vertices and normals at `weights` (missing weights count 0).
    pub fn shape(&self, weights: &[f32]) -> (Vec<Vec3>, Vec<Vec3>) {
        let mut p = self.base_positions.clone();
        let mut n = self.base_normals.clone();
        for (k, &w) in weights.iter().enumerate() {
            if w == 0.0 {
                continue;
            }
            if let Some(d) = self.position_deltas.get(k) {
                for (p, d) in p.iter_mut().zip(d) {
                    *p += *d * w;
                }
            }
            if let Some(d) = self.normal_deltas.get(k) {
                for (n, d) in n.iter_mut().zip(d) {
                    *n += *d * w;
                }
            }
        }
        for (n, base) in n.iter_mut().zip(&self.base_normals) {
            *n = n.try_normalize().unwrap_or(*base);
        }
        (p, n)
    }
}

/// Every mesh of `skins` and `morphs` that `keep` keeps, bent by `bending`: `(mesh,
/// positions, normals)`, its morph targets weighted first, then its skin bent by its joints
/// ([`Animations::bend_where`](super::Animations::bend_where)).
pub fn bend_meshes(
    skins: &[Skin],
    morphs: &[Morph],
    bending: &Bending,
    keep: impl Fn(usize) -> bool,
) -> Vec<(usize, Vec<Vec3>, Vec<Vec3>)> {
    let mut out: Vec<(usize, Vec<Vec3>, Vec<Vec3>)> = morphs
        .iter()
        .filter(|m| keep(m.mesh))
        .map(|m| {
            let (p, n) = m.shape(m.weights_in(bending));
            (m.mesh, p, n)
        })
        .collect();
    for s in skins.iter().filter(|s| keep(s.mesh)) {
        match out.iter_mut().find(|(mesh, _, _)| *mesh == s.mesh) {
            Some((_, p, n)) => (*p, *n) = s.bend_from(&bending.worlds, p, n),
            None => {
                let (p, n) = s.bend(&bending.worlds);
                out.push((s.mesh, p, n));
            }
        }
    }
    out
}
