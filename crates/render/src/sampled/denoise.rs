//! The denoiser of sampled shadow rays (`RayOptions::denoise`, `--denoise`): one pass for
//! every light, whatever their number.
//!
//! With `--light-samples K` each pixel traces K of its lights, picked by importance, and the
//! image is noise. Most of that noise is visibility: the unshadowed light is cheap to sum
//! exactly over every light of the pixel's cluster, only the rays are few. So the lighting
//! pass writes, per pixel, the exact unshadowed direct light `U` and the ratio `r` of its
//! sampled estimate with shadows to the same estimate without (Heitz et al., "Combining
//! Analytic Direct Illumination and Stochastic Shadows", 2018; with K samples of weight
//! `wsum / w` whose luminance is `wsum`, `r` is the mean of the K rays' visibility). Only `r`
//! is filtered, so texture and lighting detail stay sharp:
//!
//! 0. **stratified samples**: where frames are denoised the lighting pass draws each sample
//!    after its light loop, inverting the loop's running sum of light weights at a point of
//!    a low-discrepancy sequence started apart per pixel (`lights.wgsl`, `sample_point`): a
//!    pixel's samples over frames cover its lights' distribution evenly instead of
//!    independently, so their mean over n frames converges about as 1/n rather than 1/√n,
//!    while each frame's sample alone is still drawn in proportion to the weights
//!    (unbiased). A sized light's point is spread over frames the same way, and lights
//!    listed near their neighbours in space (the seeded layouts above 64 lights are) spread
//!    a pixel's samples over space. Checkpoints of the running sum bound what the draw
//!    weighs again. A plain frame (no denoiser) keeps one-pass reservoir sampling.
//! 1. **temporal**: each pixel's surface point is projected into the previous frame (where
//!    it was, if its instance moved: motion.rs); where the point was seen there
//!    (within two pixel footprints, its surface facing within 26°) its history — mean and
//!    second moment of `r`, frame count up to [`MAX_HISTORY`] — is blended with this
//!    frame's `r`, else it starts anew (disocclusion). The rays' random numbers change every
//!    frame.
//! 2. **spatial**: [`ATROUS_STEPS`] passes of a five-tap à-trous wavelet (steps 1, 2, 4, 8
//!    pixels) whose weights stop at edges of geometry (normal, distance to the pixel's plane)
//!    and of the ratio itself (a tolerance of [`RATIO_SIGMAS`] standard deviations of the
//!    samples plus a half, over the frames of history to the ¾, so that it narrows about as
//!    the stratified mean converges), in the spirit of SVGF. Pixels with [`SETTLED_FRAMES`]
//!    or more frames of history skip the passes of step 4 and 8: their own mean is better
//!    than the wide passes' blur.
//! 3. **composite**: the lighting pass's `fs_composite` shades `ambient + emission + U · r̄`
//!    and tone-maps it into the frame.
//!
//! These choices were measured: docs/techniques.md, "The denoiser's stratified samples" and
//! "The denoiser's filter".
//!
//! Where every light is traced (`light_samples` 0) the only noise is the sized lights' area
//! samples, new each frame: there the denoiser only accumulates (no spatial pass), and with
//! a still camera the per-channel ratio times the exact `U` is the running mean of the
//! traced light itself, which converges to the exact soft shadow without bias (until
//! [`MAX_HISTORY`] frames; then a moving average of that many).
//!
//! What is biased: `U · r̄` is exact where every light of a pixel is seen alike (all lit,
//! all shadowed) and for one light; where lights of different colours or strengths are
//! shadowed differently the ratio mixes them (the colour of the unshadowed sum is kept); the
//! filters blur the ratio across a few pixels where the edge stops do not hold; history lags
//! a change of casters until it is replaced.
//!
//! **When lights change** the unshadowed light is exact at once, and the history is
//! corrected in the same frame: where at most [`MAX_LIGHT_FIXES`] records went or came since
//! the last frame ([`light_fixes`], slot by slot), they follow the frame's lights in the
//! lights buffer, the lighting pass traces each once at every pixel (a sized light on a
//! 4 × 4 grid; over shadow maps it reads the slot's map this frame, a sized light's
//! percentage-closer fraction), and the temporal pass adds what the lights that came add to the history's
//! means and takes away what those that went took (exact in expectation, whatever
//! distribution drew the history's samples). The history's frame count is cut to its share
//! of samples of the lights that stay, and that frame draws the lost share of a full
//! history's [`MAX_HISTORY`] frames in samples again (K times 1 + that, at most 16; its
//! estimate counts as that many frames: lighting.wgsl `catch_up_samples`), so the lights
//! that stay are not left with fewer samples than a history of them alone. The frame of a
//! change pays for these rays; a light that changes every frame pays every frame.
//!
//! More records at once (a new scene's lights) fall back: in the frame of the change each
//! pixel's history counts as many frames as the share of its unshadowed light that this
//! frame's exact unshadowed light keeps, to the fourth power, and a history cut below one
//! frame is dropped (a pixel the change did not reach keeps its history whole). How these
//! rules measured, and what was tried before them: docs/techniques.md, "The denoiser when
//! lights change".
//!
//! **When casters move** over surfaces that do not, their old shadows would stay in the
//! ratio's history. The renderer hands the denoiser a sphere per moved caster (per run of
//! [`BENT_CHUNK`] vertices of a mesh bent on the CPU, per joint of one bent on the GPU)
//! around where it was and is; while casters moved, the lighting pass tests the segment of
//! every light it visits for a pixel against them (`moved_caster_between`), and the share of
//! the pixel's unshadowed light whose segment passes one cuts its history by
//! [`SHADOW_MOVED_POWER`] (a point that moved itself keeps [`MOVING_HISTORY`]); with reuse
//! the frame draws the lost frames again there, beside the reservoirs (lighting.wgsl
//! `moved_catch_up_samples`). What this does not do: tell a changed visibility from an
//! unchanged one (temporal gradients, A-SVGF), so the samples go wherever the conservative
//! spheres reach.

