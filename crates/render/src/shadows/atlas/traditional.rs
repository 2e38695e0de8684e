//! `traditional`: one depth-only render pass per shadow view, the whole (CPU-culled) scene
//! each time (seed 004's shadow pass; seed 000 §19.2, the baseline the layered techniques
//! beat). Position-only vertex input and no fragment stage, as seed 004 recommends: the only
//! output is depth.

use manyshadows_scene::light_space::{PointShadows, ViewKind};

use crate::error::Fills;
use crate::error::Technique;
use crate::gpu::context::GpuContext;
use crate::gpu::shaders::{compose, COMMON};
use crate::gpu::types::VIEW_UNIFORM_STRIDE;
use crate::gpu_scene::casters::ALPHA_MASK;
use crate::gpu_scene::instances::{POSITION_LAYOUT, UV_LAYOUT_1};
use crate::gpu_scene::skinning::{MAX_BONES, SKIN_LAYOUT};
use crate::shadows::atlas::shared::atlas_report;
use crate::shadows::atlas::shared::{atlas_attachment, TileClear};
use crate::shadows::cost::{price, Cost, LightingRead};
use crate::shadows::descriptor::{Build, Culling, TechniqueInfo, Wgsl};
use crate::shadows::lookup::ATLAS_LOOKUP;
use crate::shadows::lookup::PARABOLOID;
use crate::shadows::source::ShadowStats;
use crate::shadows::technique::{visible_casters, Generation, ShadowInput, ShadowTechnique};

impl Technique {
    /// One depth pass per shadow view (seed 004).
    pub const TRADITIONAL: Technique = Technique::named("traditional");
}

/// `traditional`'s declaration.
pub const INFO: TechniqueInfo = TechniqueInfo {
    technique: Technique::TRADITIONAL,
    summary: "one depth pass per shadow view, instances culled on the CPU",
    origin: "seed 004's shadow pass; seed 000 section 19.2 (the baseline)",
    fills: Fills::Atlas,
    culling: Culling::Instances,
    point_shadows: &[PointShadows::Cube, PointShadows::DualParaboloid],
    needs: &[],
    soft_shadows: true,
    // Milliseconds of its shadow stage per (triangle, view) pair taken on, (instance, view) pair,
    // texel of the tiles, texel of the whole atlas, view, and fixed, on lavapipe
    // (docs/benchmarks.md, "What a frame will cost: `bench estimate`").
    cost: Cost {
        lighting: LightingRead::Maps,
        shadows_ms: |w| {
            price(
                &[3.30e-05, 2.57e-02, 3.84e-06, 0.0, 0.0, 0.0],
                &w.atlas_units(),
            )
        },
    },
    camera_pixels_only: false,
    follows_camera: false,
    report: |r| atlas_report(r, Culling::Instances),
    instead: "",
    lookup: ATLAS_LOOKUP,
    build: Build::Atlas(|ctx| Ok(Box::new(Traditional::new(ctx)))),
    shaders,
};

/// Bytes of the per-view uniform the shaders read: view-projection and params.
const VIEW_BINDING: u64 = 80;

/// The depth-only pass.
fn shader() -> String {
    compose(&[COMMON, ALPHA_MASK, include_str!("traditional.wgsl")])
}

/// The depth-only pass into dual-paraboloid views (clip distances cut the hemisphere).
fn paraboloid_shader() -> String {
    compose(&[
        "enable clip_distances;",
        COMMON,
        PARABOLOID,
        ALPHA_MASK,
        include_str!("traditional_dp.wgsl"),
    ])
}

fn shaders() -> Vec<Wgsl> {
    vec![
        Wgsl::core("traditional", shader()),
        Wgsl::with(
            "traditional_dp",
            paraboloid_shader(),
            wgpu::Features::CLIP_DISTANCES,
        ),
    ]
}

