//! The scene data model: meshes, instances, Phong materials, a camera, probes and the scene
//! that holds them with its lights (`light`, re-exported here).
//!
//! Everything here is plain data with no GPU types, so loaders, built-in scenes, the light-space
//! maths and the CPU reference can all be used (and tested) without a graphics device.

use glam::{Mat4, Vec2, Vec3};

use crate::look::{Lighting, Pbr};
use crate::texture::{AlphaMode, Texture, TextureRef};

use crate::error::SceneError;
use crate::light::validate_light;
pub use crate::light::{Attenuation, Light, LightKind, MAX_ANGULAR_SIZE_DEG, MAX_COORDINATE};

/// An indexed triangle mesh in object space.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// A name for messages (file name, primitive name).
    pub name: String,
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Per-vertex unit normals, one per position.
    pub normals: Vec<Vec3>,
    /// Texture coordinates, one per position, or empty when the mesh has none (then every
    /// vertex reads texel (0, 0) of its material's textures). glTF's convention: (0, 0) is the
    /// top-left corner of the image, v grows downwards (OBJ's v is flipped on load).
    pub uvs: Vec<Vec2>,
    /// Triangle list: three indices per triangle into `positions`.
    pub indices: Vec<u32>,
}

impl Mesh {
    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    /// Axis-aligned bounds `(min, max)` of the positions; `None` for an empty mesh.
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        let first = *self.positions.first()?;
        Some(
            self.positions
                .iter()
                .fold((first, first), |(lo, hi), &p| (lo.min(p), hi.max(p))),
        )
    }

    /// Replaces the normals with area-weighted vertex normals computed from the triangles.
    /// Vertices used by no (or only degenerate) triangles get `+Y`.
    pub fn compute_normals(&mut self) {
        let mut acc = vec![Vec3::ZERO; self.positions.len()];
        for tri in self.indices.chunks_exact(3) {
            let [a, b, c] = [tri[0] as usize, tri[1] as usize, tri[2] as usize];
            if a >= acc.len() || b >= acc.len() || c >= acc.len() {
                continue;
            }
            let n = (self.positions[b] - self.positions[a])
                .cross(self.positions[c] - self.positions[a]);
            acc[a] += n;
            acc[b] += n;
            acc[c] += n;
        }
        self.normals = acc
            .into_iter()
            .map(|n| n.try_normalize().unwrap_or(Vec3::Y))
            .collect();
    }

    /// Checks the mesh is usable: indices in range, a multiple of three, one normal per
    /// position, every coordinate finite. Degenerate (zero-area) triangles are allowed: they
    /// rasterize to nothing and cast no shadow.
    pub fn validate(&self) -> Result<(), SceneError> {
        let bad = |reason: String| SceneError::InvalidMesh {
            mesh: self.name.clone(),
            reason,
        };
        if !self.indices.len().is_multiple_of(3) {
            return Err(bad(format!(
                "{} indices is not a multiple of 3",
                self.indices.len()
            )));
        }
        if self.normals.len() != self.positions.len() {
            return Err(bad(format!(
                "{} normals for {} positions",
                self.normals.len(),
                self.positions.len()
            )));
        }
        if let Some(i) = self
            .indices
            .iter()
            .find(|&&i| i as usize >= self.positions.len())
        {
            return Err(bad(format!(
                "index {i} is out of range ({} vertices)",
                self.positions.len()
            )));
        }
        if let Some(i) = self.positions.iter().position(|p| !p.is_finite()) {
            return Err(bad(format!(
                "vertex {i} has a non-finite position {:?}",
                self.positions[i]
            )));
        }
        if let Some(i) = self.normals.iter().position(|n| !n.is_finite()) {
            return Err(bad(format!("vertex {i} has a non-finite normal")));
        }
        if !self.uvs.is_empty() && self.uvs.len() != self.positions.len() {
            return Err(bad(format!(
                "{} texture coordinates for {} positions",
                self.uvs.len(),
                self.positions.len()
            )));
        }
        if let Some(i) = self.uvs.iter().position(|t| !t.is_finite()) {
            return Err(bad(format!(
                "vertex {i} has non-finite texture coordinates"
            )));
        }
        Ok(())
    }
}