use crate::error::RenderError;
use crate::frame::gbuffer::GBuffer;
use crate::gpu::bindings::{Binding, Part};
use crate::gpu::context::GpuContext;
use crate::gpu::types::LightData;

pub use crate::sampled::options::MAX_HISTORY;

/// Frames of history at most for a point whose instance moved since the last frame (its
/// history found where it was: motion.rs): the light on a moving surface changes, and
/// a long history lags it. Chosen by measurement on a moving box (4 frames erred less than
/// 1, 2, 8 or the whole history); docs/techniques.md, "Histories under motion".
pub const MOVING_HISTORY: u32 = 4;

/// Casters moved since the last frame that the lighting pass tests shadow rays against (each
/// one sphere around where it was and where it is); more are merged into one sphere around
/// the rest. A pixel whose sampled light's segment passes one keeps at most
/// [`MOVING_HISTORY`] frames of history: its shadow may have moved under it
/// (`denoise_lighting.wgsl`, `moved_caster_between`).
pub const MAX_MOVED_CASTERS: usize = 64;

/// The denoiser's WGSL: its passes and what `last_frame_position` needs.
fn shader_source() -> String {
    format!(
        "const MOVING_HISTORY: f32 = {:?}f;\nconst SHADOW_MOVED_POWER: f32 = {:?}f;\n{}{}",
        MOVING_HISTORY as f32,
        SHADOW_MOVED_POWER,
        include_str!("denoise.wgsl"),
        crate::sampled::motion::wgsl()
    )
}

/// Most light records a frame corrects the history for (a light changed in place counts
/// twice: its old record goes, its new one comes); a change of more lights at once falls
/// back to cutting each pixel's history by the change of its unshadowed light (see the
/// module's notes).
pub const MAX_LIGHT_FIXES: usize = 8;

