//! Clustered light lists (Olsson, Billeter and Assarsson, "Clustered Deferred and Forward
//! Shading", HPG 2012; seed 002 uses the same clusters for its virtual shadow maps): with
//! thousands of lights a pixel must not loop over all of them, only over those that can reach
//! it.
//!
//! **The grid.** The view is cut into square screen tiles ([`ClusterOptions::tile`] pixels)
//! and [`ClusterOptions::slices`] depth slices, exponential in view depth between the nearest
//! and farthest depth that holds geometry (the camera's near and far planes close the first
//! and last slice). A cluster is one (tile, slice) cell: a small frustum segment.
//!
//! **Only occupied clusters** (seed 002's observation that most cells of the grid hold no
//! visible sample): after the G-buffer, one thread per pixel marks its sample's cluster; one
//! thread per cluster then hands each marked cluster a *slot* of a fixed pool. A slot is a
//! bit set over all lights — `ceil(lights/32)` light words, plus one summary bit per light
//! word — so a list can never overflow: every light that reaches a cluster has its bit.
//!
//! **Assignment.** The CPU lists the spot and point lights whose bounding sphere
//! ([`manyshadows_scene::Light::bounding_sphere`]) meets the camera frustum; a light outside
//! it reaches no visible sample. Directional lights reach everywhere: every slot starts with
//! their bits. On the GPU one thread per (listed light, depth slice) projects the sphere's
//! box within the slice to a tile rectangle and tests every occupied cluster in it: sphere
//! against the cluster's view-space box, and for spots the cone against the box's bounding
//! sphere (a conservative test: it only rejects clusters wholly outside the cone). Bits are
//! set with `atomicOr`, so the result does not depend on thread order. The box spans only the
//! view depths of the cluster's own samples, which the marking keeps per cluster (Olsson et
//! al.'s explicit bounds; a far slice is metres deep where the surfaces a tile sees in it are
//! not), which cuts the lights per cluster and with them the lighting pass, more cheaply than
//! finer slices (docs/decisions.md, "Cluster boxes cut to their samples' depths").
//!
//! **Shading** (`lighting.wgsl`, `visibility.wgsl`) walks a slot's set bits in ascending
//! order — summary word, then light word, then bit — and applies the same per-light code as
//! the loop over every light, in the same order. Since every light in reach of a pixel is in
//! its cluster's set, the clustered sum is the *same* floating-point sum as the full loop, bit
//! for bit ([`LightLoop::All`] keeps the full loop as the reference; a test compares them).
//!
//! **When the pool is full** (more occupied clusters than slots: only with a pool budget far
//! below the default, or enormous frames), the clusters left without a slot are marked
//! *overflowed* and their pixels loop over every light: slower, never wrong, and counted in
//! [`ClusterStats::overflowed`].

use manyshadows_scene::light_space;
use manyshadows_scene::Scene;
use wgpu::util::DeviceExt;

use crate::error::RenderError;
use crate::frame::eyes::{Eyes, Stereo};
use crate::frame::gbuffer::GBuffer;
use crate::gpu::context::GpuContext;
use crate::gpu::timing::{GpuTimer, Span};
use crate::gpu::types::ClusterUniforms;

/// Tile side in pixels where every cluster of the grid has a slot in the pool at
/// `SMALL_TILE` no more (large frames with many lights).
pub const DEFAULT_TILE: u32 = 32;
/// Tile side in pixels by default where the pool holds a slot for every cluster of that grid
/// ([`ClusterOptions::tile_for`]). Smaller tiles cut the lights a pixel visits that do not
/// reach it, so the lighting pass grows less with the light count; chosen by measurement
/// (docs/decisions.md, "Cluster tile size").
pub const SMALL_TILE: u32 = 16;
/// Default number of depth slices.
pub const DEFAULT_SLICES: u32 = 24;
/// Default budget of the slot pool (further capped by the adapter's storage-binding limit).
pub const DEFAULT_POOL_BYTES: u64 = 128 << 20;

/// Which lights each pixel's shading visits.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[non_exhaustive]
pub enum LightLoop {
    /// Only the lights of the pixel's cluster (the default).
    #[default]
    Clustered,
    /// Every light, for every pixel: the reference the clustered result must equal.
    All,
}

impl LightLoop {
    /// Every mode.
    pub const ALL: &'static [LightLoop] = &[LightLoop::Clustered, LightLoop::All];

