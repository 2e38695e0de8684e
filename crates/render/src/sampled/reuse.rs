//! Temporal reuse of sampled shadow rays (`RayOptions::reuse`, `--reuse`): each pixel keeps,
//! per sample, a reservoir across frames (ReSTIR DI, Bitterli et al. 2020), so one ray per
//! pixel and frame gathers what many frames found.
//!
//! A sample is a light. Each frame the lighting pass draws a new one from the pixel's cluster
//! with probability proportional to its unshadowed term `f` (exactly: every light of the loop
//! is a candidate), and finds last frame's reservoir of the same surface point (the point
//! projected into the last frame; a pixel there within two pixel footprints of it whose
//! surface faced within 26° of the same way, else none: disocclusion). Both candidates are
//! weighed by the **target `f · V` at this pixel**, their visibility traced now (two rays),
//! with confidence weights `1 / (1 + M)` and `M / (1 + M)`
//! (`M`: the frames the old reservoir stands for, at most [`MAX_CONFIDENCE`]); one is kept,
//! with its unbiased contribution weight `W`, and the pixel's estimate of its shadowed direct
//! light is `f(y) V(y) W`. As `M` grows the kept light is drawn nearly in proportion to
//! `f · V`, where the new draw alone follows `f` and finds a shadowed light as often as the
//! shadow covers: the estimate's noise falls with the frames instead of staying that of one
//! ray.
//!
//! What is unbiased and what not: both targets are evaluated at this pixel with this frame's
//! lights and casters (a moved or changed light is weighed anew; a light past the count is
//! dropped; when the number of lights changes the history is dropped, since indices no longer
//! name the same lights). With a still camera and still casters the old reservoir's lights
//! are those the pixel sees now, the confidence weights sum to 1 over them, and the estimate
//! is unbiased (`tests/reuse.rs` checks that its mean over seeds is the exact image). Where
//! the point moved, or a caster uncovered a light the old reservoir could not hold, that
//! light is found only by the new draw, with weight `1 / (1 + M)`: the estimate darkens there
//! until the reservoir has drawn it (a few frames). A point on an instance that moved is
//! looked for where it was last frame (motion.rs), and its old reservoir stands for at
//! most [`MOVING_CONFIDENCE`] frames: what lit it there may not light it here. A sized
//! light's target uses one point of its shape per ray (the visibility of a fresh point each
//! frame): unbiased in the mean over points, but not a fixed target.
//!
//! **Spatial reuse** (`RayOptions::spatial`, `--spatial`): after the lighting pass, a second
//! pass (`fs_spatial`, lights.wgsl) resamples each pixel's reservoir, as temporal reuse
//! left it, together with those of up to [`SPATIAL_NEIGHBOURS`] pixels drawn from a disc of
//! [`SPATIAL_RADIUS`] pixels (pixels whose view depth is within 10 % and whose normals are
//! within 26°: the choice depends on geometry only). Each candidate light `y_i` is weighed by
//! `m_i · p̂(y_i) · W_i`, `p̂` being this pixel's target `f · V` (a ray from here to each
//! neighbour's light and point), and the light drawn is shaded with `W = Σ w / p̂(y)`. The
//! MIS weights `m_i`:
//! - **unbiased**: the generalized balance heuristic `c_i p̂_i(y_i) / Σ_o c_o p̂_o(y_i)` over
//!   every pixel resampled, each neighbour's target at each candidate traced from that
//!   neighbour (`n + n²` rays for `n` neighbours). They sum to one wherever any of the
//!   pixels could have drawn the light, so the estimate stays unbiased (`tests/reuse.rs`
//!   checks that the mean over seeds is the exact image).
//! - **biased**: `c_i / Σ c` (`n` rays). Where a neighbour cannot draw a light this pixel
//!   sees (the light is shadowed there), its weight is still counted: the image darkens near
//!   shadow edges.
//!
//! The confidences `c_i`: this pixel's reservoir counts the frames it stands for (`M`), a
//! neighbour's counts one. Counting the neighbours' `M` too (ReSTIR's usual weights) made a
//! still image worse as its reservoirs converged: a neighbour's light stands for that
//! neighbour's sum, and its ratio `p̂(y_i) / p̂_i(y_i)` at one light is a far noisier
//! estimate of this pixel's than this pixel's own frames. For the same reason the light
//! spatial reuse draws is shaded but not kept: the next frame's temporal reuse starts from
//! each pixel's own reservoir (fed back, the image grew noisier frame by frame as
//! neighbours' lights spread and repeated). The disc is small: in a wider one most
//! neighbours fail the depth test on a floor. The figures: docs/techniques.md, "Ray-traced
//! shadows: `--technique raytraced`" (its `--spatial` paragraph), and docs/decisions.md
//! ("Spatial reuse: neighbours count one, and the drawn light is not fed back").