/// A Phong material (seed 004): colours of the ambient, diffuse and specular terms and the
/// specular exponent, optionally textured, alpha-masked and double-sided.
///
/// A base-colour texture multiplies the ambient and diffuse colours (the lighting stays
/// Phong: the texture is the diffuse reflectance's pattern). Its alpha times
/// [`Material::base_alpha`] decides coverage when [`Material::alpha_mode`] is `Mask` (or
/// `Blend`, treated as a mask at 0.5): uncovered texels are holes for the camera *and* for
/// every shadow technique (see [`crate::masks`]).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Material {
    /// Ambient reflectance (multiplies each light's ambient colour).
    #[serde(default = "Material::default_ambient")]
    pub ambient: Vec3,
    /// Diffuse reflectance.
    #[serde(default = "Material::default_diffuse")]
    pub diffuse: Vec3,
    /// Specular reflectance.
    #[serde(default = "Material::default_specular")]
    pub specular: Vec3,
    /// Specular exponent (higher = tighter highlight).
    #[serde(default = "Material::default_shininess")]
    pub shininess: f32,
    /// Base-colour texture (sRGB colour, linear alpha): multiplies `ambient` and `diffuse`.
    /// Not part of the TOML format (textures come from glTF and OBJ files and built-in scenes).
    #[serde(skip)]
    pub base_color_texture: Option<TextureRef>,
    /// Tangent-space normal map (glTF convention: +Y up in the image's green channel).
    #[serde(skip)]
    pub normal_texture: Option<TextureRef>,
    /// glTF's metallic-roughness texture (linear data: green = roughness, blue = metallic),
    /// multiplying [`Material::pbr`]'s factors texel by texel; used by the glTF BRDF only.
    #[serde(skip)]
    pub metallic_roughness_texture: Option<TextureRef>,
    /// glTF's emissive texture (sRGB colour), multiplying [`Material::emissive`] texel by
    /// texel.
    #[serde(skip)]
    pub emissive_texture: Option<TextureRef>,
    /// Alpha of the base colour (glTF `baseColorFactor.a`): multiplies the texture's alpha.
    #[serde(default = "Material::default_alpha")]
    pub base_alpha: f32,
    /// How alpha is used: `opaque` (ignored), `mask` (holes where alpha < `alpha_cutoff`),
    /// `blend` (treated as `mask` at 0.5: deferred shading and shadow maps hold one surface per
    /// pixel or texel).
    #[serde(default)]
    pub alpha_mode: AlphaMode,
    /// Coverage threshold of `mask` materials (glTF `alphaCutoff`, default 0.5).
    #[serde(default = "Material::default_cutoff")]
    pub alpha_cutoff: f32,
    /// glTF `doubleSided`. For shadows it means the caster is never back-face culled,
    /// whatever its mesh's closure.
    #[serde(default)]
    pub double_sided: bool,
    /// The camera sees only the front faces (counter-clockwise, as glTF winds them): glTF's
    /// single-sided materials (an outline shell, an inverted hull, shows only at the
    /// silhouette). Off for the built-in scenes and TOML and OBJ files, whose surfaces the
    /// camera shades from both sides.
    #[serde(default)]
    pub cull_back_faces: bool,
    /// Metallic-roughness parameters for the glTF BRDF (glTF files); `None`: derived from the
    /// Phong colours when shaded physically ([`Pbr::from_phong`]).
    #[serde(default)]
    pub pbr: Option<Pbr>,
    /// Emitted radiance, added to the shaded colour whatever the lights (glTF
    /// `emissiveFactor × KHR_materials_emissive_strength`; in a physical scene in nits, i.e.
    /// candela per square metre, through the exposure like the lights). Default black.
    #[serde(default)]
    pub emissive: Vec3,
    /// How much of the nearest reflection probe's light the surface mirrors (0..=1, the same
    /// at every angle), for Phong shading; 0 (default) mirrors nothing. The glTF BRDF derives
    /// its reflection from metallic and roughness instead ([`Probe`]).
    #[serde(default)]
    pub reflect: f32,
}