    /// CLI name: `clustered` or `all`.
    pub fn name(self) -> &'static str {
        match self {
            LightLoop::Clustered => "clustered",
            LightLoop::All => "all",
        }
    }
}

impl std::str::FromStr for LightLoop {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        LightLoop::ALL
            .iter()
            .copied()
            .find(|m| m.name() == s)
            .ok_or_else(|| format!("unknown light loop '{s}' (expected clustered or all)"))
    }
}

/// Shape of the cluster grid.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub struct ClusterOptions {
    /// Tile side in pixels (at least 1); `None` = chosen for the frame and lights
    /// ([`ClusterOptions::tile_for`]).
    pub tile: Option<u32>,
    /// Depth slices (1..=256).
    pub slices: u32,
    /// Budget of the slot pool in bytes (capped by the adapter's storage-binding limit);
    /// `None` = 128 MiB.
    pub pool_bytes: Option<u64>,
}

impl ClusterOptions {
    /// Checks every value that has a range of its own ([`RenderError::InvalidOption`] names
    /// the first one out of range, as `RenderSettings` names the field).
    pub fn validate(&self) -> Result<(), RenderError> {
        if self.tile == Some(0) {
            return Err(RenderError::invalid_option(
                "clusters.tile",
                0,
                "at least 1 pixel, or None to choose by the frame and lights",
            ));
        }
        if !(1..=256).contains(&self.slices) {
            return Err(RenderError::invalid_option(
                "clusters.slices",
                self.slices,
                "1 to 256 depth slices",
            ));
        }
        if self.pool_bytes == Some(0) {
            return Err(RenderError::invalid_option(
                "clusters.pool_bytes",
                0,
                "at least 1 byte, or None for the default",
            ));
        }
        Ok(())
    }

    /// The tile side a `width` × `height` frame (of `eyes` side-by-side eyes) with `lights`
    /// lights gets: the one set, else `SMALL_TILE` where a pool of `pool_limit` bytes (the
    /// budget, capped by the device) holds a slot for every cluster of that grid, so no
    /// cluster can overflow that the default tile's grid would not, else `DEFAULT_TILE`.
    pub fn tile_for(
        &self,
        (width, height): (u32, u32),
        eyes: u32,
        lights: usize,
        pool_limit: u64,
    ) -> u32 {
        if let Some(tile) = self.tile {
            return tile;
        }
        let [across, down] = grid_tiles((width, height), eyes, SMALL_TILE);
        let clusters = u64::from(across) * u64::from(down) * u64::from(self.slices);
        let (summary, words) = slot_words(lights);
        if clusters * u64::from(summary + words) * 4 <= pool_limit {
            SMALL_TILE
        } else {
            DEFAULT_TILE
        }
    }
}

impl Default for ClusterOptions {
    fn default() -> Self {
        Self {
            tile: None,
            slices: DEFAULT_SLICES,
            pool_bytes: None,
        }
    }
}

/// What the last frame's clustering did.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
#[non_exhaustive]
pub struct ClusterStats {
    /// Tiles across and down.
    pub tiles: [u32; 2],
    /// Tile side in pixels.
    pub tile: u32,
    /// Depth slices.
    pub slices: u32,
    /// Clusters in the grid.
    pub clusters: u32,
    /// Clusters holding at least one visible sample.
    pub occupied: u32,
    /// Occupied clusters that got no slot (their pixels loop over every light).
    pub overflowed: u32,
    /// Slots in the pool.
    pub capacity: u32,
    /// Spot and point lights whose bounding sphere meets the view (the assignment's input).
    pub lights_in_view: u32,
    /// Mean lights per occupied cluster with a slot (directional lights included).
    pub mean_lights: f64,
    /// Most lights in one cluster.
    pub max_lights: u32,
    /// Bytes of the slot pool.
    pub pool_bytes: u64,
}

