//! The window and its event loop (winit): the flags checked and the scene loaded, the window
//! opened with a wgpu surface on the first resume, and each window event handed on (keys and
//! mouse to the fly camera unless the panel took them, resizes to the surface and the
//! renderer, redraws to the frame) until the window closes, Esc is pressed or
//! `--exit-after` frames are presented.

use std::sync::Arc;

use anyhow::{bail, Context as _, Result};
use manyshadows::scene::Scene;
use manyshadows::{wgpu, GpuContext};
use winit::application::ApplicationHandler;
use winit::event::{ElementState, MouseButton, WindowEvent};
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::keyboard::{KeyCode, PhysicalKey};
use winit::window::{Window, WindowId};

use crate::view::args::{parse_script, ViewArgs};
use crate::view::state::State;

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
    if args.per_technique.light_samples > 0
        && args.technique.info().fills == manyshadows::Fills::Mask
    {
        bail!(
            "--light-samples {}: technique {} takes no sampled lights (it answers every light \
             in one mask; shadow rays or shadow maps sample them)",
            args.per_technique.light_samples,
            args.technique
        );
    }
    let scene = load(args)?;
    // The animation flags, checked before any window opens (the state makes the player).
    crate::view::player::Player::new(&scene, args)?;
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
    manyshadows_cli::load_scene_for_view(manyshadows_cli::ViewScene {
        scene: args.scene.clone(),
        mesh: args.mesh.clone(),
        lights: args.lights,
        seed: args.seed,
        light_sizes: args.light_sizes,
        camera: args.camera,
        model: args.model,
        probes: args.probes,
    })
}

/// The event loop's application: the flags, the camera script, the scene as loaded, and the
/// window's state once it is open (or the error that closed it).
struct App {
    args: ViewArgs,
    script: Option<Vec<[f32; 6]>>,
    scene: Scene,
    state: Option<State>,
    error: Option<anyhow::Error>,
}

impl App {
    /// Opens the window, its surface and the GPU that presents to it.
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
        let config = surface_config(&surface, &ctx, window.inner_size())?;
        surface.configure(&ctx.device, &config);
        State::new(window, surface, config, ctx, &self.scene, &self.args)
    }
}

/// The surface's configuration at `size`: a raw 8-bit format, presented in order (FIFO).
fn surface_config(
    surface: &wgpu::Surface<'static>,
    ctx: &GpuContext,
    size: winit::dpi::PhysicalSize<u32>,
) -> Result<wgpu::SurfaceConfiguration> {
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
    Ok(wgpu::SurfaceConfiguration {
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
        format,
        width: size.width.max(1),
        height: size.height.max(1),
        present_mode: wgpu::PresentMode::Fifo,
        desired_maximum_frame_latency: 2,
        alpha_mode: caps.alpha_modes[0],
        view_formats: vec![],
        color_space: wgpu::SurfaceColorSpace::Auto,
    })
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
                        (_, pressed) => state.fly.key(code, pressed == ElementState::Pressed),
                    }
                }
            }
            WindowEvent::MouseInput {
                state: s,
                button: MouseButton::Right,
                ..
            } => state.fly.look(s == ElementState::Pressed),
            WindowEvent::CursorMoved { position, .. } if state.fly.looking => {
                state.fly.cursor_moved(position.x, position.y);
            }
            WindowEvent::MouseWheel { delta, .. } if !used => state.fly.wheel(delta),
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
