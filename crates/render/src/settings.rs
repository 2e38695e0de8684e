//! What a caller chooses for a frame: [`RenderSettings`]. It sits above every technique and
//! gathers what each defines: the shadow choices every source reads
//! ([`crate::shadows::options`]), the light loop and cluster grid ([`crate::frame::clusters`]),
//! and each technique's own knobs from its folder (irregular, virtual and ray-traced shadows).
//! Each knob checks its own range; [`RenderSettings::validate`] asks them all. The sources
//! never read this struct: the registry hands them [`RenderSettings::source_settings`].

use manyshadows_scene::atlas::FitPolicy;

use crate::error::{RenderError, Technique};
use crate::frame::clusters::{ClusterOptions, LightLoop};
use crate::frame::eyes::Stereo;
use crate::probes::maps::ProbePasses;
use crate::sampled::options::RayOptions;
use crate::shading::look::Look;
use crate::shadows::irregular::maps::IrregularOptions;
use crate::shadows::options::{Pcf, ShadowBias, ShadowOptions, SoftShadows};
use crate::shadows::source::{SourceSettings, TechniqueOptions};
use crate::shadows::vsm::plan::VirtualOptions;

/// Where skinned and morphed meshes are bent ([`RenderSettings::deform`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Deform {
    /// A compute pass writes the bent vertices into the scene's buffers from the joints'
    /// matrices and the morph weights, which are all the CPU evaluates (gpu_scene/deform.rs);
    /// the bounds come from the joints.
    #[default]
    Gpu,
    /// The CPU bends every vertex and uploads it (`Renderer::set_mesh_vertices`); the bounds
    /// are the bent vertices' own. The same vertices up to rounding: for comparison.
    Cpu,
}

/// How a frame is rendered.
#[derive(Clone, Debug)]
#[non_exhaustive]
pub struct RenderSettings {
    /// Image width in pixels (with [`Self::stereo`] both eyes side by side, each `width / 2`).
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Shadow generation technique.
    pub technique: Technique,
    /// Culling and caster options of the technique.
    pub shadow: ShadowOptions,
    /// Keep what did not change between frames (default on): the atlas tiles of views that
    /// saw no change, the virtual pages of unchanged faces away from moved casters. Changes
    /// reach the renderer only through its setters, so nothing is kept that a change
    /// touched; the first frame is the same either way. Off draws every map anew each frame
    /// (what a benchmark of a whole frame's shadow work wants).
    pub cache_shadows: bool,
    /// At most this many shadow views drawn per frame (atlas techniques; implies
    /// [`Self::cache_shadows`]): the others wait, served from their older depth where their
    /// tile holds it and unshadowed where it holds nothing of them yet, counted in
    /// [`crate::Frame::shadow_stats`]. `None`: every view that changed is drawn.
    pub shadow_budget: Option<u32>,
    /// Point-light shadows: six cube faces or two paraboloid hemispheres.
    pub point_shadows: manyshadows_scene::light_space::PointShadows,
    /// Shadow filtering.
    pub pcf: Pcf,
    /// Receiver bias.
    pub bias: ShadowBias,
    /// Soft shadows of sized lights (taps, largest penumbra).
    pub soft: SoftShadows,
    /// Largest atlas side (clamped to the adapter's limit); `None` =
    /// [`DEFAULT_MAX_ATLAS_SIZE`](crate::shadows::plan::DEFAULT_MAX_ATLAS_SIZE).
    pub max_atlas_size: Option<u32>,
    /// What to do when the shadow maps do not fit the atlas.
    pub fit: FitPolicy,
    /// Also compute the hard visibility mask.
    pub visibility: bool,
    /// Also read back how much of each light reaches each pixel (`Frame::soft_visibility`):
    /// the filtered answer of sized lights' soft shadows, what soft shadows are scored on.
    pub soft_visibility: bool,
    /// Knobs of [`Technique::IRREGULAR`] (ignored by the other techniques).
    pub irregular: IrregularOptions,
    /// Knobs of [`Technique::VIRTUAL`] (ignored by the other techniques).
    pub virtual_maps: VirtualOptions,
    /// Knobs of [`Technique::RAYTRACED`] (ignored by the other techniques).
    pub rays: RayOptions,
    /// Which lights each pixel visits: its cluster's (default) or every light (reference).
    pub light_loop: LightLoop,
    /// The cluster grid.
    pub clusters: ClusterOptions,
    /// Shading model, exposure and tone map (default: as the scene's lighting says).
    pub look: Look,
    /// Two eyes side by side (`None`: one camera): `frame::eyes`.
    pub stereo: Option<Stereo>,
    /// How reflection probes' face G-buffers are drawn (scenes with probes).
    pub probe_passes: ProbePasses,
    /// Where skinned and morphed meshes are bent as an animation plays
    /// ([`crate::Renderer::set_time`]): on the GPU (default) or the CPU.
    pub deform: Deform,
    /// Options of techniques without a field here (one added beside the built-in ones),
    /// one per type: [`RenderSettings::with_technique_options`].
    pub technique_options: Vec<std::sync::Arc<dyn TechniqueOptions>>,
}

