//! Reflection probes, the part the lighting pass reads: every probe's six faces of linear
//! radiance in one texture array, and each probe's position and box (seed 000's reflection
//! cube maps; the faces are drawn by `faces.rs` through the frame's own G-buffer,
//! shadows and lighting code).
//!
//! A surface's reflection comes from the probe nearest it: its reflected view ray, followed to
//! the wall of the box the probe stands for (parallax correction) where the probe has one, is
//! looked up on the face it points at (`maps.wgsl`). How much is mirrored: Phong materials
//! their `Material::reflect` at normal incidence, the glTF BRDF its Fresnel reflectance
//! (0.04 for dielectrics, the base colour for metals) times the gloss `(1 − roughness)²`;
//! Schlick's Fresnel raises either towards 1 at grazing angles. One bounce: the faces
//! themselves are lit without reflections. The faces are sampled bilinearly at level 0 (sharp
//! mirror images; no blur by roughness).

use manyshadows_scene::{Probe, Scene};

use crate::error::RenderError;
use crate::gpu::bindings::{Binding, Part};
use crate::gpu::context::GpuContext;

/// Format of the faces: linear radiance, before exposure and tone map (what the lighting pass
/// writes with `ShadingConsts::linear_out`).
pub const FACE_FORMAT: wgpu::TextureFormat = crate::shading::lighting::LINEAR_FORMAT;

/// The probes' WGSL: the reflection's lookups, without the bindings' declarations.
pub(crate) const PROBES_WGSL: &str = include_str!("maps.wgsl");

/// The lighting pass's bindings of the probes: every face (layers `6·k .. 6·k + 5` of probe
/// `k`, linear radiance), its sampler, and the probes' records (a uniform of at most
/// `Probe::MAX_COUNT` records, which `maps.wgsl` spells as 64: WebGPU allows 8 storage buffers
/// per stage, and the lighting pass with a shadow source's own buffers is near that).
const LIGHTING_BINDINGS: &[Binding] = &[
    Binding::texture_array("probe_faces"),
    Binding::sampler("probe_sampler"),
    Binding::uniform("probes", "ProbeList"),
];

/// Without probes: nothing to mirror (the calls sit behind `PROBES`, false).
const NO_PROBES_WGSL: &str = "
fn probe_reflected(p: vec3<f32>, n: vec3<f32>, v: vec3<f32>) -> vec3<f32> { return vec3<f32>(0.0); }
fn probe_fresnel(f0: vec3<f32>, n: vec3<f32>, v: vec3<f32>) -> vec3<f32> { return vec3<f32>(0.0); }
";

/// The probes' part of the lighting pass: with `maps`, `PROBES` and the reflection's lookups
/// of their faces; without, functions that mirror nothing (never called: `PROBES` is false).
pub fn lighting_part(maps: Option<&ProbeMaps>) -> Part<'_> {
    let mut part = lighting_part_declared(maps.is_some());
    if let Some(m) = maps {
        part.resources = vec![
            wgpu::BindingResource::TextureView(&m.view),
            wgpu::BindingResource::Sampler(&m.sampler),
            m.data.as_entire_binding(),
        ];
    }
    part
}

/// [`lighting_part`]'s WGSL and bindings alone (no resources), with probes or without: what a
/// shader is composed of.
pub fn lighting_part_declared(on: bool) -> Part<'static> {
    if on {
        Part {
            wgsl: format!("const PROBES: bool = true;\n{PROBES_WGSL}"),
            bindings: LIGHTING_BINDINGS,
            resources: Vec::new(),
            follow: &[],
            own: &[],
        }
    } else {
        Part::wgsl(format!("const PROBES: bool = false;\n{NO_PROBES_WGSL}"))
    }
}

/// `ProbeData` of `maps.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct ProbeData {
    /// xyz position, w the first layer.
    pub position: [f32; 4],
    /// The box's lowest corner, w 1 when there is a box.
    pub box_lo: [f32; 4],
    /// The box's highest corner.
    pub box_hi: [f32; 4],
}