/// The light records that went and came between the lights of the last denoised frame
/// (`old`) and this frame's (`new`), compared slot by slot: a slot whose record changed gives
/// both, a slot past the shorter list one. Each record carries its slot in its unused
/// `attenuation.w` (as f32: shadow maps hold this frame's lights by slot, and the lighting
/// pass reads a changed light's visibility through its slot's map). `None` when they are more
/// than [`MAX_LIGHT_FIXES`] (the lighting pass corrects the history for each: see the
/// module's notes).
pub fn light_fixes(
    old: &[LightData],
    new: &[LightData],
) -> Option<(Vec<LightData>, Vec<LightData>)> {
    let mut gone = Vec::new();
    let mut came = Vec::new();
    for i in 0..old.len().max(new.len()) {
        let (a, b) = (old.get(i), new.get(i));
        if a.map(bytemuck::bytes_of) == b.map(bytemuck::bytes_of) {
            continue;
        }
        let slotted = |l: &LightData| LightData {
            attenuation: [
                l.attenuation[0],
                l.attenuation[1],
                l.attenuation[2],
                i as f32,
            ],
            ..*l
        };
        gone.extend(a.map(slotted));
        came.extend(b.map(slotted));
        if gone.len() + came.len() > MAX_LIGHT_FIXES {
            return None;
        }
    }
    Some((gone, came))
}

/// À-trous passes (steps 1, 2, 4, 8 pixels: a 31-pixel footprint). Of five taps each, the
/// pixel and its four neighbours along the axes (the 3-tap B-spline on the cross: the
/// diagonals come from the passes' composition). Chosen by measurement: the cross filters as
/// well as 3 × 3 taps at less cost, and fewer or more passes left more error (more blur than
/// noise removed); docs/techniques.md, "The denoiser's filter".
pub const ATROUS_STEPS: u32 = 4;

const _: () = assert!(
    ATROUS_STEPS.is_multiple_of(2),
    "the last à-trous pass must write DenoiseBuffers::ratio"
);

/// Ratio tolerance of the à-trous weights, in standard deviations of the temporal variance,
/// over frames^¾ of history ([`SETTLED_FRAMES`]). The ratio's weight is a Gaussian of the
/// difference over 1.2 tolerances, `exp(−(Δr / 1.2 tol)²)`, rather than `exp(−|Δr| / tol)`:
/// differences within it, mostly noise, average almost fully, those past it, mostly
/// shadows' edges, hardly. The tolerance, its exponent and the Gaussian's width were chosen
/// by sweeps of the still and moving sequences' error; docs/techniques.md, "The denoiser's
/// filter".
const RATIO_SIGMAS: f32 = 1.5;

/// Frames of history from which a pixel skips the à-trous passes of step
/// [`SETTLED_STEP`] and wider (its own mean, over 4 or more stratified frames, is better
/// than their blur; the two narrow passes still filter it), with the ratio's tolerance over
/// frames^¾ instead of frames. Together the two lower the still frames' error, where either
/// alone does little (measured: docs/techniques.md, "The denoiser's filter"). A skipped pass
/// costs a copy and reads no G-buffer.
const SETTLED_FRAMES: u32 = 4;

/// The narrowest à-trous step (pixels) that [`SETTLED_FRAMES`] skips.
const SETTLED_STEP: u32 = 4;

/// `DenoiseParams` in denoise.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct DenoiseParams {
    prev_view_proj: [[f32; 4]; 4],
    size: [u32; 4],
    pixel: [f32; 4],
    camera: [f32; 4],
}

/// The lighting pass's bindings of the denoiser (declared in `denoise_lighting.wgsl`'s order).
const LIGHTING_BINDINGS: &[Binding] = &[
    Binding::storage_rw("denoise_px", "array<vec4<f32>>"),
    Binding::storage_rw("denoise_ratio", "array<vec4<f32>>"),
];

/// The fragment entry point that shades the filtered ratio into the frame, drawn by the
/// renderer after the denoiser's passes.
pub const COMPOSITE: &str = "fs_composite";

/// The denoiser's part of the lighting pass: with `buffers`, `DENOISE` and what writes them
/// (and [`COMPOSITE`]); without, the same functions doing nothing (never called: `DENOISE`
/// is false). Either way `CATCH_UP_FRAMES`, the most frames of samples a frame whose lights
/// changed draws again ([`MAX_HISTORY`]).
pub fn lighting_part(buffers: Option<&DenoiseBuffers>) -> Part<'_> {
    let mut part = lighting_part_declared(buffers.is_some());
    if let Some(b) = buffers {
        part.resources = vec![b.pixels.as_entire_binding(), b.ratio.as_entire_binding()];
    }
    part
}