impl Default for RenderSettings {
    fn default() -> Self {
        Self {
            width: 1280,
            height: 720,
            technique: Technique::default(),
            shadow: ShadowOptions::default(),
            cache_shadows: true,
            shadow_budget: None,
            point_shadows: Default::default(),
            pcf: Pcf::default(),
            bias: ShadowBias::default(),
            soft: SoftShadows::default(),
            max_atlas_size: None,
            fit: FitPolicy::default(),
            visibility: false,
            soft_visibility: false,
            irregular: IrregularOptions::default(),
            virtual_maps: VirtualOptions::default(),
            rays: RayOptions::default(),
            light_loop: LightLoop::default(),
            clusters: ClusterOptions::default(),
            look: Look::default(),
            stereo: None,
            probe_passes: ProbePasses::default(),
            deform: Deform::default(),
            technique_options: Vec::new(),
        }
    }
}

impl RenderSettings {
    /// Checks every value that has a range of its own, before anything is built: the first
    /// one out of range is [`RenderError::InvalidOption`] naming the field as this struct
    /// does (`irregular.hash`). Limits that depend on the device (the largest image, atlas or
    /// pool) are checked, or clamped with a note in the frame's statistics, by
    /// [`crate::Renderer::new`]. Nothing is clamped silently here.
    pub fn validate(&self) -> Result<(), RenderError> {
        fn bad(
            option: &'static str,
            value: impl std::fmt::Display,
            expected: &'static str,
        ) -> RenderError {
            RenderError::InvalidOption {
                option,
                value: value.to_string(),
                expected,
            }
        }
        if self.width == 0 {
            return Err(bad("width", self.width, "at least 1 pixel"));
        }
        if self.height == 0 {
            return Err(bad("height", self.height, "at least 1 pixel"));
        }
        if self.shadow_budget == Some(0) {
            return Err(bad(
                "shadow_budget",
                0,
                "at least 1 view per frame (or none for no budget)",
            ));
        }
        if let Some(m) = self
            .max_atlas_size
            .filter(|&m| m < manyshadows_scene::atlas::MIN_TILE)
        {
            return Err(bad(
                "max_atlas_size",
                m,
                "the atlas must hold at least one tile of the smallest size (16 texels)",
            ));
        }
        for (option, v) in [
            ("bias.constant", self.bias.constant),
            ("bias.slope", self.bias.slope),
            ("bias.normal_offset", self.bias.normal_offset),
        ] {
            if !v.is_finite() {
                return Err(bad(option, v, "a finite number of texels"));
            }
        }
        self.soft.validate()?;
        if let Some(stereo) = &self.stereo {
            stereo.validate(self.width)?;
            if self.rays.denoise || self.rays.reuse {
                return Err(bad(
                    "stereo",
                    "on with rays.denoise or rays.reuse",
                    "one camera: history is reprojected through one camera, not yet per eye",
                ));
            }
        }
        // Sampled lights take their visibility from shadow rays or from the shadow maps
        // (an atlas or virtual pages); irregular maps answer every light in one mask.
        let fills = self.technique.info().fills;
        let samples = matches!(
            fills,
            crate::error::Fills::Rays | crate::error::Fills::Atlas | crate::error::Fills::Pages
        );
        if self.rays.light_samples > 0 && !samples {
            return Err(bad(
                "rays.light_samples",
                format!(
                    "{} with technique {}",
                    self.rays.light_samples,
                    self.technique.name()
                ),
                "sampled lights need shadow rays or shadow maps to take their visibility from: \
                 technique irregular answers every light in one mask (light_samples 0)",
            ));
        }
        if self.rays.denoise
            && fills != crate::error::Fills::Rays
            && !(samples && self.rays.light_samples > 0)
        {
            return Err(bad(
                "rays.denoise",
                format!("on with technique {}", self.technique.name()),
                "sampled lights to denoise (light_samples 1 to 16 with a shadow-map technique), \
                 or shadow rays: technique raytraced",
            ));
        }
        if self.rays.reuse && !samples {
            return Err(bad(
                "rays.reuse",
                format!("on with technique {}", self.technique.name()),
                "sampled lights to reuse: technique raytraced or a shadow-map technique",
            ));
        }
        // Which pages sampled lights make: only where a technique fills pages and samples.
        let paged = fills == crate::error::Fills::Pages && self.rays.light_samples > 0;
        let defaults = VirtualOptions::default();
        for (option, set) in [
            (
                "virtual_maps.sampled_pages",
                self.virtual_maps.sampled_pages != defaults.sampled_pages,
            ),
            (
                "virtual_maps.sampled_keep_frames",
                self.virtual_maps.sampled_keep_frames != defaults.sampled_keep_frames,
            ),
        ] {
            if set && !paged {
                return Err(bad(
                    option,
                    format!(
                        "set with technique {} and light_samples {}",
                        self.technique.name(),
                        self.rays.light_samples
                    ),
                    "sampled lights over pages made on demand: technique virtual with \
                     light_samples 1 to 16",
                ));
            }
        }
        self.clusters.validate()?;
        self.irregular.validate()?;
        self.virtual_maps.validate()?;
        self.rays.validate()?;
        for o in &self.technique_options {
            o.validate()?;
        }
        self.look.validate()?;
        Ok(())
    }
}

