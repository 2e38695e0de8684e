//! The registry: every technique's [`TechniqueInfo`], in the order menus and tables list them.
//! Adding a technique is its module (with its `INFO` and its `Technique` constant) and one
//! line in [`TECHNIQUES`]; the CLI, the benchmarks, the viewer and the web page read this list.

use crate::settings::Technique;
use crate::shadows::atlas::technique::ShadowTechnique;
use crate::shadows::atlas::{compute, gpu_driven, layered, multiview, traditional};
use crate::shadows::descriptor::{Build, TechniqueInfo};
use crate::shadows::{irregular, raytraced, vsm};
use crate::{GpuContext, RenderError};

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
        let info = self.info();
        match info.build {
            Build::Atlas(build) => {
                info.check(ctx)?;
                build(ctx)
            }
            Build::Source(_) => Err(RenderError::NoAtlas {
                technique: self,
                fills: info.fills,
            }),
        }
    }
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
    /// feature it does not declare fails here.
    #[test]
    fn every_technique_shader_validates_for_webgpu() {
        let mut n = 0;
        for info in TECHNIQUES {
            let shaders = info.shaders();
            assert!(!shaders.is_empty(), "{} declares no WGSL", info.technique);
            for w in shaders {
                crate::gpu::shaders::validate_for_webgpu(w.name, &w.source, w.features)
                    .unwrap_or_else(|e| panic!("technique {}: {e}", info.technique));
                n += 1;
            }
        }
        assert!(n >= TECHNIQUES.len());
    }
}
