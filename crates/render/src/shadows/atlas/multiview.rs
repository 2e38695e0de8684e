//! `multiview`: one render pass per group of equal-size views through wgpu's `MULTIVIEW`
//! feature (seed 000 §19.5; seed 003's cube in one pass).
//!
//! Multiview renders into the layers of an array texture, but the atlas is one 2D texture with
//! tiles of different sizes. So consecutive views of the draw list with the same tile size form
//! a group (a point light's six cube faces, a run of equal cascades or spot lights), at most
//! `max_multiview_view_count` views (6 on lavapipe; at most 31, see `MAX_VIEWS`). Each group is
//! rendered into layers `0..n` of a scratch `Depth32Float` array (viewport = the tile size,
//! `@builtin(view_index)` picks the view), then a small render pass copies every layer into its
//! atlas tile: a quad per tile whose fragments load the scratch texel and write it as
//! `frag_depth` (depth copies into a sub-rectangle are not allowed by
//! `copy_texture_to_texture`). Rasterizing at the tile size from the origin gives the same
//! texels as `traditional`'s viewport at the tile's integer offset.
//!
//! World positions come from the per-frame caster transform ([`crate::gpu_scene::casters`]);
//! per-triangle culling pulls each triangle's corners as `layered` does and emits a degenerate
//! triangle when the triangle is dropped for that view.
//!
//! Without `MULTIVIEW` (OpenGL) the technique refuses to start and names `layered`, which
//! produces the same atlas in one instanced draw.

use std::collections::HashMap;
use std::num::NonZeroU32;

use manyshadows_scene::light_space::PointShadows;

use crate::error::Fills;
use crate::error::RenderError;
use crate::error::Technique;
use crate::gpu::context::GpuContext;
use crate::gpu::pipelines::dynamic_uniform_entry;
use crate::gpu::shaders::{compose, COMMON};
use crate::gpu_scene::casters::ALPHA_MASK;
use crate::shadows::atlas::shared::atlas_report;
use crate::shadows::atlas::shared::{atlas_attachment, CachedGroup, TileClear, UniformRecords};
use crate::shadows::cost::{price, Cost, LightingRead};
use crate::shadows::depth::CULL;
use crate::shadows::depth::{layered_depth_pipeline, masked_depth_pipeline};
use crate::shadows::descriptor::{Build, Culling, Need, TechniqueInfo, Wgsl};
use crate::shadows::lookup::ATLAS_LOOKUP;
use crate::shadows::options::CullMode;
use crate::shadows::source::ShadowStats;
use crate::shadows::technique::{Generation, ShadowTechnique};

impl Technique {
    /// Groups of equal-size views per multiview pass (seed 000).
    pub const MULTIVIEW: Technique = Technique::named("multiview");
}

/// `multiview`'s declaration.
pub const INFO: TechniqueInfo = TechniqueInfo {
    technique: Technique::MULTIVIEW,
    summary: "one multiview pass per group of equal-size views (cube faces, cascades), then a \
              copy into the tiles",
    origin: "seed 000 section 19.5; seed 003's cube map in one pass",
    fills: Fills::Atlas,
    culling: Culling::VertexStage,
    point_shadows: &[PointShadows::Cube],
    needs: &[Need::multiview(
        "one render pass per group of up to 6-32 equal-size shadow views",
    )],
    soft_shadows: true,
    // Milliseconds of its shadow stage per (triangle, view) pair taken on, (instance, view) pair,
    // texel of the tiles, texel of the whole atlas, view, and fixed, on lavapipe
    // (docs/benchmarks.md, "What a frame will cost: `bench estimate`").
    cost: Cost {
        lighting: LightingRead::Maps,
        shadows_ms: |w| {
            price(
                &[7.27e-05, 8.92e-02, 4.47e-06, 0.0, 0.0, 0.0],
                &w.atlas_units(),
            )
        },
    },
    camera_pixels_only: false,
    follows_camera: false,
    report: |r| atlas_report(r, Culling::VertexStage),
    instead: "use technique layered, which fills the same atlas with one instanced draw",
    lookup: ATLAS_LOOKUP,
    build: Build::Atlas(|ctx| Ok(Box::new(Multiview::new(ctx)?))),
    shaders: || {
        vec![
            Wgsl::with("multiview", shader(), wgpu::Features::MULTIVIEW),
            Wgsl::core("multiview_copy", copy_shader()),
        ]
    },
};