use crate::error::RenderError;
use crate::gpu::bindings::{Binding, Part};
use crate::gpu::context::GpuContext;
use crate::sampled::options::SpatialReuse;

pub use crate::sampled::options::MAX_CONFIDENCE;

/// Frames a reservoir may stand for at a point whose instance moved since the last frame
/// (its reservoirs found where it was: motion.rs): one, so the old light weighs as
/// much as the new draw. A light that lit the point where it was may be shadowed or
/// turned away now, and one that lights it now may never have been drawn: with the full
/// confidence the moving surface darkens and stays noisy. Chosen by measurement on a moving
/// box (of caps of 1, 2, 4 and the usual 20, 1 erred least); docs/techniques.md, "Histories
/// under motion".
pub const MOVING_CONFIDENCE: u32 = 1;

/// Neighbours each pixel's spatial reuse draws (`RayOptions::spatial`; those failing the
/// depth and normal tests are left out).
pub const SPATIAL_NEIGHBOURS: u32 = 3;

/// Radius, in pixels, of the disc spatial reuse draws neighbours from.
pub const SPATIAL_RADIUS: f32 = 6.0;

/// `ReuseParams` of the lighting pass's reuse WGSL (`REUSE_WGSL`, in [`lighting_part`]).
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct ReuseParams {
    prev_view_proj: [[f32; 4]; 4],
    /// width, height, samples per pixel, most frames of confidence.
    size: [u32; 4],
    /// world size of a pixel at distance 1, 1 = no history this frame, the half read (0 or
    /// 1), unused.
    flags: [f32; 4],
    /// eye position (xyz).
    camera: [f32; 4],
}

/// The buffers the lighting pass binds.
pub struct ReuseBuffers {
    /// `ReuseParams`.
    pub params: wgpu::Buffer,
    /// Two halves, one read and one written per frame, each per pixel `1 + K` `vec4<u32>`:
    /// the surface point (float bits of xyz; w its unit normal as four signed bytes, the
    /// fourth 1, and 0 where the pixel kept no reservoirs), then
    /// per sample the light, `W` and `M` (float bits) and the point on a sized light's shape
    /// (two unorm16). With spatial reuse a third part of the same layout: the pixel's colour
    /// less its sampled direct light and the samples after temporal reuse, which the
    /// spatial pass resamples with its neighbours'.
    pub reservoirs: wgpu::Buffer,
    /// The G-buffer's instance per pixel (motion.rs `InstanceMotion::instance_view`).
    pub instance: wgpu::TextureView,
    /// Per instance, this frame's world → last frame's (`InstanceMotion::back`).
    pub motion_back: wgpu::Buffer,
}

/// Reservoirs of one frame size and sample count, and what the next frame reuses.
pub struct Reuse {
    /// What the lighting pass binds.
    pub buffers: ReuseBuffers,
    width: u32,
    height: u32,
    samples: u32,
    /// Spatial reuse after the lighting pass.
    spatial: SpatialReuse,
    /// The half the next frame reads.
    parity: u32,
    /// Camera world → clip and light count of the last frame (`None`: no history).
    prev: Option<(glam::Mat4, usize)>,
}

