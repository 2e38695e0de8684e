//! The arguments commands share (`GpuArgs`, `RenderArgs`), the parsers of option values, and
//! how `render`'s arguments become [`RenderSettings`] (with the errors that name the flag
//! behind a bad value).

use std::path::PathBuf;

pub use crate::light_args::{LightSizeArgs, SoftArgs};
pub(crate) use crate::technique_args::{parse_on_off, parse_spatial};
use anyhow::{bail, Result};
use clap::{Args, Parser, ValueEnum};
use manyshadows::scene::atlas::FitPolicy;
use manyshadows::scene::light_space::PointShadows;
use manyshadows::scene::loaders::{Ground, LoadOptions};

use manyshadows::{
    AdapterRequest, CullMode, Exposure, GpuContext, Look, Pcf, RenderSettings, Shading, ShadowBias,
    ShadowOptions, Technique, ToneMap,
};

/// Adapter choice: `--backend`, `--adapter`, `--limits` (shared by every subcommand that
/// renders, and by the viewer).
#[derive(Args, Debug, Clone)]
pub struct GpuArgs {
    /// Graphics backend (default: WGPU_BACKEND, else the best adapter of any backend:
    /// hardware first, then Vulkan on the CPU, then OpenGL on the CPU).
    #[arg(long, value_enum)]
    pub(crate) backend: Option<Backend>,
    /// Use the adapter whose name contains this text (default: WGPU_ADAPTER_NAME).
    #[arg(long)]
    pub(crate) adapter: Option<String>,
    /// Create the device with smaller limits than the adapter's: `webgpu` = what a browser
    /// gives by default (8 storage buffers per stage, 8192² textures, 128 MiB storage
    /// bindings) — how the renderer behaves on a small device, without one.
    #[arg(long, value_enum)]
    pub(crate) limits: Option<Limits>,
}

#[derive(ValueEnum, Clone, Copy, Debug)]
pub(crate) enum Limits {
    /// WebGPU's default limits.
    Webgpu,
}

#[derive(ValueEnum, Clone, Copy, Debug)]
pub(crate) enum Backend {
    Vulkan,
    Gl,
    Metal,
    Dx12,
}

impl GpuArgs {
    /// The adapter request these options describe.
    pub fn request(&self) -> AdapterRequest {
        AdapterRequest::default()
            .with_backends(self.backend.map(|b| match b {
                Backend::Vulkan => wgpu_backends("vulkan"),
                Backend::Gl => wgpu_backends("gl"),
                Backend::Metal => wgpu_backends("metal"),
                Backend::Dx12 => wgpu_backends("dx12"),
            }))
            .with_name(self.adapter.clone())
            .with_limits(self.limits.map(|l| match l {
                Limits::Webgpu => manyshadows::webgpu_default_limits(),
            }))
    }
}

pub(crate) fn wgpu_backends(name: &str) -> manyshadows::wgpu::Backends {
    manyshadows::wgpu::Backends::from_comma_list(name)
}