/// [`lighting_part`]'s WGSL and bindings alone (no resources), with the denoiser `on` or
/// not: what a shader is composed of.
pub fn lighting_part_declared(on: bool) -> Part<'static> {
    let consts = format!(
        "const DENOISE: bool = {on};\nconst CATCH_UP_FRAMES: f32 = {:?}f;\n\
         const DENOISE_MOVED_SLOTS: u32 = {}u;\nconst SHADOW_MOVED_POWER: f32 = {:?}f;\n",
        MAX_HISTORY as f32,
        MAX_MOVED_CASTERS + 1,
        SHADOW_MOVED_POWER
    );
    if on {
        Part {
            wgsl: format!("{consts}{}", include_str!("denoise_lighting.wgsl")),
            bindings: LIGHTING_BINDINGS,
            resources: Vec::new(),
            follow: &[],
            own: &[COMPOSITE],
        }
    } else {
        Part::wgsl(format!(
            "{consts}fn denoise_store(px: vec2<i32>, a: vec4<f32>, s: vec3<f32>, \
                 u: vec3<f32>, r: vec3<f32>, f: f32) {{}}\n\
                 fn denoise_set_shadowed(px: vec2<i32>, s: vec3<f32>) {{}}\n\
                 fn denoise_store_fix(px: vec2<i32>, s: vec3<f32>, u: vec3<f32>, g: f32) {{}}\n\
                 fn moved_caster_between(i: u32, s: Surface) -> bool {{ return false; }}\n\
                 fn moved_casters() -> u32 {{ return 0u; }}\n\
                 fn denoise_note_shadow_moved(px: vec2<i32>, share: f32) {{}}\n"
        ))
    }
}

/// The buffers the lighting pass writes and its composite reads.
pub struct DenoiseBuffers {
    /// Per pixel two `vec4<f32>`: `[U.rgb, r]`, `[ambient + emission, 1 = geometry]`.
    pub pixels: wgpu::Buffer,
    /// Per pixel `[r̄, variance, frames, 0]`: the filtered ratio the composite reads.
    pub ratio: wgpu::Buffer,
}

/// The denoiser's buffers and passes for one frame size.
pub struct Denoiser {
    /// What the lighting pass reads and writes.
    pub buffers: DenoiseBuffers,
    width: u32,
    height: u32,
    /// One parameter block per pass: the temporal one, then one per à-trous step.
    params: Vec<wgpu::Buffer>,
    temporal: wgpu::ComputePipeline,
    atrous: wgpu::ComputePipeline,
    /// Temporal bind groups by the history buffer read (0 or 1; the two history buffers, read
    /// from one and written to the other, alternating per frame, and the à-trous ping-pong
    /// partner of `buffers.ratio` live in the bind groups).
    temporal_groups: [wgpu::BindGroup; 2],
    /// À-trous bind groups in pass order.
    atrous_groups: Vec<wgpu::BindGroup>,
    /// Whether the à-trous passes run (sampled lights); without, frames only accumulate.
    spatial: bool,
    /// Which history buffer this frame reads.
    parity: usize,
    /// Camera world → clip of the last frame denoised (`None`: no history yet).
    prev_view_proj: Option<glam::Mat4>,
    /// The light records of the last frame denoised, which a change of lights is compared
    /// with ([`light_fixes`]).
    seen_lights: Vec<LightData>,
    /// What [`Denoiser::follow_lights`] found for the next frame; [`Denoiser::record`] takes
    /// it (a frame prepared but never recorded keeps it for the next).
    change: Option<LightChange>,
    /// Casters moved since the last frame: a sphere around each one's old and new bounds.
    moved: Vec<(glam::Vec3, f32)>,
    /// Whether the ratio buffer's tail holds moved casters (to be cleared once none move).
    moved_written: bool,
}

/// A change of lights the next denoised frame follows.
struct LightChange {
    /// This frame's light records, the last seen once the frame is recorded.
    lights: Vec<LightData>,
    /// Where the records that went and came begin in the lights buffer, and how many went
    /// (low 16 bits) and came (high 16 bits) (`FrameUniforms::modes.zw`): the lighting pass
    /// writes each pixel's correction of the history for them, which the temporal pass
    /// adds. `None`: more changed than are corrected for, and the temporal pass cuts each
    /// pixel's frame count by the change of its unshadowed light.
    fix: Option<[u32; 2]>,
}

