//! The registry of atlas techniques: the one place a [`Technique`] becomes the
//! [`ShadowTechnique`] that fills the atlas. Adding a technique is a module beside this one,
//! one line here and one in [`Technique`]. No other module names the techniques.

use crate::settings::{ShadowOptions, Technique, IRREGULAR_NO_ATLAS, VIRTUAL_NO_ATLAS};
use crate::shadows::atlas::technique::ShadowTechnique;
use crate::shadows::atlas::{compute, gpu_driven, layered, multiview, traditional};
use crate::{GpuContext, RenderError};

/// Builds `technique`'s pipelines; fails with a clear message where the adapter lacks a
/// feature the technique needs, and with [`RenderError::NoAtlas`] for the techniques that
/// fill no atlas.
pub fn create(
    technique: Technique,
    ctx: &GpuContext,
    options: &ShadowOptions,
) -> Result<Box<dyn ShadowTechnique>, RenderError> {
    let _ = options;
    Ok(match technique {
        Technique::Traditional => Box::new(traditional::Traditional::new(ctx)),
        Technique::Layered => Box::new(layered::Layered::new(ctx)?),
        Technique::Multiview => Box::new(multiview::Multiview::new(ctx)?),
        Technique::GpuDriven => Box::new(gpu_driven::GpuDriven::new(ctx)?),
        Technique::Compute => Box::new(compute::Compute::new(ctx)?),
        Technique::Irregular => {
            return Err(RenderError::NoAtlas {
                technique: Technique::Irregular,
                detail: IRREGULAR_NO_ATLAS.into(),
            })
        }
        Technique::Virtual => {
            return Err(RenderError::NoAtlas {
                technique: Technique::Virtual,
                detail: VIRTUAL_NO_ATLAS.into(),
            })
        }
    })
}

impl Technique {
    /// Builds the technique's pipelines; fails with a clear message where the adapter lacks
    /// a feature the technique needs ([`create`]).
    pub fn create(
        self,
        ctx: &GpuContext,
        options: &ShadowOptions,
    ) -> Result<Box<dyn ShadowTechnique>, RenderError> {
        create(self, ctx, options)
    }
}
