//! What the page can change, as a query string (`scene=atrium&technique=layered&lights=64`):
//! [`WebSettings`], parsed with every key and value checked by name, and the camera relative
//! to the scene's own that the page's mouse, touch and keys move ([`View`]).

use manyshadows::scene::light_space::PointShadows;
use manyshadows::scene::Camera;
use manyshadows::{LightLoop, Pcf, RenderSettings, Technique};

/// What the page can change. Unknown keys and bad values are errors (named), not ignored.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct WebSettings {
    pub(crate) scene: String,
    pub(crate) width: u32,
    pub(crate) height: u32,
    pub(crate) technique: Technique,
    pub(crate) point_shadows: PointShadows,
    pub(crate) pcf: Pcf,
    pub(crate) lights: Option<usize>,
    /// Seeded lights added to the scene's own (`render --add-lights N`; the page's light
    /// count for a model).
    pub(crate) add_lights: Option<usize>,
    /// The exposure (`auto`, an EV100 or `xSCALE`, as `render --exposure`); `None` follows
    /// the scene.
    pub(crate) exposure: Option<manyshadows::Exposure>,
    pub(crate) seed: u64,
    pub(crate) light_loop: LightLoop,
    /// Where the camera is, relative to the scene's own camera (the page's orbit slider, its
    /// mouse, touch and keys).
    pub(crate) view: View,
    /// Every light's size times this (the page's light-size slider: 1 = the scene's sizes,
    /// 0 = hard shadows).
    pub(crate) light_size: f32,
    /// Lights sampled per pixel (0: every light), their reuse across frames and the denoiser
    /// (`render --light-samples K --reuse --denoise`; the visibility from the technique's shadow
    /// maps, as there).
    pub(crate) light_samples: u32,
    pub(crate) reuse: bool,
    pub(crate) denoise: bool,
}

impl Default for WebSettings {
    fn default() -> Self {
        Self {
            scene: "atrium".into(),
            width: 480,
            height: 270,
            technique: Technique::default(),
            point_shadows: PointShadows::default(),
            pcf: Pcf::default(),
            lights: None,
            add_lights: None,
            exposure: None,
            seed: 1,
            light_loop: LightLoop::default(),
            view: View::default(),
            light_size: 1.0,
            light_samples: 0,
            reuse: false,
            denoise: false,
        }
    }
}

/// The largest frame side the page asks for (the renderer checks the device's own limit too).
pub(crate) const MAX_SIDE: u32 = 2048;

impl WebSettings {
    pub(crate) fn parse(query: &str) -> Result<Self, String> {
        let mut s = Self::default();
        for pair in query
            .trim_start_matches('?')
            .split('&')
            .filter(|p| !p.is_empty())
        {
            let (k, v) = pair.split_once('=').unwrap_or((pair, ""));
            let num = |what: &str| -> Result<u64, String> {
                v.parse::<u64>()
                    .map_err(|_| format!("{what} '{v}' is not a whole number"))
            };
            match k {
                "scene" => s.scene = v.to_string(),
                "w" | "width" => s.width = num("width")? as u32,
                "h" | "height" => s.height = num("height")? as u32,
                "technique" => s.technique = v.parse()?,
                "point" | "point_shadows" => s.point_shadows = v.parse()?,
                "pcf" => s.pcf = v.parse()?,
                "lights" => {
                    s.lights = if v.is_empty() || v == "default" {
                        None
                    } else {
                        Some(num("lights")? as usize)
                    }
                }
                "add_lights" => {
                    s.add_lights = if v.is_empty() || v == "0" {
                        None
                    } else {
                        Some(num("add_lights")? as usize)
                    }
                }
                "exposure" => {
                    s.exposure = if v.is_empty() || v == "default" {
                        None
                    } else {
                        Some(v.parse().map_err(|e| format!("exposure: {e}"))?)
                    }
                }
                "seed" => s.seed = num("seed")?,
                "loop" | "light_loop" => s.light_loop = v.parse()?,
                "orbit" => s.view.yaw_deg = finite(v, "orbit", "a number of degrees")?,
                "pitch" => {
                    s.view.pitch_deg = finite(v, "pitch", "a number of degrees")?;
                    if s.view.pitch_deg.abs() > 180.0 {
                        return Err(format!("pitch '{v}' is not between -180 and 180 degrees"));
                    }
                }
                "zoom" => {
                    s.view.zoom = finite(v, "zoom", "a factor")?;
                    if !(ZOOM_RANGE.0..=ZOOM_RANGE.1).contains(&s.view.zoom) {
                        return Err(format!(
                            "zoom '{v}' is not a factor from {} to {}",
                            ZOOM_RANGE.0, ZOOM_RANGE.1
                        ));
                    }
                }
                "pan_x" => s.view.pan[0] = finite(v, "pan_x", "a number")?,
                "pan_y" => s.view.pan[1] = finite(v, "pan_y", "a number")?,
                "size" => {
                    s.light_size = v
                        .parse::<f32>()
                        .ok()
                        .filter(|k| k.is_finite() && (0.0..=4.0).contains(k))
                        .ok_or_else(|| format!("size '{v}' is not a factor from 0 to 4"))?
                }
                "samples" => s.light_samples = num("samples")?.min(u64::from(u32::MAX)) as u32,
                "reuse" => s.reuse = switch(v, "reuse")?,
                "denoise" => s.denoise = switch(v, "denoise")?,
                // Keys the page itself uses.
                "report" | "auto" => {}
                _ => return Err(format!("unknown setting '{k}'")),
            }
        }
        for (name, side) in [("width", s.width), ("height", s.height)] {
            if !(1..=MAX_SIDE).contains(&side) {
                return Err(format!(
                    "{name} {side} must be between 1 and {MAX_SIDE} pixels"
                ));
            }
        }
        Ok(s)
    }