/// What a single-sided surface (a material the camera sees only from the front,
/// [`Material::cull_back_faces`], and not [`Material::double_sided`]) shadows. glTF defines
/// single-sided materials for the camera only, so a renderer must choose; every shadow
/// technique of manyshadows and its exact references choose the same way (docs/decisions.md,
/// "What a single-sided surface shadows").
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum SingleSidedShadows {
    /// A single-sided surface blocks a light only where that light, looking as a camera would,
    /// sees its front: a shadow ray from a point towards a light passes single-sided triangles
    /// whose front faces the point. An outline shell (an inverted hull around an object) casts
    /// nothing, a closed mesh casts as ever, a single-sided floor lit from below casts nothing.
    #[default]
    Front,
    /// Every triangle blocks light from either side, single-sided or not (the rule before
    /// there was a choice).
    Both,
}

impl SingleSidedShadows {
    /// Every rule, the default first.
    pub const ALL: [SingleSidedShadows; 2] = [Self::Front, Self::Both];

    /// Its name on the command line and in summaries.
    pub fn name(self) -> &'static str {
        match self {
            Self::Front => "front",
            Self::Both => "both",
        }
    }
}

impl std::fmt::Display for SingleSidedShadows {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for SingleSidedShadows {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Self::ALL
            .into_iter()
            .find(|r| r.name() == s.trim())
            .ok_or_else(|| {
                format!("unknown single-sided shadow rule '{s}' (expected front or both)")
            })
    }
}

impl Material {
    /// Whether this material's triangles block light only where a light sees their front,
    /// under `rule`: single-sided for the camera (`cull_back_faces`, not `double_sided`) and
    /// the rule [`SingleSidedShadows::Front`]. Alpha-tested casters keep blocking from both
    /// sides wherever their mask is solid: the caller leaves them out.
    pub fn casts_front_only(&self, rule: SingleSidedShadows) -> bool {
        rule == SingleSidedShadows::Front && self.cull_back_faces && !self.double_sided
    }

    fn default_ambient() -> Vec3 {
        Vec3::splat(0.8)
    }
    fn default_diffuse() -> Vec3 {
        Vec3::splat(0.8)
    }
    fn default_specular() -> Vec3 {
        Vec3::splat(0.2)
    }
    fn default_shininess() -> f32 {
        16.0
    }
    fn default_alpha() -> f32 {
        1.0
    }
    fn default_cutoff() -> f32 {
        0.5
    }

    /// The coverage threshold alpha is compared with, or `None` for opaque materials:
    /// `alpha_cutoff` for `mask`, 0.5 for `blend`.
    pub fn effective_cutoff(&self) -> Option<f32> {
        match self.alpha_mode {
            AlphaMode::Opaque => None,
            AlphaMode::Mask => Some(self.alpha_cutoff),
            AlphaMode::Blend => Some(0.5),
        }
    }

    /// A matte material of one colour (ambient = diffuse = `color`, faint white specular).
    pub fn matte(color: Vec3) -> Self {
        Self {
            ambient: color,
            diffuse: color,
            specular: Vec3::splat(0.1),
            shininess: 8.0,
            ..Self::default()
        }
    }

    /// This material with `texture` as its base colour (repeat wrapping).
    pub fn with_texture(mut self, texture: usize) -> Self {
        self.base_color_texture = Some(TextureRef::repeat(texture));
        self
    }

    /// The same material mirroring `reflect` of the nearest probe's light ([`Material::reflect`]).
    pub fn reflecting(mut self, reflect: f32) -> Self {
        self.reflect = reflect;
        self
    }

    /// This material alpha-masked at `cutoff` (double-sided, as foliage cards are).
    pub fn masked(mut self, cutoff: f32) -> Self {
        self.alpha_mode = AlphaMode::Mask;
        self.alpha_cutoff = cutoff;
        self.double_sided = true;
        self
    }
}

