//! How shaded light becomes a pixel: the shading model ([`Shading`]), the exposure
//! ([`Exposure`]) and the tone map ([`ToneMap`]), gathered in [`Look`]. Each is `None` by
//! default and then follows the scene's [`Lighting`]:
//!
//! | scene | shading | exposure | tone map |
//! |---|---|---|---|
//! | Phong (built-in, TOML, OBJ, PLY) | Phong | ×1.4 (EV100 ≈ −0.75) | exponential |
//! | physical (glTF) | glTF BRDF | automatic: an incident-light meter at the camera target | Khronos PBR Neutral |
//!
//! so the seeds' scenes keep their look to the bit, and a glTF file is shown as every glTF
//! viewer shows it.
//!
//! **Why Khronos PBR Neutral.** It is the tone map made for showing glTF materials as their
//! author chose them: colours below 0.76 (after exposure) pass unchanged, so a base colour
//! under a light of the right exposure reads as itself, and only highlights are compressed
//! (and desaturated towards white, as film does). AgX and ACES shift hues and contrast
//! everywhere, which suits a film look but not a check against another viewer. three.js,
//! Filament and the Khronos sample viewer all have it (`NeutralToneMapping` in three.js), so a
//! frame can be compared with theirs pixel for pixel.
//!
//! **Automatic exposure.** A photographer's incident-light meter held at the point the camera
//! looks at ([`Camera::target`](manyshadows_scene::Camera)): the illuminance `E` (lux) every
//! light gives a surface there facing it (point and spot lights `I / d²` inside their range
//! and cone, with glTF's range window; directional lights their lux), and `EV100 =
//! log₂(E · 100 / 250)` (meter calibration constant C = 250). A white diffuse surface facing
//! the lights then shows at about 0.66 before tone mapping. Without light at the target the
//! exposure is EV100 0. The exposure scale is `1 / (1.2 · 2^EV100)` (the saturation-based
//! sensitivity of a 100 ISO sensor, as Filament and Frostbite write it).

use glam::Vec3;
use manyshadows_scene::{LightKind, Lighting, Scene};

use crate::error::RenderError;

/// The shading model of every surface.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shading {
    /// Seed 004's Phong model: ambient + diffuse + specular (`shininess`).
    Phong,
    /// The glTF specification's metallic-roughness BRDF (appendix B): Lambert diffuse, GGX
    /// distribution, height-correlated Smith visibility, Schlick Fresnel.
    Pbr,
}

impl Shading {
    /// The name on the command line and in summaries.
    pub fn name(self) -> &'static str {
        match self {
            Shading::Phong => "phong",
            Shading::Pbr => "pbr",
        }
    }

    fn code(self) -> u32 {
        match self {
            Shading::Phong => 0,
            Shading::Pbr => 1,
        }
    }
}

/// How linear colour (after exposure) becomes a displayable value in 0..1.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ToneMap {
    /// `1 − e^(−x)`: the seeds' scenes, where many overlapping lights add up past 1.
    Exponential,
    /// Khronos PBR Neutral (2024): identity below 0.76, highlights compressed and
    /// desaturated towards white.
    Neutral,
    /// None: values above 1 clip.
    Clamp,
}

impl ToneMap {
    /// The name on the command line and in summaries.
    pub fn name(self) -> &'static str {
        match self {
            ToneMap::Exponential => "exponential",
            ToneMap::Neutral => "neutral",
            ToneMap::Clamp => "clamp",
        }
    }

    fn code(self) -> u32 {
        match self {
            ToneMap::Exponential => 0,
            ToneMap::Neutral => 1,
            ToneMap::Clamp => 2,
        }
    }
}

/// How bright the scene is shown.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Exposure {
    /// The incident-light meter at the camera target (module documentation).
    Auto,
    /// A photographic exposure value at ISO 100: linear colour is scaled by
    /// `1 / (1.2 · 2^EV100)`. Higher is darker; a sunny day is about 15, an office about 7.
    Ev100(f32),
    /// Linear colour times this factor (the Phong scenes' 1.4).
    Scale(f32),
}

impl std::str::FromStr for Shading {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s.trim().to_ascii_lowercase().as_str() {
            "phong" => Ok(Shading::Phong),
            "pbr" | "gltf" => Ok(Shading::Pbr),
            _ => Err(format!(
                "unknown shading model '{s}' (expected phong or pbr)"
            )),
        }
    }
}

