//! What the open window holds between frames: its surface, the GPU and the renderer, the
//! panel's choices (a change of technique, point shadows, PCF, caching, budget, visibility or
//! light size rebuilds the renderer), egui's state, the fly camera, the overlays and the last frame's
//! numbers the panel shows.

use std::sync::Arc;
use std::time::Instant;

use anyhow::Result;
use manyshadows::scene::light_size::LightSizes;
use manyshadows::scene::light_space::PointShadows;
use manyshadows::scene::Scene;
use manyshadows::{wgpu, Fills, GpuContext, Pcf, RenderSettings, Renderer, Technique};
use winit::window::Window;

use crate::view::args::ViewArgs;
use crate::view::camera::FlyCamera;
use crate::view::overlays::Overlays;
use crate::view::player::Player;

/// What the panel edits; a change of technique, point shadows or PCF rebuilds the renderer.
#[derive(Clone, Copy, PartialEq)]
pub(super) struct Choice {
    pub(super) technique: Technique,
    pub(super) point_shadows: PointShadows,
    pub(super) pcf: Pcf,
    pub(super) cache: bool,
    /// At most this many shadow views drawn per frame (atlas techniques).
    pub(super) budget: Option<u32>,
    /// The hard visibility mask is computed (for the per-light view).
    pub(super) visibility: bool,
    /// Every light's size times this (1: the scene's sizes, 0: hard shadows).
    pub(super) light_size: f32,
    /// Shading model, exposure and tone map (from the command line).
    pub(super) look: manyshadows::Look,
    /// Lights traced per pixel (shadow rays; 0: every light).
    pub(super) light_samples: u32,
    /// Shadow rays denoised / accumulated over frames.
    pub(super) denoise: bool,
    /// Sampled lights reused across frames.
    pub(super) reuse: bool,
    /// The shadow maps' soft-shadow taps and largest penumbra (`--soft-taps`,
    /// `--max-penumbra`).
    pub(super) soft: manyshadows::SoftShadows,
    /// With `reuse`: between neighbours too (`--spatial`).
    pub(super) spatial: manyshadows::SpatialReuse,
    /// Stereo eyes this far apart, side by side (`--stereo`).
    pub(super) stereo: Option<f32>,
    /// How the probes' faces are drawn (`--probe-passes`).
    pub(super) probe_passes: manyshadows::ProbePasses,
    /// The technique options of the flags (irregular and virtual maps, the rays' area
    /// samples and seed); the panel's light samples, denoiser and reuse above take the place
    /// of theirs.
    pub(super) options: manyshadows_cli::TechniqueArgs,
    /// What single-sided surfaces shadow (`--single-sided-shadows`).
    pub(super) single_sided: manyshadows::SingleSidedShadows,
}

/// The open window and everything drawn into it.
pub(super) struct State {
    pub(super) window: Arc<Window>,
    pub(super) surface: wgpu::Surface<'static>,
    pub(super) config: wgpu::SurfaceConfiguration,
    pub(super) ctx: GpuContext,
    pub(super) renderer: Renderer,
    pub(super) choice: Choice,
    /// The panel's light count (applied with its button), the layout's seed and the light
    /// sizes the flags ask for (kept when the panel scatters new lights).
    pub(super) light_count: usize,
    pub(super) seed: u64,
    pub(super) light_sizes: LightSizes,
    pub(super) egui_ctx: egui::Context,
    pub(super) egui_state: egui_winit::State,
    pub(super) egui_renderer: egui_wgpu::Renderer,
    /// The panel is shown (F1).
    pub(super) panel: bool,
    pub(super) fly: FlyCamera,
    pub(super) last_frame: Instant,
    pub(super) started: Instant,
    pub(super) frames: u64,
    pub(super) gpu_ms: manyshadows::GpuTimes,
    pub(super) frame_ms: f64,
    pub(super) message: Option<String>,
    /// `--insist`: frames of minutes are not refused.
    pub(super) insist: bool,
    pub(super) overlays: Overlays,
    /// Shadow views drawn by the last frame (fewer than planned when caching keeps maps).
    pub(super) views_drawn: u64,
    /// The last frame's views left waiting by a budget: (stale, oldest in frames, unshadowed).
    pub(super) views_waiting: (u32, u32, u32),
    /// A glTF file's animation (`None`: the scene does not move by itself).
    pub(super) player: Option<Player>,
}

/// The renderer's settings for a `width`×`height` frame with `c` (the budget only for
/// techniques that fill an atlas).
/// Whether technique `t` takes sampled lights: shadow rays, or shadow maps (an atlas or
/// virtual pages) that answer for each sampled light; irregular maps answer every light.
pub(super) fn samples_lights(t: manyshadows::Technique) -> bool {
    matches!(t.info().fills, Fills::Rays | Fills::Atlas | Fills::Pages)
}