#[derive(Args, Debug, Clone)]
pub(crate) struct RenderArgs {
    /// Built-in scene name, a TOML scene file (see docs/SCENE_FORMAT.md), or a model file
    /// (.gltf/.glb with its materials, textures, KHR_lights_punctual lights and camera; .obj
    /// with its MTL; .ply/.ply.gz), rendered with its own lights and camera (a light rig of 8
    /// and a framing camera when it has none). Built-ins: atrium, terrain, dragon, cubes,
    /// courtyard (textures and alpha-masked foliage, lattice, banners), courtyard-opaque,
    /// plane-spot, plane-point, plane-directional, crowd (64 skinned tubes swaying: animation), walker (one skinned figure walking: animation).
    #[arg(long, default_value = "atrium")]
    pub(crate) scene: String,
    /// Shadow technique (--help lists them all, with what each fills and needs).
    #[arg(long, default_value_t = Technique::default(), value_parser = parse_technique, long_help = crate::techniques::help())]
    pub(crate) technique: Technique,
    /// Per-view triangle culling of the single-pass techniques: none, frustum, backface
    /// (closed meshes only, so shadows never change) or all. The default technique, one pass
    /// per view, culls whole instances on the CPU and ignores it.
    #[arg(long, default_value = "all", value_parser = parse_cull)]
    pub(crate) cull: CullMode,
    /// Point-light shadows: cube (six 90° faces) or dual-paraboloid (two hemispheres, each
    /// map twice the per-face resolution; needs finely tessellated geometry, see --subdivide).
    /// `--help` under --technique says which techniques render which.
    #[arg(long, default_value = "cube", value_parser = parse_point_shadows)]
    pub(crate) point_shadows: PointShadows,
    /// Split every triangle into four this many times before rendering (4^N triangles), e.g.
    /// to give dual-paraboloid maps the fine geometry their non-linear warp needs.
    #[arg(long, default_value_t = 0)]
    pub(crate) subdivide: u32,
    /// Render this many frames; with more than one, one shadow caster (see --move-instance)
    /// moves a little each frame and a line per frame reports the shadow work. The last frame
    /// is written.
    #[arg(long, default_value_t = 1)]
    pub(crate) frames: u32,
    /// Draw every shadow map anew each frame. By default the atlas tiles of views that saw no
    /// change since the last frame are kept (seed 004's caching; with --technique virtual,
    /// the pages of unchanged faces away from moved casters); with --frames, each frame's line
    /// shows how many views (pages) it redrew.
    #[arg(long, conflicts_with = "shadow_budget")]
    pub(crate) no_cache: bool,
    /// Keep what did not change between frames: the default (kept for older command lines).
    #[arg(long, hide = true, conflicts_with = "no_cache")]
    pub(crate) cache: bool,