impl std::str::FromStr for ToneMap {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s.trim().to_ascii_lowercase().as_str() {
            "exponential" => Ok(ToneMap::Exponential),
            "neutral" => Ok(ToneMap::Neutral),
            "clamp" | "none" => Ok(ToneMap::Clamp),
            _ => Err(format!(
                "unknown tone map '{s}' (expected neutral, exponential or clamp)"
            )),
        }
    }
}

impl std::str::FromStr for Exposure {
    type Err = String;
    /// `auto`, an EV100 (`9.5`, `-2`), or a scale written `x1.4` (`×1.4`).
    fn from_str(s: &str) -> Result<Self, String> {
        let t = s.trim().to_ascii_lowercase();
        if t == "auto" {
            return Ok(Exposure::Auto);
        }
        let (scale, num) = match t.strip_prefix('x').or_else(|| t.strip_prefix('×')) {
            Some(rest) => (true, rest),
            None => (false, t.as_str()),
        };
        let v: f32 = num.parse().map_err(|_| {
            format!("'{s}' is not an exposure (expected auto, an EV100 such as 9.5, or a scale such as x1.4)")
        })?;
        let e = if scale {
            Exposure::Scale(v)
        } else {
            Exposure::Ev100(v)
        };
        Look {
            exposure: Some(e),
            ..Look::default()
        }
        .validate()
        .map_err(|e| e.to_string())?;
        Ok(e)
    }
}

/// The exposure scale of the Phong scenes' look (what every frame used before there was a
/// choice).
pub const PHONG_EXPOSURE: f32 = 1.4;

/// The shading model, exposure and tone map of a frame; `None` follows the scene (module
/// documentation).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Look {
    /// Phong or the glTF BRDF.
    pub shading: Option<Shading>,
    /// Exposure.
    pub exposure: Option<Exposure>,
    /// Tone map.
    pub tone_map: Option<ToneMap>,
}

/// A [`Look`] decided for a scene and camera.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ResolvedLook {
    /// The shading model.
    pub shading: Shading,
    /// The tone map.
    pub tone_map: ToneMap,
    /// The factor linear colour is multiplied by before the tone map.
    pub exposure_scale: f32,
    /// The same exposure as an EV100.
    pub ev100: f32,
    /// Whether the exposure was metered (`Exposure::Auto`), and the illuminance metered in
    /// lux (scene units for a Phong scene).
    pub metered: Option<f32>,
    /// The scene's light units.
    pub lighting: Lighting,
    /// Whether any material emits light.
    pub emission: bool,
}

fn scale_of_ev100(ev: f32) -> f32 {
    1.0 / (1.2 * ev.exp2())
}

fn ev100_of_scale(scale: f32) -> f32 {
    (1.0 / (1.2 * scale)).log2()
}

impl Look {
    /// Checks an explicit exposure: an EV100 within ±64, a scale finite and above 0
    /// ([`RenderError::InvalidOption`] naming `look.exposure`).
    pub fn validate(&self) -> Result<(), RenderError> {
        let bad = |value: String, expected: &'static str| {
            Err(RenderError::InvalidOption {
                option: "look.exposure",
                value,
                expected,
            })
        };
        match self.exposure {
            Some(Exposure::Ev100(ev)) if !ev.is_finite() || ev.abs() > 64.0 => {
                bad(format!("EV100 {ev}"), "an EV100 in -64..=64")
            }
            Some(Exposure::Scale(s)) if !(s.is_finite() && s > 0.0) => {
                bad(format!("scale {s}"), "a finite scale above 0")
            }
            _ => Ok(()),
        }
    }

    /// The choices for `scene` seen from its camera.
    pub fn resolve(&self, scene: &Scene) -> ResolvedLook {
        let physical = scene.lighting == Lighting::Physical;
        let shading = self.shading.unwrap_or(if physical {
            Shading::Pbr
        } else {
            Shading::Phong
        });
        let tone_map = self.tone_map.unwrap_or(if physical {
            ToneMap::Neutral
        } else {
            ToneMap::Exponential
        });
        let exposure = self.exposure.unwrap_or(if physical {
            Exposure::Auto
        } else {
            Exposure::Scale(PHONG_EXPOSURE)
        });
        let (exposure_scale, ev100, metered) = match exposure {
            Exposure::Scale(s) => (s, ev100_of_scale(s), None),
            Exposure::Ev100(ev) => (scale_of_ev100(ev), ev, None),
            Exposure::Auto => {
                let e = incident_illuminance(scene, scene.camera.target);
                let ev = if e > 0.0 && e.is_finite() {
                    (e * 100.0 / METER_CALIBRATION).log2()
                } else {
                    0.0
                };
                (scale_of_ev100(ev), ev, Some(e))
            }
        };
        ResolvedLook {
            shading,
            tone_map,
            exposure_scale,
            ev100,
            metered,
            lighting: scene.lighting,
            emission: scene
                .materials
                .iter()
                .any(|m| m.emissive.max_element() > 0.0),
        }
    }
}