/// `MultiviewParams` of `multiview.wgsl` (and `multiview_copy.wgsl`), one per view group.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct MultiviewParams {
    /// First draw-list entry of the group, cullable triangles, cull bits, unused.
    pub(crate) counts: [u32; 4],
    /// Atlas side in texels, unused ×3.
    pub(crate) atlas: [f32; 4],
}

/// Bytes of one group's parameters (`MultiviewParams` in multiview.wgsl).
const PARAMS_SIZE: u64 = std::mem::size_of::<MultiviewParams>() as u64;

/// The vertex shaders (one view per `view_index`).
fn shader() -> String {
    compose(&[COMMON, CULL, ALPHA_MASK, include_str!("multiview.wgsl")])
}

/// The copy of scratch layers into atlas tiles.
fn copy_shader() -> String {
    compose(&[COMMON, include_str!("multiview_copy.wgsl")])
}

/// Splits `draw_list` into runs of consecutive views whose tiles have the same side, at most
/// `max` views each: `(first position in the list, views)`.
pub fn groups(draw_list: &[u32], tile_size: impl Fn(u32) -> u32, max: u32) -> Vec<(u32, u32)> {
    let max = max.max(1);
    let mut out: Vec<(u32, u32)> = Vec::new();
    let mut prev_size = None;
    for (k, &view) in draw_list.iter().enumerate() {
        let size = tile_size(view);
        match out.last_mut() {
            Some(g) if prev_size == Some(size) && g.1 < max => g.1 += 1,
            _ => out.push((k as u32, 1)),
        }
        prev_size = Some(size);
    }
    out
}

#[cfg(test)]
use crate::gpu::context::mesa_major;
pub use crate::gpu::context::{clips_into_layer_zero, MAX_MULTIVIEW_VIEWS as MAX_VIEWS};

/// Views one multiview pass renders on `ctx`'s device
/// ([`GpuContext::multiview_views_per_pass`]).
pub fn views_per_pass_on(ctx: &GpuContext) -> u32 {
    ctx.multiview_views_per_pass()
}

/// The view mask of a pass or pipeline over views `0..n` (`n` in `1..=MAX_VIEWS`).
fn view_mask(n: u32) -> Option<NonZeroU32> {
    NonZeroU32::new((1u32 << n.clamp(1, MAX_VIEWS)) - 1)
}

/// The multiview technique's pipelines and scratch texture.
pub struct Multiview {
    module: wgpu::ShaderModule,
    layout: wgpu::BindGroupLayout,
    pipeline_layout: wgpu::PipelineLayout,
    /// Geometry pipelines by (views in the group, pulled vertices, alpha-tested): a
    /// pipeline's multiview mask must equal its pass's.
    pipelines: HashMap<(u32, bool, bool), wgpu::RenderPipeline>,
    copy_pipeline: wgpu::RenderPipeline,
    copy_layout: wgpu::BindGroupLayout,
    scratch: Option<Scratch>,
    clear: TileClear,
    max_views: u32,
    /// One `MultiviewParams` per group, rewritten each generation.
    params: UniformRecords,
    group: CachedGroup,
    /// Also binds the scratch array: invalidated when the scratch is replaced.
    copy_group: CachedGroup,
}

/// The scratch depth array a group renders into.
struct Scratch {
    texture: wgpu::Texture,
    side: u32,
    layers: u32,
    /// Layers `0..n` as a render target, by `n`.
    targets: HashMap<u32, wgpu::TextureView>,
    /// Every layer, for the copy's `textureLoad`.
    all: wgpu::TextureView,
}

