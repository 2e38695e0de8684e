//! The options of sampled lights and of traced shadows ([`RayOptions`], `RenderSettings::rays`):
//! how many lights a pixel samples, their reuse and denoising, and the grid of rays over a
//! sized light. They sit with the sampled lights' histories; the ray-traced technique reads
//! them too.

use crate::error::RenderError;

/// Frames of history the denoiser keeps at most (the weight of a new frame never drops below
/// 1/32).
pub const MAX_HISTORY: u32 = 32;

/// Frames a reservoir of reused samples may stand for (the weight of a new draw never falls
/// below `1 / (1 + MAX_CONFIDENCE)`): ReSTIR's usual cap of 20 bounds how long a stale choice
/// lasts.
pub const MAX_CONFIDENCE: u32 = 20;

/// Most lights one pixel may sample (`MAX_SAMPLES` in the sampled lights' WGSL).
pub const MAX_LIGHT_SAMPLES: u32 = 16;

/// Knobs of ray-traced shadows.
#[non_exhaustive]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RayOptions {
    /// Lights a pixel traces a shadow ray to: 0 (default) traces every light of the pixel's
    /// cluster, exactly; `K` in `1..=16` picks K of them by resampled importance sampling
    /// (probability proportional to each light's unshadowed contribution) and weights them so
    /// the image is unbiased: noisy, with a cost that does not grow with the light count.
    pub light_samples: u32,
    /// Seed of the sampling (the same seed gives the same image).
    pub seed: u32,
    /// Samples per side of the stratified grid over a sized light's shape (the light's
    /// fraction seen from a pixel is traced with `area_samples²` rays; 0 counts as 1). With
    /// `light_samples` K > 0 the lighting pass traces one point of each sampled light instead.
    pub area_samples: u32,
    /// With `light_samples` K > 0: denoise the sampled rays (sampled/denoise.rs): the exact
    /// unshadowed light times the shadow ratio accumulated over frames and filtered. Biased
    /// where lights of one pixel are shadowed differently; see the module. With
    /// `light_samples` 0: accumulate the sized lights' area samples over frames (new points
    /// each frame, no filter), so still frames converge to the exact soft shadows.
    pub denoise: bool,
    /// With `light_samples` K > 0: keep each pixel's sampled lights across frames and reuse
    /// them (sampled/reuse.rs: ReSTIR's temporal reuse, the target being the light's
    /// unshadowed term times its visibility, two rays per sample and frame), so a still image
    /// converges as frames pass. Unbiased for a still camera and casters; see the module.
    pub reuse: bool,
    /// With `reuse`: each pixel's reservoirs also resample those of a few neighbours after
    /// temporal reuse (ReSTIR's spatial reuse, sampled/reuse.rs), in one pass after the
    /// lighting pass. [`SpatialReuse::Unbiased`] weighs each neighbour's light by where
    /// every pixel involved could have drawn it (rays from each), [`SpatialReuse::Biased`]
    /// by their frame counts alone (cheaper, darker where neighbours see different lights).
    pub spatial: SpatialReuse,
    /// With `denoise`: where a light traced at a still point passes a shadow caster that moved
    /// since the last frame, the point's history is cut by that light's share of its light
    /// (sampled/denoise.rs, "When casters move"), so a moving caster's old shadow leaves the
    /// ratio. On by default; off keeps such histories whole (what it does, measured).
    pub moved_shadows: bool,
}

/// Spatial reuse of sampled lights ([`RayOptions::spatial`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum SpatialReuse {
    /// Temporal reuse only.
    #[default]
    Off,
    /// Neighbours' lights weighed by their reservoirs' frame counts (`1/M` weights among
    /// pixels of similar depth and normal): one ray per neighbour; biased where a neighbour
    /// could not have drawn a light this pixel sees (shadow edges).
    Biased,
    /// Neighbours' lights weighed by the generalized balance heuristic over every pixel
    /// involved (each pixel's target `f · V` at each light: rays from every pixel): unbiased.
    Unbiased,
}

impl SpatialReuse {
    /// Every mode, in the order the CLI lists them.
    pub const ALL: [SpatialReuse; 3] = [Self::Off, Self::Biased, Self::Unbiased];

    /// The mode's name (the CLI's value).
    pub fn name(self) -> &'static str {
        match self {
            Self::Off => "off",
            Self::Biased => "biased",
            Self::Unbiased => "unbiased",
        }
    }

    /// The mode named `name`, if any.
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|m| m.name() == name)
    }

    /// The shader's code (0 off, 1 biased, 2 unbiased).
    pub(crate) fn code(self) -> u32 {
        self as u32
    }
}

impl Default for RayOptions {
    fn default() -> Self {
        Self {
            light_samples: 0,
            seed: 0,
            area_samples: DEFAULT_AREA_SAMPLES,
            denoise: false,
            reuse: false,
            spatial: SpatialReuse::Off,
            moved_shadows: true,
        }
    }
}

/// Default samples per side of a sized light's grid (4 rays per pixel and light).
pub const DEFAULT_AREA_SAMPLES: u32 = 2;

impl RayOptions {
    /// Frames of history the denoiser holds once it has seen `frames` frames (it keeps at
    /// most a fixed number: older frames weigh nothing).
    pub fn denoise_history(frames: u32) -> u32 {
        frames.min(MAX_HISTORY)
    }

    /// Frames a reservoir of reused light samples stands for once `frames` frames were drawn
    /// (its own and at most a fixed number of earlier ones).
    pub fn reuse_confidence(frames: u32) -> u32 {
        frames.min(MAX_CONFIDENCE + 1)
    }

    /// Checks every value that has a range of its own ([`RenderError::InvalidOption`] names
    /// the first one out of range, as `RenderSettings` names the field).
    pub fn validate(&self) -> Result<(), RenderError> {
        if self.light_samples > MAX_LIGHT_SAMPLES {
            return Err(RenderError::invalid_option(
                "rays.light_samples",
                self.light_samples,
                "0 (every light) to 16 sampled lights per pixel",
            ));
        }
        if self.area_samples > 16 {
            return Err(RenderError::invalid_option(
                "rays.area_samples",
                self.area_samples,
                "0 to 16 samples per side of a sized light's grid (256 rays)",
            ));
        }
        if self.reuse && self.light_samples == 0 {
            return Err(RenderError::invalid_option(
                "rays.reuse",
                "on with every light traced (light_samples 0)",
                "sampled lights to reuse: light_samples 1 to 16",
            ));
        }
        if self.spatial != SpatialReuse::Off && !self.reuse {
            return Err(RenderError::invalid_option(
                "rays.spatial",
                format!("{} without rays.reuse", self.spatial.name()),
                "spatial reuse resamples the reservoirs temporal reuse keeps: rays.reuse on",
            ));
        }
        Ok(())
    }
}

with_setters!(RayOptions {
    with_light_samples: light_samples: u32,
    with_seed: seed: u32,
    with_area_samples: area_samples: u32,
    with_denoise: denoise: bool,
    with_reuse: reuse: bool,
    with_spatial: spatial: SpatialReuse,
    with_moved_shadows: moved_shadows: bool,
});