    pub(crate) fn render_settings(&self) -> RenderSettings {
        RenderSettings::default()
            .with_width(self.width)
            .with_height(self.height)
            .with_technique(self.technique)
            .with_point_shadows(self.point_shadows)
            .with_pcf(self.pcf)
            .with_light_loop(self.light_loop)
            .with_rays(
                manyshadows::RayOptions::default()
                    .with_light_samples(self.light_samples)
                    .with_reuse(self.reuse)
                    .with_denoise(self.denoise),
            )
            .with_look(manyshadows::Look {
                exposure: self.exposure,
                ..Default::default()
            })
    }
}

/// `1`/`on` or `0`/`off`.
fn switch(v: &str, key: &str) -> Result<bool, String> {
    match v {
        "1" | "on" | "true" => Ok(true),
        "0" | "off" | "false" | "" => Ok(false),
        _ => Err(format!("{key} '{v}' is not 1 or 0")),
    }
}

fn finite(v: &str, key: &str, what: &str) -> Result<f32, String> {
    v.parse::<f32>()
        .ok()
        .filter(|x| x.is_finite())
        .ok_or_else(|| format!("{key} '{v}' is not {what}"))
}

/// How far the page zooms: the camera's distance to its target times this, at most.
pub(crate) const ZOOM_RANGE: (f32, f32) = (0.02, 50.0);

/// The camera relative to the scene's own: turned about the target (yaw about the vertical,
/// pitch up and down), its distance to the target times `zoom`, and the target moved across
/// the view by `pan` (in units of the scene camera's distance to its target).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct View {
    pub(crate) yaw_deg: f32,
    pub(crate) pitch_deg: f32,
    pub(crate) zoom: f32,
    pub(crate) pan: [f32; 2],
}

impl Default for View {
    fn default() -> Self {
        Self {
            yaw_deg: 0.0,
            pitch_deg: 0.0,
            zoom: 1.0,
            pan: [0.0; 2],
        }
    }
}

impl View {
    /// The camera of `base` moved by this view; `base` itself, bit for bit, for the default.
    pub(crate) fn camera(&self, base: &Camera) -> Camera {
        if *self == View::default() {
            return *base;
        }
        let offset = base.position - base.target;
        let dist = offset.length().max(1e-6);
        let base_yaw = offset.x.atan2(offset.z);
        let base_pitch = (offset.y / dist).clamp(-1.0, 1.0).asin();
        // Short of straight up or down, where the view's up vector would flip.
        let limit = 89.0f32.to_radians();
        let pitch = (base_pitch + self.pitch_deg.to_radians()).clamp(-limit, limit);
        let yaw = base_yaw + self.yaw_deg.to_radians();
        let dir = glam::Vec3::new(
            pitch.cos() * yaw.sin(),
            pitch.sin(),
            pitch.cos() * yaw.cos(),
        );
        let right = (-dir).cross(glam::Vec3::Y).normalize_or_zero();
        let up = right.cross(-dir);
        let mut c = *base;
        c.target = base.target + (right * self.pan[0] + up * self.pan[1]) * dist;
        c.position = c.target + dir * dist * self.zoom;
        c
    }
}