impl Multiview {
    /// Builds the pipelines; the registry has checked `MULTIVIEW`. A device that has the
    /// feature but allows no view is refused the same way.
    pub fn new(ctx: &GpuContext) -> Result<Self, RenderError> {
        let max_views = views_per_pass_on(ctx);
        if max_views == 0 {
            return Err(RenderError::missing_feature(
                ctx,
                "technique multiview",
                "the MULTIVIEW feature with at least one view per pass",
                INFO.instead,
            ));
        }
        if clips_into_layer_zero(&ctx.info) {
            static WARNED: std::sync::Once = std::sync::Once::new();
            WARNED.call_once(|| {
                log::warn!(
                "multiview: {} renders every primitive that needs clipping into view 0's layer \
                 (lavapipe before Mesa 25 drops the view index), so each multiview pass holds \
                 one view here; expect no multiview speed-up on this adapter",
                crate::gpu::context::describe_adapter(&ctx.info)
            )
            });
        }
        let device = &ctx.device;
        let module = crate::gpu::shaders::module(device, "multiview.shader", &shader());
        let vs = wgpu::ShaderStages::VERTEX;
        let layout = crate::gpu::pipelines::bind_group_layout(
            device,
            "multiview.layout",
            &[
                dynamic_uniform_entry(0, vs, PARAMS_SIZE),
                crate::gpu::pipelines::storage_entry(1, vs),
                crate::gpu::pipelines::storage_entry(2, vs),
                crate::gpu::pipelines::storage_entry(3, vs),
                crate::gpu::pipelines::storage_entry(4, wgpu::ShaderStages::VERTEX_FRAGMENT),
                crate::gpu::pipelines::storage_entry(5, vs),
            ],
        );
        let pipeline_layout =
            crate::gpu::pipelines::pipeline_layout(device, "multiview.pipeline_layout", &[&layout]);

        let vf = wgpu::ShaderStages::VERTEX_FRAGMENT;
        let copy_layout = crate::gpu::pipelines::bind_group_layout(
            device,
            "multiview.copy_layout",
            &[
                dynamic_uniform_entry(0, vf, PARAMS_SIZE),
                crate::gpu::pipelines::storage_entry(1, vf),
                crate::gpu::pipelines::storage_entry(2, vf),
                wgpu::BindGroupLayoutEntry {
                    binding: 3,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Depth,
                        view_dimension: wgpu::TextureViewDimension::D2Array,
                        multisampled: false,
                    },
                    count: None,
                },
            ],
        );
        let copy_module =
            crate::gpu::shaders::module(device, "multiview_copy.shader", &copy_shader());
        let copy_pipeline_layout = crate::gpu::pipelines::pipeline_layout(
            device,
            "multiview.copy_pipeline_layout",
            &[&copy_layout],
        );
        // A copy: every texel of the tile is replaced.
        let copy_pipeline = crate::shadows::depth::overwrite_pipeline(
            device,
            &copy_pipeline_layout,
            &copy_module,
            "vs_copy",
            Some("fs_copy"),
        );
        Ok(Self {
            module,
            layout,
            pipeline_layout,
            pipelines: HashMap::new(),
            copy_pipeline,
            copy_layout,
            scratch: None,
            clear: TileClear::new(ctx),
            max_views,
            params: UniformRecords::new(ctx, "multiview.params", PARAMS_SIZE),
            group: CachedGroup::default(),
            copy_group: CachedGroup::default(),
        })
    }

    /// Most views one multiview pass renders on this adapter.
    #[cfg_attr(not(feature = "internals"), allow(dead_code))] // benchmarks and tests
    pub fn views_per_pass(&self) -> u32 {
        self.max_views
    }

    /// The geometry pipeline for groups of `n` views (alpha-tested casters: `masked`).
    fn pipeline(
        &mut self,
        ctx: &GpuContext,
        n: u32,
        pulled: bool,
        masked: bool,
    ) -> &wgpu::RenderPipeline {
        let (module, layout) = (&self.module, &self.pipeline_layout);
        self.pipelines
            .entry((n, pulled, masked))
            .or_insert_with(|| {
                let mask = view_mask(n);
                let entry = match (pulled, masked) {
                    (true, false) => "vs_pulled",
                    (false, false) => "vs_indexed",
                    (true, true) => "vs_pulled_masked",
                    (false, true) => "vs_indexed_masked",
                };
                // Culling is per view in the shader; survivors cast from both sides.
                if masked {
                    masked_depth_pipeline(&ctx.device, layout, module, entry, &[], mask)
                } else {
                    layered_depth_pipeline(&ctx.device, layout, module, entry, &[], mask)
                }
            })
    }

    /// Makes sure the scratch array holds `layers` layers of `side`² texels.
    fn ensure_scratch(&mut self, ctx: &GpuContext, side: u32, layers: u32) {
        if let Some(s) = &self.scratch {
            if s.side >= side && s.layers >= layers {
                return;
            }
        }
        let (side, layers) = match &self.scratch {
            Some(s) => (side.max(s.side), layers.max(s.layers)),
            None => (side, layers),
        };
        let texture =
            crate::gpu::pipelines::depth_texture(&ctx.device, "multiview.scratch", side, layers);
        let all = texture.create_view(&wgpu::TextureViewDescriptor {
            label: Some("multiview.scratch.all"),
            dimension: Some(wgpu::TextureViewDimension::D2Array),
            ..Default::default()
        });
        self.copy_group.invalidate();
        self.scratch = Some(Scratch {
            texture,
            side,
            layers,
            targets: HashMap::new(),
            all,
        });
    }
}