/// The traditional technique's pipelines and layout.
pub struct Traditional {
    pipeline: wgpu::RenderPipeline,
    /// Alpha-tested instances (positions and texture coordinates, `fs_alpha`).
    masked: wgpu::RenderPipeline,
    /// Dual-paraboloid views (needs `CLIP_DISTANCES`; `None` without it), opaque and
    /// alpha-tested.
    paraboloid: Option<(wgpu::RenderPipeline, wgpu::RenderPipeline)>,
    skinned: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    clear: TileClear,
    no_bones: wgpu::Buffer,
    /// What the culled pipelines of single-sided casters are built from, on first need.
    pipeline_layout: wgpu::PipelineLayout,
    module: wgpu::ShaderModule,
    dp_module: Option<wgpu::ShaderModule>,
    /// Single-sided casters that cast only where a light sees their front
    /// (`CasterGeometry::front_only`), drawn with the rasterizer's back-face culling: by
    /// (vertex entry, winding of their front), built when a scene first has them.
    culled: std::collections::HashMap<(&'static str, Class), wgpu::RenderPipeline>,
}

/// Which pipeline a caster of a view is drawn with.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
enum Class {
    /// Opaque, both faces drawn.
    Opaque,
    /// Alpha-tested.
    Masked,
    /// Single-sided, casting only where the light sees its front: back faces culled, fronts
    /// counter-clockwise in the view (every shadow view keeps world-space winding: right-handed
    /// look-to views, unmirrored projections).
    FrontCcw,
    /// The same under a mirroring instance transform: fronts clockwise.
    FrontCw,
}

impl Class {
    fn of(input: &ShadowInput<'_>, d: &crate::gpu_scene::instances::DrawItem) -> Class {
        use crate::gpu_scene::instances::CameraCull;
        if input.casters.is_masked(d.material) {
            Class::Masked
        } else if input.casters.casts_front_only(d.instance) {
            // `camera_cull` follows the instance's current transform (mirrored or not).
            match d.camera_cull {
                CameraCull::BackCw => Class::FrontCw,
                _ => Class::FrontCcw,
            }
        } else {
            Class::Opaque
        }
    }
}

impl Traditional {
    /// Builds the depth-only pipeline.
    pub fn new(ctx: &GpuContext) -> Self {
        let device = &ctx.device;
        let module = crate::gpu::shaders::module(device, "traditional.shader", &shader());
        let layout = crate::gpu::pipelines::bind_group_layout(
            device,
            "traditional.layout",
            &[
                crate::gpu::pipelines::dynamic_uniform_entry(
                    0,
                    wgpu::ShaderStages::VERTEX,
                    VIEW_BINDING,
                ),
                crate::gpu::pipelines::storage_entry(1, wgpu::ShaderStages::VERTEX),
                crate::gpu::pipelines::uniform_entry(2, wgpu::ShaderStages::VERTEX),
                crate::gpu::pipelines::storage_entry(3, wgpu::ShaderStages::FRAGMENT),
            ],
        );
        let pipeline_layout = crate::gpu::pipelines::pipeline_layout(
            device,
            "traditional.pipeline_layout",
            &[&layout],
        );
        let dp_module = ctx.has(wgpu::Features::CLIP_DISTANCES).then(|| {
            crate::gpu::shaders::module(device, "traditional_dp.shader", &paraboloid_shader())
        });
        let pipeline = |module: &wgpu::ShaderModule,
                        entry: &str,
                        vertex: wgpu::VertexBufferLayout<'static>| {
            crate::shadows::depth::depth_pipeline(
                device,
                &pipeline_layout,
                module,
                entry,
                &[Some(vertex)],
            )
        };
        let no_bones = wgpu::util::DeviceExt::create_buffer_init(
            device,
            &wgpu::util::BufferInitDescriptor {
                label: Some("traditional.no_bones"),
                contents: bytemuck::cast_slice(&[glam::Mat4::IDENTITY.to_cols_array(); MAX_BONES]),
                usage: wgpu::BufferUsages::UNIFORM,
            },
        );
        let masked = |module: &wgpu::ShaderModule, entry: &str| {
            crate::shadows::depth::masked_depth_pipeline(
                device,
                &pipeline_layout,
                module,
                entry,
                &[Some(POSITION_LAYOUT), Some(UV_LAYOUT_1)],
                None,
            )
        };
        Self {
            pipeline: pipeline(&module, "vs_depth", POSITION_LAYOUT),
            masked: masked(&module, "vs_depth_masked"),
            skinned: pipeline(&module, "vs_skinned", SKIN_LAYOUT),
            paraboloid: dp_module.as_ref().map(|m| {
                (
                    pipeline(m, "vs_paraboloid", POSITION_LAYOUT),
                    masked(m, "vs_paraboloid_masked"),
                )
            }),
            layout,
            clear: TileClear::new(ctx),
            no_bones,
            pipeline_layout,
            module,
            dp_module,
            culled: std::collections::HashMap::new(),
        }
    }