impl Default for Material {
    fn default() -> Self {
        Self {
            ambient: Self::default_ambient(),
            diffuse: Self::default_diffuse(),
            specular: Self::default_specular(),
            shininess: Self::default_shininess(),
            base_color_texture: None,
            normal_texture: None,
            metallic_roughness_texture: None,
            emissive_texture: None,
            base_alpha: Self::default_alpha(),
            alpha_mode: AlphaMode::Opaque,
            alpha_cutoff: Self::default_cutoff(),
            double_sided: false,
            cull_back_faces: false,
            pbr: None,
            emissive: Vec3::ZERO,
            reflect: 0.0,
        }
    }
}

/// One placement of a mesh in the world.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Instance {
    /// Index into [`Scene::meshes`].
    pub mesh: usize,
    /// Index into [`Scene::materials`].
    pub material: usize,
    /// Object-to-world transform (affine).
    pub transform: Mat4,
    /// Whether this instance is drawn into shadow maps.
    pub casts_shadows: bool,
}

impl Instance {
    /// Mesh `mesh` with material `material` placed by `transform`, casting shadows.
    pub fn caster(mesh: usize, material: usize, transform: Mat4) -> Self {
        Self {
            mesh,
            material,
            transform,
            casts_shadows: true,
        }
    }
}

/// A perspective camera.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Camera {
    /// Eye position.
    pub position: Vec3,
    /// Point looked at.
    pub target: Vec3,
    /// Up direction (need not be orthogonal to the view direction).
    #[serde(default = "Camera::default_up")]
    pub up: Vec3,
    /// Vertical field of view in degrees.
    #[serde(default = "Camera::default_fov")]
    pub fov_y_deg: f32,
    /// Near plane distance.
    #[serde(default = "Camera::default_near")]
    pub near: f32,
    /// Far plane distance.
    #[serde(default = "Camera::default_far")]
    pub far: f32,
}

impl Camera {
    fn default_up() -> Vec3 {
        Vec3::Y
    }
    fn default_fov() -> f32 {
        60.0
    }
    fn default_near() -> f32 {
        0.1
    }
    fn default_far() -> f32 {
        200.0
    }

    /// A camera at `position` looking at `target` with default up, field of view and planes.
    pub fn look_at(position: Vec3, target: Vec3) -> Self {
        Self {
            position,
            target,
            up: Self::default_up(),
            fov_y_deg: Self::default_fov(),
            near: Self::default_near(),
            far: Self::default_far(),
        }
    }

    /// World-to-view matrix (right-handed, looking down −Z).
    pub fn view(&self) -> Mat4 {
        Mat4::look_at_rh(self.position, self.target, self.up)
    }

    /// The camera's right direction (unit; the view matrix's x axis in world space).
    pub fn right(&self) -> Vec3 {
        (self.target - self.position)
            .normalize()
            .cross(self.up)
            .normalize()
    }

    /// The same camera moved `by` along its right direction, target and all: a stereo pair's
    /// eye is `shifted(∓separation / 2)` (parallel eyes, no toe-in, so both eyes share the
    /// view direction, the view depth of every point, and the projection).
    pub fn shifted(&self, by: f32) -> Camera {
        let d = self.right() * by;
        Camera {
            position: self.position + d,
            target: self.target + d,
            ..*self
        }
    }

    /// View-to-clip matrix for the given aspect ratio (wgpu depth range 0..1).
    pub fn projection(&self, aspect: f32) -> Mat4 {
        Mat4::perspective_rh(self.fov_y_deg.to_radians(), aspect, self.near, self.far)
    }

    /// Checks the camera is usable (finite, distinct eye and target, sane planes and angle).
    pub fn validate(&self) -> Result<(), SceneError> {
        let bad = |reason: &str| SceneError::InvalidCamera(reason.to_string());
        if !(self.position.is_finite() && self.target.is_finite() && self.up.is_finite()) {
            return Err(bad("position, target and up must be finite"));
        }
        let dir = self.target - self.position;
        if dir.length_squared() < 1e-12 {
            return Err(bad("position and target coincide"));
        }
        if dir.normalize().cross(self.up).length_squared() < 1e-8 {
            return Err(bad("up is parallel to the view direction"));
        }
        if !(self.fov_y_deg > 0.5 && self.fov_y_deg < 179.0) {
            return Err(bad("fov_y_deg must be between 0.5 and 179 degrees"));
        }
        if !(self.near > 0.0 && self.far > self.near && self.far.is_finite()) {
            return Err(bad("need 0 < near < far < infinity"));
        }
        Ok(())
    }
}