impl Reuse {
    /// Reservoirs for a `w` × `h` frame with `samples` (1..=16) lights per pixel; buffers past
    /// the device's storage-binding limit are [`RenderError::TooLarge`].
    /// With `spatial` a third part holds what the lighting pass leaves to spatial reuse
    /// (`SPATIAL_SCRATCH` below). Surfaces of moving instances are followed by `motion`
    /// through the instance `gbuffer` keeps (motion.rs).
    pub fn new(
        ctx: &GpuContext,
        w: u32,
        h: u32,
        samples: u32,
        spatial: SpatialReuse,
        (gbuffer, motion): (
            &crate::frame::gbuffer::GBuffer,
            &crate::sampled::motion::InstanceMotion,
        ),
    ) -> Result<Self, RenderError> {
        let parts = if spatial == SpatialReuse::Off { 2 } else { 3 };
        let bytes = parts * u64::from(w) * u64::from(h) * u64::from(samples + 1) * 16;
        let limits = ctx.limits();
        let limit = limits
            .max_storage_buffer_binding_size
            .min(limits.max_buffer_size);
        if bytes > limit {
            return Err(RenderError::TooLarge {
                what: format!(
                    "the reservoirs of a {w}x{h} frame with {samples} light samples per pixel"
                ),
                needed: bytes,
                limit,
                unit: "bytes",
                limit_name: "max_storage_buffer_binding_size",
            });
        }
        let device = &ctx.device;
        let buffers = ReuseBuffers {
            params: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("reuse.params"),
                size: std::mem::size_of::<ReuseParams>() as u64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            reservoirs: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("reuse.reservoirs"),
                size: bytes,
                usage: wgpu::BufferUsages::STORAGE,
                mapped_at_creation: false,
            }),
            instance: motion.instance_view(gbuffer),
            motion_back: motion.back.clone(),
        };
        Ok(Self {
            buffers,
            width: w,
            height: h,
            samples,
            spatial,
            parity: 0,
            prev: None,
        })
    }

    /// Writes the parameters of a frame seen through `view_proj` from `eye` with a vertical
    /// field of view of `fov_y_deg`, lit by `lights` lights, before its lighting pass; the
    /// next call reads what this frame writes.
    pub fn prepare(
        &mut self,
        ctx: &GpuContext,
        (view_proj, eye, fov_y_deg): (glam::Mat4, glam::Vec3, f32),
        lights: usize,
    ) {
        let pixel = 2.0 * (0.5 * fov_y_deg).to_radians().tan() / self.height as f32;
        let history = self.prev.filter(|&(_, n)| n == lights);
        let params = ReuseParams {
            prev_view_proj: history.map_or(view_proj, |(m, _)| m).to_cols_array_2d(),
            size: [self.width, self.height, self.samples, MAX_CONFIDENCE],
            flags: [
                pixel,
                if history.is_some() { 0.0 } else { 1.0 },
                self.parity as f32,
                0.0,
            ],
            camera: eye.extend(1.0).to_array(),
        };
        ctx.queue
            .write_buffer(&self.buffers.params, 0, bytemuck::bytes_of(&params));
        self.parity = 1 - self.parity;
        self.prev = Some((view_proj, lights));
    }
}

/// The lighting pass's bindings of reuse (`REUSE_WGSL` names them): the parameters, the
/// reservoirs (two halves, one read and one written per frame; per pixel 1 + K vec4: [surface
/// point (float bits), its normal as four signed bytes (0: none kept)], then per sample
/// [light, W and M (float bits), point on a sized light's shape (2 × unorm16)]), the instance
/// seen per pixel and per instance its motion since the last frame (motion.rs:
/// `last_frame_position`).
const LIGHTING_BINDINGS: &[Binding] = &[
    Binding::uniform("reuse", "ReuseParams"),
    Binding::storage_rw("reservoirs", "array<vec4<u32>>"),
    Binding::texture_u32("gbuf_instance"),
    Binding::storage("motion_back", "array<mat4x4<f32>>"),
];

/// The fragment entry point of spatial reuse, drawn right after the lighting pass.
const SPATIAL_PASS: &str = "fs_spatial";

/// Reuse's part of the lighting pass: with `reuse`, `REUSE`, the reservoirs' bindings and
/// functions, what finds a moving instance's point where it was (motion.rs) and, with spatial
/// reuse, its pass; without, the same functions doing nothing (never called: `REUSE` is
/// false). Either way the spatial constants (`SPATIAL`: 0 off, 1 biased, 2 unbiased).
pub fn lighting_part(reuse: Option<&Reuse>) -> Part<'_> {
    let mut part = lighting_part_declared(reuse.map(|r| r.spatial));
    if let Some(r) = reuse {
        part.resources = vec![
            r.buffers.params.as_entire_binding(),
            r.buffers.reservoirs.as_entire_binding(),
            wgpu::BindingResource::TextureView(&r.buffers.instance),
            r.buffers.motion_back.as_entire_binding(),
        ];
    }
    part
}

