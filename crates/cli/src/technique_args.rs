//! The options of one technique or another (irregular maps' grid and hash, virtual maps' pool,
//! sides, level of detail, floor, bias and marking, and the sampled lights of shadow rays),
//! declared once and flattened into `render`, `compare` and the viewer. Their defaults are the
//! library's own (`VirtualOptions::default()`, `RayOptions::default()`), so the help shows
//! what the renderer does without them; [`TechniqueArgs::apply`] hands every one to the
//! settings, whichever technique is chosen (a value that cannot apply to it is refused by the
//! renderer by name, never dropped).

use clap::{Args, ValueEnum};
use manyshadows::{IrregularOptions, RayOptions, RenderSettings, SpatialReuse, VirtualOptions};

/// `--virtual-marking`.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum VirtualMarking {
    /// By 4x4-pixel tiles, per pixel where the tile's bounds leave it uncertain.
    Tiles,
    /// Every (pixel, light) pair.
    Pixels,
}

/// `--virtual-pages`.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum VirtualPages {
    /// Those of the sampled (pixel, light) pairs.
    Sampled,
    /// Every light's.
    Every,
}

/// Per-technique options (see the module).
#[derive(Args, Debug, Clone, Copy, PartialEq)]
pub struct TechniqueArgs {
    /// Grid side (texels) of each light view for --technique irregular (default: the view's
    /// shadow resolution, at most 512). Changes speed, not the result.
    #[arg(long)]
    pub irregular_grid: Option<u32>,
    /// Multimap hash of --technique irregular: N texels share a list head (seed 001's
    /// equalising hash; default: one list per texel). Changes speed, not the result.
    #[arg(long)]
    pub irregular_hash: Option<u32>,
    /// Page pool of --technique virtual, MiB of 32-bit depth: the largest square of whole 128²
    /// pages that fits (256 = an 8192² pool of 4,096 pages, 512 = 11520² of 8,100 pages), at
    /// most the adapter's largest texture; the summary says when that is less than asked.
    /// Pages that do not fit fall back to coarser levels, counted in the summary. To compare
    /// at equal memory, set it to the atlas size the other techniques report.
    #[arg(long, default_value_t = (VirtualOptions::default().pool_bytes >> 20) as u32)]
    pub page_pool: u32,
    /// Largest virtual side of a face for --technique virtual (rounded to a power of two and
    /// clamped to 128..=16384 texels).
    #[arg(long, default_value_t = VirtualOptions::default().max_side)]
    pub virtual_side: u32,
    /// Shadow texels per screen pixel that --technique virtual aims for (1 = no texel wider
    /// than the pixel footprint; 2 = twice as fine, four times the pages; 0.7 about 0.6 times
    /// the pages, with more misclassified pixels where pixels are wide): point lights' cube
    /// faces get it, spot and directional lights' faces it times --virtual-directed-lod.
    #[arg(long, default_value_t = VirtualOptions::default().lod)]
    pub virtual_lod: f32,
    /// Factor on --virtual-lod for the faces of spot and directional lights (0.8 by default:
    /// their texels up to 1.25 pixels, which costs them few misclassified pixels while point
    /// lights' cube faces, seeing walls near the light, keep --virtual-lod; 1 gives every face
    /// --virtual-lod).
    #[arg(long, default_value_t = VirtualOptions::default().directed_lod)]
    pub virtual_directed_lod: f32,
    /// --technique virtual: no face samples coarser than the tile the atlas techniques would
    /// give the same view (`on`, default: virtual maps never misclassify more than the atlas
    /// where the atlas is finer than the screen asks, e.g. few lights in a small frame), or
    /// only what the screen's level of detail asks (`off`: fewer pages there).
    #[arg(long, default_value = "on", value_parser = parse_on_off,
          action = clap::ArgAction::Set, value_name = "on|off")]
    pub virtual_atlas_floor: bool,
    /// --technique virtual's receiver bias as a fraction of --bias-constant, --bias-slope and
    /// --bias-normal (those count texels; a virtual page's texels match the screen pixel, and
    /// a whole texel of bias leaks light at contacts: 0.5 by default, 0 to 16).
    #[arg(long, default_value_t = VirtualOptions::default().bias_scale)]
    pub virtual_bias: f32,
    /// How --technique virtual finds the pages the samples need: `tiles` bounds the samples
    /// of 4x4-pixel tiles and marks a light's page once where every sample needing one needs
    /// the same page, per pixel elsewhere; `pixels` marks every (pixel, light) pair. The same
    /// pages either way (the summary's `marking` line says how the tiles went); `pixels` is
    /// for measuring.
    #[arg(long, value_enum, default_value_t = VirtualMarking::Tiles)]
    pub virtual_marking: VirtualMarking,
    /// --technique virtual with --light-samples: which pages are made. `sampled` (default):
    /// only those of the (pixel, light) pairs the frame samples (and, for
    /// --virtual-keep-frames frames, those asked before), found by a pass that runs the light
    /// choice before the shadows; `every`: every light's that reaches a pixel (the same image
    /// where the samples look, more pages: for measuring).
    #[arg(long, value_enum, default_value_t = VirtualPages::Sampled)]
    pub virtual_pages: VirtualPages,
    /// --technique virtual with --light-samples: frames a page stays resident after a sample
    /// last asked for it (0 to 64). The samples change every frame, so without this a page is
    /// drawn anew each time a pixel comes back to its light.
    #[arg(long, default_value_t = VirtualOptions::default().sampled_keep_frames)]
    pub virtual_keep_frames: u32,
    /// Shade K lights per pixel, picked among the pixel's cluster lights by importance (their
    /// unshadowed contribution) and weighted so the image stays unbiased — noisy, at a
    /// lighting cost that does not grow with the light count. Their visibility: shadow rays
    /// with technique raytraced, else the technique's shadow maps (virtual and the atlas
    /// techniques: a hard light's depth test, a sized light's PCSS fraction; no ray queries
    /// needed). Irregular maps refuse it. 0 (default) shades every cluster light.
    #[arg(long, default_value_t = RayOptions::default().light_samples)]
    pub light_samples: u32,
    /// With --light-samples K: denoise the sampled lights. The exact unshadowed light of every
    /// cluster light times the samples' shadow ratio, accumulated over frames at each surface
    /// point (reprojected when the camera moves) and filtered by an edge-stopping wavelet
    /// (one pass for all lights). Biased where a pixel's lights are shadowed differently; with
    /// --frames it converges as the frames go by.
    ///
    /// Without --light-samples (every light traced): accumulate the sized lights' area
    /// samples over frames, new points on each light every frame and no filter, so
    /// `--frames N --still` converges to the exact soft shadows (unbiased; the error falls as
    /// 1/sqrt(N) up to the denoiser's longest history).
    #[arg(long)]
    pub denoise: bool,
    /// With --light-samples K: reuse each pixel's sampled lights across frames (ReSTIR's
    /// temporal reuse). Each frame a new light is drawn and weighed against the one the
    /// pixel kept (found where the surface point was last frame) by its unshadowed light
    /// times its visibility, both read now (two rays per sample with shadow rays): lights that reach the
    /// pixel are kept, so with --frames a still image's noise falls frame by frame. Unbiased
    /// for a still camera and casters; combine with --denoise for the cleanest frames.
    #[arg(long)]
    pub reuse: bool,
    /// With --reuse: after temporal reuse each pixel also resamples the lights of a few
    /// neighbours (ReSTIR's spatial reuse; pixels of similar depth and normal): the first
    /// frames are far less noisy. `unbiased` weighs each neighbour's light by how every
    /// pixel involved could have drawn it (rays from each), `biased` by one count per
    /// neighbour (fewer rays; darker where neighbours see other lights); `off`: temporal
    /// reuse only.
    #[arg(long, default_value = "off", value_parser = parse_spatial)]
    pub spatial: SpatialReuse,
    /// With shadow rays: rays per side of the stratified grid over each sized light's shape
    /// (N² rays per pixel and light when every light is traced; 0 counts as 1; at most 16).
    /// More: smoother penumbrae, at N² the cost of a hard shadow ray.
    #[arg(long, default_value_t = RayOptions::default().area_samples)]
    pub area_samples: u32,
    /// Seed of --light-samples' choices (the same seed gives the same image).
    #[arg(long, default_value_t = RayOptions::default().seed)]
    pub ray_seed: u32,
}