impl Scratch {
    /// Layers `0..n` as a multiview render target.
    fn target(&mut self, n: u32) -> &wgpu::TextureView {
        let texture = &self.texture;
        self.targets.entry(n).or_insert_with(|| {
            texture.create_view(&wgpu::TextureViewDescriptor {
                label: Some("multiview.scratch.target"),
                dimension: Some(wgpu::TextureViewDimension::D2Array),
                base_array_layer: 0,
                array_layer_count: Some(n),
                ..Default::default()
            })
        })
    }
}

impl ShadowTechnique for Multiview {
    fn record(&mut self, g: Generation<'_>) -> ShadowStats {
        let input = g.input;
        let mut stats = ShadowStats::default();
        let ctx = input.ctx;
        let casters = input.casters;
        let cull = input.options.cull;
        let tiles = &input.atlas.tiles;
        let groups = groups(input.draw_list, |v| tiles[v as usize].size, self.max_views);
        let side = input
            .draw_list
            .iter()
            .map(|&v| tiles[v as usize].size)
            .max()
            .unwrap_or(1);
        let layers = groups.iter().map(|g| g.1).max().unwrap_or(1);
        self.ensure_scratch(ctx, side, layers);

        let pulled = cull != CullMode::None;
        let any_masked = casters.first_masked_triangle < casters.triangles;
        for &(_, n) in &groups {
            self.pipeline(ctx, n, pulled, false);
            if any_masked {
                self.pipeline(ctx, n, pulled, true);
            }
        }

        // One parameter record per group, at the uniform-offset alignment.
        let records: Vec<MultiviewParams> = groups
            .iter()
            .map(|&(first, _)| MultiviewParams {
                counts: [first, casters.cullable_triangles, cull.bits_for(casters), 0],
                atlas: [input.atlas.size as f32, 0.0, 0.0, 0.0],
            })
            .collect();
        self.params.write(ctx, &records);
        let params = &self.params;
        let device = &ctx.device;
        let buffers = [
            params.buffer(),
            &input.atlas.views_buffer,
            &input.atlas.eyes,
            &casters.world,
            &casters.corners,
            &input.atlas.draw_list,
        ];
        let layout = &self.layout;
        let bind_group =
            self.group.get(&buffers, || {
                let mut entries = vec![wgpu::BindGroupEntry {
                    binding: 0,
                    resource: params.binding(),
                }];
                entries.extend(buffers[1..].iter().enumerate().map(|(i, b)| {
                    wgpu::BindGroupEntry {
                        binding: i as u32 + 1,
                        resource: b.as_entire_binding(),
                    }
                }));
                device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("multiview.bind_group"),
                    layout,
                    entries: &entries,
                })
            });
        let copy_buffers = [
            params.buffer(),
            &input.atlas.views_buffer,
            &input.atlas.draw_list,
        ];
        let copy_layout = &self.copy_layout;
        let all = &self.scratch.as_ref().expect("scratch").all;
        let copy_bind_group = self.copy_group.get(&copy_buffers, || {
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("multiview.copy_bind_group"),
                layout: copy_layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: params.binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: input.atlas.views_buffer.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 2,
                        resource: input.atlas.draw_list.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 3,
                        resource: wgpu::BindingResource::TextureView(all),
                    },
                ],
            })
        });

        g.encoder.push_debug_group("multiview");
        {
            let mut pass = g.input.ctx.raster_fence().begin_compute_pass(
                g.encoder,
                &wgpu::ComputePassDescriptor {
                    label: Some("multiview.transform"),
                    timestamp_writes: g.timer.compute_writes(g.span, true, false),
                },
            );
            let s = g.timer.begin_compute_stats(&mut pass);
            casters.record(&mut pass, false);
            g.timer.end_compute_stats(&mut pass, s);
            stats.passes += 1;
        }
        // Opaque casters, then the alpha-tested ones (caster_layout.rs puts them last).
        let opaque = 3 * casters.first_masked_triangle;
        let corners = 3 * casters.triangles;
        for (group, &(first, n)) in groups.iter().enumerate() {
            let offset = [params.offset(group)];
            let size = tiles[input.draw_list[first as usize] as usize].size;
            let ranges = [
                (0..opaque, self.pipelines.get(&(n, pulled, false))),
                (opaque..corners, self.pipelines.get(&(n, pulled, true))),
            ];
            let scratch = self.scratch.as_mut().expect("scratch");
            {
                let mut pass = g.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("multiview.group"),
                    color_attachments: &[],
                    depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                        view: scratch.target(n),
                        depth_ops: Some(wgpu::Operations {
                            load: wgpu::LoadOp::Clear(1.0),
                            store: wgpu::StoreOp::Store,
                        }),
                        stencil_ops: None,
                    }),
                    timestamp_writes: None,
                    occlusion_query_set: None,
                    multiview_mask: view_mask(n),
                });
                let s = g.timer.begin_render_stats(&mut pass);
                pass.set_viewport(0.0, 0.0, size as f32, size as f32, 0.0, 1.0);
                if input.options.discard_raster {
                    pass.set_scissor_rect(0, 0, 0, 0);
                } else {
                    pass.set_scissor_rect(0, 0, size, size);
                }
                pass.set_bind_group(0, bind_group, &offset);
                pass.set_index_buffer(casters.corners.slice(..), wgpu::IndexFormat::Uint32);
                for (range, pipeline) in ranges {
                    let Some(pipeline) = pipeline.filter(|_| !range.is_empty()) else {
                        continue;
                    };
                    pass.set_pipeline(pipeline);
                    if pulled {
                        pass.draw(range, 0..1);
                    } else {
                        pass.draw_indexed(range, 0, 0..1);
                    }
                    stats.draws += 1;
                }
                g.timer.end_render_stats(&mut pass, s);
                stats.passes += 1;
            }
            let last = group + 1 == groups.len();
            let mut pass = g.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("multiview.copy"),
                color_attachments: &[],
                depth_stencil_attachment: Some(atlas_attachment(input, group == 0 && input.full())),
                timestamp_writes: g.timer.render_writes(g.span, false, last),
                occlusion_query_set: None,
                multiview_mask: None,
            });
            let s = g.timer.begin_render_stats(&mut pass);
            if group == 0 {
                self.clear.record(ctx, input, &mut pass);
            }
            if input.options.discard_raster {
                pass.set_scissor_rect(0, 0, 0, 0);
            }
            pass.set_pipeline(&self.copy_pipeline);
            pass.set_bind_group(0, copy_bind_group, &offset);
            pass.draw(0..6 * n, 0..1);
            g.timer.end_render_stats(&mut pass, s);
            stats.passes += 1;
            stats.draws += 1;
        }
        g.encoder.pop_debug_group();
        stats.triangles += casters.triangles as u64 * input.draw_list.len() as u64;
        stats
    }
}

