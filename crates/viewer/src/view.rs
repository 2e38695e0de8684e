//! The viewer: the renderer in a window (winit + a wgpu surface), with a fly camera
//! and an on-screen panel (egui) to switch technique, point-shadow mode, PCF, light count and
//! caching at run time and to read the frame's GPU time per stage, lights, shadow views and
//! shadow memory.
//!
//! Each frame the renderer draws straight into the window's surface texture
//! (`Renderer::render_to`), then egui draws the panel over it. A camera script (`--script`)
//! replaces the fly camera, one camera per frame, and `--exit-after` ends the run, so a test
//! can drive the window and compare a screenshot of it with `render`'s frame.

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use anyhow::{bail, Context as _, Result};
use clap::Args;
use glam::{Mat4, Vec3};
use manyshadows::scene::light_space::PointShadows;
use manyshadows::scene::{Camera, LightKind, Scene};
use manyshadows::{wgpu, Fills, GpuContext, Pcf, RenderSettings, Renderer, Technique};
use winit::application::ApplicationHandler;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::keyboard::{KeyCode, PhysicalKey};
use winit::window::{Window, WindowId};

#[derive(Args, Debug, Clone)]
pub struct ViewArgs {
    /// Built-in scene name or a TOML scene file (as for `render`).
    #[arg(long, default_value = "atrium")]
    scene: String,
    /// Mesh file for the dragon scene (.obj, .gltf/.glb, .ply, .ply.gz).
    #[arg(long)]
    mesh: Option<PathBuf>,
    /// Number of lights, placed by a seeded layout (default: the scene's own lights); the
    /// panel changes it at run time.
    #[arg(long)]
    lights: Option<usize>,
    /// Seed of the light layout.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Shadow technique to start with (as for `render`; the panel switches it).
    #[arg(long, default_value_t = Technique::default(), value_parser = manyshadows_cli::parse_technique)]
    technique: Technique,
    /// Point-light shadows to start with: cube or dual-paraboloid.
    #[arg(long, default_value = "cube", value_parser = manyshadows_cli::parse_point_shadows)]
    point_shadows: PointShadows,
    /// Filtering to start with: off, 2x2 or 3x3.
    #[arg(long, default_value = "2x2", value_parser = manyshadows_cli::parse_pcf)]
    pcf: Pcf,
    /// Start with every shadow map drawn anew each frame (the panel's "keep unchanged maps"
    /// box unticked); by default the maps (pages) of views that saw no change are kept.
    #[arg(long, conflicts_with = "shadow_budget")]
    no_cache: bool,
    /// Keep what did not change between frames: the default (kept for older command lines).
    #[arg(long, hide = true, conflicts_with = "no_cache")]
    cache: bool,
    /// Draw at most N shadow views per frame (atlas techniques; with the caching): the rest
    /// wait their turn, served from their older depth or unshadowed until drawn (the panel
    /// counts them).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    shadow_budget: Option<u32>,
    /// Move the smallest caster in a circle and sway the first spot or point light (of two
    /// or more): only the shadow maps that see the caster or belong to that light are
    /// redrawn (unless --no-cache; the panel counts them).
    #[arg(long)]
    animate: bool,
    /// Camera to start from, `PX,PY,PZ,TX,TY,TZ` (default: the scene's camera).
    #[arg(long, value_parser = manyshadows_cli::parse_camera, allow_hyphen_values = true)]
    camera: Option<[f32; 6]>,
    /// Window width (the frame is rendered at the window's size).
    #[arg(long, default_value_t = 960)]
    width: u32,
    /// Window height.
    #[arg(long, default_value_t = 540)]
    height: u32,
    /// Camera script: one camera per line, `PX PY PZ TX TY TZ` (commas allowed, `#`
    /// comments); frame k uses line k, and the last camera stays after the script ends.
    #[arg(long)]
    script: Option<PathBuf>,
    /// Close the window after this many frames.
    #[arg(long)]
    exit_after: Option<u64>,
    /// Start with the panel hidden (F1 toggles it).
    #[arg(long)]
    hide_panel: bool,
    /// Start with the shadow-atlas picture shown (read back once a second).
    #[arg(long)]
    show_atlas: bool,
    /// Start with this light's hard visibility shown (white = lit; read back once a second).
    #[arg(long)]
    show_visibility: Option<usize>,
    /// Start following this light (the camera at the light, looking where it shines).
    #[arg(long)]
    follow: Option<usize>,
    #[command(flatten)]
    gpu: manyshadows_cli::GpuArgs,
}