/// `on` / `off` (also yes/no, true/false, 1/0).
pub(crate) fn parse_on_off(s: &str) -> Result<bool, String> {
    match s.trim().to_ascii_lowercase().as_str() {
        "on" | "yes" | "true" | "1" => Ok(true),
        "off" | "no" | "false" | "0" => Ok(false),
        _ => Err(format!("'{s}' is neither on nor off")),
    }
}

/// `--spatial`: a spatial reuse mode by name.
pub fn parse_spatial(s: &str) -> Result<manyshadows::SpatialReuse, String> {
    manyshadows::SpatialReuse::from_name(s).ok_or_else(|| {
        let names: Vec<&str> = manyshadows::SpatialReuse::ALL
            .iter()
            .map(|m| m.name())
            .collect();
        format!("unknown spatial reuse '{s}': one of {}", names.join(", "))
    })
}

impl Default for TechniqueArgs {
    /// What no flag asks for: the library's defaults.
    fn default() -> Self {
        #[derive(clap::Parser)]
        struct Only {
            #[command(flatten)]
            technique: TechniqueArgs,
        }
        <Only as clap::Parser>::parse_from(["manyshadows"]).technique
    }
}

impl TechniqueArgs {
    /// Irregular maps' options.
    pub fn irregular(&self) -> IrregularOptions {
        IrregularOptions::default()
            .with_grid(self.irregular_grid)
            .with_hash(self.irregular_hash)
    }

