//! What the command line says of the lights' shapes and their soft shadows: `--light-size`
//! and `--sun-size` (every light's size instead of the scene's own), `--soft-taps` and
//! `--max-penumbra` (the shadow maps' percentage-closer soft shadows). Shared by `render`,
//! `compare` and the viewer.

use anyhow::Result;
use clap::Args;
use manyshadows::scene::light_size::LightSizes;

/// `--soft-taps`, `--max-penumbra`: the shadow maps' percentage-closer soft shadows of sized
/// lights (shared by `render` and `compare`).
#[derive(Args, Debug, Clone, Copy)]
pub struct SoftArgs {
    /// Taps of the shadow maps' soft shadows of sized lights: `B,F` depths read by the blocker
    /// search and comparisons by the penumbra filter, or one number for both (1 to 64 each).
    ///
    /// Each sized light's shadow at a pixel reads B depths around it to find the casters
    /// between it and the light (their mean distance sets the penumbra's width) and then F
    /// comparisons over that width: fewer taps are faster and noisier (`bench soft --taps`
    /// measures what they cost). Hard lights and shadow rays ignore it.
    #[arg(long, default_value = "16,16", value_parser = parse_soft_taps)]
    pub soft_taps: (u32, u32),
    /// Largest penumbra radius the shadow maps filter, in shadow texels (1 to 256): wider
    /// penumbrae are clamped in the atlas and filtered at coarser levels by virtual maps,
    /// which read at most 63 texels at one level (what their page marking reaches).
    #[arg(long, default_value_t = manyshadows::SoftShadows::default().max_penumbra)]
    pub max_penumbra: f32,
}

impl SoftArgs {
    /// The renderer's soft-shadow settings.
    pub fn soft(&self) -> manyshadows::SoftShadows {
        manyshadows::SoftShadows::default()
            .with_blocker_taps(self.soft_taps.0)
            .with_filter_taps(self.soft_taps.1)
            .with_max_penumbra(self.max_penumbra)
    }
}

/// `--soft-taps`: `B,F` or one number for both.
fn parse_soft_taps(s: &str) -> Result<(u32, u32), String> {
    tap_pair(
        s,
        ',',
        "blocker and filter taps as B,F (e.g. 8,16) or one number for both",
    )
}

/// Blocker and filter taps from `B<sep>F`, or one number for both; `usage` says the form in
/// the error. `--soft-taps` (`B,F`) and `bench soft --taps` (`B/F`, its list split at commas).
pub(crate) fn tap_pair(s: &str, sep: char, usage: &str) -> Result<(u32, u32), String> {
    let bad = || format!("'{s}': {usage}");
    let n: Vec<u32> = s
        .split(sep)
        .map(|t| t.trim().parse::<u32>().map_err(|_| bad()))
        .collect::<Result<_, _>>()?;
    match n[..] {
        [t] => Ok((t, t)),
        [b, f] => Ok((b, f)),
        _ => Err(bad()),
    }
}

/// `--light-size`, `--sun-size`: every light's size instead of the scene's own (shared by
/// `render`, `compare` and the viewer, and applied wherever they load a scene).
#[derive(Args, Debug, Clone, Copy, Default)]
pub struct LightSizeArgs {
    /// Radius of every spot and point light, world units, for soft shadows (0 = hard; suns:
    /// --sun-size).
    ///
    /// A point light becomes a sphere of this radius, a spot light a disc of it facing along
    /// its cone: the larger, the wider the penumbrae. 0 = points, hard shadows. Default: the
    /// scene's own sizes: the built-in scenes make each light's radius 2% of its range
    /// (cubes and plane-* are hard), scene and glTF files say theirs (0 when they don't).
    /// Directional lights are sized by --sun-size.
    #[arg(long, value_name = "RADIUS", allow_negative_numbers = true)]
    pub light_size: Option<f32>,
    /// Angular diameter of every directional light, degrees, below 30, for soft shadows (the
    /// sun: 0.53; 0 = hard).
    ///
    /// How wide the light's disc looks from the scene: the sun and the moon are about 0.53°.
    /// The larger, the wider the penumbrae; 0 = parallel rays, hard shadows. Default: the
    /// scene's own sizes: the built-in scenes' suns are 0.53° (cubes and plane-* are hard),
    /// scene and glTF files say theirs (0 when they don't).
    #[arg(long, value_name = "DEGREES", allow_negative_numbers = true)]
    pub sun_size: Option<f32>,
}

impl LightSizeArgs {
    /// The sizes asked for, checked (a negative or non-finite size, a sun of 30° or more is
    /// an error naming its flag).
    pub fn sizes(&self) -> Result<LightSizes> {
        let radius = LightSizes {
            radius: self.light_size,
            sun_deg: None,
        };
        radius
            .check()
            .map_err(|e| anyhow::anyhow!("--light-size: {e}"))?;
        let sun = LightSizes {
            radius: None,
            sun_deg: self.sun_size,
        };
        sun.check()
            .map_err(|e| anyhow::anyhow!("--sun-size: {e}"))?;
        Ok(LightSizes {
            radius: self.light_size,
            sun_deg: self.sun_size,
        })
    }
}
