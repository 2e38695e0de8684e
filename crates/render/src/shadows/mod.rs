//! Shadows, between the frame's passes that feed them (G-buffer, clusters) and those that read
//! them (lighting, visibility). From the bottom up:
//!
//! - [`plan`]: every shadow view of a frame and its atlas tile, and the priority fit;
//! - [`depth`] and [`cluster_draw`]: the depth-only pipelines every shadow map is drawn with,
//!   and the cluster culling + indirect multi-draw rounds `gpu-driven` and the virtual maps
//!   share (with their WGSL); [`image`]: depth read-back and pictures;
//! - [`source`]: the [`ShadowSource`] trait the renderer drives, its
//!   output, and the view table of the sources that fill no atlas;
//! - one folder per kind of source: [`atlas`] (the atlas, its techniques, their registry and
//!   generator), [`irregular`] (a visibility mask), [`vsm`] (virtual shadow maps: a page pool);
//! - `create`: the one place a technique becomes a source.
//!
//! `shadow_lookup.wgsl` (view selection, bias, atlas addressing) and `paraboloid.wgsl` (the
//! dual-paraboloid warp) lie here too: every pass that reads shadows composes them
//! ([`crate::gpu::shaders`]).

pub mod atlas;
pub mod cluster_draw;
pub mod depth;
pub mod descriptor;
pub mod image;
pub mod irregular;
pub mod plan;
pub mod raytraced;
pub mod registry;
pub mod source;
pub mod vsm;

use manyshadows_scene::Scene;

use crate::gpu_scene::instances::GpuScene;
use crate::settings::RenderSettings;
use crate::shadows::atlas::source::AtlasSource;
use crate::shadows::descriptor::{Build, SourceArgs};
use crate::shadows::source::{PlanParams, ShadowSource};
use crate::{GpuContext, RenderError};

/// The one mapping from a technique to its source: its declaration's needs and point-shadow
/// modes checked, then an atlas technique under the generator, or the technique's own source.
pub(crate) fn create(
    ctx: &GpuContext,
    scene: &Scene,
    gpu: &GpuScene,
    settings: &RenderSettings,
    max_atlas: u32,
) -> Result<Box<dyn ShadowSource>, RenderError> {
    let info = settings.technique.info();
    info.check(ctx)?;
    // Refused whether or not the scene has point lights now: `set_lights` may add some.
    info.check_point_shadows(settings.point_shadows)?;
    let params = PlanParams::new(settings, max_atlas);
    Ok(match info.build {
        Build::Atlas(_) => Box::new(AtlasSource::new(
            ctx,
            scene,
            gpu,
            params,
            settings.technique,
            settings,
        )?),
        Build::Source(build) => build(SourceArgs {
            ctx,
            scene,
            gpu,
            params,
            settings,
        })?,
    })
}