    /// Virtual maps' options.
    pub fn virtual_maps(&self) -> VirtualOptions {
        VirtualOptions::default()
            .with_pool_bytes(u64::from(self.page_pool) << 20)
            .with_max_side(self.virtual_side)
            .with_lod(self.virtual_lod)
            .with_directed_lod(self.virtual_directed_lod)
            .with_atlas_floor(self.virtual_atlas_floor)
            .with_bias_scale(self.virtual_bias)
            .with_tile_marking(self.virtual_marking == VirtualMarking::Tiles)
            .with_sampled_pages(self.virtual_pages == VirtualPages::Sampled)
            .with_sampled_keep_frames(self.virtual_keep_frames)
    }

    /// The sampled lights' and shadow rays' options.
    pub fn rays(&self) -> RayOptions {
        RayOptions::default()
            .with_light_samples(self.light_samples)
            .with_denoise(self.denoise)
            .with_reuse(self.reuse)
            .with_spatial(self.spatial)
            .with_area_samples(self.area_samples)
            .with_seed(self.ray_seed)
    }

    /// `settings` with every technique's options these flags give.
    pub fn apply(&self, settings: RenderSettings) -> RenderSettings {
        settings
            .with_irregular(self.irregular())
            .with_virtual_maps(self.virtual_maps())
            .with_rays(self.rays())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// No flag gives the library's defaults, so `render`, `compare` and the viewer start from
    /// the renderer's own settings.
    #[test]
    fn no_flag_is_the_library_default() {
        let a = TechniqueArgs::default();
        assert_eq!(a.virtual_maps(), VirtualOptions::default());
        assert_eq!(a.rays(), RayOptions::default());
        assert_eq!(a.irregular(), IrregularOptions::default());
    }
}
