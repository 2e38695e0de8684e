//! The panel's pictures: the shadow atlas (or the virtual maps' page pool) and one light's
//! hard visibility, read back from the renderer at most once a second while shown (a
//! read-back of a 4096² atlas is 64 MiB) and kept as egui textures between read-backs.

use std::time::Instant;

use manyshadows::Renderer;

/// The pictures, what the panel says about them, and the light they (and the camera, when
/// following) are about.
#[derive(Default)]
pub(super) struct Overlays {
    /// The atlas picture is shown.
    pub(super) atlas: bool,
    pub(super) atlas_texture: Option<egui::TextureHandle>,
    pub(super) atlas_note: String,
    /// The light whose visibility is shown.
    pub(super) light: usize,
    pub(super) visibility_texture: Option<egui::TextureHandle>,
    pub(super) visibility_note: String,
    refreshed: Option<Instant>,
    /// Follow this light: the camera sits at it and looks where it shines.
    pub(super) follow: Option<usize>,
}

impl Overlays {
    /// Nothing read back yet: the atlas shown or not, the light shown (and followed).
    pub(super) fn new(atlas: bool, light: usize, follow: Option<usize>) -> Overlays {
        Overlays {
            atlas,
            light,
            follow,
            ..Default::default()
        }
    }

    /// Reads the shown pictures back from `renderer` into `egui` textures, once a second at
    /// most; `visibility` says whether the per-light picture is shown (the renderer then
    /// computes the mask it reads).
    pub(super) fn refresh(
        &mut self,
        renderer: &mut Renderer,
        visibility: bool,
        egui_ctx: &egui::Context,
    ) {
        let due = self
            .refreshed
            .is_none_or(|t| t.elapsed().as_secs_f32() >= 1.0);
        if !due || !(self.atlas || visibility) {
            return;
        }
        self.refreshed = Some(Instant::now());
        if self.atlas {
            self.refresh_atlas(renderer, egui_ctx);
        }
        if visibility {
            self.refresh_visibility(renderer, egui_ctx);
        }
    }

    fn refresh_atlas(&mut self, renderer: &Renderer, egui_ctx: &egui::Context) {
        // The atlas, or the page pool; a technique that fills the mask has neither.
        match renderer.shadow_picture() {
            Ok(p) => {
                let (side, rgb, what) = (p.side, p.rgb, p.description);
                let (w, small) = shrink_rgb(side, &rgb, 256);
                let image = egui::ColorImage::from_rgb([w, w], &small);
                self.atlas_texture =
                    Some(egui_ctx.load_texture("atlas", image, Default::default()));
                self.atlas_note = format!("{what}, shown at {w}²");
            }
            Err(e) => {
                self.atlas_texture = None;
                self.atlas_note = e.to_string();
            }
        }
    }

    fn refresh_visibility(&mut self, renderer: &mut Renderer, egui_ctx: &egui::Context) {
        // One more frame, read back with its visibility mask.
        match renderer.render() {
            Ok(frame) => match frame.visibility {
                Some(v) if v.lights > 0 => {
                    let k = self.light.min(v.lights as usize - 1);
                    let grey = v.light_image(k as u32);
                    let image =
                        egui::ColorImage::from_gray([v.width as usize, v.height as usize], &grey);
                    self.visibility_texture =
                        Some(egui_ctx.load_texture("visibility", image, Default::default()));
                    self.visibility_note = format!("light {k}: white = lit, black = shadowed");
                }
                _ => self.visibility_note = "no lights".into(),
            },
            Err(e) => self.visibility_note = e.to_string(),
        }
    }
}

/// `rgb` (`side`² pixels) shrunk by an integer factor to at most `max` per side (nearest).
fn shrink_rgb(side: u32, rgb: &[u8], max: u32) -> (usize, Vec<u8>) {
    let f = side.div_ceil(max).max(1) as usize;
    let w = side as usize / f;
    let mut out = Vec::with_capacity(w * w * 3);
    for y in 0..w {
        for x in 0..w {
            let i = (y * f * side as usize + x * f) * 3;
            out.extend_from_slice(&rgb[i..i + 3]);
        }
    }
    (w, out)
}