    /// Builds, on first need, the culled pipelines `record` will ask for this frame.
    fn prepare_culled(&mut self, device: &wgpu::Device, input: &ShadowInput<'_>) {
        if !input.casters.front_only {
            return;
        }
        let skinned = input.scene.skin.is_some();
        let mut wanted: Vec<(&'static str, Class)> = Vec::new();
        for class in [Class::FrontCcw, Class::FrontCw] {
            if !input
                .scene
                .draws
                .iter()
                .any(|d| d.casts_shadows && Class::of(input, d) == class)
            {
                continue;
            }
            wanted.push((if skinned { "vs_skinned" } else { "vs_depth" }, class));
            if self.dp_module.is_some() && !skinned {
                wanted.push(("vs_paraboloid", class));
            }
        }
        for key in wanted {
            if self.culled.contains_key(&key) {
                continue;
            }
            let (entry, class) = key;
            let (module, vertex) = match entry {
                "vs_paraboloid" => (self.dp_module.as_ref().unwrap(), POSITION_LAYOUT),
                "vs_skinned" => (&self.module, SKIN_LAYOUT),
                _ => (&self.module, POSITION_LAYOUT),
            };
            let front = if class == Class::FrontCw {
                wgpu::FrontFace::Cw
            } else {
                wgpu::FrontFace::Ccw
            };
            let pipeline = crate::shadows::depth::culled_depth_pipeline(
                device,
                &self.pipeline_layout,
                module,
                entry,
                &[Some(vertex)],
                front,
            );
            self.culled.insert(key, pipeline);
        }
    }

    fn bind_group(&self, ctx: &GpuContext, input: &ShadowInput<'_>) -> wgpu::BindGroup {
        let bones = input
            .scene
            .skin
            .as_ref()
            .map_or(&self.no_bones, |s| &s.bones);
        ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("traditional.bind_group"),
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                        buffer: &input.atlas.view_uniforms,
                        offset: 0,
                        size: wgpu::BufferSize::new(VIEW_BINDING),
                    }),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: input.scene.instances.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: bones.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 3,
                    resource: input.casters.corners.as_entire_binding(),
                },
            ],
        })
    }
}

/// Records one draw per visible caster of `view` drawn with the pipeline of `class`; the
/// culled count of that class goes with it.
fn draw_casters(
    pass: &mut wgpu::RenderPass<'_>,
    input: &ShadowInput<'_>,
    view: &manyshadows_scene::light_space::ShadowView,
    class: Class,
    stats: &mut ShadowStats,
) {
    let scene = input.scene;
    let is_masked = |d: &&crate::gpu_scene::instances::DrawItem| Class::of(input, d) == class;
    let mut drawn = 0u64;
    for d in visible_casters(scene, view).filter(is_masked) {
        let m = d.mesh;
        pass.draw_indexed(
            m.first_index..m.first_index + m.index_count,
            m.base_vertex,
            d.instance..d.instance + 1,
        );
        stats.draws += 1;
        stats.triangles += m.index_count as u64 / 3;
        drawn += 1;
    }
    let casters = scene
        .draws
        .iter()
        .filter(|d| d.casts_shadows)
        .filter(is_masked)
        .count() as u64;
    stats.culled += casters - drawn;
}

