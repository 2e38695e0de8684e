//! The flags of `manyshadows compare` and its long help: what to score (scenes, techniques,
//! shadow resolutions), how to render it (frame size, biases, atlas, virtual maps), who
//! traces the reference, and where the images and the JSON go.

use std::path::PathBuf;

use clap::Args;
use manyshadows::{ShadowBias, Technique};

use crate::args::{GpuArgs, LightSizeArgs};

/// Who traces the reference.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum ReferenceTracer {
    /// The CPU (obvhs BVH, watertight triangle test): the default truth.
    Cpu,
    /// The GPU, with ray queries (the technique that fills rays, every light of every pixel):
    /// the same rays from the same points, practical at 1080p × 1,024 lights.
    Gpu,
}

/// The options of `manyshadows compare`.
#[derive(Args, Debug, Clone)]
pub struct CompareArgs {
    /// Built-in scene name or a TOML scene file (as for `render`); several, comma-separated,
    /// are scored one after the other, each into its own sub-directory of --out-dir (e.g.
    /// `atrium,plane-spot,plane-point,plane-directional`).
    #[arg(long = "scene", default_value = "atrium", value_delimiter = ',')]
    pub(super) scenes: Vec<String>,
    /// The one scene this run scores (set from `scenes` for each run).
    #[arg(skip)]
    pub(super) scene: String,
    /// Techniques to score, comma-separated (default: every technique).
    #[arg(long, value_delimiter = ',', value_parser = crate::args::parse_technique)]
    pub(super) techniques: Vec<Technique>,
    /// Number of lights, placed by a seeded layout. Default: 8 for the atrium (a quick run),
    /// otherwise the scene's own lights.
    #[arg(long)]
    pub(super) lights: Option<usize>,
    /// Keep the scene's own lights and add this many of the seeded layout (as `render
    /// --add-lights`).
    #[arg(long, value_name = "N", conflicts_with = "lights")]
    pub(super) add_lights: Option<usize>,
    /// Seed of the light layout.
    #[arg(long, default_value_t = 1)]
    pub(super) seed: u64,
    /// Camera position and target, `PX,PY,PZ,TX,TY,TZ` (default: the scene's camera; the web
    /// page's score button scores the page's camera, which `window.manyshadows.camera()`
    /// gives in this form).
    #[arg(long, value_parser = crate::args::parse_camera, allow_hyphen_values = true,
          conflicts_with = "camera_path")]
    pub(super) camera: Option<[f32; 6]>,
    /// Light types the layout uses: all (mixed), spot, point or directional.
    #[arg(long, default_value = "all")]
    pub(super) light_types: String,
    #[command(flatten)]
    pub(super) light_sizes: LightSizeArgs,
    #[command(flatten)]
    pub(super) soft_maps: crate::args::SoftArgs,
    #[command(flatten)]
    pub(super) model: crate::args::ModelArgs,
    #[command(flatten)]
    pub(super) animation: crate::args::AnimationArgs,
    /// Reflection probes, seeded as `render --probes N` does (0: none); default the scene's
    /// own (the atrium's two). Their faces are lit like the frame and reflected into it, so
    /// they are part of the frames scored (and of a frame's cost).
    #[arg(long, value_name = "N")]
    pub(super) probes: Option<usize>,
    /// Point-light shadows: cube or dual-paraboloid (scored by the same reference).
    #[arg(long, default_value = "cube", value_parser = crate::args::parse_point_shadows)]
    pub(super) point_shadows: manyshadows::scene::light_space::PointShadows,
    /// Split every triangle into four this many times first (as for `render`).
    #[arg(long, default_value_t = 0)]
    pub(super) subdivide: u32,
    /// Mesh file for the dragon scene.
    #[arg(long)]
    pub(super) mesh: Option<PathBuf>,
    /// Shadow-map resolutions to score, comma-separated; every technique runs at each
    /// (default: the scene's own resolutions).
    #[arg(long, value_delimiter = ',')]
    pub(super) shadow_resolutions: Vec<u32>,
    /// Image width.
    #[arg(long, default_value_t = 960)]
    pub(super) width: u32,
    /// Image height.
    #[arg(long, default_value_t = 540)]
    pub(super) height: u32,
    /// Half-width of the edge band in pixels (Chebyshev distance to a reference edge).
    #[arg(long, default_value_t = 2)]
    pub(super) edge_band: u32,
    /// With --frames N: also score every frame's hard visibility mask, per technique, against
    /// the CPU reference traced for that frame (the scene as it stands then: the moving
    /// instance, the animation's pose): false shadow and false light outside the edge band.
    /// One CPU reference per frame. Not with --light-samples (sampled lights keep no hard mask).
    #[arg(long)]
    pub(super) misclassified: bool,
    /// Receiver bias towards the light, in shadow texels.
    #[arg(long, default_value_t = ShadowBias::default().constant, allow_negative_numbers = true)]
    pub(super) bias_constant: f32,
    /// Receiver bias towards the light per unit of tan(angle between normal and light), texels.
    #[arg(long, default_value_t = ShadowBias::default().slope, allow_negative_numbers = true)]
    pub(super) bias_slope: f32,
    /// Receiver offset along the surface normal, texels.
    #[arg(long, default_value_t = ShadowBias::default().normal_offset, allow_negative_numbers = true)]
    pub(super) bias_normal: f32,
    /// Alpha-tested casters in the shadow passes: on (holes in foliage, lattices and banners
    /// let light through, as in the reference) or off (they cast as solid cards, what a
    /// renderer that ignores alpha would draw; the reference keeps its holes, so this scores
    /// that mistake).
    #[arg(long, default_value = "on", value_parser = crate::args::parse_on_off, action = clap::ArgAction::Set)]
    pub(super) shadow_alpha: bool,
    /// What single-sided surfaces shadow, in every technique and in the reference alike: front
    /// (only where a light sees their front: outline shells and floors lit from below cast
    /// nothing) or both (every face casts). Double-sided and alpha-tested surfaces always cast
    /// from both sides.
    #[arg(long, default_value_t = manyshadows::SingleSidedShadows::default())]
    pub(super) single_sided_shadows: manyshadows::SingleSidedShadows,
    /// Largest shadow-atlas side in texels (clamped to the adapter's limit).
    #[arg(long, default_value_t = manyshadows::DEFAULT_MAX_ATLAS_SIZE)]
    pub(super) atlas_max: u32,
    /// Fail when the shadow maps don't fit the atlas, instead of shrinking them.
    #[arg(long)]
    pub(super) strict_atlas: bool,
    /// Options of one technique or another (irregular, virtual, shadow rays), as `render`
    /// takes them; the sampled rays' (--light-samples, --reuse, --spatial, --denoise) score a
    /// sequence only (--frames).
    #[command(flatten)]
    pub(super) per_technique: crate::technique_args::TechniqueArgs,
    /// Who traces the exact reference: cpu (default, the truth every technique is scored
    /// against) or gpu (ray queries; needs EXPERIMENTAL_RAY_QUERY, for frames and light counts
    /// the CPU would take too long for). It traces the soft reference too, with at most 256
    /// samples per (pixel, sized light).
    #[arg(long, value_enum, default_value_t = ReferenceTracer::Cpu)]
    pub(super) reference: ReferenceTracer,
    /// Samples of the soft reference per (pixel, sized light), rounded up to a square (256 =
    /// a 16x16 grid, at most 65,536); 0 = score hard shadows only.
    ///
    /// When the scene has a sized light that casts shadows (--light-size, --sun-size, the
    /// built-in scenes' own sizes), the CPU traces this many rays from each pixel to points
    /// spread over each sized light, and each technique's soft visibility is scored against
    /// the fraction they see. More samples, a closer reference: on the analytic penumbra
    /// test its mean error is 0.0048 at 256 samples and 0.0017 at 1,024, at 4 times the rays
    /// (docs/quality.md).
    ///
    /// Default: 256, or where that would trace more than one comparison's budget of 3 billion
    /// soft rays (about ten minutes on two cores; pixels x sized lights x samples), the
    /// largest square under it, at least 16, said in a note and in the table (a number given
    /// here is never changed: past the budget it is refused).
    #[arg(long, value_name = "N")]
    pub(super) soft_samples: Option<u32>,
    /// The soft-shadow filter: on (lights rendered with their sizes), off (every light
    /// rendered hard, size 0, while the references keep the sizes), or on,off (each technique
    /// both ways, the hard runs labelled -hard): what the filter buys.
    #[arg(long, default_value = "on", value_name = "on|off[,..]", value_delimiter = ',', value_parser = crate::args::parse_on_off)]
    pub(super) soft: Vec<bool>,
    /// Directory for the frame, the difference images and reference.msvis.
    #[arg(long, default_value = "compare")]
    pub(super) out_dir: PathBuf,
    /// Also write every number as JSON.
    #[arg(long)]
    pub(super) json: Option<PathBuf>,
    /// Also write one difference image per light and technique.
    #[arg(long)]
    pub(super) per_light_images: bool,
    /// Score even a technique whose frame is far beyond the rest (more than 2 G caster
    /// triangle-view pairs, e.g. every triangle sent to each of thousands of views): without
    /// it such a technique is skipped with its estimate when every technique is asked for,
    /// and refused when named.
    #[arg(long)]
    pub(super) insist: bool,
    /// Score a sequence of this many frames instead of one frame: each technique renders
    /// every frame (keeping what it keeps across frames: cached maps, reused lights, the
    /// denoiser's history), and each frame is scored against the exact image of that same
    /// frame (every cluster light traced). See "Sequences" in --help.
    #[arg(long, default_value_t = 1, value_name = "N")]
    pub(super) frames: u32,
    /// With --frames: degrees the camera turns about its target per frame.
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub(super) orbit: f32,
    /// With --frames: a fly path, one camera per line, `PX PY PZ TX TY TZ` (as `render
    /// --camera-path`).
    #[arg(long, value_name = "FILE", conflicts_with = "orbit")]
    pub(super) camera_path: Option<PathBuf>,
    /// With --frames: the instance that moves (default: the smallest shadow caster).
    #[arg(long, conflicts_with = "still")]
    pub(super) move_instance: Option<usize>,
    /// With --frames: move no caster.
    #[arg(long)]
    pub(super) still: bool,
    /// Say each part of a technique's frame as the GPU finishes it (G-buffer and light
    /// clusters, shadows, lighting), as `render --stages`; on by itself for a frame whose
    /// shadow work is estimated past 200 M (caster triangle, view) pairs.
    #[arg(long)]
    pub(super) stages: bool,
    #[command(flatten)]
    pub(super) gpu: GpuArgs,
}