/// Help shown in the panel and by `--help`.
pub(crate) const CONTROLS: &str = "W/A/S/D move, Q/E down/up, right mouse button + drag look, \
     wheel changes speed, F1 panel, Esc quits";

fn parse_script(text: &str) -> Result<Vec<[f32; 6]>> {
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let line = line.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        out.push(
            manyshadows_cli::parse_camera(line)
                .map_err(|e| anyhow::anyhow!("script line {}: {e}", i + 1))?,
        );
    }
    if out.is_empty() {
        bail!("the script has no camera lines");
    }
    Ok(out)
}

/// Runs the viewer until the window closes.
pub(crate) fn run(args: &ViewArgs) -> Result<()> {
    if args.width == 0 || args.height == 0 {
        bail!("--width and --height must be at least 1");
    }
    let script = match &args.script {
        Some(p) => Some(parse_script(
            &std::fs::read_to_string(p).with_context(|| format!("reading {}", p.display()))?,
        )?),
        None => None,
    };
    let scene = load(args)?;
    for (flag, k) in [
        ("--show-visibility", args.show_visibility),
        ("--follow", args.follow),
    ] {
        if let Some(k) = k.filter(|&k| k >= scene.lights.len()) {
            bail!(
                "{flag} {k}: the scene has {} lights (0 to {})",
                scene.lights.len(),
                scene.lights.len().saturating_sub(1)
            );
        }
    }
    let event_loop = EventLoop::new().context(
        "opening a window needs a display: run it on a desktop, or under Xvfb \
         (`Xvfb :99 & DISPLAY=:99 manyshadows view`)",
    )?;
    let mut app = App {
        args: args.clone(),
        script,
        scene,
        state: None,
        error: None,
    };
    event_loop.run_app(&mut app)?;
    match app.error {
        Some(e) => Err(e),
        None => Ok(()),
    }
}

fn load(args: &ViewArgs) -> Result<Scene> {
    manyshadows_cli::load_scene_for_view(
        &args.scene,
        args.mesh.clone(),
        args.lights,
        args.seed,
        args.camera,
    )
}

struct App {
    args: ViewArgs,
    script: Option<Vec<[f32; 6]>>,
    scene: Scene,
    state: Option<State>,
    error: Option<anyhow::Error>,
}

/// What the panel edits; a change of technique, point shadows or PCF rebuilds the renderer.
#[derive(Clone, Copy, PartialEq)]
struct Choice {
    technique: Technique,
    point_shadows: PointShadows,
    pcf: Pcf,
    cache: bool,
    /// At most this many shadow views drawn per frame (atlas techniques).
    budget: Option<u32>,
    /// The hard visibility mask is computed (for the per-light view).
    visibility: bool,
}

struct State {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    ctx: GpuContext,
    renderer: Renderer,
    choice: Choice,
    /// The panel's light count (applied with its button) and the layout's seed.
    light_count: usize,
    seed: u64,
    egui_ctx: egui::Context,
    egui_state: egui_winit::State,
    egui_renderer: egui_wgpu::Renderer,
    panel: bool,
    camera: Camera,
    yaw: f32,
    pitch: f32,
    speed: f32,
    keys: std::collections::HashSet<KeyCode>,
    looking: bool,
    last_cursor: Option<(f64, f64)>,
    last_frame: Instant,
    started: Instant,
    frames: u64,
    gpu_ms: manyshadows::GpuTimes,
    frame_ms: f64,
    message: Option<String>,
    overlays: Overlays,
    /// Shadow views drawn by the last frame (fewer than planned when caching keeps maps).
    views_drawn: u64,
    /// The last frame's views left waiting by a budget: (stale, oldest in frames, unshadowed).
    views_waiting: (u32, u32, u32),
}