with_setters!(RenderSettings {
    with_width: width: u32,
    with_height: height: u32,
    with_technique: technique: Technique,
    with_shadow: shadow: ShadowOptions,
    with_cache_shadows: cache_shadows: bool,
    with_shadow_budget: shadow_budget: Option<u32>,
    with_point_shadows: point_shadows: manyshadows_scene::light_space::PointShadows,
    with_pcf: pcf: Pcf,
    with_bias: bias: ShadowBias,
    with_soft: soft: SoftShadows,
    with_max_atlas_size: max_atlas_size: Option<u32>,
    with_fit: fit: FitPolicy,
    with_visibility: visibility: bool,
    with_soft_visibility: soft_visibility: bool,
    with_look: look: Look,
    with_irregular: irregular: IrregularOptions,
    with_virtual_maps: virtual_maps: VirtualOptions,
    with_rays: rays: RayOptions,
    with_light_loop: light_loop: LightLoop,
    with_clusters: clusters: ClusterOptions,
    with_stereo: stereo: Option<Stereo>,
    with_probe_passes: probe_passes: ProbePasses,
    with_deform: deform: Deform,
});

impl RenderSettings {
    /// What the shadow sources read of these settings: the shared choices, and every
    /// technique's own options for each to find by type.
    pub fn source_settings(&self) -> SourceSettings<'_> {
        SourceSettings {
            technique: self.technique,
            width: self.width,
            height: self.height,
            shadow: self.shadow,
            cache_shadows: self.cache_shadows,
            shadow_budget: self.shadow_budget,
            visibility: self.visibility,
            point_shadows: self.point_shadows,
            fit: self.fit,
            options: [
                &self.irregular as &(dyn std::any::Any + Send + Sync),
                &self.virtual_maps,
                &self.rays,
            ]
            .into_iter()
            .chain(self.technique_options.iter().map(|o| o.as_any()))
            .collect(),
        }
    }

    /// These settings with `options` for the technique that reads them (replacing options of
    /// the same type): how a technique without a field here gets its options
    /// ([`TechniqueOptions`]).
    #[must_use]
    pub fn with_technique_options<T: TechniqueOptions>(mut self, options: T) -> Self {
        self.technique_options
            .retain(|o| o.as_any().type_id() != std::any::TypeId::of::<T>());
        self.technique_options.push(std::sync::Arc::new(options));
        self
    }

    /// Default settings at `width`×`height`.
    pub fn new(width: u32, height: u32) -> Self {
        Self::default().with_width(width).with_height(height)
    }
}

#[cfg(test)]
mod technique_options_tests {
    use super::*;

    /// The options of a technique added beside the built-in ones.
    #[derive(Clone, Debug, Default)]
    struct Cones {
        spread: f32,
    }

    impl TechniqueOptions for Cones {
        fn validate(&self) -> Result<(), RenderError> {
            if self.spread.is_finite() && self.spread > 0.0 {
                Ok(())
            } else {
                Err(RenderError::invalid_option(
                    "cones.spread",
                    self.spread,
                    "a finite spread above 0",
                ))
            }
        }

        fn as_any(&self) -> &(dyn std::any::Any + Send + Sync) {
            self
        }
    }

    #[test]
    fn options_without_a_field_are_found_by_type_and_checked() {
        let s = RenderSettings::default()
            .with_technique_options(Cones { spread: 2.0 })
            .with_technique_options(Cones { spread: 3.0 });
        assert_eq!(s.technique_options.len(), 1, "one per type");
        assert_eq!(s.source_settings().options::<Cones>().spread, 3.0);
        assert_eq!(
            s.source_settings().options::<VirtualOptions>(),
            VirtualOptions::default(),
            "the built-in ones are still found"
        );
        assert!(s.validate().is_ok());
        let bad = s.with_technique_options(Cones { spread: f32::NAN });
        assert!(
            matches!(
                bad.validate(),
                Err(RenderError::InvalidOption {
                    option: "cones.spread",
                    ..
                })
            ),
            "{:?}",
            bad.validate()
        );
    }
}