    /// At most N shadow views drawn per frame (atlas techniques; needs the caching): the views
    /// that changed wait their turn, new tiles and larger (nearer, more important) views
    /// first; a waiting view is served from its older depth where its tile holds it (counted
    /// stale, with the age of the oldest) and unshadowed until drawn where it holds nothing
    /// yet (counted waiting). With --frames, each frame's line says how many of each
    #[arg(long, value_name = "N")]
    pub(crate) shadow_budget: Option<u32>,
    /// Render even a frame whose shadow work is far beyond the rest (more than 2 G
    /// triangle-view pairs, e.g. a technique that sends every triangle to each of thousands
    /// of views): without it such a frame is refused with its estimate and the techniques that
    /// scale, before anything is drawn.
    #[arg(long)]
    pub(crate) insist: bool,
    /// With --frames > 1, turn the camera this many degrees per frame around its target (about
    /// its up axis). The shadow plan follows: cascades refit, lights that leave the screen
    /// give up their maps and lights that enter it get them.
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub(crate) orbit: f32,
    /// A fly path for --frames: one camera per line, `PX PY PZ TX TY TZ` (commas allowed, `#`
    /// comments); frame k takes line k and the last camera stays after the path ends (the
    /// viewer's --script format). Frame 1 takes line 1 in place of the scene's camera.
    #[arg(long, value_name = "FILE", conflicts_with_all = ["orbit", "camera"])]
    pub(crate) camera_path: Option<std::path::PathBuf>,
    /// The instance that moves when --frames > 1 (default: the smallest shadow caster).
    #[arg(long, conflicts_with = "still")]
    pub(crate) move_instance: Option<usize>,
    /// With --frames > 1, move no caster (with --orbit the camera still turns): still frames,
    /// e.g. for --denoise to accumulate.
    #[arg(long)]
    pub(crate) still: bool,
    /// Say each part of a frame as the GPU finishes it (G-buffer and light clusters,
    /// shadows, lighting), with the time so far: the parts are submitted and waited for one
    /// by one. On by itself for a frame whose shadow work is estimated past 200 M (caster
    /// triangle, view) pairs (a tenth of what runs only with --insist), so a frame of
    /// minutes is not silent; the image is the same either way.
    #[arg(long)]
    pub(crate) stages: bool,
    /// Number of lights, placed by a seeded layout (default: the scene's own lights).
    #[arg(long)]
    pub(crate) lights: Option<usize>,
    /// Keep the scene's own lights (a model's, or the rig it was given) and add this many of
    /// the seeded layout around it (what the web page's light count does for a model).
    #[arg(long, value_name = "N", conflicts_with = "lights")]
    pub(crate) add_lights: Option<usize>,
    /// Seed of the light layout.
    #[arg(long, default_value_t = 1)]
    pub(crate) seed: u64,
    /// Light types the layout uses: all (mixed), spot, point or directional.
    #[arg(long, default_value = "all")]
    pub(crate) light_types: String,
    /// Mesh file for the dragon scene (.obj, .gltf/.glb, .ply, .ply.gz); without it a
    /// procedural stand-in of ~35k triangles is used.
    #[arg(long)]
    pub(crate) mesh: Option<PathBuf>,
    #[command(flatten)]
    pub(crate) model: ModelArgs,
    #[command(flatten)]
    pub(crate) animation: AnimationArgs,
    /// Shadow-map resolution per view (texels per side) for every light.
    #[arg(long)]
    pub(crate) shadow_resolution: Option<u32>,
    /// Reflection probes: N seeded along the scene's longest side, each standing for its
    /// slab of the scene's bounds (0: none). Default: the scene's own ([[probe]] in a TOML
    /// scene; the atrium's two in the nave, with its floor, marble and bronze reflective;
    /// none for the other built-in scenes and model files). Each probe's six faces are lit
    /// like the frame and redrawn when a light or caster changes; surfaces mirror the nearest
    /// (Phong: a material's `reflect`; glTF: metallic and roughness).
    #[arg(long, value_name = "N")]
    pub(crate) probes: Option<usize>,
    /// Texels per side of each probe face (8 to 1024).
    #[arg(long, default_value_t = manyshadows::scene::Probe::DEFAULT_RESOLUTION)]
    pub(crate) probe_resolution: u32,
    /// How the probes' face G-buffers are drawn: per-face (one pass each, the baseline),
    /// layered (every face of every probe in one instanced pass, each copy clipped to its
    /// tile of an atlas; seed 000's layered rendering), multiview (each probe's six faces in
    /// one multiview pass; Vulkan) or gpu-driven (triangle clusters culled per face by a
    /// compute pass, drawn into the layered atlas's tiles by indirect multi-draws; seed 002).
    #[arg(long, default_value_t = manyshadows::ProbePasses::default(),
          value_parser = parse_probe_passes)]
    pub(crate) probe_passes: manyshadows::ProbePasses,
    #[command(flatten)]
    pub(crate) light_sizes: LightSizeArgs,
    #[command(flatten)]
    pub(crate) soft: SoftArgs,
    #[command(flatten)]
    pub(crate) look: LookArgs,
    /// Camera position and target, `PX,PY,PZ,TX,TY,TZ` (default: the scene's camera).
    #[arg(long, value_parser = parse_camera, allow_hyphen_values = true)]
    pub(crate) camera: Option<[f32; 6]>,
    /// Image width (with --stereo: of each eye; the image is twice as wide).
    #[arg(long, default_value_t = 1280)]
    pub(crate) width: u32,
    /// Image height.
    #[arg(long, default_value_t = 720)]
    pub(crate) height: u32,
    /// Stereo: a left and a right eye this far apart (world units; a person's eyes are about
    /// 0.065 m apart, the built-in scenes' units are metres), written side by side, each
    /// --width wide. Both eyes are lit from the same shadow maps; see --stereo-passes for how
    /// their G-buffers are drawn.
    #[arg(long, value_name = "SEPARATION", allow_hyphen_values = true)]
    pub(crate) stereo: Option<f32>,
    /// With --stereo, how the two eyes' G-buffers are drawn: layered (default: one pass, one
    /// draw per instance for both eyes, each copy clipped to its half; seed 000's layered
    /// rendering), multiview (one multiview pass into a layer per eye, copied into the halves;
    /// Vulkan) or per-eye (one pass per eye, the baseline).
    #[arg(long, default_value_t = manyshadows::EyePasses::default(), value_parser = parse_eye_passes,
          requires = "stereo")]
    pub(crate) stereo_passes: manyshadows::EyePasses,
    /// Percentage-closer filtering: off, 2x2 or 3x3.
    #[arg(long, default_value = "2x2", value_parser = parse_pcf)]
    pub(crate) pcf: Pcf,
    /// Receiver bias towards the light, in shadow texels.
    #[arg(long, default_value_t = ShadowBias::default().constant)]
    pub(crate) bias_constant: f32,
    /// Receiver bias towards the light per unit of tan(angle between normal and light), texels.
    #[arg(long, default_value_t = ShadowBias::default().slope)]
    pub(crate) bias_slope: f32,
    /// Receiver offset along the surface normal, texels.
    #[arg(long, default_value_t = ShadowBias::default().normal_offset)]
    pub(crate) bias_normal: f32,
    /// Shadows: on, or off (every light lights as if nothing stood in its way: for looking
    /// at shading alone, or comparing it with a viewer that draws no shadows).
    #[arg(long, default_value = "on", value_parser = parse_on_off, action = clap::ArgAction::Set)]
    pub(crate) shadows: bool,
    /// Alpha-tested casters in the shadow passes: on (holes in foliage, lattices and banners
    /// let light through) or off (they cast as solid cards, as a renderer that ignores alpha
    /// would draw them; the camera still sees the holes).
    #[arg(long, default_value = "on", value_parser = parse_on_off, action = clap::ArgAction::Set)]
    pub(crate) shadow_alpha: bool,
    /// What single-sided surfaces (glTF's default, `double_sided = false` in TOML) shadow:
    /// front (only where a light sees their front, as a camera placed at the light would see
    /// them: outline shells and floors lit from below cast nothing; closed meshes cast as
    /// always) or both (every face casts, as a renderer that ignores the material's sides
    /// does). Double-sided and alpha-tested surfaces always cast from both sides.
    #[arg(long, default_value_t = manyshadows::SingleSidedShadows::default())]
    pub(crate) single_sided_shadows: manyshadows::SingleSidedShadows,
    /// Largest shadow-atlas side in texels (clamped to the adapter's limit).
    #[arg(long, default_value_t = manyshadows::DEFAULT_MAX_ATLAS_SIZE)]
    pub(crate) atlas_max: u32,
    /// Fail when the shadow maps don't fit the atlas. By default maps that don't fit degrade by
    /// importance: lights that reach nothing on screen get no maps, the least important lights
    /// (smallest angle at the camera) get smaller maps first, and as a last resort no shadows;
    /// the summary counts each.
    #[arg(long)]
    pub(crate) strict_atlas: bool,
    #[command(flatten)]
    pub(crate) per_technique: crate::technique_args::TechniqueArgs,
    /// Which lights each pixel visits: clustered (the lights assigned to its cluster of a
    /// tiles x depth-slices grid, built on the GPU each frame) or all (every light: the
    /// reference the clustered image must equal, and slow past a few hundred lights).
    #[arg(long, default_value = "clustered", value_parser = parse_light_loop)]
    pub(crate) light_loop: manyshadows::LightLoop,
    /// Cluster tile side in pixels [default: 16 where the slot pool holds every cluster of
    /// that grid (128 MiB: e.g. 640x360 with up to 16,384 lights, 1280x720 with up to ~6,000),
    /// else 32].
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    pub(crate) cluster_tile: Option<u32>,
    /// Exponential depth slices of the cluster grid (1 to 256).
    #[arg(long, default_value_t = manyshadows::ClusterOptions::default().slices)]
    pub(crate) cluster_slices: u32,
    /// Output image.
    #[arg(long, short, default_value = "frame.png")]
    pub(crate) out: PathBuf,
    /// Also write the shadow atlas as a picture (linearized depth, tiles outlined).
    #[arg(long)]
    pub(crate) atlas_out: Option<PathBuf>,
    /// Also write the hard visibility mask into this directory: visibility.msvis (raw bits,
    /// format in the renderer's visibility module docs) and one PNG per light (white = lit).
    #[arg(long)]
    pub(crate) visibility_out: Option<PathBuf>,
    /// Also write every frame of a sequence into this folder (made if missing), as
    /// frame_0001.png, frame_0002.png, … (`--out` still gets the last).
    #[arg(long, value_name = "DIR")]
    pub(crate) out_dir: Option<PathBuf>,
    /// Also write the summary as JSON.
    #[arg(long)]
    pub(crate) json: Option<PathBuf>,
    #[command(flatten)]
    pub(crate) gpu: GpuArgs,
}