impl ProbeData {
    fn new(k: usize, p: &Probe) -> Self {
        let centre = p.position + p.offset;
        let half = 0.5 * p.size;
        let has_box = p.size.min_element() > 0.0;
        Self {
            position: p.position.extend((6 * k) as f32).to_array(),
            box_lo: (centre - half)
                .extend(if has_box { 1.0 } else { 0.0 })
                .to_array(),
            box_hi: (centre + half).extend(0.0).to_array(),
        }
    }
}

/// How the probes' face G-buffers are drawn.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[non_exhaustive]
pub enum ProbePasses {
    /// One G-buffer pass per face (the baseline).
    #[default]
    PerFace,
    /// Every face of every probe in one layered pass: each instance drawn once per face
    /// (instance → face), into the face's tile of one atlas G-buffer, clip distances keeping
    /// it there (seed 000's technique on colour targets; needs `CLIP_DISTANCES`); each tile is
    /// then copied into the face G-buffer its lighting reads.
    Layered,
    /// A probe's six faces in one multiview pass (`view_index` → face) into six-layer targets,
    /// each layer copied into the face G-buffer (needs six views per multiview pass).
    Multiview,
    /// GPU-driven (seed 002's route): every instance's mesh cut into clusters of triangles,
    /// a compute pass culling each cluster per face (its bounding sphere against the face's
    /// frustum, its normal cone against the face's eye where the material shows only front
    /// faces) and writing indirect commands, drawn into the tiles of the layered way's atlas
    /// by one indirect multi-draw per round (needs `CLIP_DISTANCES` and indirect execution).
    Clusters,
}

impl ProbePasses {
    /// Every way, baseline first.
    pub const ALL: &'static [ProbePasses] = &[
        ProbePasses::PerFace,
        ProbePasses::Layered,
        ProbePasses::Multiview,
        ProbePasses::Clusters,
    ];

    /// How the faces' G-buffers are drawn this way, in words (for summaries).
    pub fn describe(self) -> &'static str {
        match self {
            ProbePasses::PerFace => "G-buffers one pass per face",
            ProbePasses::Layered => "G-buffers of every face in one layered pass",
            ProbePasses::Multiview => "G-buffers of each probe's six faces in one multiview pass",
            ProbePasses::Clusters => {
                "G-buffers of every face from triangle clusters culled per face on the GPU, \
                 indirect multi-draws"
            }
        }
    }

    /// CLI name: `per-face`, `layered`, `multiview` or `gpu-driven`.
    pub fn name(self) -> &'static str {
        match self {
            ProbePasses::PerFace => "per-face",
            ProbePasses::Layered => "layered",
            ProbePasses::Multiview => "multiview",
            ProbePasses::Clusters => "gpu-driven",
        }
    }
}

impl std::fmt::Display for ProbePasses {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for ProbePasses {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        ProbePasses::ALL
            .iter()
            .copied()
            .find(|p| p.name() == s)
            .ok_or_else(|| {
                let names: Vec<&str> = ProbePasses::ALL.iter().map(|p| p.name()).collect();
                format!(
                    "unknown probe passes '{s}' (expected one of: {})",
                    names.join(", ")
                )
            })
    }
}

/// `FaceView` of `gbuffer_faces.wgsl`: a probe face drawn layered.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct FaceView {
    /// World → clip.
    pub view_proj: [[f32; 4]; 4],
    /// xyz where the face is seen from.
    pub eye: [f32; 4],
    /// The tile: left and top pixel, side, unused.
    pub tile: [f32; 4],
}

/// What drawing the probes did in a frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
#[non_exhaustive]
pub struct ProbeStats {
    /// Probes in the scene.
    pub probes: u32,
    /// Texels per face side.
    pub side: u32,
    /// Faces drawn this frame (0 when every face was kept).
    pub faces_drawn: u32,
    /// Bytes of the faces (linear radiance, `Rgba16Float`).
    pub bytes: u64,
}

