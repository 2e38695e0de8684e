//! `layered`: every shadow view in one render pass and one instanced draw (seed 000 §19.3).
//!
//! wgpu has no geometry shader and cannot pick a render-target layer per primitive, so the
//! seed's layered rendering maps onto the atlas: instance *i* of the draw renders into view
//! `draw_list[i]`, and the vertex shader moves clip-space xy into that view's tile while four
//! clip distances keep the triangle inside it. The per-vertex work that does not depend on the
//! view (model transform, skinning) runs once per frame in the caster transform
//! ([`crate::gpu_scene::casters`]); per view only the view-projection remains.
//!
//! Culling (seed 000 Listings 19.9 and 19.10) happens per triangle and view in the vertex
//! shader: with culling on, the draw is non-indexed and each invocation pulls its triangle's
//! three corners, tests them, and emits a degenerate triangle when the triangle is dropped.
//! Without culling the draw is indexed, so post-transform vertex reuse still applies.

use manyshadows_scene::light_space::PointShadows;

use crate::error::Fills;
use crate::error::RenderError;
use crate::error::Technique;
use crate::gpu::context::GpuContext;
use crate::gpu::shaders::{compose, COMMON};
use crate::gpu_scene::casters::ALPHA_MASK;
use crate::shadows::atlas::shared::atlas_report;
use crate::shadows::atlas::shared::{atlas_attachment, CachedGroup, TileClear};
use crate::shadows::cost::{price, Cost, LightingRead};
use crate::shadows::depth::{depth_pipeline, masked_depth_pipeline};
use crate::shadows::depth::{CULL, TILE, TILE_MASK};
use crate::shadows::descriptor::{Build, Culling, Need, TechniqueInfo, Wgsl};
use crate::shadows::lookup::ATLAS_LOOKUP;
use crate::shadows::lookup::PARABOLOID;
use crate::shadows::source::ShadowStats;
use crate::shadows::technique::{Generation, ShadowTechnique};

impl Technique {
    /// Every view in one instanced draw (seed 000).
    pub const LAYERED: Technique = Technique::named("layered");
}

/// `layered`'s declaration.
pub const INFO: TechniqueInfo = TechniqueInfo {
    technique: Technique::LAYERED,
    summary: "one instanced draw into every tile; per-view triangle culling in the vertex shader",
    origin: "seed 000 section 19.3 (layered rendering), Listings 19.9 and 19.10 (culling)",
    fills: Fills::Atlas,
    culling: Culling::VertexStage,
    point_shadows: &[PointShadows::Cube, PointShadows::DualParaboloid],
    needs: &[Need::feature(
        wgpu::Features::CLIP_DISTANCES,
        "to keep each view inside its atlas tile",
    )],
    soft_shadows: true,
    // Milliseconds of its shadow stage per (triangle, view) pair taken on, (instance, view) pair,
    // texel of the tiles, texel of the whole atlas, view, and fixed, on lavapipe
    // (docs/benchmarks.md, "What a frame will cost: `bench estimate`").
    cost: Cost {
        lighting: LightingRead::Maps,
        shadows_ms: |w| price(&[9.91e-05, 0.0, 0.0, 8.89e-07, 0.0, 0.0], &w.atlas_units()),
    },
    camera_pixels_only: false,
    follows_camera: false,
    report: |r| atlas_report(r, Culling::VertexStage),
    instead: "use technique traditional",
    lookup: ATLAS_LOOKUP,
    build: Build::Atlas(|ctx| Ok(Box::new(Layered::new(ctx)?))),
    shaders: || {
        vec![Wgsl::with(
            "layered",
            shader(),
            wgpu::Features::CLIP_DISTANCES,
        )]
    },
};

/// `LayeredParams` of `layered.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct LayeredParams {
    /// Cullable triangles, cull bits, unused, unused.
    pub(crate) counts: [u32; 4],
    /// Atlas side in texels, its reciprocal, unused, unused.
    pub(crate) atlas: [f32; 4],
}

/// The vertex shaders (indexed and pulling, opaque and alpha-tested).
fn shader() -> String {
    compose(&[
        "enable clip_distances;",
        COMMON,
        CULL,
        TILE,
        PARABOLOID,
        ALPHA_MASK,
        TILE_MASK,
        include_str!("layered.wgsl"),
    ])
}

/// The layered technique's pipelines.
pub struct Layered {
    indexed: wgpu::RenderPipeline,
    pulled: wgpu::RenderPipeline,
    /// The same for the alpha-tested range of the casters (`fs_alpha`).
    indexed_masked: wgpu::RenderPipeline,
    pulled_masked: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    clear: TileClear,
    /// `LayeredParams`, rewritten each generation.
    params: wgpu::Buffer,
    group: CachedGroup,
}