fn settings(width: u32, height: u32, c: Choice) -> RenderSettings {
    let samples = if samples_lights(c.technique) {
        c.light_samples
    } else {
        0
    };
    let reused = c.reuse && c.stereo.is_none() && samples > 0;
    // Two eyes split the window: an even width (an odd window's last column is scaled over).
    let width = if c.stereo.is_some() {
        (width & !1).max(2)
    } else {
        width
    };
    RenderSettings::default()
        .with_width(width)
        .with_height(height)
        .with_stereo(c.stereo.map(manyshadows::Stereo::new))
        .with_probe_passes(c.probe_passes)
        .with_technique(c.technique)
        .with_point_shadows(c.point_shadows)
        .with_pcf(c.pcf)
        .with_shadow(
            manyshadows::ShadowOptions::default().with_casters(
                manyshadows::CasterOptions::default().with_single_sided(c.single_sided),
            ),
        )
        .with_cache_shadows(c.cache)
        .with_shadow_budget(
            c.budget
                .filter(|_| c.technique.info().fills == Fills::Atlas),
        )
        .with_visibility(c.visibility)
        .with_look(c.look)
        .with_soft(c.soft)
        .with_irregular(c.options.irregular())
        .with_virtual_maps(c.options.virtual_maps())
        .with_rays(
            c.options
                .rays()
                // The panel offers light samples where the technique takes them (irregular
                // maps refuse them); the slider keeps its value for when it comes back.
                .with_light_samples(samples)
                // Reuse and the denoiser follow one camera: not with stereo eyes; with shadow
                // maps they need samples (rays accumulate area samples without).
                .with_denoise(
                    c.denoise
                        && c.stereo.is_none()
                        && (c.technique.info().fills == Fills::Rays || samples > 0),
                )
                .with_reuse(reused)
                .with_spatial(if reused {
                    c.spatial
                } else {
                    manyshadows::SpatialReuse::Off
                }),
        )
}

impl State {
    /// The state of a window whose `surface` is configured as `config`: the renderer with
    /// the choices `args` starts with, egui set up for the window, the camera at the scene's.
    pub(super) fn new(
        window: Arc<Window>,
        surface: wgpu::Surface<'static>,
        config: wgpu::SurfaceConfiguration,
        ctx: GpuContext,
        scene: &Scene,
        args: &ViewArgs,
    ) -> Result<State> {
        let choice = Choice {
            technique: args.technique,
            point_shadows: args.point_shadows,
            pcf: args.pcf,
            cache: !args.no_cache,
            budget: args.shadow_budget,
            visibility: args.show_visibility.is_some(),
            light_size: 1.0,
            look: args.look.look(),
            light_samples: args.per_technique.light_samples,
            denoise: args.per_technique.denoise,
            reuse: args.per_technique.reuse,
            soft: args.soft.soft(),
            spatial: args.per_technique.spatial,
            options: args.per_technique,
            stereo: args.stereo,
            probe_passes: args.probe_passes,
            single_sided: args.single_sided_shadows,
        };
        let player = Player::new(scene, args)?;
        let renderer = Renderer::new(&ctx, scene, settings(config.width, config.height, choice))?;
        if !args.insist {
            if let Some(why) = manyshadows_cli::shadow_work_refusal(&renderer) {
                anyhow::bail!("{why}");
            }
        }
        let egui_ctx = egui::Context::default();
        let egui_state = egui_winit::State::new(
            egui_ctx.clone(),
            egui::ViewportId::ROOT,
            &window,
            Some(window.scale_factor() as f32),
            None,
            Some(ctx.limits().max_texture_dimension_2d as usize),
        );
        let egui_renderer = egui_wgpu::Renderer::new(
            &ctx.device,
            config.format,
            egui_wgpu::RendererOptions::default(),
        );
        log::info!("viewer: {} on {}", args.scene, ctx.describe());
        Ok(State {
            window,
            surface,
            config,
            ctx,
            renderer,
            choice,
            light_count: scene.lights.len(),
            seed: args.seed,
            light_sizes: args.light_sizes.sizes()?,
            egui_ctx,
            egui_state,
            egui_renderer,
            panel: !args.hide_panel,
            fly: FlyCamera::new(scene.camera),
            last_frame: Instant::now(),
            started: Instant::now(),
            frames: 0,
            gpu_ms: Default::default(),
            frame_ms: 0.0,
            message: None,
            insist: args.insist,
            views_drawn: 0,
            views_waiting: (0, 0, 0),
            player,
            overlays: Overlays::new(
                args.show_atlas,
                args.show_visibility.or(args.follow).unwrap_or(0),
                args.follow,
            ),
        })
    }

    /// A new renderer for `scene` (at the current camera) with `choice`; a choice this device
    /// cannot render is said on the panel and the old renderer kept.
    pub(super) fn rebuild(&mut self, scene: &Scene, choice: Choice) {
        let mut s = scene.clone();
        s.camera = self.fly.camera;
        for l in &mut s.lights {
            l.size *= choice.light_size;
            if matches!(l.kind, manyshadows::scene::LightKind::Directional { .. }) {
                l.size = l.size.min(manyshadows::scene::MAX_ANGULAR_SIZE_DEG * 0.99);
            }
        }
        match Renderer::new(
            &self.ctx,
            &s,
            settings(self.config.width, self.config.height, choice),
        ) {
            // A frame of minutes would freeze the window: said, and the old renderer kept.
            Ok(r) => match manyshadows_cli::shadow_work_refusal(&r).filter(|_| !self.insist) {
                Some(why) => self.message = Some(why),
                None => {
                    self.renderer = r;
                    self.choice = choice;
                    self.message = None;
                    if let Some(p) = &mut self.player {
                        p.forget();
                    }
                }
            },
            // Unsupported choices (multiview without the feature, say) are said, not fatal.
            Err(e) => self.message = Some(format!("{e}")),
        }
    }
}