/// The lighting shader's compile-time choices: constants rather than uniforms, so the Phong
/// scenes' shader is the very code it was before there was a choice (a branch on a uniform
/// would change how the compiler fuses its multiply-adds, and a few pixels by one level).
/// What plugs into the pass (sampled lights, their histories, probes) brings its own
/// constants with its part.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadingConsts {
    /// Phong or the glTF BRDF.
    pub shading: Shading,
    /// glTF's falloff (inverse square and range window) instead of the lights' attenuation.
    pub physical_falloff: bool,
    /// Light colours times this (1: no multiplication).
    pub light_scale: f32,
    /// The tone map.
    pub tone_map: ToneMap,
    /// An exposure scale fixed for the renderer's life (every exposure but the metered
    /// one); `None`: the frame's uniform.
    pub fixed_exposure: Option<f32>,
    /// Whether emission is added (only scenes with emissive materials pay for it).
    pub emission: bool,
    /// Whether the G-buffer keeps emissive texels to multiply emission by.
    pub emission_texture: bool,
    /// Whether the pass writes linear radiance (before exposure and tone map) into a float
    /// target: a probe's faces.
    pub linear_out: bool,
    /// Whether sized lights' soft shadows are compiled in (always, but for the test that
    /// lights of size 0 give the frame the pass gives without them, byte for byte).
    pub soft_shadows: bool,
}

impl Default for ShadingConsts {
    fn default() -> Self {
        Self {
            shading: Shading::Phong,
            physical_falloff: false,
            light_scale: 1.0,
            tone_map: ToneMap::Exponential,
            fixed_exposure: Some(PHONG_EXPOSURE),
            emission: false,
            emission_texture: false,
            linear_out: false,
            soft_shadows: true,
        }
    }
}

impl ShadingConsts {
    /// The WGSL constants (`SHADING_MODEL`, `PHYSICAL_FALLOFF`, `LIGHT_SCALE`, `TONE_MAP`,
    /// `EXPOSURE_IS_FIXED`, `FIXED_EXPOSURE`, `EMISSION`, `EMISSION_TEXTURE`, `LINEAR_OUT`,
    /// `SOFT_SHADOWS`).
    pub(crate) fn wgsl(&self) -> String {
        format!(
            "const SHADING_MODEL: u32 = {}u;\nconst PHYSICAL_FALLOFF: bool = {};\n\
             const LIGHT_SCALE: f32 = {:?}f;\nconst TONE_MAP: u32 = {}u;\n\
             const EXPOSURE_IS_FIXED: bool = {};\nconst FIXED_EXPOSURE: f32 = {:?}f;\n\
             const EMISSION: bool = {};\nconst EMISSION_TEXTURE: bool = {};\n\
             const LINEAR_OUT: bool = {};\nconst SOFT_SHADOWS: bool = {};\n",
            self.shading.code(),
            self.physical_falloff,
            self.light_scale,
            self.tone_map.code(),
            self.fixed_exposure.is_some(),
            self.fixed_exposure.unwrap_or(1.0),
            self.emission,
            self.emission_texture,
            self.linear_out,
            self.soft_shadows,
        )
    }
}

/// Incident-light meter calibration constant (lux · s at ISO 100).
const METER_CALIBRATION: f32 = 250.0;

/// glTF's range window of a point or spot light: `clamp(1 − (d / range)⁴, 0, 1)²`.
pub fn range_window(d: f32, range: f32) -> f32 {
    let x = d / range;
    (1.0 - x * x * x * x).clamp(0.0, 1.0).powi(2)
}