/// Bytes at the end of the ratio buffer for the moved casters: a count, then
/// [`MAX_MOVED_CASTERS`] spheres (`denoise_lighting.wgsl`, `DENOISE_MOVED_SLOTS`).
fn moved_tail_bytes() -> u64 {
    (MAX_MOVED_CASTERS as u64 + 1) * 16
}

/// How a still point's history is cut where a light traced there passes a caster that moved
/// since the last frame ([`MAX_MOVED_CASTERS`]): it counts as many frames as the share of
/// the point's unshadowed light the other lights carry, to this power.
pub const SHADOW_MOVED_POWER: f32 = 4.0;

/// Vertices per sphere of a bent mesh (`Denoiser::note_bent`).
pub const BENT_CHUNK: usize = 32;

/// `spheres` brought down to at most `max`: ordered along the axis they spread most on and
/// enclosed in runs of neighbours (each run one sphere), so that close ones merge.
fn merged(mut spheres: Vec<(glam::Vec3, f32)>, max: usize) -> Vec<(glam::Vec3, f32)> {
    if spheres.len() <= max {
        return spheres;
    }
    let (lo, hi) = spheres.iter().fold(
        (glam::Vec3::splat(f32::MAX), glam::Vec3::splat(f32::MIN)),
        |(lo, hi), (c, _)| (lo.min(*c), hi.max(*c)),
    );
    let spread = hi - lo;
    let axis = if spread.x >= spread.y && spread.x >= spread.z {
        0
    } else if spread.y >= spread.z {
        1
    } else {
        2
    };
    spheres.sort_by(|a, b| a.0[axis].total_cmp(&b.0[axis]));
    let run = spheres.len().div_ceil(max);
    spheres
        .chunks(run)
        .map(|c| {
            c.iter()
                .copied()
                .reduce(enclosing)
                .expect("a run is not empty")
        })
        .collect()
}

/// The smallest sphere around two spheres (centre, radius).
fn enclosing(a: (glam::Vec3, f32), b: (glam::Vec3, f32)) -> (glam::Vec3, f32) {
    let d = a.0.distance(b.0);
    if d + b.1 <= a.1 {
        return a;
    }
    if d + a.1 <= b.1 {
        return b;
    }
    let r = 0.5 * (d + a.1 + b.1);
    let c = a.0 + (b.0 - a.0) * ((r - a.1) / d.max(1e-30));
    (c, r)
}

fn storage(ctx: &GpuContext, label: &str, bytes: u64) -> wgpu::Buffer {
    ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: bytes.max(16),
        usage: wgpu::BufferUsages::STORAGE,
        mapped_at_creation: false,
    })
}