/// `manyshadows compare --help`.
pub const LONG_ABOUT: &str = "\
Score every shadow technique against an exact CPU ray-traced reference.

For each pixel of one frame, the reference casts a ray from the pixel's own G-buffer point
(moved 1e-4 x max(1, |p|) along its normal) to every light that reaches it, through a BVH of
all shadow-casting triangles. Each technique renders the same frame and its hard visibility
mask (no PCF) is compared with the reference, per light type:

  false shadow  the reference sees the light, the technique shadows the pixel
  false light   the reference is shadowed, the technique lights the pixel
  edge band     pixels within --edge-band pixels of a reference shadow edge (outline, spot
                cone, range, contact line); errors there are reported apart
  footprint     screen pixels one shadow texel spans at the pixel (perspective aliasing)

Fractions are of the (pixel, light) pairs within a light's reach whose normal faces it;
pixels facing away (the light adds nothing to them) are counted apart in the JSON
(back_facing_*). Writes the lit frame,
one difference image per technique (red = false shadow, green = false light; dark red and
dark green inside the edge band; over the dimmed frame) and reference.msvis to --out-dir.

Soft shadows. When a light that casts shadows has a size (the built-in scenes' lights do;
--light-size, --sun-size), the CPU also traces the soft reference: --soft-samples rays from
each pixel to points spread over each sized light (a jittered grid), the fraction that gets
through. Each technique's soft visibility (the filtered fraction it shades with) is scored
against it, and its frame against the same frame shaded with the reference's fractions:

  umbra         mean |technique - reference| where the reference sees none of the light
  penumbra      ... where it sees some of it (the soft edge itself)
  lit           ... where it sees all of it
  image RMSE    root mean square difference of the 8-bit RGB channels of the two frames
  FLIP          their mean perceptual difference (NVIDIA's FLIP), its error map written as
                flip-<variant>.png beside diff-<variant>.png

The frame shaded with the reference is soft-reference.png. --soft off renders every light
hard (size 0) against the same soft reference, --soft on,off runs each technique both ways
(rows -hard): what the soft filter buys. The GPU reference (--reference gpu) traces the soft
reference too, with the ray-traced technique's shadow rays (at most 256 per pair). --soft-
samples 0 skips them (hard scores only; the hard scores never change with these flags).

Sequences (--frames N). The camera turns --orbit degrees a frame (or flies --camera-path)
and a caster circles (the smallest, --move-instance, none with --still), as for `render
--frames`; every technique renders every frame, keeping what it keeps from frame to frame,
and so does the exact renderer: every cluster light traced (sized lights by their area
samples). Per frame and technique: the RMSE of the 8-bit RGB channels against the exact
frame, and FLIP; per technique the mean, first, last and largest. The techniques that cast
rays take --light-samples, --reuse and --denoise. Writes sequence.png (error and GPU time
per frame), the last frame of each technique and of the exact renderer, and with --json
every frame's numbers. No CPU reference is traced.

Examples:
  manyshadows compare                                          # atrium, 8 lights, all techniques
  manyshadows compare --scene plane-spot --shadow-resolutions 256,1024,2048
  manyshadows compare --scene atrium --lights 16 --shadow-resolutions 512 --json q.json
  manyshadows compare --scene courtyard --width 320 --height 180 --soft on,off   # PCSS vs hard
  manyshadows compare --lights 1024 --frames 30 --orbit 0.15 --light-samples 1 --reuse \
      --denoise --width 640 --height 360   # a moving sequence, rays sampled and denoised";