/// The panel's pictures: the shadow atlas and one light's visibility, read back at most
/// once a second while shown (a read-back of a 4096² atlas is 64 MiB).
#[derive(Default)]
struct Overlays {
    atlas: bool,
    atlas_texture: Option<egui::TextureHandle>,
    atlas_note: String,
    light: usize,
    visibility_texture: Option<egui::TextureHandle>,
    visibility_note: String,
    refreshed: Option<Instant>,
    /// Follow this light: the camera sits at it and looks where it shines.
    follow: Option<usize>,
}

fn settings(width: u32, height: u32, c: Choice) -> RenderSettings {
    RenderSettings::default()
        .with_width(width)
        .with_height(height)
        .with_technique(c.technique)
        .with_point_shadows(c.point_shadows)
        .with_pcf(c.pcf)
        .with_cache_shadows(c.cache)
        .with_shadow_budget(
            c.budget
                .filter(|_| c.technique.info().fills == Fills::Atlas),
        )
        .with_visibility(c.visibility)
}

impl App {
    fn start(&mut self, event_loop: &ActiveEventLoop) -> Result<State> {
        let title = format!("manyshadows — {}", self.args.scene);
        let window = Arc::new(
            event_loop.create_window(
                Window::default_attributes()
                    .with_title(title)
                    .with_resizable(true)
                    .with_inner_size(winit::dpi::PhysicalSize::new(
                        self.args.width,
                        self.args.height,
                    )),
            )?,
        );
        let req = self.args.gpu.request();
        let mut desc = wgpu::InstanceDescriptor::new_with_display_handle(Box::new(
            event_loop.owned_display_handle(),
        ))
        .with_env();
        desc.backends = req.resolved_backends();
        let instance = wgpu::Instance::new(desc);
        let surface = instance
            .create_surface(window.clone())
            .context("creating the window's surface")?;
        let ctx = GpuContext::with_instance(instance, &req, Some(&surface))?;
        let size = window.inner_size();
        let caps = surface.get_capabilities(&ctx.adapter);
        // egui draws in gamma space and warns on sRGB targets ("egui prefers Rgba8Unorm or
        // Bgra8Unorm"); the frame's copy (`render_to`) encodes for raw 8-bit targets itself.
        let format = caps
            .formats
            .iter()
            .copied()
            .find(|f| {
                matches!(
                    f,
                    wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Rgba8Unorm
                )
            })
            .or_else(|| caps.formats.first().copied())
            .context("the surface offers no format")?;
        let config = wgpu::SurfaceConfiguration {
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            format,
            width: size.width.max(1),
            height: size.height.max(1),
            present_mode: wgpu::PresentMode::Fifo,
            desired_maximum_frame_latency: 2,
            alpha_mode: caps.alpha_modes[0],
            view_formats: vec![],
            color_space: wgpu::SurfaceColorSpace::Auto,
        };
        surface.configure(&ctx.device, &config);
        let choice = Choice {
            technique: self.args.technique,
            point_shadows: self.args.point_shadows,
            pcf: self.args.pcf,
            cache: !self.args.no_cache,
            budget: self.args.shadow_budget,
            visibility: self.args.show_visibility.is_some(),
        };
        let renderer = Renderer::new(
            &ctx,
            &self.scene,
            settings(config.width, config.height, choice),
        )?;
        let egui_ctx = egui::Context::default();
        let egui_state = egui_winit::State::new(
            egui_ctx.clone(),
            egui::ViewportId::ROOT,
            &window,
            Some(window.scale_factor() as f32),
            None,
            Some(ctx.limits().max_texture_dimension_2d as usize),
        );
        let egui_renderer =
            egui_wgpu::Renderer::new(&ctx.device, format, egui_wgpu::RendererOptions::default());
        let camera = self.scene.camera;
        let dir = (camera.target - camera.position).normalize();
        log::info!("viewer: {} on {}", self.args.scene, ctx.describe());
        Ok(State {
            window,
            surface,
            config,
            ctx,
            renderer,
            choice,
            light_count: self.scene.lights.len(),
            seed: self.args.seed,
            egui_ctx,
            egui_state,
            egui_renderer,
            panel: !self.args.hide_panel,
            camera,
            yaw: dir.x.atan2(-dir.z),
            pitch: dir.y.clamp(-1.0, 1.0).asin(),
            speed: (camera.target - camera.position).length().max(0.5),
            keys: Default::default(),
            looking: false,
            last_cursor: None,
            last_frame: Instant::now(),
            started: Instant::now(),
            frames: 0,
            gpu_ms: Default::default(),
            frame_ms: 0.0,
            message: None,
            views_drawn: 0,
            views_waiting: (0, 0, 0),
            overlays: Overlays {
                atlas: self.args.show_atlas,
                light: self.args.show_visibility.or(self.args.follow).unwrap_or(0),
                follow: self.args.follow,
                ..Default::default()
            },
        })
    }
}