/// [`lighting_part`]'s WGSL and bindings alone (no resources): with reuse and its spatial
/// mode, or without (`None`): what a shader is composed of.
pub fn lighting_part_declared(reuse: Option<SpatialReuse>) -> Part<'static> {
    let spatial = reuse.unwrap_or(SpatialReuse::Off);
    let consts = format!(
        "const REUSE: bool = {};\nconst SPATIAL: u32 = {}u;\nconst SPATIAL_NEIGHBOURS: u32 = {}u;\n\
         const SPATIAL_RADIUS: f32 = {:?}f;\nconst SPATIAL_SLOTS: u32 = {}u;\n",
        reuse.is_some(),
        spatial.code(),
        SPATIAL_NEIGHBOURS,
        SPATIAL_RADIUS,
        SPATIAL_NEIGHBOURS + 1,
    );
    if reuse.is_none() {
        return Part::wgsl(format!("{consts}{NO_REUSE_WGSL}"));
    }
    Part {
        wgsl: format!(
            "{consts}const MOVING_CONFIDENCE: f32 = {:?}f;\n{REUSE_WGSL}{}",
            MOVING_CONFIDENCE as f32,
            crate::sampled::motion::wgsl()
        ),
        bindings: LIGHTING_BINDINGS,
        resources: Vec::new(),
        follow: if spatial == SpatialReuse::Off {
            &[]
        } else {
            &[SPATIAL_PASS]
        },
        own: &[],
    }
}

/// The lighting pass's side of temporal reuse: last frame's reservoirs of a
/// surface point, and this frame's written for the next.
const REUSE_WGSL: &str = "
struct ReuseParams {
    prev_view_proj: mat4x4<f32>,
    // width, height, samples per pixel, most frames of confidence.
    size: vec4<u32>,
    // world size of a pixel at distance 1, 1 = no history this frame, the half read.
    flags: vec4<f32>,
    camera: vec4<f32>,
}
fn reuse_record(half: u32, px: vec2<u32>) -> u32 {
    let stride = reuse.size.z + 1u;
    return (half * reuse.size.x * reuse.size.y + px.y * reuse.size.x + px.x) * stride;
}

// Where last frame kept the reservoirs of the surface point `p` with unit normal `n` seen at
// pixel `px` (a record index of the half read), or 0xffffffff: the nearest pixel to where
// `p` was seen (where it was, if its instance moved), if it saw a point within two pixel
// footprints of that whose surface faced the same way (`same_facing`).
fn reuse_history(px: vec2<i32>, p: vec3<f32>, n: vec3<f32>) -> u32 {
    if (reuse.flags.y != 0.0) {
        return 0xffffffffu;
    }
    let back = instance_back(vec2<u32>(px));
    let was = last_frame_position(vec2<u32>(px), back, p);
    reuse_moved = any(was != p);
    let clip = reuse.prev_view_proj * vec4<f32>(was, 1.0);
    if (clip.w <= 0.0) {
        return 0xffffffffu;
    }
    let ndc = clip.xy / clip.w;
    let q = floor(vec2<f32>((ndc.x * 0.5 + 0.5) * f32(reuse.size.x), (0.5 - ndc.y * 0.5) * f32(reuse.size.y)));
    if (q.x < 0.0 || q.y < 0.0 || q.x >= f32(reuse.size.x) || q.y >= f32(reuse.size.y)) {
        return 0xffffffffu;
    }
    let r = reuse_record(u32(reuse.flags.z), vec2<u32>(q));
    let kept = reservoirs[r];
    let footprint = distance(p, reuse.camera.xyz) * reuse.flags.x;
    if (kept.w == 0u || distance(bitcast<vec3<f32>>(kept.xyz), was) > 2.0 * footprint + 1e-6) {
        return 0xffffffffu;
    }
    if (!same_facing(unpack4x8snorm(kept.w).xyz, last_frame_normal(back, n))) {
        return 0xffffffffu;
    }
    return r;
}

// Whether the point `reuse_history` last looked for moved with its instance.
var<private> reuse_moved: bool;

// Most frames a reservoir stands for (fewer on a surface that moved: reuse.rs
// MOVING_CONFIDENCE).
fn reuse_cap() -> f32 {
    return select(f32(reuse.size.w), MOVING_CONFIDENCE, reuse_moved);
}

