//! The cameras a frame's image is made of: one, or a stereo pair side by side (seed 000 names
//! stereo "a particularly good candidate" for single-pass rendering: both eyes see nearly the
//! same triangles).
//!
//! **The layout.** With [`Stereo`] the frame's image (`RenderSettings::width` × `height`) holds
//! the left eye in its left half and the right eye in its right half, each `width / 2` wide.
//! Every pass that works per pixel (clusters, shadows that read the G-buffer, lighting, the
//! masks, read-backs) runs over the whole image unchanged; only the passes that form the
//! camera's picture ask which eye a pixel belongs to: the G-buffer (each eye's projection),
//! the clusters (each eye's frustum tiles) and the lighting (each eye's position for the view
//! vector).
//!
//! **The eyes** are parallel ([`manyshadows_scene::Camera::shifted`]): the camera moved by
//! ∓separation/2 along its right direction, target and all, with the same projection at
//! aspect `(width / 2) / height`. Parallel eyes share the view direction, so every point has
//! the same view depth in both, and one cluster depth slicing serves both.
//!
//! **Shadows** are planned for the centre camera at the whole image's aspect: its frustum
//! holds both eyes' from `separation / (2·tan(fov_x/2))` in front of the eyes onwards
//! (a few centimetres for a human eye separation), so every map technique and cascade fit
//! covers what either eye sees.
//!
//! **How the G-buffer is drawn** ([`EyePasses`]): one pass per eye (the baseline), one layered
//! pass (each instance drawn twice, instance → eye, clip distances keep each copy in its half;
//! seed 000's technique on colour targets), or one multiview pass where the adapter has it
//! (both eyes into a two-layer target, copied into the halves).

use manyshadows_scene::Camera;

use crate::error::RenderError;

/// How a stereo frame's G-buffer is drawn.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[non_exhaustive]
pub enum EyePasses {
    /// One render pass per eye over every instance (the baseline).
    PerEye,
    /// One render pass, one draw per instance covering both eyes (instance → eye), clip
    /// distances keeping each eye in its half (needs `CLIP_DISTANCES`).
    #[default]
    Layered,
    /// One multiview render pass into a two-layer target, each layer then copied into its
    /// half (needs `MULTIVIEW`).
    Multiview,
}

impl EyePasses {
    /// Every way, baseline first.
    pub const ALL: &'static [EyePasses] =
        &[EyePasses::PerEye, EyePasses::Layered, EyePasses::Multiview];

    /// CLI name: `per-eye`, `layered` or `multiview`.
    pub fn name(self) -> &'static str {
        match self {
            EyePasses::PerEye => "per-eye",
            EyePasses::Layered => "layered",
            EyePasses::Multiview => "multiview",
        }
    }

    /// How the G-buffer is drawn this way, in words (for summaries).
    pub fn describe(self) -> &'static str {
        match self {
            EyePasses::PerEye => "drawn in one pass per eye",
            EyePasses::Layered => {
                "drawn in one layered pass (each instance once for both eyes, clipped to its half)"
            }
            EyePasses::Multiview => {
                "drawn in one multiview pass (a layer per eye, copied into the halves)"
            }
        }
    }

    /// The device feature this way needs, and what for.
    pub fn needs(self) -> Option<(wgpu::Features, &'static str)> {
        match self {
            EyePasses::PerEye => None,
            EyePasses::Layered => Some((
                wgpu::Features::CLIP_DISTANCES,
                "to keep each eye's copy of a triangle in its half",
            )),
            EyePasses::Multiview => Some((
                wgpu::Features::MULTIVIEW,
                "to draw both eyes in one multiview pass",
            )),
        }
    }
}

impl std::fmt::Display for EyePasses {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for EyePasses {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        EyePasses::ALL
            .iter()
            .copied()
            .find(|m| m.name() == s)
            .ok_or_else(|| {
                format!("unknown eye passes '{s}' (expected per-eye, layered or multiview)")
            })
    }
}

/// Two eyes side by side in one frame.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct Stereo {
    /// Distance between the eyes in world units (finite, ≥ 0; a person's is about 0.065 m).
    pub separation: f32,
    /// How the G-buffer is drawn.
    pub passes: EyePasses,
}

impl Stereo {
    /// Eyes `separation` apart, drawn the default way (layered).
    pub fn new(separation: f32) -> Self {
        Self {
            separation,
            passes: EyePasses::default(),
        }
    }

    /// The same, drawn `passes`' way.
    pub fn with_passes(self, passes: EyePasses) -> Self {
        Self { passes, ..self }
    }

    /// Checks the separation and that `width` splits into two eyes.
    pub fn validate(&self, width: u32) -> Result<(), RenderError> {
        if !(self.separation.is_finite() && self.separation >= 0.0) {
            return Err(RenderError::invalid_option(
                "stereo.separation",
                self.separation,
                "a finite distance of at least 0",
            ));
        }
        if width < 2 || !width.is_multiple_of(2) {
            return Err(RenderError::invalid_option(
                "width",
                width,
                "an even number of pixels with stereo (each eye is width / 2)",
            ));
        }
        Ok(())
    }
}

/// The frame's cameras: one, or the left and right eye.
#[derive(Clone, Debug, PartialEq)]
pub struct Eyes {
    /// Left to right.
    pub cameras: Vec<Camera>,
    /// Width of one eye's half in pixels (the whole width when mono).
    pub eye_width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Half the eye separation (0 when mono): the left eye sits at −this along the centre
    /// camera's right direction, the right eye at +this.
    pub half_separation: f32,
}

impl Eyes {
    /// The cameras of a `width`×`height` frame of `camera`, stereo or not.
    pub fn new(camera: &Camera, stereo: Option<Stereo>, (width, height): (u32, u32)) -> Self {
        match stereo {
            None => Self {
                cameras: vec![*camera],
                eye_width: width,
                height,
                half_separation: 0.0,
            },
            Some(s) => {
                let h = 0.5 * s.separation;
                Self {
                    cameras: vec![camera.shifted(-h), camera.shifted(h)],
                    eye_width: (width / 2).max(1),
                    height,
                    half_separation: h,
                }
            }
        }
    }

    /// Width / height of one eye.
    pub fn aspect(&self) -> f32 {
        self.eye_width as f32 / self.height.max(1) as f32
    }

    /// Eye `i`'s world → clip.
    pub fn view_proj(&self, i: usize) -> glam::Mat4 {
        let c = &self.cameras[i];
        c.projection(self.aspect()) * c.view()
    }

    /// Eye `i`'s offset along the centre camera's right direction.
    pub fn offset(&self, i: usize) -> f32 {
        if self.cameras.len() == 1 {
            0.0
        } else if i == 0 {
            -self.half_separation
        } else {
            self.half_separation
        }
    }
}
