//! The registry: every technique's [`TechniqueInfo`], in the order menus and tables list them,
//! and `create`, where a technique becomes the frame's shadow source. Adding a technique is
//! its module (with its `INFO` and its `Technique` constant) and one line in [`TECHNIQUES`];
//! the CLI, the benchmarks, the viewer and the web page read this list. It is the one module
//! that names the techniques, above all of them and above the settings that hold their
//! options.

use manyshadows_scene::Scene;

use crate::error::{RenderError, Technique};
use crate::gpu::context::GpuContext;
use crate::gpu_scene::instances::GpuScene;
use crate::settings::RenderSettings;
use crate::shadows::atlas::source::AtlasSource;
use crate::shadows::atlas::{compute, gpu_driven, layered, multiview, traditional};
use crate::shadows::descriptor::{Build, SourceArgs, TechniqueInfo};
use crate::shadows::source::{PlanParams, ShadowSource};
use crate::shadows::technique::ShadowTechnique;
use crate::shadows::{irregular, raytraced, vsm};

/// Every technique, the default first.
pub const TECHNIQUES: &[&TechniqueInfo] = &[
    &traditional::INFO,
    &layered::INFO,
    &multiview::INFO,
    &gpu_driven::INFO,
    &compute::INFO,
    &irregular::source::INFO,
    &vsm::source::INFO,
    &raytraced::source::INFO,
];

impl Technique {
    /// Every technique, in the registry's order (the default first).
    pub fn all() -> Vec<Technique> {
        TECHNIQUES.iter().map(|i| i.technique).collect()
    }

    /// The technique's declaration: summary, what it fills, its point-shadow modes and needs.
    pub fn info(self) -> &'static TechniqueInfo {
        TECHNIQUES
            .iter()
            .find(|i| i.technique == self)
            .expect("a Technique is only made by a registered module")
    }

    /// One line for `--help` and tables.
    pub fn summary(self) -> &'static str {
        self.info().summary
    }

    /// Builds an atlas technique's pipelines, after checking its needs against the device;
    /// [`RenderError::NoAtlas`] for a technique that fills no atlas.
    pub fn create(self, ctx: &GpuContext) -> Result<Box<dyn ShadowTechnique>, RenderError> {
        self.info().create_atlas(ctx)
    }
}

/// The frame's shadow source for `settings.technique`: its declaration's needs and
/// point-shadow modes checked, then an atlas technique under the generator, or the
/// technique's own source.
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
    let source_settings = settings.source_settings();
    let args = SourceArgs {
        ctx,
        scene,
        gpu,
        params: PlanParams::new(&source_settings, max_atlas),
        settings: &source_settings,
    };
    Ok(match info.build {
        Build::Atlas(_) => Box::new(AtlasSource::new(args, info)?),
        Build::Source(build) => build(args)?,
    })
}

/// The registry's first technique.
impl Default for Technique {
    fn default() -> Self {
        TECHNIQUES[0].technique
    }
}

impl std::str::FromStr for Technique {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        TECHNIQUES
            .iter()
            .map(|i| i.technique)
            .find(|t| t.name() == s)
            .ok_or_else(|| {
                format!(
                    "unknown technique '{s}' (techniques: {})",
                    TECHNIQUES
                        .iter()
                        .map(|i| i.technique.name())
                        .collect::<Vec<_>>()
                        .join(", ")
                )
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_unique_and_parse_back() {
        let all = Technique::all();
        for (i, t) in all.iter().enumerate() {
            assert!(!all[..i].contains(t), "{t} is registered twice");
            assert_eq!(t.name().parse::<Technique>(), Ok(*t));
            assert!(
                !t.info().point_shadows.is_empty(),
                "{t} renders no point shadows"
            );
        }
        assert!("nonsense".parse::<Technique>().is_err());
        assert_eq!(Technique::default(), all[0]);
    }

    /// Every technique's WGSL parses and validates as a WebGPU device with the features its
    /// shader declares would (no more): what a browser would accept. A shader needing a
    /// feature it does not declare fails here. Its lookup is checked composed into the
    /// visibility pass here, into the lighting pass with every part by the renderer's tests
    /// (`renderer/parts.rs`).
    #[test]
    fn every_technique_shader_validates_for_webgpu() {
        let mut n = 0;
        for info in TECHNIQUES {
            let mut shaders = info.shaders();
            shaders.push(crate::shadows::descriptor::Wgsl::with(
                "visibility",
                crate::shading::visibility::shader(&info.lookup),
                info.lookup.features,
            ));
            for w in shaders {
                crate::gpu::shaders::validate_for_webgpu(w.name, &w.source, w.features)
                    .unwrap_or_else(|e| panic!("technique {}: {e}", info.technique));
                n += 1;
            }
        }
        assert!(n >= TECHNIQUES.len());
    }
}