// Sample `j` of the record `r` (from reuse_history): light, W, M, point.
fn reuse_load(r: u32, j: u32) -> vec4<u32> {
    return reservoirs[r + 1u + j];
}

// This frame's record of pixel `px`: its surface point and unit normal (`kept` false: none
// kept, the next frame starts anew there).
fn reuse_store_point(px: vec2<i32>, p: vec3<f32>, n: vec3<f32>, kept: bool) {
    if (choosing) {
        return;
    }
    let r = reuse_record(1u - u32(reuse.flags.z), vec2<u32>(px));
    // The normal as four signed bytes, the fourth 1 (never 0: 0 marks none kept).
    let facing = select(0u, pack4x8snorm(vec4<f32>(n, 1.0)), kept);
    reservoirs[r] = vec4<u32>(bitcast<vec3<u32>>(p), facing);
}

// Sample `j` of pixel `px` for the next frame, and with spatial reuse for `fs_spatial` too
// (the third part, SPATIAL_SCRATCH, where neighbours read it this frame).
fn reuse_store(px: vec2<i32>, j: u32, light: u32, w: f32, m: f32, point: vec2<f32>) {
    if (choosing) {
        return;
    }
    let sample = vec4<u32>(light, bitcast<u32>(w), bitcast<u32>(m), pack2x16unorm(point));
    reservoirs[reuse_record(1u - u32(reuse.flags.z), vec2<u32>(px)) + 1u + j] = sample;
    if (SPATIAL != 0u) {
        reservoirs[reuse_record(SPATIAL_SCRATCH, vec2<u32>(px)) + 1u + j] = sample;
    }
}

// Spatial reuse (reuse.rs): the third part of `reservoirs` holds per pixel what the lighting
// pass leaves to `fs_spatial`: [the colour but its sampled direct light (linear, float
// bits), SPATIAL_* what it is], then the pixel's samples after temporal reuse.
const SPATIAL_SCRATCH: u32 = 2u;
// The colour is whole (no samples: every light of the pixel traced, or none sampled).
const SPATIAL_WHOLE: u32 = 0u;
// The colour lacks the sampled direct light: fs_spatial resamples and adds it.
const SPATIAL_SAMPLED: u32 = 1u;
// No geometry: the sky, as it is.
const SPATIAL_SKY: u32 = 2u;

fn spatial_store_rest(px: vec2<i32>, rest: vec3<f32>, what: u32) {
    if (choosing) {
        return;
    }
    let r = reuse_record(SPATIAL_SCRATCH, vec2<u32>(px));
    reservoirs[r] = vec4<u32>(bitcast<vec3<u32>>(rest), what);
}

fn spatial_rest(px: vec2<i32>) -> vec4<u32> {
    return reservoirs[reuse_record(SPATIAL_SCRATCH, vec2<u32>(px))];
}

// Sample `j` of pixel `px` after temporal reuse: light, W, M, point.
fn spatial_load(px: vec2<i32>, j: u32) -> vec4<u32> {
    return reservoirs[reuse_record(SPATIAL_SCRATCH, vec2<u32>(px)) + 1u + j];
}

";

/// The same functions where nothing is reused (never called: `REUSE` is false).
const NO_REUSE_WGSL: &str = "
fn reuse_history(px: vec2<i32>, p: vec3<f32>, n: vec3<f32>) -> u32 { return 0xffffffffu; }
fn reuse_load(r: u32, j: u32) -> vec4<u32> { return vec4<u32>(0u); }
fn reuse_cap() -> f32 { return 0.0; }
fn reuse_store_point(px: vec2<i32>, p: vec3<f32>, n: vec3<f32>, kept: bool) {}
fn reuse_store(px: vec2<i32>, j: u32, light: u32, w: f32, m: f32, point: vec2<f32>) {}
const SPATIAL_WHOLE: u32 = 0u;
const SPATIAL_SAMPLED: u32 = 1u;
const SPATIAL_SKY: u32 = 2u;
fn spatial_store_rest(px: vec2<i32>, rest: vec3<f32>, what: u32) {}
fn spatial_rest(px: vec2<i32>) -> vec4<u32> { return vec4<u32>(0u); }
fn spatial_load(px: vec2<i32>, j: u32) -> vec4<u32> { return vec4<u32>(0u); }
";