/// The illuminance (lux in a physical scene) every light gives a surface at `p` facing it:
/// what an incident-light meter reads there. Shadows are not considered.
pub fn incident_illuminance(scene: &Scene, p: Vec3) -> f32 {
    let physical = scene.lighting == Lighting::Physical;
    scene
        .lights
        .iter()
        .map(|l| {
            let peak = l.diffuse.max_element().max(0.0);
            let (position, range) = match l.kind {
                LightKind::Directional { .. } => return peak,
                LightKind::Point { position, range } => (position, range),
                LightKind::Spot {
                    position,
                    direction,
                    cutoff_deg,
                    range,
                } => {
                    let to = (p - position).normalize_or_zero();
                    if to.dot(direction.normalize_or_zero()) < cutoff_deg.to_radians().cos() {
                        return 0.0;
                    }
                    (position, range)
                }
            };
            let d = p.distance(position);
            if d > range {
                return 0.0;
            }
            if physical {
                peak * range_window(d, range) / (d * d).max(0.01)
            } else {
                let a = l.attenuation;
                peak / (a.constant + a.linear * d + a.quadratic * d * d).max(1e-6)
            }
        })
        .sum()
}

impl ResolvedLook {
    /// What `FrameUniforms::look` and `FrameUniforms::modes` hold: the exposure scale (a
    /// metered one changes with the camera) and the tone map.
    pub(crate) fn uniforms(&self) -> ([f32; 4], [u32; 4]) {
        (
            [self.exposure_scale, 0.0, 0.0, 0.0],
            [self.tone_map.code(), 0, 0, 0],
        )
    }

    /// What the lighting shader is compiled with (these are fixed for a renderer).
    pub(crate) fn consts(&self) -> ShadingConsts {
        // Light colours are scaled so that one model's units read right in the other: a
        // Phong light of colour 1 lights a white surface to 1, a physical one of E lux to
        // E / π; shading a Phong scene physically multiplies by π, and the other way round
        // divides (no multiplication at all when model and units agree).
        let light_scale = match (self.shading, self.lighting) {
            (Shading::Pbr, Lighting::Phong) => std::f32::consts::PI,
            (Shading::Phong, Lighting::Physical) => std::f32::consts::FRAC_1_PI,
            _ => 1.0,
        };
        ShadingConsts {
            shading: self.shading,
            physical_falloff: self.lighting == Lighting::Physical,
            light_scale,
            tone_map: self.tone_map,
            fixed_exposure: self.metered.is_none().then_some(self.exposure_scale),
            emission: self.emission,
            emission_texture: false,
            linear_out: false,
            soft_shadows: true,
        }
    }