#[cfg(test)]
mod tests {
    use super::{copy_shader, groups, shader, view_mask, MultiviewParams, MAX_VIEWS};
    use crate::gpu::types::layout::same_layout;

    #[test]
    fn params_match_the_wgsl() {
        same_layout!(in shader(), MultiviewParams, counts, atlas);
        same_layout!(in copy_shader(), MultiviewParams, counts, atlas);
    }

    #[test]
    fn groups_split_on_size_and_count() {
        // A point light (6 equal faces), three cascades of two sizes, two spot lights.
        let sizes = [256, 256, 256, 256, 256, 256, 512, 512, 256, 128, 128];
        let list: Vec<u32> = (0..sizes.len() as u32).collect();
        let g = groups(&list, |v| sizes[v as usize], 6);
        assert_eq!(g, vec![(0, 6), (6, 2), (8, 1), (9, 2)]);
        let g = groups(&list, |v| sizes[v as usize], 4);
        assert_eq!(g, vec![(0, 4), (4, 2), (6, 2), (8, 1), (9, 2)]);
        // A partial draw list groups by list position.
        let g = groups(&[1, 2, 7, 9], |v| sizes[v as usize], 6);
        assert_eq!(g, vec![(0, 2), (2, 1), (3, 1)]);
        assert!(groups(&[], |_| 1, 6).is_empty());
    }