impl Default for Camera {
    fn default() -> Self {
        Self::look_at(Vec3::new(0.0, 5.0, 10.0), Vec3::ZERO)
    }
}

/// A reflection probe: a cube map of the lit scene as seen from `position`, which
/// reflective surfaces near it sample (box-projected onto `size` when that is not zero).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Probe {
    /// Where the cube map is seen from.
    pub position: Vec3,
    /// Edge lengths of the box whose walls the probe stands for: a reflected ray is followed
    /// to the box's wall and the cube map looked up towards that point (parallax-corrected
    /// reflections, right for a room the box fits). Zero: the surroundings are taken as far
    /// away and the plain direction is looked up.
    #[serde(default)]
    pub size: Vec3,
    /// The box's centre relative to `position` (default: the box is centred on the probe).
    #[serde(default)]
    pub offset: Vec3,
    /// Texels per face side (8 to 1024).
    #[serde(default = "Probe::default_resolution")]
    pub resolution: u32,
}

impl Probe {
    /// Default texels per face side.
    pub const DEFAULT_RESOLUTION: u32 = 128;
    /// Largest texels per face side.
    pub const MAX_RESOLUTION: u32 = 1024;
    /// Most probes in a scene.
    pub const MAX_COUNT: usize = 64;

    fn default_resolution() -> u32 {
        Self::DEFAULT_RESOLUTION
    }

    /// A probe at `position` standing for a box of `size` centred on it, at the default
    /// resolution.
    pub fn new(position: Vec3, size: Vec3) -> Self {
        Self {
            position,
            size,
            offset: Vec3::ZERO,
            resolution: Self::DEFAULT_RESOLUTION,
        }
    }

    /// The same probe standing for the box of `size` whose lowest corner is `lo` (the probe
    /// need not be at its centre).
    pub fn with_box(self, lo: Vec3, size: Vec3) -> Self {
        Self {
            size,
            offset: lo + 0.5 * size - self.position,
            ..self
        }
    }

    /// The six cameras of the cube's faces, in the order +X, −X, +Y, −Y, +Z, −Z: 90° field of
    /// view, square, looking from `position` along each axis (the same cameras a caller can
    /// render with to see what a face holds).
    pub fn face_cameras(&self, near: f32, far: f32) -> [Camera; 6] {
        let axes = [
            (Vec3::X, Vec3::NEG_Y),
            (Vec3::NEG_X, Vec3::NEG_Y),
            (Vec3::Y, Vec3::Z),
            (Vec3::NEG_Y, Vec3::NEG_Z),
            (Vec3::Z, Vec3::NEG_Y),
            (Vec3::NEG_Z, Vec3::NEG_Y),
        ];
        axes.map(|(forward, up)| Camera {
            position: self.position,
            target: self.position + forward,
            up,
            fov_y_deg: 90.0,
            near,
            far,
        })
    }

    fn validate(&self) -> Result<(), String> {
        if !self.position.is_finite() {
            return Err("position must be finite".into());
        }
        if !(self.size.is_finite() && self.size.min_element() >= 0.0) {
            return Err("size must be finite and >= 0 on every axis".into());
        }
        if !self.offset.is_finite() {
            return Err("offset must be finite".into());
        }
        if !(8..=Self::MAX_RESOLUTION).contains(&self.resolution) {
            return Err(format!(
                "resolution {} must be between 8 and {}",
                self.resolution,
                Self::MAX_RESOLUTION
            ));
        }
        Ok(())
    }
}

/// A whole scene: what the renderer draws and lights.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Scene {
    /// A name for messages and summaries.
    pub name: String,
    /// Meshes, referenced by instances.
    pub meshes: Vec<Mesh>,
    /// Materials, referenced by instances.
    pub materials: Vec<Material>,
    /// Images, referenced by materials.
    pub textures: Vec<Texture>,
    /// Mesh placements.
    pub instances: Vec<Instance>,
    /// Lights.
    pub lights: Vec<Light>,
    /// The viewpoint.
    pub camera: Camera,
    /// Units of the lights and the shading the scene's author meant (the renderer's defaults
    /// for shading, exposure and tone map).
    pub lighting: Lighting,
    /// Reflection probes (none: no reflections).
    pub probes: Vec<Probe>,
    /// What moves over time: a glTF file's node animations (empty: a still scene). The
    /// instances above are the rest pose; [`Animations::pose`](crate::animation::Animations::pose)
    /// gives their transforms at a time.
    pub animations: crate::animation::Animations,
}