/// Which of a glTF file's animations plays, and when: shared by `render`, `compare` and the
/// viewer.
#[derive(Args, Debug, Clone, Default, PartialEq)]
pub struct AnimationArgs {
    /// A glTF file's animation to play: its name, its number from 0, or `all` (every one at
    /// once) [default: 0, the first]. Refused for a scene without animations, with the list
    /// where the name is not found.
    #[arg(long, value_name = "NAME|INDEX|all")]
    pub animation: Option<String>,
    /// Seconds into the animation for the (first) frame [default: 0]. Playback loops: a time
    /// past the animation's end is taken modulo its length.
    #[arg(long, value_name = "T", allow_negative_numbers = true)]
    pub time: Option<f32>,
    /// With --frames N: frames per second of animation time, frame k at --time + k / F
    /// [default: 30].
    #[arg(long, value_name = "F")]
    pub fps: Option<f32>,
}

/// Default --fps.
pub(crate) const DEFAULT_FPS: f32 = 30.0;

/// When a sequence's frames stand in a file's animation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Clock {
    pub(crate) playing: manyshadows::scene::animation::Playing,
    /// Seconds at frame 0.
    pub(crate) start: f32,
    pub(crate) fps: f32,
}

impl Clock {
    /// Seconds at frame `f` (from 0).
    pub(crate) fn at(&self, f: u32) -> f32 {
        self.start + f as f32 / self.fps
    }
}