    /// One line for summaries: `glTF BRDF, EV100 9.3 (metered: 1250 lx at the camera
    /// target), Khronos PBR Neutral`.
    pub fn describe(&self) -> String {
        let shading = match self.shading {
            Shading::Phong => "Phong shading",
            Shading::Pbr => "glTF BRDF shading",
        };
        let unit = match self.lighting {
            Lighting::Physical => " lx",
            Lighting::Phong => " (scene units)",
        };
        let exposure = match self.metered {
            Some(e) => format!(
                "EV100 {:.2} (automatic: {e:.4}{unit} metered at the camera target)",
                self.ev100
            ),
            None => format!("EV100 {:.2} (×{:.4})", self.ev100, self.exposure_scale),
        };
        let tone = match self.tone_map {
            ToneMap::Exponential => "exponential tone map",
            ToneMap::Neutral => "Khronos PBR Neutral tone map",
            ToneMap::Clamp => "no tone map (clamped)",
        };
        format!("{shading}, {exposure}, {tone}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use manyshadows_scene::{Attenuation, Camera, Light};

    fn scene(lighting: Lighting, lights: Vec<Light>) -> Scene {
        Scene {
            lights,
            lighting,
            camera: Camera::look_at(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO),
            ..Default::default()
        }
    }

    fn point(position: Vec3, range: f32, intensity: f32) -> Light {
        Light {
            kind: LightKind::Point { position, range },
            ambient: Vec3::ZERO,
            diffuse: Vec3::splat(intensity),
            specular: Vec3::splat(intensity),
            attenuation: Attenuation {
                constant: 1.0,
                linear: 0.0,
                quadratic: 1.0,
            },
            casts_shadows: true,
            shadow_resolution: 256,
            size: 0.0,
        }
    }

    #[test]
    fn phong_scenes_keep_their_look() {
        let r = Look::default().resolve(&scene(Lighting::Phong, vec![]));
        assert_eq!(r.shading, Shading::Phong);
        assert_eq!(r.tone_map, ToneMap::Exponential);
        assert_eq!(r.exposure_scale, PHONG_EXPOSURE);
        assert_eq!(
            r.consts(),
            ShadingConsts::default(),
            "the shader as it always was"
        );
    }

    #[test]
    fn the_meter_reads_the_inverse_square_and_sets_ev100() {
        // 400 cd at 2 m: 100 lx (the window at 2 of 20 is 0.9999²).
        let s = scene(
            Lighting::Physical,
            vec![point(Vec3::new(0.0, 2.0, 0.0), 20.0, 400.0)],
        );
        let e = incident_illuminance(&s, Vec3::ZERO);
        assert!((e - 100.0 * range_window(2.0, 20.0)).abs() < 1e-3, "{e}");
        let r = Look::default().resolve(&s);
        assert_eq!(r.shading, Shading::Pbr);
        assert_eq!(r.tone_map, ToneMap::Neutral);
        // EV100 = log2(100 · 100 / 250) = log2(40) ≈ 5.32.
        assert!((r.ev100 - 40f32.log2()).abs() < 1e-3, "{}", r.ev100);
        // A white Lambertian surface facing the light: E / π · scale ≈ 0.66.
        let white = e / std::f32::consts::PI * r.exposure_scale;
        assert!((white - 0.663).abs() < 0.01, "{white}");
        // Out of range: nothing metered, EV100 0.
        let dark = scene(
            Lighting::Physical,
            vec![point(Vec3::new(0.0, 9.0, 0.0), 5.0, 400.0)],
        );
        assert_eq!(Look::default().resolve(&dark).ev100, 0.0);
    }

    #[test]
    fn explicit_choices_win_and_bad_exposures_are_refused() {
        let look = Look {
            shading: Some(Shading::Phong),
            exposure: Some(Exposure::Ev100(3.0)),
            tone_map: Some(ToneMap::Clamp),
        };
        let r = look.resolve(&scene(Lighting::Physical, vec![]));
        assert_eq!((r.shading, r.tone_map), (Shading::Phong, ToneMap::Clamp));
        assert!((r.exposure_scale - 1.0 / 9.6).abs() < 1e-6);
        assert!(
            r.consts().light_scale < 0.5,
            "physical light shaded with Phong is divided by π"
        );
        for bad in [
            Exposure::Ev100(f32::NAN),
            Exposure::Ev100(100.0),
            Exposure::Scale(0.0),
            Exposure::Scale(f32::INFINITY),
        ] {
            let l = Look {
                exposure: Some(bad),
                ..Look::default()
            };
            assert!(l.validate().is_err(), "{bad:?}");
        }
    }

    #[test]
    fn names_parse_as_the_command_line_writes_them() {
        assert_eq!("pbr".parse::<Shading>(), Ok(Shading::Pbr));
        assert_eq!("Phong".parse::<Shading>(), Ok(Shading::Phong));
        assert!("lambert".parse::<Shading>().is_err());
        assert_eq!("neutral".parse::<ToneMap>(), Ok(ToneMap::Neutral));
        assert_eq!("clamp".parse::<ToneMap>(), Ok(ToneMap::Clamp));
        assert!("agx".parse::<ToneMap>().is_err());
        assert_eq!("auto".parse::<Exposure>(), Ok(Exposure::Auto));
        assert_eq!("9.5".parse::<Exposure>(), Ok(Exposure::Ev100(9.5)));
        assert_eq!("-2".parse::<Exposure>(), Ok(Exposure::Ev100(-2.0)));
        assert_eq!("x1.4".parse::<Exposure>(), Ok(Exposure::Scale(1.4)));
        for bad in ["", "bright", "nan", "1e9", "x0", "x-1"] {
            assert!(bad.parse::<Exposure>().is_err(), "{bad:?}");
        }
    }
}
