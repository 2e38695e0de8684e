//! The interface every atlas technique implements: what it is given ([`ShadowInput`]), one
//! generation as it records it ([`Generation`]), and the trait ([`ShadowTechnique`]). The
//! techniques are created through their declarations ([`crate::shadows::descriptor`],
//! [`crate::registry`]).

use manyshadows_scene::light_space::ShadowView;

use crate::gpu::context::GpuContext;
use crate::gpu::timing::{GpuTimer, Span};
use crate::gpu_scene::casters::CasterGeometry;
use crate::gpu_scene::instances::{DrawItem, GpuScene};
use crate::shadows::options::ShadowOptions;
use crate::shadows::source::ShadowStats;
use crate::shadows::storage::ShadowAtlas;

/// What a technique is given to fill the atlas.
pub struct ShadowInput<'a> {
    /// GPU context.
    pub ctx: &'a GpuContext,
    /// Scene buffers.
    pub scene: &'a GpuScene,
    /// Views to fill (same order as the atlas tiles).
    pub views: &'a [ShadowView],
    /// The atlas to fill.
    pub atlas: &'a ShadowAtlas,
    /// World-space caster geometry (techniques that use it record its transform).
    pub casters: &'a CasterGeometry,
    /// Culling and raster options.
    pub options: &'a ShadowOptions,
    /// The views to draw this time, ascending (all of them unless caching kept some);
    /// also uploaded to [`ShadowAtlas::draw_list`].
    pub draw_list: &'a [u32],
}

impl ShadowInput<'_> {
    /// True if every view is drawn: the whole atlas may be cleared at once. Otherwise only the
    /// listed views' tiles may be touched.
    pub fn full(&self) -> bool {
        self.draw_list.len() == self.views.len()
    }
}

/// One generation as a technique records it: what to draw and where to record it.
pub struct Generation<'a> {
    /// The views, atlas and geometry; `input.draw_list` is never empty here.
    pub input: &'a ShadowInput<'a>,
    /// The encoder the passes are recorded into.
    pub encoder: &'a mut wgpu::CommandEncoder,
    /// Timestamp and pipeline-statistics queries.
    pub timer: &'a GpuTimer,
    /// The timer span of the generation's passes.
    pub span: Option<Span>,
}

/// A shadow-generation technique: fills every view's tile of the atlas with depth. Its name
/// is [`Technique::name`](crate::error::Technique::name) of the
/// [`Technique`](crate::error::Technique) that created it.
pub trait ShadowTechnique {
    /// Records the generation of a non-empty draw list (see [`ShadowTechnique::generate`],
    /// which calls it).
    fn record(&mut self, generation: Generation<'_>) -> ShadowStats;

    /// Records the generation into `encoder`; `span` is the timer span for its passes. An
    /// empty draw list records nothing. Techniques keep their uniform buffers and bind groups
    /// across generations and rewrite the uniforms with `Queue::write_buffer`, so submit each
    /// generation before recording the next one.
    fn generate(
        &mut self,
        input: &ShadowInput<'_>,
        encoder: &mut wgpu::CommandEncoder,
        timer: &GpuTimer,
        span: Option<Span>,
    ) -> ShadowStats {
        if input.draw_list.is_empty() {
            return ShadowStats::default();
        }
        self.record(Generation {
            input,
            encoder,
            timer,
            span,
        })
    }
}

/// Per-view CPU culling shared by techniques that draw instance by instance: the shadow
/// casters whose bounding sphere touches the view's frustum.
pub fn visible_casters<'a>(
    scene: &'a GpuScene,
    view: &ShadowView,
) -> impl Iterator<Item = &'a DrawItem> + 'a {
    let view = *view;
    scene
        .draws
        .iter()
        .filter(move |d| d.casts_shadows && view.sphere_visible(d.sphere.0, d.sphere.1))
}