impl AnimationArgs {
    /// The clock these flags ask for on `scene` (`None`: it does not move), checked: a flag
    /// for a scene without animations, an animation not in the file, a time or rate that is
    /// not a finite positive number, --fps for a single frame, are refused by name.
    pub(crate) fn clock(
        &self,
        scene: &manyshadows::scene::Scene,
        frames: u32,
    ) -> Result<Option<Clock>> {
        let anims = &scene.animations;
        if anims.is_empty() {
            let flag = [
                ("--animation", self.animation.is_some()),
                ("--time", self.time.is_some()),
                ("--fps", self.fps.is_some()),
            ]
            .into_iter()
            .find(|(_, given)| *given);
            if let Some((flag, _)) = flag {
                bail!(
                    "{flag}: scene {} has no animation that moves a mesh (a glTF file's node \
                     animations play; built-in, TOML, OBJ and PLY scenes stand still)",
                    scene.name
                );
            }
            return Ok(None);
        }
        let playing = match &self.animation {
            Some(a) => anims
                .choose(a)
                .map_err(|e| anyhow::anyhow!("--animation {a}: {e}"))?,
            None => manyshadows::scene::animation::Playing::One(0),
        };
        let start = self.time.unwrap_or(0.0);
        if !(start.is_finite() && start >= 0.0) {
            bail!("--time {start}: must be a finite number of seconds, 0 or more");
        }
        if let Some(f) = self.fps {
            if frames <= 1 {
                bail!("--fps {f}: applies to a sequence (--frames 2 or more)");
            }
            if !(f.is_finite() && f > 0.0 && f <= 10_000.0) {
                bail!("--fps {f}: must be a number of frames per second above 0, at most 10,000");
            }
        }
        Ok(Some(Clock {
            playing,
            start,
            fps: self.fps.unwrap_or(DEFAULT_FPS),
        }))
    }
}

/// How a model file (.gltf/.glb/.obj/.ply) is loaded: shared by `render`, `compare` and the
/// viewer (the benches render built-in scenes only).
#[derive(Args, Debug, Clone, Copy, PartialEq, Eq)]
pub struct ModelArgs {
    /// Let a model file read files outside its own folder: absolute paths and `..` in glTF
    /// buffer and image URIs, OBJ `mtllib` and MTL texture paths, symbolic links that lead
    /// out. Without it such paths are refused by name (a model file is untrusted input).
    #[arg(long)]
    pub allow_outside_paths: bool,
    /// A ground plane under a model file, catching its shadows: auto (only under a model
    /// without a floor of its own: no large horizontal surface at the bottom of its bounds),
    /// on or off; `--ground` alone is on. Not for built-in or TOML scenes.
    #[arg(long, default_value = "auto", num_args = 0..=1, default_missing_value = "on",
          value_parser = parse_ground, value_name = "auto|on|off")]
    pub ground: Ground,
}