impl State {
    fn rebuild(&mut self, scene: &Scene, choice: Choice) {
        let mut s = scene.clone();
        s.camera = self.camera;
        match Renderer::new(
            &self.ctx,
            &s,
            settings(self.config.width, self.config.height, choice),
        ) {
            Ok(r) => {
                self.renderer = r;
                self.choice = choice;
                self.message = None;
            }
            // Unsupported choices (multiview without the feature, say) are said, not fatal.
            Err(e) => self.message = Some(format!("{e}")),
        }
    }

    fn fly(&mut self, dt: f32) {
        let forward = Vec3::new(
            self.yaw.sin() * self.pitch.cos(),
            self.pitch.sin(),
            -self.yaw.cos() * self.pitch.cos(),
        );
        let right = forward.cross(Vec3::Y).normalize_or_zero();
        let mut step = Vec3::ZERO;
        for (k, d) in [
            (KeyCode::KeyW, forward),
            (KeyCode::KeyS, -forward),
            (KeyCode::KeyD, right),
            (KeyCode::KeyA, -right),
            (KeyCode::KeyE, Vec3::Y),
            (KeyCode::KeyQ, -Vec3::Y),
        ] {
            if self.keys.contains(&k) {
                step += d;
            }
        }
        let dist = (self.camera.target - self.camera.position)
            .length()
            .max(0.1);
        self.camera.position += step.normalize_or_zero() * self.speed * dt;
        self.camera.target = self.camera.position + forward * dist;
    }