    /// Every mask the technique uses names views `0..n` the way wgpu 30 checks it
    /// (`(mask + 1).is_power_of_two()`, in wrapping u32 arithmetic), so no pipeline or pass
    /// asks for `SELECTIVE_MULTIVIEW`; 32 views would not.
    #[test]
    fn view_masks_need_no_selective_multiview() {
        for n in 1..=MAX_VIEWS {
            let mask = view_mask(n).expect("a view").get();
            assert_eq!(mask.count_ones(), n);
            assert!(
                mask.wrapping_add(1).is_power_of_two(),
                "{n} views: {mask:#x}"
            );
        }
        assert!(!u32::MAX.wrapping_add(1).is_power_of_two());
    }

    #[test]
    fn only_lavapipe_before_mesa_25_runs_one_view_per_pass() {
        let info = |backend, name: &str, driver_info: &str| wgpu::AdapterInfo {
            name: name.into(),
            driver_info: driver_info.into(),
            backend,
            ..wgpu::AdapterInfo::new(wgpu::DeviceType::Cpu, backend)
        };
        let lavapipe = |d: &str| info(wgpu::Backend::Vulkan, "llvmpipe (LLVM 15.0.6, 256 bits)", d);
        assert!(super::clips_into_layer_zero(&lavapipe("Mesa 22.3.6")));
        assert!(!super::clips_into_layer_zero(&lavapipe(
            "Mesa 25.0.7-2~bpo12+1"
        )));
        assert!(super::clips_into_layer_zero(&lavapipe("unknown")));
        assert!(!super::clips_into_layer_zero(&info(
            wgpu::Backend::Vulkan,
            "NVIDIA H200",
            "580.159.04"
        )));
        assert_eq!(super::mesa_major("Mesa 25.0.7-2~bpo12+1"), Some(25));
    }
}