impl Layered {
    /// Builds the pipelines; needs `CLIP_DISTANCES`.
    pub fn new(ctx: &GpuContext) -> Result<Self, RenderError> {
        let device = &ctx.device;
        let module = crate::gpu::shaders::module(device, "layered.shader", &shader());
        let vs = wgpu::ShaderStages::VERTEX;
        let layout = crate::gpu::pipelines::bind_group_layout(
            device,
            "layered.layout",
            &[
                crate::gpu::pipelines::uniform_entry(0, vs),
                crate::gpu::pipelines::storage_entry(1, vs),
                crate::gpu::pipelines::storage_entry(2, vs),
                crate::gpu::pipelines::storage_entry(3, vs),
                crate::gpu::pipelines::storage_entry(4, wgpu::ShaderStages::VERTEX_FRAGMENT),
                crate::gpu::pipelines::storage_entry(5, vs),
            ],
        );
        let pipeline_layout =
            crate::gpu::pipelines::pipeline_layout(device, "layered.pipeline_layout", &[&layout]);
        let pipeline = |entry: &str| depth_pipeline(device, &pipeline_layout, &module, entry, &[]);
        let masked = |entry: &str| {
            masked_depth_pipeline(device, &pipeline_layout, &module, entry, &[], None)
        };
        Ok(Self {
            indexed: pipeline("vs_indexed"),
            pulled: pipeline("vs_pulled"),
            indexed_masked: masked("vs_indexed_masked"),
            pulled_masked: masked("vs_pulled_masked"),
            layout,
            clear: TileClear::new(ctx),
            params: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("layered.params"),
                size: std::mem::size_of::<LayeredParams>() as u64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            group: CachedGroup::default(),
        })
    }
}

impl ShadowTechnique for Layered {
    fn record(&mut self, g: Generation<'_>) -> ShadowStats {
        let input = g.input;
        let mut stats = ShadowStats::default();
        let views = input.draw_list.len() as u32;
        let casters = input.casters;
        let ctx = input.ctx;
        let cull = input.options.cull;
        let atlas = input.atlas.size as f32;
        let params = LayeredParams {
            counts: [casters.cullable_triangles, cull.bits_for(casters), 0, 0],
            atlas: [atlas, 1.0 / atlas, 0.0, 0.0],
        };
        ctx.queue
            .write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
        let buffers = [
            &self.params,
            &input.atlas.views_buffer,
            &input.atlas.eyes,
            &casters.world,
            &casters.corners,
            &input.atlas.draw_list,
        ];
        let (device, layout) = (&ctx.device, &self.layout);
        let bind_group = self.group.get(&buffers, || {
            crate::gpu::pipelines::buffer_bind_group(device, "layered.bind_group", layout, &buffers)
        });

        g.encoder.push_debug_group("layered");
        {
            let mut pass = g.input.ctx.raster_fence().begin_compute_pass(
                g.encoder,
                &wgpu::ComputePassDescriptor {
                    label: Some("layered.transform"),
                    timestamp_writes: g.timer.compute_writes(g.span, true, false),
                },
            );
            let s = g.timer.begin_compute_stats(&mut pass);
            casters.record(&mut pass, false);
            g.timer.end_compute_stats(&mut pass, s);
            stats.passes += 1;
        }
        let mut pass = g.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("layered.draw"),
            color_attachments: &[],
            depth_stencil_attachment: Some(atlas_attachment(input, input.full())),
            timestamp_writes: g.timer.render_writes(g.span, false, true),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        let s = g.timer.begin_render_stats(&mut pass);
        self.clear.record(ctx, input, &mut pass);
        if input.options.discard_raster {
            pass.set_scissor_rect(0, 0, 0, 0);
        }
        pass.set_bind_group(0, bind_group, &[]);
        // Opaque casters, then the alpha-tested ones (caster_layout.rs puts them last).
        let opaque = 3 * casters.first_masked_triangle;
        let corners = 3 * casters.triangles;
        let ranges = [
            (0..opaque, &self.indexed, &self.pulled),
            (opaque..corners, &self.indexed_masked, &self.pulled_masked),
        ];
        for (range, indexed, pulled) in ranges {
            if range.is_empty() {
                continue;
            }
            if cull == crate::shadows::options::CullMode::None {
                pass.set_pipeline(indexed);
                pass.set_index_buffer(casters.corners.slice(..), wgpu::IndexFormat::Uint32);
                pass.draw_indexed(range, 0, 0..views);
            } else {
                pass.set_pipeline(pulled);
                pass.draw(range, 0..views);
            }
            stats.draws += 1;
        }
        self.clear.reset_clip_distances(&mut pass);
        g.timer.end_render_stats(&mut pass, s);
        drop(pass);
        g.encoder.pop_debug_group();
        stats.passes += 1;
        stats.triangles += casters.triangles as u64 * views as u64;
        stats
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gpu::types::layout::same_layout;

    #[test]
    fn params_match_the_wgsl() {
        same_layout!(in shader(), LayeredParams, counts, atlas);
    }
}