/// The eight corners of the box from `lo` to `hi`.
fn box_corners(lo: Vec3, hi: Vec3) -> [Vec3; 8] {
    std::array::from_fn(|i| {
        Vec3::new(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        )
    })
}

impl Scene {
    /// Places the instances that [`Scene::animations`] move where `playing` has them at `t`
    /// seconds (looping past the end, see [`animation`](crate::animation)), and shapes the
    /// meshes their morph targets and skins deform as they then stand; the rest stay.
    pub fn set_time(&mut self, playing: crate::animation::Playing, t: f32) {
        for (k, m) in self.animations.pose(playing, t) {
            if let Some(i) = self.instances.get_mut(k) {
                i.transform = m;
            }
        }
        for (mesh, positions, normals) in self.animations.deformed(playing, t) {
            if let Some(m) = self.meshes.get_mut(mesh) {
                m.positions = positions;
                m.normals = normals;
            }
            self.animations.bent_bounds.remove(&mesh);
        }
    }

    /// The shadow caster with the smallest mesh (bounding-box diagonal times the instance's
    /// largest scale): moving it changes the fewest shadow views. `None` without casters.
    pub fn smallest_caster(&self) -> Option<usize> {
        self.instances
            .iter()
            .enumerate()
            .filter(|(_, i)| i.casts_shadows)
            .filter_map(|(k, i)| {
                let (lo, hi) = self.meshes.get(i.mesh)?.bounds()?;
                let scale = i.transform.to_scale_rotation_translation().0.max_element();
                Some((k, (hi - lo).length() * scale))
            })
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(k, _)| k)
    }

    /// Total triangles drawn (summed over instances).
    pub fn triangle_count(&self) -> usize {
        self.instances
            .iter()
            .map(|i| self.meshes.get(i.mesh).map_or(0, Mesh::triangle_count))
            .sum()
    }

    /// Mesh `mesh`'s box `(min, max)` as it stands: its box in `Animations::bent_bounds`
    /// where it is bent away from its vertices (on the GPU), else its vertices' box; `None`
    /// for an empty or missing mesh.
    pub fn mesh_bounds(&self, mesh: usize) -> Option<(Vec3, Vec3)> {
        let bent = self.animations.bent_bounds.get(&mesh).copied();
        bent.or_else(|| self.meshes.get(mesh).and_then(Mesh::bounds))
    }

    /// World-space bounds `(min, max)` of all instances (optionally only shadow casters);
    /// `None` if there is no geometry. A mesh bent on the GPU counts with its box in
    /// `Animations::bent_bounds`.
    pub fn world_bounds(&self, casters_only: bool) -> Option<(Vec3, Vec3)> {
        let mut out: Option<(Vec3, Vec3)> = None;
        for inst in &self.instances {
            if casters_only && !inst.casts_shadows {
                continue;
            }
            let Some((lo, hi)) = self.mesh_bounds(inst.mesh) else {
                continue;
            };
            for corner in box_corners(lo, hi) {
                let p = inst.transform.transform_point3(corner);
                out = Some(match out {
                    None => (p, p),
                    Some((a, b)) => (a.min(p), b.max(p)),
                });
            }
        }
        out
    }

    /// Checks every reference, number and shape in the scene; the renderer calls this first so
    /// bad input becomes a clear error instead of a GPU fault.
    pub fn validate(&self) -> Result<(), SceneError> {
        for m in &self.meshes {
            m.validate()?;
        }
        for (i, inst) in self.instances.iter().enumerate() {
            if inst.mesh >= self.meshes.len() {
                return Err(SceneError::InvalidInstance {
                    index: i,
                    reason: format!(
                        "mesh {} does not exist ({} meshes)",
                        inst.mesh,
                        self.meshes.len()
                    ),
                });
            }
            if inst.material >= self.materials.len() {
                return Err(SceneError::InvalidInstance {
                    index: i,
                    reason: format!(
                        "material {} does not exist ({} materials)",
                        inst.material,
                        self.materials.len()
                    ),
                });
            }
            if !inst.transform.is_finite() || inst.transform.determinant().abs() < 1e-12 {
                return Err(SceneError::InvalidInstance {
                    index: i,
                    reason: "transform must be finite and invertible".into(),
                });
            }
            // Each value may be finite while their product is not (a huge mesh scaled up).
            if let Some((lo, hi)) = self.meshes[inst.mesh].bounds() {
                let max = crate::light::MAX_COORDINATE;
                for corner in box_corners(lo, hi) {
                    let w = inst.transform.transform_point3(corner);
                    if !(w.is_finite() && w.abs().max_element() <= max) {
                        return Err(SceneError::InvalidInstance {
                            index: i,
                            reason: format!(
                                "its mesh reaches {w} in the world, past the largest coordinate \
                                 {max:e} (world units)"
                            ),
                        });
                    }
                }
            }
        }
        for (i, m) in self.materials.iter().enumerate() {
            let ok = m.ambient.is_finite()
                && m.diffuse.is_finite()
                && m.specular.is_finite()
                && (0.0..=1.0).contains(&m.reflect)
                && m.shininess.is_finite()
                && m.shininess >= 0.0;
            let bad = |reason: String| SceneError::InvalidMaterial { index: i, reason };
            if !ok {
                return Err(bad(
                    "colours must be finite, shininess >= 0 and reflect 0..=1".into(),
                ));
            }
            if !(m.base_alpha.is_finite() && m.alpha_cutoff.is_finite()) {
                return Err(bad("base_alpha and alpha_cutoff must be finite".into()));
            }
            for (what, t) in [
                ("base-colour", m.base_color_texture),
                ("normal", m.normal_texture),
            ] {
                if let Some(t) = t.filter(|t| t.texture >= self.textures.len()) {
                    return Err(bad(format!(
                        "its {what} texture {} does not exist ({} textures)",
                        t.texture,
                        self.textures.len()
                    )));
                }
            }
        }
        for (i, t) in self.textures.iter().enumerate() {
            t.validate()
                .map_err(|reason| SceneError::InvalidTexture { index: i, reason })?;
        }
        for (i, l) in self.lights.iter().enumerate() {
            validate_light(l).map_err(|reason| SceneError::InvalidLight { index: i, reason })?;
        }
        if self.probes.len() > Probe::MAX_COUNT {
            return Err(SceneError::InvalidProbe {
                index: Probe::MAX_COUNT,
                reason: format!(
                    "{} probes; a scene holds at most {}",
                    self.probes.len(),
                    Probe::MAX_COUNT
                ),
            });
        }
        for (i, p) in self.probes.iter().enumerate() {
            p.validate()
                .map_err(|reason| SceneError::InvalidProbe { index: i, reason })?;
        }
        self.camera.validate()
    }

    /// `count` probes seeded along the world bounds' longest horizontal axis, a quarter of
    /// the way up from the bottom, each standing for its slab of the bounds (`--probes N`);
    /// none without bounds.
    pub fn seeded_probes(&self, count: usize, resolution: u32) -> Vec<Probe> {
        let Some((lo, hi)) = self.world_bounds(false) else {
            return Vec::new();
        };
        let ext = hi - lo;
        let axis = if ext.x >= ext.z { Vec3::X } else { Vec3::Z };
        let along = ext.dot(axis);
        let step = along / count.max(1) as f32;
        (0..count)
            .map(|k| {
                let mut position = (lo + hi) * 0.5;
                position.y = lo.y + 0.25 * ext.y;
                position += axis * (lo.dot(axis) + (k as f32 + 0.5) * step - position.dot(axis));
                let size = ext - axis * (along - step);
                Probe {
                    position,
                    size,
                    offset: Vec3::new(0.0, 0.25 * ext.y, 0.0),
                    resolution,
                }
            })
            .collect()
    }
}