    fn frame(&mut self, app_scene: &mut Scene, script: Option<&[[f32; 6]]>, animate: bool) {
        let now = Instant::now();
        let dt = (now - self.last_frame).as_secs_f32().min(0.25);
        self.last_frame = now;
        match script {
            Some(cams) => {
                let c = cams[(self.frames as usize).min(cams.len() - 1)];
                self.camera.position = Vec3::new(c[0], c[1], c[2]);
                self.camera.target = Vec3::new(c[3], c[4], c[5]);
            }
            None => self.fly(dt),
        }
        if let Some(k) = self.overlays.follow {
            if let Some(l) = self.renderer.scene().lights.get(k) {
                let forward = (self.camera.target - self.camera.position).normalize_or_zero();
                match l.kind {
                    LightKind::Spot {
                        position,
                        direction,
                        ..
                    } => {
                        self.camera.position = position;
                        self.camera.target = position + direction;
                    }
                    LightKind::Point { position, .. } => {
                        self.camera.position = position;
                        self.camera.target = position + forward;
                    }
                    LightKind::Directional { .. } => {}
                }
            }
        }
        if let Err(e) = self.renderer.set_camera(self.camera) {
            self.message = Some(format!("camera: {e}"));
        }
        if animate {
            let t = (now - self.started).as_secs_f32();
            if let Some(k) = app_scene.smallest_caster() {
                let offset = Vec3::new(0.4 * t.cos() - 0.4, 0.0, 0.4 * t.sin());
                let _ = self.renderer.set_instance_transform(
                    k,
                    Mat4::from_translation(offset) * app_scene.instances[k].transform,
                );
            }
            // One local light sways 0.3 m left and right (the others keep their maps).
            let lights = &self.renderer.scene().lights;
            if lights.len() >= 2 {
                let local = lights.iter().position(|l| {
                    matches!(l.kind, LightKind::Spot { .. } | LightKind::Point { .. })
                });
                if let Some(i) = local {
                    let mut light = app_scene.lights[i];
                    let sway = Vec3::new(0.3 * (0.7 * t).sin(), 0.0, 0.0);
                    match &mut light.kind {
                        LightKind::Spot { position, .. } | LightKind::Point { position, .. } => {
                            *position += sway
                        }
                        LightKind::Directional { .. } => {}
                    }
                    let _ = self.renderer.set_light(i, light);
                }
            }
        }
        let texture = match self.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t)
            | wgpu::CurrentSurfaceTexture::Suboptimal(t) => t,
            other => {
                log::warn!("surface: {other:?}; reconfiguring");
                self.surface.configure(&self.ctx.device, &self.config);
                return;
            }
        };
        let t0 = Instant::now();
        match self.renderer.render_to(&texture.texture) {
            Ok(submitted) => {
                let st = &submitted.shadow_stats;
                self.views_drawn = u64::from(st.views_drawn);
                self.views_waiting = (st.views_stale, st.stale_frames, st.views_waiting);
                // Times of an earlier frame, when one has finished: no wait for this one.
                if let Some(t) = self.renderer.poll_gpu_timings() {
                    self.gpu_ms = t;
                }
            }
            Err(e) => self.message = Some(format!("frame: {e}")),
        }
        self.frame_ms = t0.elapsed().as_secs_f64() * 1e3;
        if self.panel {
            self.refresh_overlays();
            self.draw_panel(app_scene, &texture.texture);
        }
        self.ctx.queue.present(texture);
        self.frames += 1;
        // A line per frame on stdout: scripts and tests follow the run by it.
        // The CPU time of the frame's record and submit, timings poll included: no wait for
        // the GPU (the surface's acquire above is the loop's only wait).
        println!(
            "presented frame {}: {} of {} shadow views drawn; CPU {:.2} ms; GPU {} (an earlier frame)",
            self.frames,
            self.views_drawn,
            self.renderer.shadow_views(),
            self.frame_ms,
            self.gpu_ms
                .total()
                .map_or("not yet".to_string(), |t| format!("{t:.1} ms")),
        );
    }

    fn refresh_overlays(&mut self) {
        let o = &mut self.overlays;
        let due = o.refreshed.is_none_or(|t| t.elapsed().as_secs_f32() >= 1.0);
        if !due || !(o.atlas || self.choice.visibility) {
            return;
        }
        o.refreshed = Some(Instant::now());
        if o.atlas {
            // The atlas, or the page pool; a technique that fills the mask has neither.
            match self.renderer.shadow_picture() {
                Ok(p) => {
                    let (side, rgb, what) = (p.side, p.rgb, p.description);
                    let (w, small) = shrink_rgb(side, &rgb, 256);
                    let image = egui::ColorImage::from_rgb([w, w], &small);
                    o.atlas_texture = Some(self.egui_ctx.load_texture(
                        "atlas",
                        image,
                        Default::default(),
                    ));
                    o.atlas_note = format!("{what}, shown at {w}²");
                }
                Err(e) => {
                    o.atlas_texture = None;
                    o.atlas_note = e.to_string();
                }
            }
        }
        if self.choice.visibility {
            // One more frame, read back with its visibility mask.
            match self.renderer.render() {
                Ok(frame) => match frame.visibility {
                    Some(v) if v.lights > 0 => {
                        let k = o.light.min(v.lights as usize - 1);
                        let grey = v.light_image(k as u32);
                        let image = egui::ColorImage::from_gray(
                            [v.width as usize, v.height as usize],
                            &grey,
                        );
                        o.visibility_texture = Some(self.egui_ctx.load_texture(
                            "visibility",
                            image,
                            Default::default(),
                        ));
                        o.visibility_note = format!("light {k}: white = lit, black = shadowed");
                    }
                    _ => o.visibility_note = "no lights".into(),
                },
                Err(e) => o.visibility_note = e.to_string(),
            }
        }
    }

    fn draw_panel(&mut self, app_scene: &mut Scene, target: &wgpu::Texture) {
        let raw = self.egui_state.take_egui_input(&self.window);
        let mut choice = self.choice;
        let mut apply_lights = false;
        let layout = self.renderer.shadow_layout();
        let views = layout.views;
        let lights = self.renderer.scene().lights.len();
        let features = self.ctx.device.features();
        // Each technique of the registry with what this device lacks for it.
        let menu: Vec<(Technique, Vec<String>)> = Technique::all()
            .into_iter()
            .map(|t| {
                (
                    t,
                    t.info().unmet(&self.ctx).iter().map(|n| n.name()).collect(),
                )
            })
            .collect();
        let gpu_ms = self.gpu_ms.clone();
        let frame_ms = self.frame_ms;
        let views_drawn = self.views_drawn;
        let (stale, oldest, waiting) = self.views_waiting;
        let technique = self.choice.technique;
        let message = self.message.clone();
        let mut light_count = self.light_count;
        let overlays = &mut self.overlays;
        let out = self.egui_ctx.run_pass(raw, |ctx| {
            egui::Window::new("manyshadows")
                .default_pos([8.0, 8.0])
                .show(ctx, |ui| {
                    ui.label(CONTROLS);
                    ui.separator();
                    egui::ComboBox::from_label("technique")
                        .selected_text(choice.technique.to_string())
                        .show_ui(ui, |ui| {
                            for (t, unmet) in &menu {
                                let mut label = t.to_string();
                                if !unmet.is_empty() {
                                    label.push_str(&format!(
                                        " (needs {}; this device lacks it)",
                                        unmet.join(", ")
                                    ));
                                }
                                ui.selectable_value(&mut choice.technique, *t, label);
                            }
                        });
                    egui::ComboBox::from_label("point shadows")
                        .selected_text(choice.point_shadows.name())
                        .show_ui(ui, |ui| {
                            for p in [PointShadows::Cube, PointShadows::DualParaboloid] {
                                ui.selectable_value(&mut choice.point_shadows, p, p.name());
                            }
                        });
                    egui::ComboBox::from_label("PCF")
                        .selected_text(choice.pcf.name())
                        .show_ui(ui, |ui| {
                            for &p in Pcf::ALL {
                                ui.selectable_value(&mut choice.pcf, p, p.name());
                            }
                        });
                    ui.checkbox(&mut choice.cache, "keep unchanged maps (cache)");
                    ui.horizontal(|ui| {
                        let mut on = choice.budget.is_some();
                        let mut n = choice.budget.unwrap_or(16);
                        ui.checkbox(&mut on, "shadow budget");
                        ui.add_enabled(
                            on,
                            egui::Slider::new(&mut n, 1..=256)
                                .logarithmic(true)
                                .text("views per frame (atlas)"),
                        );
                        choice.budget = on.then_some(n);
                    });
                    ui.horizontal(|ui| {
                        ui.add(
                            egui::Slider::new(&mut light_count, 0..=4096)
                                .logarithmic(true)
                                .text("lights"),
                        );
                        apply_lights = ui.button("apply").clicked();
                    });
                    ui.separator();
                    let side = layout.side;
                    ui.label(format!(
                        "{lights} lights, {views} shadow views, {} {side}² ({:.1} MiB)",
                        layout.fills.describe(),
                        (side as f64).powi(2) * 4.0 / (1 << 20) as f64
                    ));
                    if layout.fills == Fills::Mask {
                        ui.label(format!(
                            "{technique}: fills {} (exact tests per camera sample)",
                            layout.fills.describe()
                        ));
                    } else if layout.fills == Fills::Pages {
                        ui.label(format!(
                            "{technique}: pages in a pool, no atlas (faces planned per frame)"
                        ));
                    } else {
                        ui.label(format!(
                            "shadow views drawn this frame: {views_drawn} of {views}"
                        ));
                        if choice.budget.is_some() {
                            ui.label(format!(
                                "waiting for the budget: {stale} stale (oldest {oldest} \
                                 frames), {waiting} with no shadow yet"
                            ));
                        }
                    }
                    ui.label(format!(
                        "frame CPU (record + submit, no GPU wait) {frame_ms:.1} ms"
                    ));
                    if gpu_ms.is_empty() {
                        ui.label("GPU time per stage: no timestamp queries on this device");
                    }
                    for (stage, ms) in gpu_ms.iter() {
                        ui.label(format!("GPU {stage}: {ms:.2} ms"));
                    }
                    if let Some(m) = &message {
                        ui.colored_label(egui::Color32::from_rgb(255, 120, 80), m);
                    }
                    ui.separator();
                    ui.checkbox(&mut overlays.atlas, "show the shadow atlas (page pool)");
                    ui.checkbox(&mut choice.visibility, "show one light's visibility");
                    ui.horizontal(|ui| {
                        ui.add(
                            egui::DragValue::new(&mut overlays.light)
                                .range(0..=lights.saturating_sub(1)),
                        );
                        ui.label("light");
                        let mut following = overlays.follow.is_some();
                        if ui.checkbox(&mut following, "follow it").changed() {
                            overlays.follow = following.then_some(overlays.light);
                        }
                    });
                    if let Some(f) = overlays.follow.as_mut() {
                        *f = overlays.light;
                    }
                    if !features.contains(wgpu::Features::PIPELINE_STATISTICS_QUERY) {
                        ui.label("(no pipeline statistics on this device: benches count less)");
                    }
                });
            if overlays.atlas {
                egui::Window::new(if layout.fills == Fills::Pages {
                    "page pool"
                } else {
                    "shadow atlas"
                })
                .anchor(egui::Align2::RIGHT_TOP, [-8.0, 8.0])
                .show(ctx, |ui| {
                    ui.label(&overlays.atlas_note);
                    if let Some(t) = &overlays.atlas_texture {
                        ui.image(t);
                    }
                });
            }
            if choice.visibility {
                egui::Window::new("visibility")
                    .anchor(egui::Align2::RIGHT_BOTTOM, [-8.0, -8.0])
                    .show(ctx, |ui| {
                        ui.label(&overlays.visibility_note);
                        if let Some(t) = &overlays.visibility_texture {
                            let size = t.size_vec2();
                            let scale = (240.0 / size.x).min(1.0);
                            ui.add(egui::Image::new(t).fit_to_exact_size(size * scale));
                        }
                    });
            }
        });
        self.egui_state
            .handle_platform_output(&self.window, out.platform_output);
        let jobs = self.egui_ctx.tessellate(out.shapes, out.pixels_per_point);
        let device = &self.ctx.device;
        let queue = &self.ctx.queue;
        for (id, deltas) in &out.textures_delta.set {
            for delta in deltas {
                self.egui_renderer.update_texture(device, queue, *id, delta);
            }
        }
        let screen = egui_wgpu::ScreenDescriptor {
            size_in_pixels: [self.config.width, self.config.height],
            pixels_per_point: out.pixels_per_point,
        };
        let mut encoder = device.create_command_encoder(&Default::default());
        let mut cmds =
            self.egui_renderer
                .update_buffers(device, queue, &mut encoder, &jobs, &screen);
        {
            let view = target.create_view(&Default::default());
            let mut pass = encoder
                .begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("viewer.panel"),
                    color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                        view: &view,
                        depth_slice: None,
                        resolve_target: None,
                        ops: wgpu::Operations {
                            load: wgpu::LoadOp::Load,
                            store: wgpu::StoreOp::Store,
                        },
                    })],
                    ..Default::default()
                })
                .forget_lifetime();
            self.egui_renderer.render(&mut pass, &jobs, &screen);
        }
        cmds.push(encoder.finish());
        queue.submit(cmds);
        for id in &out.textures_delta.free {
            self.egui_renderer.free_texture(id);
        }
        self.light_count = light_count;
        if apply_lights {
            app_scene.lights = manyshadows::scene::builtin::scatter_lights(
                app_scene,
                light_count,
                self.seed,
                manyshadows::scene::builtin::LightMix::All,
                None,
            );
            let c = self.choice;
            self.rebuild(app_scene, c);
        }
        if choice != self.choice {
            self.rebuild(app_scene, choice);
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

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.state.is_some() {
            return;
        }
        match self.start(event_loop) {
            Ok(s) => {
                s.window.request_redraw();
                self.state = Some(s);
            }
            Err(e) => {
                self.error = Some(e);
                event_loop.exit();
            }
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        let Some(state) = self.state.as_mut() else {
            return;
        };
        let used = state
            .egui_state
            .on_window_event(&state.window, &event)
            .consumed;
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::Resized(size) if size.width > 0 && size.height > 0 => {
                state.config.width = size.width;
                state.config.height = size.height;
                state.surface.configure(&state.ctx.device, &state.config);
                let c = state.choice;
                state.rebuild(&self.scene, c);
            }
            WindowEvent::KeyboardInput { event, .. } if !used => {
                if let PhysicalKey::Code(code) = event.physical_key {
                    match (code, event.state) {
                        (KeyCode::Escape, ElementState::Pressed) => event_loop.exit(),
                        (KeyCode::F1, ElementState::Pressed) if !event.repeat => {
                            state.panel = !state.panel;
                        }
                        (_, ElementState::Pressed) => {
                            state.keys.insert(code);
                        }
                        (_, ElementState::Released) => {
                            state.keys.remove(&code);
                        }
                    }
                }
            }
            WindowEvent::MouseInput {
                state: s,
                button: MouseButton::Right,
                ..
            } => {
                state.looking = s == ElementState::Pressed;
                state.last_cursor = None;
            }
            WindowEvent::CursorMoved { position, .. } if state.looking => {
                if let Some((x, y)) = state.last_cursor {
                    state.yaw += (position.x - x) as f32 * 0.004;
                    state.pitch = (state.pitch - (position.y - y) as f32 * 0.004).clamp(-1.5, 1.5);
                }
                state.last_cursor = Some((position.x, position.y));
            }
            WindowEvent::MouseWheel { delta, .. } if !used => {
                let lines = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y,
                    MouseScrollDelta::PixelDelta(p) => p.y as f32 / 40.0,
                };
                state.speed = (state.speed * 1.2f32.powf(lines)).clamp(0.01, 1000.0);
            }
            WindowEvent::RedrawRequested => {
                state.frame(&mut self.scene, self.script.as_deref(), self.args.animate);
                if self.args.exit_after.is_some_and(|n| state.frames >= n) {
                    event_loop.exit();
                }
            }
            _ => {}
        }
    }

    fn about_to_wait(&mut self, _event_loop: &ActiveEventLoop) {
        if let Some(s) = &self.state {
            s.window.request_redraw();
        }
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn scripts_parse_and_bad_lines_name_their_line() {
        let cams = super::parse_script("# a path\n0 1 2 0 0 0\n\n1,1,1, 0,0,0 # end\n").unwrap();
        assert_eq!(cams.len(), 2);
        assert_eq!(cams[1], [1.0, 1.0, 1.0, 0.0, 0.0, 0.0]);
        let e = super::parse_script("0 1 2 0 0 0\n1 2 3\n").unwrap_err();
        assert!(e.to_string().contains("line 2"), "{e}");
        assert!(super::parse_script("# nothing\n").is_err());
        assert!(super::parse_script("1 1 1 1 1 1\n").is_err());
    }
}