/// How shaded light becomes a pixel: shared by `render` and the viewer. Each follows the
/// scene when not given: Phong, ×1.4 and the exponential tone map for built-in, TOML, OBJ and
/// PLY scenes (the seeds' look); the glTF BRDF, an automatic exposure and Khronos PBR Neutral
/// for glTF files.
#[derive(Args, Debug, Clone, Copy, PartialEq, Default)]
pub struct LookArgs {
    /// Shading model: pbr (the glTF specification's metallic-roughness BRDF; default for glTF
    /// files) or phong (seed 004's model; default for every other scene).
    #[arg(long, value_parser = parse_shading, value_name = "phong|pbr")]
    pub shading: Option<Shading>,
    /// Exposure: `auto` (an incident-light meter at the camera target: EV100 = log2(lux ·
    /// 100 / 250); the default for glTF files), an EV100 (higher is darker: about 15 for a
    /// sunny day, 7 for an office, 0 for a scene lit by a few candela), or `x1.4` for a plain
    /// scale (the other scenes' default). The summary says which was used.
    #[arg(long, value_parser = parse_exposure, allow_hyphen_values = true,
          value_name = "auto|EV100|xSCALE")]
    pub exposure: Option<Exposure>,
    /// Tone map: neutral (Khronos PBR Neutral: colours below 0.76 pass unchanged, highlights
    /// roll off to white; default for glTF files), exponential (1 - e^-x: many overlapping
    /// lights never clip; the other scenes' default) or clamp (none).
    #[arg(long, value_parser = parse_tone_map, value_name = "neutral|exponential|clamp")]
    pub tone_map: Option<ToneMap>,
}

impl LookArgs {
    /// The look these flags ask for (unset ones follow the scene).
    pub fn look(&self) -> Look {
        Look {
            shading: self.shading,
            exposure: self.exposure,
            tone_map: self.tone_map,
        }
    }
}

/// `phong` or `pbr`.
pub fn parse_shading(s: &str) -> Result<Shading, String> {
    s.parse()
}

/// `auto`, an EV100 or `xSCALE`.
pub fn parse_exposure(s: &str) -> Result<Exposure, String> {
    s.parse()
}

/// `neutral`, `exponential` or `clamp`.
pub fn parse_tone_map(s: &str) -> Result<ToneMap, String> {
    s.parse()
}

impl ModelArgs {
    /// The loader options these flags ask for.
    pub fn options(&self) -> LoadOptions {
        LoadOptions {
            allow_outside_paths: self.allow_outside_paths,
            ground: self.ground,
        }
    }
}

impl Default for RenderArgs {
    /// What `manyshadows render` with no flags asks for.
    fn default() -> Self {
        #[derive(Parser)]
        struct Only {
            #[command(flatten)]
            render: RenderArgs,
        }
        Only::parse_from(["manyshadows"]).render
    }
}

/// A technique name (as `--technique` takes it).
pub fn parse_technique(s: &str) -> Result<Technique, String> {
    s.parse()
}

/// `cube` or `dual-paraboloid`.
pub fn parse_point_shadows(s: &str) -> Result<PointShadows, String> {
    s.parse()
}

pub(crate) fn parse_cull(s: &str) -> Result<CullMode, String> {
    s.parse()
}

/// `auto`, `on` or `off`.
pub fn parse_ground(s: &str) -> Result<Ground, String> {
    s.parse()
}

/// The cameras of the `--camera-path` file `path`, if one is given (`render`, `compare`,
/// `bench denoise`): read and parsed by [`parse_camera_path`], errors naming the file.
pub(crate) fn read_camera_path(
    path: Option<&std::path::Path>,
) -> anyhow::Result<Option<Vec<[f32; 6]>>> {
    use anyhow::Context;
    let Some(p) = path else {
        return Ok(None);
    };
    let text = std::fs::read_to_string(p).with_context(|| format!("reading {}", p.display()))?;
    parse_camera_path(&text)
        .with_context(|| format!("--camera-path {}", p.display()))
        .map(Some)
}