impl Denoiser {
    /// Buffers and pipelines for a `w` × `h` frame whose G-buffer is `gbuffer`, filtering in
    /// space too where `spatial` (sampled lights; else frames only accumulate), following
    /// moving instances' surfaces by `motion` (motion.rs); a frame
    /// whose per-pixel buffers (64 bytes a pixel) pass the device's storage-binding limit is
    /// [`RenderError::TooLarge`].
    pub fn new(
        ctx: &GpuContext,
        gbuffer: &GBuffer,
        w: u32,
        h: u32,
        spatial: bool,
        lights: Vec<LightData>,
        motion: &crate::sampled::motion::InstanceMotion,
    ) -> Result<Self, RenderError> {
        let device = &ctx.device;
        let pixels = u64::from(w) * u64::from(h);
        let limits = ctx.limits();
        let limit = limits
            .max_storage_buffer_binding_size
            .min(limits.max_buffer_size);
        if pixels * 64 + moved_tail_bytes() > limit {
            return Err(RenderError::TooLarge {
                what: format!("the denoiser's per-pixel buffers of a {w}x{h} frame"),
                needed: pixels * 64,
                limit,
                unit: "bytes",
                limit_name: "max_storage_buffer_binding_size",
            });
        }
        let buffers = DenoiseBuffers {
            pixels: storage(ctx, "denoise.pixels", pixels * 64),
            // Per pixel, then the casters moved since the last frame (`moved_tail_bytes`).
            ratio: ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("denoise.ratio"),
                size: pixels * 32 + moved_tail_bytes(),
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
        };
        let history = [
            storage(ctx, "denoise.history0", pixels * 64),
            storage(ctx, "denoise.history1", pixels * 64),
        ];
        let scratch = storage(ctx, "denoise.scratch", pixels * 32);
        let params: Vec<wgpu::Buffer> = (0..=ATROUS_STEPS)
            .map(|_| {
                device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("denoise.params"),
                    size: std::mem::size_of::<DenoiseParams>() as u64,
                    usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                })
            })
            .collect();
        let module = crate::gpu::shaders::module(device, "denoise.shader", &shader_source());
        let temporal = crate::gpu::pipelines::compute_pipeline_with(
            device,
            "denoise.temporal",
            None,
            &module,
            "temporal",
            &[],
        );
        let atrous = crate::gpu::pipelines::compute_pipeline_with(
            device,
            "denoise.atrous",
            None,
            &module,
            "atrous",
            &[],
        );
        let pv = gbuffer.position.create_view(&Default::default());
        let iv = motion.instance_view(gbuffer);
        let nv = gbuffer.normal.create_view(&Default::default());
        let texture = |binding, view| wgpu::BindGroupEntry {
            binding,
            resource: wgpu::BindingResource::TextureView(view),
        };
        let whole = crate::gpu::pipelines::whole_entry;
        let temporal_layout = temporal.get_bind_group_layout(0);
        let temporal_groups = [0usize, 1].map(|read| {
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("denoise.temporal"),
                layout: &temporal_layout,
                entries: &[
                    whole(0, &params[0]),
                    texture(1, &pv),
                    texture(2, &nv),
                    whole(3, &buffers.pixels),
                    whole(4, &history[read]),
                    whole(5, &history[1 - read]),
                    whole(6, &buffers.ratio),
                    texture(9, &iv),
                    whole(10, &motion.back),
                ],
            })
        });
        // The temporal pass writes `buffers.ratio`; the à-trous passes alternate so that the
        // last one writes it again (ATROUS_STEPS is even: ratio → scratch → ratio → …).
        let atrous_layout = atrous.get_bind_group_layout(0);
        let atrous_groups = (0..ATROUS_STEPS as usize)
            .map(|k| {
                let (from, to) = if k % 2 == 0 {
                    (&buffers.ratio, &scratch)
                } else {
                    (&scratch, &buffers.ratio)
                };
                device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("denoise.atrous"),
                    layout: &atrous_layout,
                    entries: &[
                        whole(0, &params[k + 1]),
                        texture(1, &pv),
                        texture(2, &nv),
                        whole(7, from),
                        whole(8, to),
                    ],
                })
            })
            .collect();
        Ok(Self {
            buffers,
            width: w,
            height: h,
            params,
            temporal,
            atrous,
            temporal_groups,
            atrous_groups,
            spatial,
            parity: 0,
            prev_view_proj: None,
            seen_lights: lights,
            change: None,
            moved: Vec::new(),
            moved_written: false,
        })
    }

    /// The lights changed: `buffer` is what the lights buffer will hold, this frame's
    /// `count` light records first (then a placeholder where there are none). Where few
    /// enough records went or came since the last frame denoised ([`light_fixes`]), they are
    /// appended to `buffer` for this frame's lighting pass, which writes the history's
    /// correction for them; else the temporal pass cuts each pixel's history by how much its
    /// unshadowed light changed. (The unshadowed light is exact at once; only the shadow
    /// ratio's history is old.)
    ///
    /// Where the visibility comes from shadow maps (`traced` false) the lighting pass reads a
    /// changed light's through its slot's map this frame: a light that went from a slot this
    /// frame no longer has (fewer lights) has no map to read, and the change falls back.
    pub fn follow_lights(&mut self, buffer: &mut Vec<LightData>, count: usize, traced: bool) {
        let records = buffer[..count].to_vec();
        let fixes = light_fixes(&self.seen_lights, &records)
            .filter(|(gone, _)| traced || gone.iter().all(|l| (l.attenuation[3] as usize) < count));
        let fix = fixes.map(|(gone, came)| {
            let first = buffer.len() as u32;
            let counts = gone.len() as u32 | ((came.len() as u32) << 16);
            buffer.extend(gone);
            buffer.extend(came);
            [first, counts]
        });
        self.change = Some(LightChange {
            lights: records,
            fix,
        });
    }

    /// A shadow caster moved before the next frame, its world bounds from `old` to `new`
    /// (centre, radius).
    pub fn note_moved(&mut self, old: (glam::Vec3, f32), new: (glam::Vec3, f32)) {
        self.moved.push(enclosing(old, new));
    }

    /// A shadow caster's mesh was bent before the next frame, its vertices from `old` to
    /// `new` (in the same order; `world` takes them to the world): one sphere per run of
    /// [`BENT_CHUNK`] vertices around where they were and are, far tighter than the whole
    /// mesh's bounds (a walking figure's limbs, not the figure).
    pub fn note_bent(&mut self, old: &[glam::Vec3], new: &[glam::Vec3], world: glam::Mat4) {
        for (a, b) in old.chunks(BENT_CHUNK).zip(new.chunks(BENT_CHUNK)) {
            let points = a.iter().chain(b).map(|&p| world.transform_point3(p));
            let (lo, hi) = points.clone().fold(
                (glam::Vec3::splat(f32::MAX), glam::Vec3::splat(f32::MIN)),
                |(lo, hi), p| (lo.min(p), hi.max(p)),
            );
            let c = 0.5 * (lo + hi);
            let r = points.map(|p| p.distance(c)).fold(0.0f32, f32::max);
            if a != b {
                self.moved.push((c, r));
            }
        }
    }

    /// Before a frame's passes: the casters moved since the last frame go to the end of the
    /// ratio buffer (a count, then the spheres; past [`MAX_MOVED_CASTERS`] the last sphere
    /// encloses the rest), for the lighting pass's test; nothing is written when none moved
    /// this frame or the last.
    pub fn upload_moved(&mut self, queue: &wgpu::Queue) {
        if self.moved.is_empty() && !self.moved_written {
            return;
        }
        let spheres = merged(std::mem::take(&mut self.moved), MAX_MOVED_CASTERS);
        let mut data = vec![[spheres.len() as f32, 0.0, 0.0, 0.0]];
        data.extend(spheres.iter().map(|(c, r)| [c.x, c.y, c.z, *r]));
        let at = self.buffers.ratio.size() - moved_tail_bytes();
        queue.write_buffer(&self.buffers.ratio, at, bytemuck::cast_slice(&data));
        self.moved_written = !spheres.is_empty();
    }

    /// `FrameUniforms::modes.zw` for the next frame: where the changed lights' records
    /// begin in the lights buffer and how many went and came (0, 0: none to correct for).
    pub fn light_fix(&self) -> [u32; 2] {
        self.change.as_ref().and_then(|c| c.fix).unwrap_or([0, 0])
    }

    /// Records the temporal and à-trous passes of a frame seen through `view_proj` from
    /// `eye` with a vertical field of view of `fov_y_deg`, after the lighting pass wrote the
    /// pixels; they begin `span` (the composite ends it).
    pub fn record(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        (view_proj, eye, fov_y_deg): (glam::Mat4, glam::Vec3, f32),
        timer: &crate::gpu::timing::GpuTimer,
        span: Option<crate::gpu::timing::Span>,
    ) {
        let pixel = 2.0 * (0.5 * fov_y_deg).to_radians().tan() / self.height as f32;
        let fresh = self.prev_view_proj.is_none();
        let change = self.change.take();
        let fixing = change.as_ref().is_some_and(|c| c.fix.is_some());
        let relit = change.as_ref().is_some_and(|c| c.fix.is_none());
        if let Some(c) = change {
            self.seen_lights = c.lights;
        }
        let prev = self.prev_view_proj.unwrap_or(view_proj);
        for (k, buffer) in self.params.iter().enumerate() {
            let step = if k == 0 { 0 } else { 1u32 << (k - 1) };
            let params = DenoiseParams {
                prev_view_proj: prev.to_cols_array_2d(),
                size: [self.width, self.height, step, MAX_HISTORY],
                pixel: [
                    pixel,
                    RATIO_SIGMAS,
                    match k {
                        0 => f32::from(u8::from(fresh)),
                        _ if step >= SETTLED_STEP => SETTLED_FRAMES as f32,
                        _ => 0.0,
                    },
                    if relit && k == 0 { 1.0 } else { 0.0 },
                ],
                camera: eye
                    .extend(if k == 0 && fixing { 1.0 } else { 0.0 })
                    .to_array(),
            };
            ctx.queue
                .write_buffer(buffer, 0, bytemuck::bytes_of(&params));
        }
        let groups = (self.width.div_ceil(8), self.height.div_ceil(8));
        // The filter reads the lit image and the G-buffer the frame drew.
        let mut pass = ctx.raster_fence().begin_compute_pass(
            encoder,
            &wgpu::ComputePassDescriptor {
                label: Some("denoise"),
                timestamp_writes: timer.compute_writes(span, true, false),
            },
        );
        pass.set_pipeline(&self.temporal);
        pass.set_bind_group(0, &self.temporal_groups[self.parity], &[]);
        pass.dispatch_workgroups(groups.0, groups.1, 1);
        if self.spatial {
            pass.set_pipeline(&self.atrous);
            for g in &self.atrous_groups {
                pass.set_bind_group(0, g, &[]);
                pass.dispatch_workgroups(groups.0, groups.1, 1);
            }
        }
        drop(pass);
        self.parity = 1 - self.parity;
        self.prev_view_proj = Some(view_proj);
    }
}

