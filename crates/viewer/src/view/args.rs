//! The viewer's flags (the scene, the technique and options to start with, the window's
//! size, a camera script and when to stop, what the panel shows first), the controls' help,
//! and the camera script's reader.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use manyshadows::scene::light_space::PointShadows;
use manyshadows::{Pcf, Technique};

#[derive(Args, Debug, Clone)]
pub struct ViewArgs {
    /// Built-in scene name or a TOML scene file (as for `render`).
    #[arg(long, default_value = "atrium")]
    pub(super) scene: String,
    /// Mesh file for the dragon scene (.obj, .gltf/.glb, .ply, .ply.gz).
    #[arg(long)]
    pub(super) mesh: Option<PathBuf>,
    /// Number of lights, placed by a seeded layout (default: the scene's own lights); the
    /// panel changes it at run time.
    #[arg(long)]
    pub(super) lights: Option<usize>,
    /// Seed of the light layout.
    #[arg(long, default_value_t = 1)]
    pub(super) seed: u64,
    #[command(flatten)]
    pub(super) light_sizes: manyshadows_cli::LightSizeArgs,
    /// `--soft-taps B,F`, `--max-penumbra T`: the shadow maps' soft shadows, as `render`.
    #[command(flatten)]
    pub(super) soft: manyshadows_cli::SoftArgs,
    #[command(flatten)]
    pub(super) model: manyshadows_cli::ModelArgs,
    #[command(flatten)]
    pub(super) look: manyshadows_cli::LookArgs,
    /// Reflection probes seeded along the scene's longest side (0: none); default the
    /// scene's own (the atrium's two), as `render --probes`.
    #[arg(long, value_name = "N")]
    pub(super) probes: Option<usize>,
    /// How the probes' face G-buffers are drawn: per-face, layered, multiview or gpu-driven
    /// (as `render --probe-passes`).
    #[arg(long, default_value_t = manyshadows::ProbePasses::default(),
          value_parser = manyshadows_cli::parse_probe_passes)]
    pub(super) probe_passes: manyshadows::ProbePasses,
    /// Shadow technique to start with (as for `render`; the panel switches it).
    #[arg(long, default_value_t = Technique::default(), value_parser = manyshadows_cli::parse_technique)]
    pub(super) technique: Technique,
    /// Point-light shadows to start with: cube or dual-paraboloid.
    #[arg(long, default_value = "cube", value_parser = manyshadows_cli::parse_point_shadows)]
    pub(super) point_shadows: PointShadows,
    /// Filtering to start with: off, 2x2 or 3x3.
    #[arg(long, default_value = "2x2", value_parser = manyshadows_cli::parse_pcf)]
    pub(super) pcf: Pcf,
    /// What single-sided surfaces shadow: front (only where a light sees their front: outline
    /// shells and floors lit from below cast nothing) or both (every face casts), as for
    /// `render`.
    #[arg(long, default_value_t = manyshadows::SingleSidedShadows::default())]
    pub(super) single_sided_shadows: manyshadows::SingleSidedShadows,
    /// The options of one technique or another, as `render` takes them; the panel changes
    /// --light-samples, --denoise, --reuse and --spatial at run time.
    #[command(flatten)]
    pub(super) per_technique: manyshadows_cli::TechniqueArgs,
    /// Start with every shadow map drawn anew each frame (the panel's "keep unchanged maps"
    /// box unticked); by default the maps (pages) of views that saw no change are kept.
    #[arg(long, conflicts_with = "shadow_budget")]
    pub(super) no_cache: bool,
    /// Keep what did not change between frames: the default (kept for older command lines).
    #[arg(long, hide = true, conflicts_with = "no_cache")]
    pub(super) cache: bool,
    /// Draw at most N shadow views per frame (atlas techniques; with the caching): the rest
    /// wait their turn, served from their older depth or unshadowed until drawn (the panel
    /// counts them).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    pub(super) shadow_budget: Option<u32>,
    /// Stereo: a left and a right eye this far apart (world units), side by side in the
    /// window, each half its width, both G-buffers drawn in one layered pass (as `render
    /// --stereo`). Not with --reuse or --denoise.
    #[arg(long, value_name = "SEPARATION", allow_hyphen_values = true,
          conflicts_with_all = ["reuse", "denoise"])]
    pub(super) stereo: Option<f32>,
    /// Move the smallest caster in a circle and sway the first spot or point light (of two
    /// or more): only the shadow maps that see the caster or belong to that light are
    /// redrawn (unless --no-cache; the panel counts them).
    #[arg(long)]
    pub(super) animate: bool,
    /// A glTF file's animation to play: its name, its number from 0, or `all` [default: 0,
    /// the first, playing from the start]. The panel plays, pauses, scrubs and changes speed.
    #[arg(long, value_name = "NAME|INDEX|all")]
    pub(super) animation: Option<String>,
    /// Seconds into the file's animation to start at (looping past its end).
    #[arg(long, value_name = "T", allow_negative_numbers = true)]
    pub(super) time: Option<f32>,
    /// Playback speed of the file's animation (1: as authored; 0 stands still).
    #[arg(
        long,
        default_value_t = 1.0,
        value_name = "X",
        allow_negative_numbers = true
    )]
    pub(super) speed: f32,
    /// Start with the file's animation paused.
    #[arg(long)]
    pub(super) paused: bool,
    /// Camera to start from, `PX,PY,PZ,TX,TY,TZ` (default: the scene's camera).
    #[arg(long, value_parser = manyshadows_cli::parse_camera, allow_hyphen_values = true)]
    pub(super) camera: Option<[f32; 6]>,
    /// Window width (the frame is rendered at the window's size).
    #[arg(long, default_value_t = 960)]
    pub(super) width: u32,
    /// Window height.
    #[arg(long, default_value_t = 540)]
    pub(super) height: u32,
    /// Camera script: one camera per line, `PX PY PZ TX TY TZ` (commas allowed, `#`
    /// comments); frame k uses line k, and the last camera stays after the script ends.
    #[arg(long)]
    pub(super) script: Option<PathBuf>,
    /// Close the window after this many frames.
    #[arg(long)]
    pub(super) exit_after: Option<u64>,
    /// Start with the panel hidden (F1 toggles it).
    #[arg(long)]
    pub(super) hide_panel: bool,
    /// Start with the shadow-atlas picture shown (read back once a second).
    #[arg(long)]
    pub(super) show_atlas: bool,
    /// Start with this light's hard visibility shown (white = lit; read back once a second).
    #[arg(long)]
    pub(super) show_visibility: Option<usize>,
    /// Accept techniques whose frames are far beyond the rest (more than 2 G caster
    /// triangle-view pairs): without it such a choice is refused with its estimate (at start)
    /// or said on the panel (switching), as `render` refuses it without --insist.
    #[arg(long)]
    pub(super) insist: bool,
    /// Start following this light (the camera at the light, looking where it shines).
    #[arg(long)]
    pub(super) follow: Option<usize>,
    #[command(flatten)]
    pub(super) gpu: manyshadows_cli::GpuArgs,
}

/// Help shown in the panel and by `--help`.
pub(crate) const CONTROLS: &str = "W/A/S/D move, Q/E down/up, right mouse button + drag look, \
     wheel changes speed, F1 panel, Esc quits";

/// The cameras of a `--script` (the format of `render --camera-path`).
pub(super) fn parse_script(text: &str) -> Result<Vec<[f32; 6]>> {
    manyshadows_cli::parse_camera_path(text).map_err(|e| anyhow::anyhow!("script {e}"))
}

#[cfg(test)]
mod tests {
    #[test]
    fn scripts_parse_and_bad_lines_name_their_line() {
        let cams = super::parse_script("# a path\n0 1 2 0 0 0\n\n1,1,1, 0,0,0 # end\n").unwrap();
        assert_eq!(cams.len(), 2);
        assert_eq!(cams[1], [1.0, 1.0, 1.0, 0.0, 0.0, 0.0]);
        let e = super::parse_script("0 1 2 0 0 0\n1 2 3\n").unwrap_err();
        assert!(e.to_string().contains("line 2"), "{e}");
        assert!(super::parse_script("# nothing\n").is_err());
        assert!(super::parse_script("1 1 1 1 1 1\n").is_err());
    }
}