/// The cluster grid's buffers and passes.
pub struct LightClusters {
    /// `ClusterUniforms` (uniform).
    pub uniforms: wgpu::Buffer,
    /// One `u32` per cluster, then two per cluster more: the view depths its samples span
    /// (see `clusters.wgsl`).
    pub slots: wgpu::Buffer,
    /// The slot pool.
    pub masks: wgpu::Buffer,
    global: wgpu::Buffer,
    assign_index: wgpu::Buffer,
    assign_sphere: wgpu::Buffer,
    control: wgpu::Buffer,
    readback: wgpu::Buffer,
    layout: wgpu::BindGroupLayout,
    bind_group: Option<wgpu::BindGroup>,
    mark: wgpu::ComputePipeline,
    compact: wgpu::ComputePipeline,
    assign: wgpu::ComputePipeline,
    stats: wgpu::ComputePipeline,
    data: ClusterUniforms,
    width: u32,
    height: u32,
    stereo: Option<Stereo>,
    options: ClusterOptions,
    enabled: bool,
    light_capacity: usize,
    pool_limit: u64,
    fence: crate::gpu::raster_fence::RasterFence,
}

/// Tiles across and down of a `width` × `height` frame of `eyes` side-by-side eyes at `tile`
/// pixels a side: each eye has its own columns (a tile never straddles the eyes).
fn grid_tiles((width, height): (u32, u32), eyes: u32, tile: u32) -> [u32; 2] {
    let eyes = eyes.max(1);
    let eye_width = (width / eyes).max(1);
    [eyes * eye_width.div_ceil(tile), height.div_ceil(tile)]
}

/// Light words and summary words of a slot for `lights` lights.
fn slot_words(lights: usize) -> (u32, u32) {
    let words = (lights as u32).div_ceil(32).max(1);
    (words.div_ceil(32).max(1), words)
}

