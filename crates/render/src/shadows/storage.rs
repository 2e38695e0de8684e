//! The depth atlas (one `Depth32Float` texture, a tile per shadow view) and the per-view
//! buffers techniques and the shadow lookups read; without a texture (1×1) it is the view table
//! of the sources that fill no atlas (irregular, virtual).

use manyshadows_scene::atlas::Tile;

use crate::error::RenderError;
use crate::gpu::context::GpuContext;
use crate::gpu::types::{ViewUniform, VIEW_UNIFORM_STRIDE};
use crate::shadows::plan::{view_eye, ShadowPlan};

/// The depth atlas and the per-view data techniques read.
pub struct ShadowAtlas {
    /// Depth32Float, `size`².
    pub texture: wgpu::Texture,
    /// Depth view of the whole atlas.
    pub view: wgpu::TextureView,
    /// Side in texels.
    pub size: u32,
    /// `array<ShadowViewData>` (storage; at least one element).
    pub views_buffer: wgpu::Buffer,
    /// One [`ViewUniform`] per view at [`VIEW_UNIFORM_STRIDE`] (dynamic uniform offsets).
    pub view_uniforms: wgpu::Buffer,
    /// Tiles in view order.
    pub tiles: Vec<Tile>,
    /// `array<vec4<f32>>` per view, what back-face culling faces: the light's position
    /// (w = 1) or, for orthographic views, the direction light travels (w = 0).
    pub eyes: wgpu::Buffer,
    /// `array<u32>`: the views a generation draws (see
    /// [`ShadowInput::draw_list`](crate::shadows::technique::ShadowInput::draw_list)).
    pub draw_list: wgpu::Buffer,
}

impl ShadowAtlas {
    /// Creates the atlas texture and view buffers for `plan`.
    pub fn new(ctx: &GpuContext, plan: &ShadowPlan) -> Result<Self, RenderError> {
        Self::with_size(ctx, plan, plan.layout.size)
    }

    /// The view buffers of `plan` with a 1×1 placeholder texture: for `irregular`, which
    /// reads the views but fills no tiles.
    pub fn views_only(ctx: &GpuContext, plan: &ShadowPlan) -> Result<Self, RenderError> {
        Self::with_size(ctx, plan, 1)
    }

    fn with_size(ctx: &GpuContext, plan: &ShadowPlan, size: u32) -> Result<Self, RenderError> {
        let (texture, view) = atlas_texture(ctx, size);
        let placeholder = |label: &str, usage: wgpu::BufferUsages| {
            ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: 16,
                usage: usage | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        let mut atlas = Self {
            texture,
            view,
            size,
            views_buffer: placeholder("shadow.views", wgpu::BufferUsages::STORAGE),
            view_uniforms: placeholder("shadow.view_uniforms", wgpu::BufferUsages::UNIFORM),
            tiles: Vec::new(),
            eyes: placeholder("shadow.eyes", wgpu::BufferUsages::STORAGE),
            draw_list: placeholder("shadow.draw_list", wgpu::BufferUsages::STORAGE),
        };
        atlas.write_views(ctx, plan)?;
        Ok(atlas)
    }

    /// Makes the atlas hold `plan` (a new frame's views): view buffers are rewritten in place
    /// (replaced only when the plan has more views than they hold), the texture only when the
    /// atlas side changed. Returns true if a buffer or the texture was replaced, so bind groups
    /// that hold them must be rebuilt.
    pub fn update(&mut self, ctx: &GpuContext, plan: &ShadowPlan) -> Result<bool, RenderError> {
        let mut replaced = false;
        // A views-only atlas keeps its 1×1 placeholder.
        if self.size != 1 && self.size != plan.layout.size {
            (self.texture, self.view) = atlas_texture(ctx, plan.layout.size);
            self.size = plan.layout.size;
            replaced = true;
        }
        Ok(replaced | self.write_views(ctx, plan)?)
    }

    /// Rewrites the lookups' view records of `plan` (the buffer already holds as many), with
    /// the tiles of the views in `empty` marked as holding no depth (side 0: no shadow
    /// information; the techniques never read views outside their draw list).
    pub fn write_view_data(&self, ctx: &GpuContext, plan: &ShadowPlan, empty: &[u32]) {
        let mut data = plan.view_data();
        for &i in empty {
            if let Some(d) = data.get_mut(i as usize) {
                d.tile = [0.0; 4];
            }
        }
        if !data.is_empty() {
            ctx.queue
                .write_buffer(&self.views_buffer, 0, bytemuck::cast_slice(&data));
        }
    }

    /// Writes the per-view buffers of `plan`, growing them if needed (true if any grew).
    fn write_views(&mut self, ctx: &GpuContext, plan: &ShadowPlan) -> Result<bool, RenderError> {
        let mut data = plan.view_data();
        let uniforms: Vec<ViewUniform> = data
            .iter()
            .map(|d| ViewUniform {
                view_proj: d.view_proj,
                params: d.params,
                _pad: [[0.0; 4]; 11],
            })
            .collect();
        if data.is_empty() {
            data.push(bytemuck::Zeroable::zeroed());
        }
        let mut uniform_bytes: Vec<u8> = bytemuck::cast_slice(&uniforms).to_vec();
        if uniform_bytes.is_empty() {
            uniform_bytes.resize(VIEW_UNIFORM_STRIDE as usize, 0);
        }
        let mut eyes: Vec<[f32; 4]> = plan.views.iter().map(|v| view_eye(v).to_array()).collect();
        eyes.resize(eyes.len().max(1), [0.0; 4]);
        let all: Vec<u32> = (0..plan.views.len().max(1) as u32).collect();
        let mut grew = crate::gpu::buffers::grow_buffer(
            ctx,
            &mut self.views_buffer,
            data_bytes(&data),
            "shadow views",
        )?;
        grew |= crate::gpu::buffers::grow_buffer(
            ctx,
            &mut self.view_uniforms,
            uniform_bytes.len() as u64,
            "shadow view uniforms",
        )?;
        grew |= crate::gpu::buffers::grow_buffer(
            ctx,
            &mut self.eyes,
            data_bytes(&eyes),
            "shadow view eyes",
        )?;
        grew |= crate::gpu::buffers::grow_buffer(
            ctx,
            &mut self.draw_list,
            data_bytes(&all),
            "shadow draw list",
        )?;
        ctx.queue
            .write_buffer(&self.views_buffer, 0, bytemuck::cast_slice(&data));
        ctx.queue
            .write_buffer(&self.view_uniforms, 0, &uniform_bytes);
        ctx.queue
            .write_buffer(&self.eyes, 0, bytemuck::cast_slice(&eyes));
        ctx.queue
            .write_buffer(&self.draw_list, 0, bytemuck::cast_slice(&all));
        self.tiles = plan.layout.tiles.clone();
        Ok(grew)
    }
}

fn data_bytes<T>(v: &[T]) -> u64 {
    std::mem::size_of_val(v) as u64
}

/// A `size`² depth atlas texture and its view.
fn atlas_texture(ctx: &GpuContext, size: u32) -> (wgpu::Texture, wgpu::TextureView) {
    let texture = crate::gpu::pipelines::depth_texture(&ctx.device, "shadow.atlas", size, 1);
    let view = texture.create_view(&wgpu::TextureViewDescriptor {
        label: Some("shadow.atlas.view"),
        dimension: Some(wgpu::TextureViewDimension::D2),
        ..Default::default()
    });
    (texture, view)
}