#[cfg(test)]
mod fix_tests {
    use super::{light_fixes, MAX_LIGHT_FIXES};
    use crate::gpu::types::LightData;

    fn light(x: f32) -> LightData {
        LightData {
            position: [x, 1.0, 2.0, 1.0],
            ..bytemuck::Zeroable::zeroed()
        }
    }

    /// Slot by slot: an unchanged list corrects nothing, a changed slot gives its old and
    /// new records, slots past the shorter list one of them, and too many changes give up.
    #[test]
    fn light_fixes_are_the_changed_slots() {
        let old: Vec<LightData> = (0..20).map(|i| light(i as f32)).collect();
        let (gone, came) = light_fixes(&old, &old).expect("nothing changed");
        assert!(gone.is_empty() && came.is_empty());
        let mut new = old.clone();
        new[7] = light(-7.0);
        let (gone, came) = light_fixes(&old, &new).expect("one changed");
        assert_eq!((gone.len(), came.len()), (1, 1));
        assert_eq!(gone[0].position[0], 7.0);
        assert_eq!(came[0].position[0], -7.0);
        // Each record carries its slot (the lighting pass reads its map through it).
        assert_eq!((gone[0].attenuation[3], came[0].attenuation[3]), (7.0, 7.0));
        let (gone, came) = light_fixes(&old, &old[..18]).expect("two went");
        assert_eq!((gone.len(), came.len()), (2, 0));
        assert_eq!(gone[1].position[0], 19.0);
        assert_eq!(gone[1].attenuation[3], 19.0);
        let (gone, came) = light_fixes(&old[..19], &old).expect("one came");
        assert_eq!((gone.len(), came.len()), (0, 1));
        let many: Vec<LightData> = (0..20).map(|i| light(100.0 + i as f32)).collect();
        assert!(light_fixes(&old, &many).is_none());
        let edge: Vec<LightData> = old
            .iter()
            .enumerate()
            .map(|(i, l)| {
                if i < MAX_LIGHT_FIXES / 2 {
                    light(-1.0 - i as f32)
                } else {
                    *l
                }
            })
            .collect();
        assert!(light_fixes(&old, &edge).is_some(), "exactly the most");
    }
}

#[cfg(test)]
mod shader_tests {
    /// The denoiser's WGSL is what a WebGPU device accepts.
    #[test]
    fn shader_validates_for_webgpu() {
        crate::gpu::shaders::validate_for_webgpu(
            "denoise",
            &super::shader_source(),
            wgpu::Features::empty(),
        )
        .unwrap_or_else(|e| panic!("{e}"));
    }
}