impl LightClusters {
    /// Builds the grid for `width`×`height` frames and `lights` lights. `enabled = false`
    /// ([`LightLoop::All`]) records nothing and makes shading loop over every light.
    pub fn new(
        ctx: &GpuContext,
        (width, height): (u32, u32),
        lights: usize,
        options: ClusterOptions,
        enabled: bool,
        stereo: Option<Stereo>,
    ) -> Result<Self, RenderError> {
        // The grid's ranges are checked by `RenderSettings::validate`.
        debug_assert!(options.tile != Some(0) && (1..=256).contains(&options.slices));
        let device = &ctx.device;
        let limit = ctx.limits().max_storage_buffer_binding_size;
        let pool_limit = options.pool_bytes.unwrap_or(DEFAULT_POOL_BYTES).min(limit);
        // With two eyes each half has its own tile columns (a tile never straddles the eyes).
        let eyes = if stereo.is_some() { 2 } else { 1 };
        let tile = options.tile_for((width, height), eyes, lights, pool_limit);
        let tiles = grid_tiles((width, height), eyes, tile);
        let clusters = tiles[0] as u64 * tiles[1] as u64 * options.slices as u64;
        // Per cluster its slot, then the depths its samples span (clusters.wgsl).
        let slot_bytes = clusters * 12;
        if slot_bytes > limit {
            return Err(RenderError::TooLarge {
                what: format!(
                    "the {clusters} light clusters of a {width}x{height} frame (use larger \
                     cluster tiles)"
                ),
                needed: slot_bytes,
                limit,
                unit: "bytes",
                limit_name: "max_storage_buffer_binding_size",
            });
        }
        let storage = wgpu::BufferUsages::STORAGE;
        let buffer = |label: &str, size: u64, usage: wgpu::BufferUsages| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: size.max(16),
                usage,
                mapped_at_creation: false,
            })
        };
        let slots = buffer(
            "clusters.slots",
            slot_bytes,
            storage | wgpu::BufferUsages::COPY_DST,
        );
        let control = buffer(
            "clusters.control",
            16,
            storage | wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
        );
        let readback = buffer(
            "clusters.readback",
            16,
            wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        );
        let uniforms = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("clusters.uniforms"),
            contents: bytemuck::bytes_of(&ClusterUniforms::default()),
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        });
        let cs = wgpu::ShaderStages::COMPUTE;
        let layout = crate::gpu::pipelines::bind_group_layout(
            device,
            "clusters.layout",
            &[
                crate::gpu::pipelines::uniform_entry(0, cs),
                crate::gpu::pipelines::uniform_entry(1, cs),
                crate::gpu::pipelines::texture_entry(2, wgpu::TextureSampleType::Uint, cs),
                crate::gpu::pipelines::storage_rw_entry(3, cs),
                crate::gpu::pipelines::storage_rw_entry(4, cs),
                crate::gpu::pipelines::storage_entry(5, cs),
                crate::gpu::pipelines::storage_entry(6, cs),
                crate::gpu::pipelines::storage_entry(7, cs),
                crate::gpu::pipelines::storage_entry(8, cs),
                crate::gpu::pipelines::storage_rw_entry(9, cs),
            ],
        );
        let module = crate::gpu::shaders::module(device, "clusters.shader", &shader());
        let pipeline_layout =
            crate::gpu::pipelines::pipeline_layout(device, "clusters.pipeline_layout", &[&layout]);
        let pipeline = |entry: &str| {
            crate::gpu::pipelines::compute_pipeline(device, entry, &pipeline_layout, &module, entry)
        };
        let mut me = Self {
            fence: ctx.raster_fence().clone(),
            uniforms,
            slots,
            masks: buffer("clusters.masks", 16, storage),
            global: buffer("clusters.global", 16, storage),
            assign_index: buffer("clusters.assign_index", 16, storage),
            assign_sphere: buffer("clusters.assign_sphere", 16, storage),
            control,
            readback,
            layout,
            bind_group: None,
            mark: pipeline("cs_mark"),
            compact: pipeline("cs_compact"),
            assign: pipeline("cs_assign"),
            stats: pipeline("cs_stats"),
            data: ClusterUniforms {
                grid: [tiles[0], tiles[1], options.slices, tile],
                counts: [0, 0, clusters as u32, eyes],
                ..Default::default()
            },
            width,
            height,
            stereo,
            options,
            enabled,
            light_capacity: 0,
            pool_limit,
        };
        me.resize(ctx, lights)?;
        Ok(me)
    }

    /// True when shading reads the lists.
    pub fn enabled(&self) -> bool {
        self.enabled
    }

    /// (Re)allocates the per-light buffers and the pool for `lights` lights, if it grew past
    /// what they hold. Returns true if buffers were replaced (bind groups must be rebuilt).
    fn resize(&mut self, ctx: &GpuContext, lights: usize) -> Result<bool, RenderError> {
        let (summary, words) = slot_words(lights);
        let stride = summary + words;
        let clusters = self.data.counts[2] as u64;
        let fits = (self.pool_limit / (stride as u64 * 4)).max(1);
        let capacity = clusters.min(fits) as u32;
        let same_layout = self.data.words[2] == stride && self.data.counts[0] == capacity;
        self.data.words = [summary, words, stride, u32::from(self.enabled)];
        self.data.counts[0] = capacity;
        if same_layout && lights <= self.light_capacity {
            return Ok(false);
        }
        let device = &ctx.device;
        let storage = wgpu::BufferUsages::STORAGE;
        let buffer = |label: &str, size: u64, usage: wgpu::BufferUsages| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: size.max(16),
                usage,
                mapped_at_creation: false,
            })
        };
        if !same_layout {
            // Only the passes write the pool: an allocation that is never recorded (the full
            // light loop) stays tiny.
            let bytes = if self.enabled {
                capacity as u64 * stride as u64 * 4
            } else {
                16
            };
            self.masks = buffer("clusters.masks", bytes, storage);
            self.global = buffer(
                "clusters.global",
                stride as u64 * 4,
                storage | wgpu::BufferUsages::COPY_DST,
            );
        }
        if lights > self.light_capacity {
            let cap = lights.next_power_of_two().max(64);
            self.assign_index = buffer(
                "clusters.assign_index",
                cap as u64 * 4,
                storage | wgpu::BufferUsages::COPY_DST,
            );
            self.assign_sphere = buffer(
                "clusters.assign_sphere",
                cap as u64 * 16,
                storage | wgpu::BufferUsages::COPY_DST,
            );
            self.light_capacity = cap;
        }
        self.bind_group = None;
        let _ = ctx;
        Ok(true)
    }

    /// Writes this frame's grid, directional bits and light list for `scene` (camera and
    /// lights). Returns true when buffers were replaced: whoever binds [`Self::slots`],
    /// [`Self::masks`] or [`Self::uniforms`] must rebuild its bind group.
    pub fn update(&mut self, ctx: &GpuContext, scene: &Scene) -> Result<bool, RenderError> {
        let replaced = self.resize(ctx, scene.lights.len())?;
        let cam = &scene.camera;
        // Parallel eyes share the view depth of every point: one slicing serves both.
        let eyes = Eyes::new(cam, self.stereo, (self.width, self.height));
        let (lo, hi) = light_space::view_depth_range(cam, scene.world_bounds(false));
        let near = lo.max(cam.near);
        let far = hi.max(near * 1.01);
        let proj = cam.projection(eyes.aspect());
        self.data.depth = [
            near,
            self.options.slices as f32 / (far / near).ln(),
            cam.near,
            cam.far,
        ];
        self.data.proj = [
            1.0 / proj.x_axis.x,
            1.0 / proj.y_axis.y,
            eyes.eye_width as f32,
            eyes.half_separation,
        ];

        let (summary, words) = (self.data.words[0] as usize, self.data.words[1] as usize);
        let mut global = vec![0u32; summary + words];
        let planes: Vec<_> = (0..eyes.cameras.len())
            .map(|e| light_space::frustum_planes(eyes.view_proj(e)))
            .collect();
        let mut index = Vec::new();
        let mut spheres: Vec<[f32; 4]> = Vec::new();
        for (i, light) in scene.lights.iter().enumerate() {
            match light.bounding_sphere() {
                None => {
                    let w = i / 32;
                    global[summary + w] |= 1 << (i % 32);
                    global[w / 32] |= 1 << (w % 32);
                }
                Some((c, r)) => {
                    if planes
                        .iter()
                        .any(|p| light_space::sphere_in_planes(p, c, r * 1.001 + 1e-4))
                    {
                        index.push(i as u32);
                        spheres.push(c.extend(r).to_array());
                    }
                }
            }
        }
        self.data.counts[1] = index.len() as u32;
        let q = &ctx.queue;
        q.write_buffer(&self.uniforms, 0, bytemuck::bytes_of(&self.data));
        q.write_buffer(&self.global, 0, bytemuck::cast_slice(&global));
        if !index.is_empty() {
            q.write_buffer(&self.assign_index, 0, bytemuck::cast_slice(&index));
            q.write_buffer(&self.assign_sphere, 0, bytemuck::cast_slice(&spheres));
        }
        Ok(replaced)
    }

    /// Binds the frame's inputs (after [`Self::update`] replaced buffers, or the lights
    /// buffer or G-buffer changed).
    pub fn bind(
        &mut self,
        ctx: &GpuContext,
        frame: &wgpu::Buffer,
        lights: &wgpu::Buffer,
        gbuffer: &GBuffer,
    ) {
        let pv = gbuffer.position.create_view(&Default::default());
        let entry = |binding, resource| wgpu::BindGroupEntry { binding, resource };
        self.bind_group = Some(ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("clusters.bind_group"),
            layout: &self.layout,
            entries: &[
                entry(0, frame.as_entire_binding()),
                entry(1, self.uniforms.as_entire_binding()),
                entry(2, wgpu::BindingResource::TextureView(&pv)),
                entry(3, self.slots.as_entire_binding()),
                entry(4, self.masks.as_entire_binding()),
                entry(5, self.global.as_entire_binding()),
                entry(6, self.assign_index.as_entire_binding()),
                entry(7, self.assign_sphere.as_entire_binding()),
                entry(8, lights.as_entire_binding()),
                entry(9, self.control.as_entire_binding()),
            ],
        }));
    }

    /// Records marking, slot allocation, assignment and statistics (nothing when disabled).
    pub fn record(&self, encoder: &mut wgpu::CommandEncoder, timer: &GpuTimer, span: Option<Span>) {
        if !self.enabled {
            return;
        }
        let Some(bind_group) = &self.bind_group else {
            debug_assert!(false, "LightClusters::bind must run before record");
            return;
        };
        encoder.clear_buffer(&self.slots, 0, None);
        encoder.clear_buffer(&self.control, 0, None);
        // The marking reads the G-buffer just drawn.
        {
            let mut pass = self.fence.begin_compute_pass(
                encoder,
                &wgpu::ComputePassDescriptor {
                    label: Some("clusters.pass"),
                    timestamp_writes: timer.compute_writes(span, true, true),
                },
            );
            pass.set_bind_group(0, bind_group, &[]);
            pass.set_pipeline(&self.mark);
            pass.dispatch_workgroups(self.width.div_ceil(8), self.height.div_ceil(8), 1);
            let (x, y) = crate::gpu::pipelines::dispatch_2d(u64::from(self.data.counts[2]), 65535);
            pass.set_pipeline(&self.compact);
            pass.dispatch_workgroups(x, y, 1);
            if self.data.counts[1] > 0 {
                pass.set_pipeline(&self.assign);
                pass.dispatch_workgroups(self.data.counts[1].div_ceil(64), 1, self.data.grid[2]);
            }
            let (x, y) = crate::gpu::pipelines::dispatch_2d(u64::from(self.data.counts[0]), 65535);
            pass.set_pipeline(&self.stats);
            pass.dispatch_workgroups(x, y, 1);
        }
        encoder.copy_buffer_to_buffer(&self.control, 0, &self.readback, 0, 16);
    }

    /// The counters of the last recorded frame (after its submission).
    pub fn read_stats(&self, ctx: &GpuContext) -> Result<ClusterStats, RenderError> {
        let d = &self.data;
        let mut stats = ClusterStats {
            tiles: [d.grid[0], d.grid[1]],
            tile: d.grid[3],
            slices: d.grid[2],
            clusters: d.counts[2],
            capacity: d.counts[0],
            lights_in_view: d.counts[1],
            pool_bytes: self.masks.size(),
            ..Default::default()
        };
        if !self.enabled {
            return Ok(stats);
        }
        let bytes = crate::gpu::readback::map_read(ctx, &self.readback, 0..16)?;
        let c: &[u32] = bytemuck::cast_slice(&bytes);
        stats.occupied = c[0];
        stats.overflowed = c[1];
        let with_slot = c[0].min(d.counts[0]);
        stats.mean_lights = if with_slot > 0 {
            c[2] as f64 / with_slot as f64
        } else {
            0.0
        };
        stats.max_lights = c[3];
        Ok(stats)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slot_words_cover_every_light() {
        assert_eq!(slot_words(0), (1, 1));
        assert_eq!(slot_words(32), (1, 1));
        assert_eq!(slot_words(33), (1, 2));
        assert_eq!(slot_words(1024), (1, 32));
        assert_eq!(slot_words(1025), (2, 33));
        assert_eq!(slot_words(16384), (16, 512));
    }

    #[test]
    fn the_small_tile_only_where_every_cluster_has_a_slot() {
        let auto = ClusterOptions::default();
        let pool = DEFAULT_POOL_BYTES;
        // 640 x 360, 24 slices: 40 x 23 x 24 = 22,080 clusters; at 16,384 lights a slot is
        // 528 words, 46.6 MB in all.
        assert_eq!(auto.tile_for((640, 360), 1, 16384, pool), SMALL_TILE);
        // 1280 x 720: 86,400 clusters, 182 MB at 16,384 lights; 11.4 MB at 1,024.
        assert_eq!(auto.tile_for((1280, 720), 1, 16384, pool), DEFAULT_TILE);
        assert_eq!(auto.tile_for((1280, 720), 1, 1024, pool), SMALL_TILE);
        // Exactly full fits; a byte less does not.
        let need = 22_080 * 528 * 4;
        assert_eq!(auto.tile_for((640, 360), 1, 16384, need), SMALL_TILE);
        assert_eq!(auto.tile_for((640, 360), 1, 16384, need - 1), DEFAULT_TILE);
        // Two eyes: each half its own columns (2 x 20 x 23 x 24).
        assert_eq!(
            auto.tile_for((640, 360), 2, 16384, 22_080 * 528 * 4),
            SMALL_TILE
        );
        // A tile set is kept whatever the pool.
        assert_eq!(auto.with_tile(8).tile_for((1280, 720), 1, 16384, 16), 8);
    }
}

impl ClusterOptions {
    /// Sets [`ClusterOptions::tile`] to `tile` pixels.
    #[must_use]
    pub fn with_tile(mut self, tile: u32) -> Self {
        self.tile = Some(tile);
        self
    }
}

with_setters!(ClusterOptions {
    with_slices: slices: u32,
    with_pool_bytes: pool_bytes: Option<u64>,
});

/// Clustered light assignment's WGSL (mark, compact, assign, statistics).
pub fn shader() -> String {
    crate::gpu::shaders::compose(&[crate::gpu::shaders::COMMON, include_str!("clusters.wgsl")])
}

#[cfg(test)]
mod shader_tests {
    /// What this module composes is WGSL a WebGPU device accepts.
    #[test]
    fn shader_validates_for_webgpu() {
        crate::gpu::shaders::validate_for_webgpu(
            "clusters",
            &super::shader(),
            wgpu::Features::empty(),
        )
        .unwrap_or_else(|e| panic!("{e}"));
    }
}