/// The probes' faces and records, as the lighting pass binds them.
pub struct ProbeMaps {
    /// `6 × probes` layers of `side`² linear radiance (and a spare, see `new`).
    pub faces: wgpu::Texture,
    /// The array view the lighting pass samples.
    pub(crate) view: wgpu::TextureView,
    /// One render-target view per face, by layer.
    pub(crate) face_views: Vec<wgpu::TextureView>,
    pub(crate) sampler: wgpu::Sampler,
    /// `ProbeList` (uniform).
    pub(crate) data: wgpu::Buffer,
    /// Texels per face side (the largest any probe asks for; every probe gets it).
    pub side: u32,
    /// Probes.
    pub count: usize,
}

impl ProbeMaps {
    /// Faces for `scene`'s probes (at least one), all at the largest resolution asked for, as
    /// far as the device's texture limits allow.
    pub fn new(ctx: &GpuContext, scene: &Scene) -> Result<Self, RenderError> {
        let count = scene.probes.len();
        let side = scene
            .probes
            .iter()
            .map(|p| p.resolution)
            .max()
            .unwrap_or(Probe::DEFAULT_RESOLUTION);
        let limits = ctx.limits();
        if side > limits.max_texture_dimension_2d {
            return Err(RenderError::TooLarge {
                what: format!("probe faces of {side}² texels"),
                needed: u64::from(side),
                limit: u64::from(limits.max_texture_dimension_2d),
                unit: "texels per side",
                limit_name: "max_texture_dimension_2d",
            });
        }
        // One spare layer: wgpu's OpenGL backend takes a square texture whose layers are a
        // multiple of six for a cube map (array), and then its 2D-array views read nothing.
        let layers = 6 * count as u32 + 1;
        if layers > limits.max_texture_array_layers {
            return Err(RenderError::TooLarge {
                what: format!("the {layers} faces of {count} probes"),
                needed: u64::from(layers),
                limit: u64::from(limits.max_texture_array_layers),
                unit: "layers",
                limit_name: "max_texture_array_layers",
            });
        }
        // A texture too large for the device's memory is invalid, and only the views made
        // from it would say so: ask now, naming the probes.
        let mib = (u64::from(side) * u64::from(side) * u64::from(layers) * 8) >> 20;
        let faces = ctx.scoped(
            &format!(
                "allocating the faces of {count} probes ({layers} layers of {side}², {mib} MiB; \
                 fewer probes or a smaller resolution need less)"
            ),
            || {
                Ok(ctx.device.create_texture(&wgpu::TextureDescriptor {
                    label: Some("probes.faces"),
                    size: wgpu::Extent3d {
                        width: side,
                        height: side,
                        depth_or_array_layers: layers,
                    },
                    mip_level_count: 1,
                    sample_count: 1,
                    dimension: wgpu::TextureDimension::D2,
                    format: FACE_FORMAT,
                    usage: wgpu::TextureUsages::TEXTURE_BINDING
                        | wgpu::TextureUsages::RENDER_ATTACHMENT
                        | wgpu::TextureUsages::COPY_SRC,
                    view_formats: &[],
                }))
            },
        )?;
        let view = faces.create_view(&wgpu::TextureViewDescriptor {
            dimension: Some(wgpu::TextureViewDimension::D2Array),
            ..Default::default()
        });
        let sampler = ctx.device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("probes.sampler"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        // `ProbeList`: the count (a vec4<u32>), then `Probe::MAX_COUNT` records (the scene
        // has at most that many: `Scene::validate`).
        let mut records = vec![ProbeData::default(); Probe::MAX_COUNT];
        for (k, p) in scene.probes.iter().take(Probe::MAX_COUNT).enumerate() {
            records[k] = ProbeData::new(k, p);
        }
        let mut bytes = bytemuck::cast_slice::<u32, u8>(&[count as u32, 0, 0, 0]).to_vec();
        bytes.extend_from_slice(bytemuck::cast_slice(&records));
        let data = wgpu::util::DeviceExt::create_buffer_init(
            &ctx.device,
            &wgpu::util::BufferInitDescriptor {
                label: Some("probes.data"),
                contents: &bytes,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            },
        );
        // One render view per face: the faces' lighting passes draw straight into them.
        let face_views = (0..layers - 1)
            .map(|layer| {
                faces.create_view(&wgpu::TextureViewDescriptor {
                    label: Some("probes.face"),
                    dimension: Some(wgpu::TextureViewDimension::D2),
                    base_array_layer: layer,
                    array_layer_count: Some(1),
                    ..Default::default()
                })
            })
            .collect();
        Ok(Self {
            faces,
            face_views,
            view,
            sampler,
            data,
            side,
            count,
        })
    }

    /// Bytes the faces take.
    pub fn bytes(&self) -> u64 {
        let texel = FACE_FORMAT.block_copy_size(None).unwrap_or(8) as u64;
        6 * self.count as u64 * u64::from(self.side) * u64::from(self.side) * texel
    }

    /// Where face `face` of probe `k` lies: its layer.
    pub fn layer(k: usize, face: usize) -> u32 {
        (6 * k + face) as u32
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    /// The direction a reflection looks up for a surface at `p` with normal `n` seen along `v`
    /// (towards the eye), through `probe` (the CPU twin of `probe_reflected`, for tests).
    fn reflected_direction(probe: &Probe, p: Vec3, n: Vec3, v: Vec3) -> Vec3 {
        let r = -v - 2.0 * (-v).dot(n) * n;
        if probe.size.min_element() <= 0.0 {
            return r;
        }
        let centre = probe.position + probe.offset;
        let (lo, hi) = (centre - 0.5 * probe.size, centre + 0.5 * probe.size);
        let safe = Vec3::select(r.abs().cmplt(Vec3::splat(1e-20)), Vec3::splat(1e-20), r);
        let far = ((hi - p) / safe).max((lo - p) / safe);
        let t = far.min_element();
        if t > 0.0 {
            p + r * t - probe.position
        } else {
            r
        }
    }

    #[test]
    fn data_matches_the_wgsl() {
        use crate::gpu::types::layout::same_layout;
        let declarations = crate::gpu::bindings::BindingList::new(LIGHTING_BINDINGS).wgsl();
        let src = crate::gpu::shaders::compose(&[&declarations, PROBES_WGSL]);
        same_layout!(in src, ProbeData, position, box_lo, box_hi);
        same_layout!(in crate::frame::gbuffer::faces_shader(), FaceView, view_proj, eye, tile);
        same_layout!(in crate::frame::gbuffer::face_layers_shader(), FaceView, view_proj, eye, tile);
        // The uniform holds every probe a scene may have.
        let list = format!("items: array<ProbeData, {}>", Probe::MAX_COUNT);
        assert!(PROBES_WGSL.contains(&list), "maps.wgsl must declare {list}");
    }

    /// A ray from the middle of a box's floor straight up reaches the ceiling above it: the
    /// probe, off to the side and lower, looks up towards that point, not straight up.
    #[test]
    fn box_projection_follows_the_ray_to_the_wall() {
        let probe = Probe::new(Vec3::new(2.0, 1.0, 0.0), Vec3::ZERO)
            .with_box(Vec3::new(-5.0, 0.0, -5.0), Vec3::new(10.0, 4.0, 10.0));
        let d = reflected_direction(&probe, Vec3::ZERO, Vec3::Y, Vec3::Y);
        // The ceiling point (0, 4, 0) seen from (2, 1, 0).
        assert!((d - Vec3::new(-2.0, 3.0, 0.0)).length() < 1e-5, "{d}");
        // Without a box the plain reflection.
        let far = Probe::new(Vec3::new(2.0, 1.0, 0.0), Vec3::ZERO);
        assert_eq!(
            reflected_direction(&far, Vec3::ZERO, Vec3::Y, Vec3::Y),
            Vec3::Y
        );
    }
}