/// The cameras of a camera path (`render --camera-path`, the viewer's `--script`): one per
/// line that is not empty once its `#` comment is cut, each as [`parse_camera`] reads it; a bad
/// line is named by its number, a path without cameras refused.
pub fn parse_camera_path(text: &str) -> anyhow::Result<Vec<[f32; 6]>> {
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let line = line.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        out.push(parse_camera(line).map_err(|e| anyhow::anyhow!("line {}: {e}", i + 1))?);
    }
    if out.is_empty() {
        anyhow::bail!("no camera lines (one `PX PY PZ TX TY TZ` per line)");
    }
    Ok(out)
}

/// `PX,PY,PZ,TX,TY,TZ`: six finite numbers.
pub fn parse_camera(s: &str) -> Result<[f32; 6], String> {
    let v: Vec<f32> = s
        .split([',', ' '])
        .filter(|t| !t.is_empty())
        .map(|t| t.parse::<f32>().map_err(|e| format!("'{t}': {e}")))
        .collect::<Result<_, _>>()?;
    match <[f32; 6]>::try_from(v.as_slice()) {
        Ok(a) if a.iter().all(|x| x.is_finite()) => {
            if a[..3] == a[3..] {
                Err("the camera position and target must differ".into())
            } else {
                Ok(a)
            }
        }
        Ok(_) => Err("camera coordinates must be finite".into()),
        Err(_) => Err(format!(
            "expected six numbers PX,PY,PZ,TX,TY,TZ, got {}",
            v.len()
        )),
    }
}

/// `off`, `2x2` or `3x3`.
pub fn parse_pcf(s: &str) -> Result<Pcf, String> {
    s.parse()
}

/// `per-face`, `layered`, `multiview` or `gpu-driven`.
pub fn parse_probe_passes(s: &str) -> Result<manyshadows::ProbePasses, String> {
    s.parse()
}

/// `layered`, `multiview` or `per-eye`.
pub(crate) fn parse_eye_passes(s: &str) -> Result<manyshadows::EyePasses, String> {
    s.parse()
}

pub(crate) fn parse_light_loop(s: &str) -> Result<manyshadows::LightLoop, String> {
    s.parse()
}

/// Refuses option values that could only be changed silently; checked before anything is
/// loaded or uploaded.
pub(crate) fn check_render_args(args: &RenderArgs) -> Result<()> {
    if args.frames == 0 {
        bail!("--frames must be at least 1");
    }
    if !args.orbit.is_finite() {
        bail!(
            "--orbit {}: must be a finite number of degrees per frame",
            args.orbit
        );
    }
    // Where the results go, before minutes of rendering: files that are not folders, a
    // folder that is not a file.
    for (flag, path) in [
        ("-o", Some(&args.out)),
        ("--atlas-out", args.atlas_out.as_ref()),
    ] {
        if let Some(p) = path.filter(|p| p.is_dir()) {
            bail!(
                "{flag} {}: that is a folder; give the PNG file to write",
                p.display()
            );
        }
    }
    if let Some(p) = args.out_dir.as_ref().filter(|p| p.exists() && !p.is_dir()) {
        bail!(
            "--out-dir {}: that is a file; give a folder (made if missing) for the frames",
            p.display()
        );
    }
    if let Some(p) = args
        .visibility_out
        .as_ref()
        .filter(|p| p.exists() && !p.is_dir())
    {
        bail!(
            "--visibility-out {}: that is a file; give a folder (made if missing) for the \
             visibility mask and one image per light",
            p.display()
        );
    }
    args.light_sizes.sizes()?;
    // The renderer checks every option's range itself; asking it here refuses a bad value
    // before anything is loaded, and names the flag that set it.
    render_settings(args, args.atlas_max)
        .validate()
        .map_err(flag_error)
}