impl ShadowTechnique for Traditional {
    fn record(&mut self, g: Generation<'_>) -> ShadowStats {
        let input = g.input;
        let bind_group = self.bind_group(input.ctx, input);
        self.prepare_culled(&input.ctx.device, input);
        let mut stats = ShadowStats::default();
        let n = input.draw_list.len();
        let (pipeline, vertices) = match &input.scene.skin {
            Some(skin) => (&self.skinned, &skin.vertices),
            None => (&self.pipeline, &input.scene.positions),
        };
        g.encoder.push_debug_group("traditional");
        for (k, &i) in input.draw_list.iter().enumerate() {
            let i = i as usize;
            let (view, tile) = (&input.views[i], &input.atlas.tiles[i]);
            let mut pass = g.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("traditional.view"),
                color_attachments: &[],
                // The first pass clears the whole atlas when every view is redrawn (or only
                // the listed tiles, when caching keeps the others); later passes keep what
                // earlier ones wrote into other tiles.
                depth_stencil_attachment: Some(atlas_attachment(input, k == 0 && input.full())),
                timestamp_writes: g.timer.render_writes(g.span, k == 0, k + 1 == n),
                occlusion_query_set: None,
                multiview_mask: None,
            });
            let s = g.timer.begin_render_stats(&mut pass);
            if k == 0 {
                self.clear.record(input.ctx, input, &mut pass);
            }
            pass.set_viewport(
                tile.x as f32,
                tile.y as f32,
                tile.size as f32,
                tile.size as f32,
                0.0,
                1.0,
            );
            if input.options.discard_raster {
                pass.set_scissor_rect(0, 0, 0, 0);
            } else {
                pass.set_scissor_rect(tile.x, tile.y, tile.size, tile.size);
            }
            let paraboloid = matches!(view.kind, ViewKind::Paraboloid(_));
            let entry = match (paraboloid, input.scene.skin.is_some()) {
                (true, _) => "vs_paraboloid",
                (false, true) => "vs_skinned",
                (false, false) => "vs_depth",
            };
            let (opaque, masked) = if paraboloid {
                match (&self.paraboloid, &input.scene.skin) {
                    (Some((p, m)), None) => (p, m),
                    // Refused up front by `ShadowGenerator`; draw nothing if it ever happens.
                    _ => {
                        g.timer.end_render_stats(&mut pass, s);
                        continue;
                    }
                }
            } else {
                (pipeline, &self.masked)
            };
            pass.set_pipeline(opaque);
            pass.set_bind_group(0, &bind_group, &[(i as u64 * VIEW_UNIFORM_STRIDE) as u32]);
            pass.set_vertex_buffer(0, vertices.slice(..));
            pass.set_index_buffer(input.scene.indices.slice(..), wgpu::IndexFormat::Uint32);
            draw_casters(&mut pass, input, view, Class::Opaque, &mut stats);
            for class in [Class::FrontCcw, Class::FrontCw] {
                // Single-sided casters that cast only where the light sees their front.
                if let Some(culled) = self.culled.get(&(entry, class)) {
                    pass.set_pipeline(culled);
                    draw_casters(&mut pass, input, view, class, &mut stats);
                }
            }
            if input.casters.first_masked_triangle < input.casters.triangles {
                // Alpha-tested casters (never skinned: CasterGeometry refuses that).
                pass.set_pipeline(masked);
                pass.set_vertex_buffer(1, input.scene.uvs.slice(..));
                draw_casters(&mut pass, input, view, Class::Masked, &mut stats);
            }
            if paraboloid {
                self.clear.reset_clip_distances(&mut pass);
            }
            g.timer.end_render_stats(&mut pass, s);
            stats.passes += 1;
        }
        g.encoder.pop_debug_group();
        stats
    }
}
