//! What a device must have for the ways a frame's views can be drawn: stereo eyes and
//! reflection probes' faces in one layered or multiview pass. Asked before a renderer is
//! built (`Renderer::new`), and by the benches to leave out what cannot run.

use super::state::Renderer;
use crate::frame::eyes::EyePasses;
use crate::gpu::context::GpuContext;
use crate::probes::maps::ProbePasses;

impl Renderer {
    /// What `ctx`'s device lacks to draw a stereo frame's eyes `passes`' way, and what for
    /// (`None`: nothing). Multiview needs two views in one pass: the `MULTIVIEW` feature with a
    /// view count of at least 2 (OpenGL's llvmpipe offers the feature with none; lavapipe
    /// before Mesa 25 one: `GpuContext::multiview_views_per_pass`).
    pub fn stereo_unmet(ctx: &GpuContext, passes: EyePasses) -> Option<String> {
        let (feature, why) = passes.needs()?;
        let met = match passes {
            EyePasses::Multiview => ctx.multiview_views_per_pass() >= 2,
            _ => ctx.has(feature),
        };
        (!met).then(|| {
            if passes == EyePasses::Multiview {
                format!(
                    "{feature:?} with two views per pass ({why}; this device: {})",
                    ctx.multiview_views_per_pass()
                )
            } else {
                format!("{feature:?} ({why})")
            }
        })
    }

    /// What `ctx`'s device lacks to draw reflection probes' faces `passes`' way (`None`:
    /// nothing): layered needs `CLIP_DISTANCES`, multiview six views per multiview pass,
    /// GPU-driven `CLIP_DISTANCES` and indirect execution.
    pub fn probe_passes_unmet(ctx: &GpuContext, passes: ProbePasses) -> Option<String> {
        match passes {
            ProbePasses::Layered | ProbePasses::Clusters
                if !ctx.has(wgpu::Features::CLIP_DISTANCES) =>
            {
                Some("CLIP_DISTANCES".into())
            }
            ProbePasses::Clusters
                if !ctx
                    .adapter
                    .get_downlevel_capabilities()
                    .flags
                    .contains(wgpu::DownlevelFlags::INDIRECT_EXECUTION) =>
            {
                Some("INDIRECT_EXECUTION".into())
            }
            ProbePasses::Multiview if ctx.multiview_views_per_pass() < 6 => Some(format!(
                "MULTIVIEW with six views per pass (this device: {})",
                ctx.multiview_views_per_pass()
            )),
            _ => None,
        }
    }
}