/// A renderer error about an option, with the CLI flag that sets the option in front.
pub(crate) fn flag_error(e: manyshadows::RenderError) -> anyhow::Error {
    const FLAGS: &[(&str, &str)] = &[
        ("width", "--width"),
        ("height", "--height"),
        ("max_atlas_size", "--atlas-max"),
        ("bias.constant", "--bias-constant"),
        ("bias.slope", "--bias-slope"),
        ("bias.normal_offset", "--bias-normal"),
        ("clusters.tile", "--cluster-tile"),
        ("clusters.slices", "--cluster-slices"),
        ("irregular.grid", "--irregular-grid"),
        ("irregular.hash", "--irregular-hash"),
        ("virtual_maps.pool_bytes", "--page-pool (MiB)"),
        ("virtual_maps.lod", "--virtual-lod"),
        ("virtual_maps.directed_lod", "--virtual-directed-lod"),
        ("virtual_maps.bias_scale", "--virtual-bias"),
        ("virtual_maps.max_side", "--virtual-side"),
        ("virtual_maps.sampled_pages", "--virtual-pages"),
        ("virtual_maps.sampled_keep_frames", "--virtual-keep-frames"),
        ("rays.light_samples", "--light-samples"),
        ("rays.denoise", "--denoise"),
        ("rays.reuse", "--reuse"),
        ("rays.spatial", "--spatial"),
        ("soft.blocker_taps", "--soft-taps (blocker)"),
        ("soft.filter_taps", "--soft-taps (filter)"),
        ("soft.max_penumbra", "--max-penumbra"),
        ("rays.area_samples", "--area-samples"),
        ("shadow_budget", "--shadow-budget"),
        ("look.exposure", "--exposure"),
        ("stereo.separation", "--stereo"),
        ("stereo", "--stereo"),
    ];
    if let manyshadows::RenderError::InvalidOption { option, .. } = &e {
        if let Some((_, flag)) = FLAGS.iter().find(|(o, _)| o == option) {
            // Other options the message names (dotted: `rays.reuse`) by their flags.
            let mut text = e.to_string();
            for (o, f) in FLAGS.iter().filter(|(o, _)| o.contains('.') && o != option) {
                text = text.replace(o, f.split(' ').next().unwrap_or(f));
            }
            return anyhow::anyhow!("{flag}: {text}");
        }
    }
    e.into()
}

/// The atlas side `--atlas-max` really allows on this adapter (a power of two, at most the
/// adapter's texture limit), with a note on stderr when it is not the number given.
pub(crate) fn effective_atlas_max(ctx: &GpuContext, requested: u32) -> u32 {
    let limit = ctx.limits().max_texture_dimension_2d;
    let capped = requested.min(limit);
    let side = 1u32 << (31 - capped.leading_zeros());
    if side != requested {
        eprintln!(
            "note: --atlas-max {requested} is used as {side} (atlas sides are powers of two{})",
            if requested > limit {
                format!(", and this adapter's largest texture is {limit}")
            } else {
                String::new()
            }
        );
    }
    side
}

/// The renderer settings `args` ask for, with the atlas cap already checked against the
/// adapter.
pub(crate) fn render_settings(args: &RenderArgs, atlas_max: u32) -> RenderSettings {
    let settings = RenderSettings::default()
        .with_width(if args.stereo.is_some() {
            args.width.saturating_mul(2)
        } else {
            args.width
        })
        .with_height(args.height)
        .with_stereo(
            args.stereo
                .map(|s| manyshadows::Stereo::new(s).with_passes(args.stereo_passes)),
        )
        .with_probe_passes(args.probe_passes)
        .with_soft(args.soft.soft())
        .with_technique(args.technique)
        .with_shadow(
            ShadowOptions::default().with_cull(args.cull).with_casters(
                manyshadows::CasterOptions::default()
                    .with_ignore_masks(!args.shadow_alpha)
                    .with_single_sided(args.single_sided_shadows),
            ),
        )
        .with_cache_shadows(!args.no_cache)
        .with_shadow_budget(args.shadow_budget)
        .with_point_shadows(args.point_shadows)
        .with_pcf(args.pcf)
        .with_bias(ShadowBias::new(
            args.bias_constant,
            args.bias_slope,
            args.bias_normal,
        ))
        .with_max_atlas_size(Some(atlas_max))
        .with_fit(if args.strict_atlas {
            FitPolicy::Strict
        } else {
            FitPolicy::Prioritize
        })
        .with_visibility(args.visibility_out.is_some())
        .with_look(args.look.look())
        .with_light_loop(args.light_loop)
        .with_clusters({
            let c = manyshadows::ClusterOptions::default().with_slices(args.cluster_slices);
            match args.cluster_tile {
                Some(t) => c.with_tile(t),
                None => c,
            }
        });
    args.per_technique.apply(settings)
}
