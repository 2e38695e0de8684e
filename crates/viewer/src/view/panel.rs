//! The on-screen panel (egui), drawn over the frame: the controls' help; the technique,
//! point-shadow, PCF, caching, budget, light-count and (for shadow rays) sampling and denoising
//! choices; a glTF file's animation (clip, play, time, speed); the shadow views, memory and times of the last frame; the pictures to show (the
//! atlas and one light's visibility, each in a window of its own) and the light to follow. Each section is a function; what the
//! panel changed is applied after it is drawn (a new choice rebuilds the renderer).

use manyshadows::scene::animation::Playing;
use manyshadows::scene::light_space::PointShadows;
use manyshadows::scene::Scene;
use manyshadows::{wgpu, Fills, GpuTimes, Pcf, ShadowLayout, SoftShadows, SpatialReuse, Technique};

use crate::view::args::CONTROLS;
use crate::view::overlays::Overlays;
use crate::view::player::{Player, MAX_SPEED};
use crate::view::state::{Choice, State};

/// What the panel shows, read from the state before egui borrows it.
struct Facts {
    layout: ShadowLayout,
    lights: usize,
    features: wgpu::Features,
    /// Each technique of the registry with what this device lacks for it.
    menu: Vec<(Technique, Vec<String>)>,
    gpu_ms: GpuTimes,
    frame_ms: f64,
    views_drawn: u64,
    /// The views a budget left waiting: (stale, oldest in frames, unshadowed).
    views_waiting: (u32, u32, u32),
    /// The technique that drew the frame.
    technique: Technique,
    message: Option<String>,
    /// The file's animations: each clip's name and duration, and the longest.
    clips: Vec<(String, f32)>,
}

/// What the panel edits this frame, applied once it is drawn.
struct Edits {
    choice: Choice,
    /// Where the file's animation stands.
    player: Option<Player>,
    light_count: usize,
    /// The light count's "apply" button was clicked.
    apply_lights: bool,
}

impl State {
    /// Draws the panel over `target` and applies what it changed (`app_scene` gets the new
    /// lights when the light count is applied).
    pub(super) fn draw_panel(&mut self, app_scene: &mut Scene, target: &wgpu::Texture) {
        let raw = self.egui_state.take_egui_input(&self.window);
        let facts = self.panel_facts();
        let mut edits = Edits {
            choice: self.choice,
            player: self.player,
            light_count: self.light_count,
            apply_lights: false,
        };
        let overlays = &mut self.overlays;
        let out = self.egui_ctx.run_pass(raw, |ctx| {
            main_window(ctx, &facts, &mut edits, overlays);
            if overlays.atlas {
                atlas_window(ctx, overlays, facts.layout.fills);
            }
            if edits.choice.visibility {
                visibility_window(ctx, overlays);
            }
        });
        self.paint_panel(out, target);
        self.apply_edits(app_scene, edits);
    }

    /// The numbers and the menu the panel shows, copied from the state.
    fn panel_facts(&self) -> Facts {
        Facts {
            layout: self.renderer.shadow_layout(),
            lights: self.renderer.scene().lights.len(),
            features: self.ctx.device.features(),
            menu: Technique::all()
                .into_iter()
                .map(|t| {
                    (
                        t,
                        t.info().unmet(&self.ctx).iter().map(|n| n.name()).collect(),
                    )
                })
                .collect(),
            gpu_ms: self.gpu_ms.clone(),
            frame_ms: self.frame_ms,
            views_drawn: self.views_drawn,
            views_waiting: self.views_waiting,
            technique: self.choice.technique,
            message: self.message.clone(),
            clips: self
                .renderer
                .scene()
                .animations
                .clips
                .iter()
                .map(|c| (c.name.clone(), c.duration()))
                .collect(),
        }
    }

    /// egui's output drawn into `target` over the frame (loaded, not cleared).
    fn paint_panel(&mut self, out: egui::FullOutput, target: &wgpu::Texture) {
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
    }

    /// The new light count kept, the lights scattered anew when it was applied, and the
    /// renderer rebuilt for a changed choice.
    fn apply_edits(&mut self, app_scene: &mut Scene, edits: Edits) {
        self.player = edits.player;
        self.light_count = edits.light_count;
        if edits.apply_lights {
            app_scene.lights = manyshadows::scene::builtin::scatter_lights(
                app_scene,
                edits.light_count,
                self.seed,
                manyshadows::scene::builtin::LightMix::All,
                None,
            );
            self.light_sizes.apply(&mut app_scene.lights);
            let c = self.choice;
            self.rebuild(app_scene, c);
        }
        if edits.choice != self.choice {
            self.rebuild(app_scene, edits.choice);
        }
    }
}

/// The panel's own window, its sections in order.
fn main_window(ctx: &egui::Context, facts: &Facts, edits: &mut Edits, overlays: &mut Overlays) {
    egui::Window::new("manyshadows")
        .default_pos([8.0, 8.0])
        .show(ctx, |ui| {
            ui.label(CONTROLS);
            ui.separator();
            technique_menu(ui, &facts.menu, &mut edits.choice.technique);
            shadow_options(ui, &mut edits.choice);
            light_count_row(ui, edits);
            if let Some(p) = &mut edits.player {
                animation_rows(ui, &facts.clips, p);
            }
            ui.separator();
            shadow_views(ui, facts, edits.choice.budget.is_some());
            times_and_message(ui, facts);
            ui.separator();
            pictures(ui, overlays, &mut edits.choice.visibility, facts.lights);
            device_note(ui, facts.features);
        });
}

/// Every technique of the registry, with what this device lacks for those it cannot run.
fn technique_menu(ui: &mut egui::Ui, menu: &[(Technique, Vec<String>)], chosen: &mut Technique) {
    egui::ComboBox::from_label("technique")
        .selected_text(chosen.to_string())
        .show_ui(ui, |ui| {
            for (t, unmet) in menu {
                let mut label = t.to_string();
                if !unmet.is_empty() {
                    label.push_str(&format!(
                        " (needs {}; this device lacks it)",
                        unmet.join(", ")
                    ));
                }
                ui.selectable_value(chosen, *t, label);
            }
        });
}

/// Point shadows, PCF, caching and the shadow budget.
fn shadow_options(ui: &mut egui::Ui, choice: &mut Choice) {
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
    ui.add(
        egui::Slider::new(&mut choice.light_size, 0.0..=4.0)
            .text("light size × (soft shadows; 0 = hard)"),
    );
    if choice.technique.info().fills != Fills::Rays {
        soft_taps(ui, &mut choice.soft);
    }
    let rays = choice.technique.info().fills == Fills::Rays;
    if crate::view::state::samples_lights(choice.technique) {
        ui.add(
            egui::Slider::new(&mut choice.light_samples, 0..=16).text(if rays {
                "lights traced per pixel (0 = every light)"
            } else {
                "lights sampled per pixel (0 = every light)"
            }),
        );
        // Without samples only rays have something to accumulate (area samples).
        if rays || choice.light_samples > 0 {
            let what = if choice.light_samples > 0 {
                "denoise the sampled lights"
            } else {
                "accumulate area samples over frames"
            };
            ui.checkbox(&mut choice.denoise, what);
        }
        if choice.light_samples > 0 {
            ui.checkbox(&mut choice.reuse, "reuse the sampled lights across frames");
            if choice.reuse {
                egui::ComboBox::from_label("and between neighbours (spatial reuse)")
                    .selected_text(choice.spatial.name())
                    .show_ui(ui, |ui| {
                        for s in SpatialReuse::ALL {
                            ui.selectable_value(&mut choice.spatial, s, s.name());
                        }
                    });
            }
        }
    }
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
}

/// The shadow maps' soft-shadow taps (`--soft-taps`, `--max-penumbra`), folded away by
/// default; the ranges are those the options accept.
fn soft_taps(ui: &mut egui::Ui, soft: &mut SoftShadows) {
    egui::CollapsingHeader::new("soft-shadow taps (PCSS)").show(ui, |ui| {
        ui.add(egui::Slider::new(&mut soft.blocker_taps, 1..=64).text("blocker search taps"));
        ui.add(egui::Slider::new(&mut soft.filter_taps, 1..=64).text("filter taps"));
        ui.add(
            egui::Slider::new(&mut soft.max_penumbra, 1.0..=256.0)
                .logarithmic(true)
                .text("largest penumbra (texels)"),
        );
    });
}

/// The light count and its "apply" button (the lights are scattered anew when applied).
fn light_count_row(ui: &mut egui::Ui, edits: &mut Edits) {
    ui.horizontal(|ui| {
        ui.add(
            egui::Slider::new(&mut edits.light_count, 0..=4096)
                .logarithmic(true)
                .text("lights"),
        );
        edits.apply_lights = ui.button("apply").clicked();
    });
}

/// The file's animation: which clip (or all), play or pause, the time to scrub, the speed.
fn animation_rows(ui: &mut egui::Ui, clips: &[(String, f32)], p: &mut Player) {
    let name = |k: Playing| match k {
        Playing::One(k) => clips.get(k).map_or("?".to_string(), |c| c.0.clone()),
        Playing::All => "all".to_string(),
    };
    let before = p.playing;
    ui.horizontal(|ui| {
        egui::ComboBox::from_label("animation")
            .selected_text(name(p.playing))
            .show_ui(ui, |ui| {
                for k in (0..clips.len()).map(Playing::One).chain([Playing::All]) {
                    ui.selectable_value(&mut p.playing, k, name(k));
                }
            });
        let mut play = !p.paused;
        ui.checkbox(&mut play, "play");
        p.paused = !play;
    });
    let duration = match p.playing {
        Playing::One(k) => clips.get(k).map_or(0.0, |c| c.1),
        Playing::All => clips.iter().map(|c| c.1).fold(0.0, f32::max),
    };
    if p.playing != before {
        p.time = p.time.min(duration);
    }
    ui.add(egui::Slider::new(&mut p.time, 0.0..=duration.max(0.0)).text("seconds"));
    ui.add(egui::Slider::new(&mut p.speed, 0.0..=MAX_SPEED).text("speed"));
}

/// The lights, shadow views and shadow memory, and what the technique fills: the views
/// drawn this frame (and those a budget left waiting), or the mask or the page pool.
fn shadow_views(ui: &mut egui::Ui, facts: &Facts, budget: bool) {
    let Facts {
        layout,
        lights,
        technique,
        views_drawn,
        ..
    } = facts;
    let (views, side) = (layout.views, layout.side);
    let (stale, oldest, waiting) = facts.views_waiting;
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
        if budget {
            ui.label(format!(
                "waiting for the budget: {stale} stale (oldest {oldest} \
                 frames), {waiting} with no shadow yet"
            ));
        }
    }
}

/// The frame's CPU time, the GPU time per stage, and the last error said (in orange).
fn times_and_message(ui: &mut egui::Ui, facts: &Facts) {
    let frame_ms = facts.frame_ms;
    ui.label(format!(
        "frame CPU (record + submit, no GPU wait) {frame_ms:.1} ms"
    ));
    if facts.gpu_ms.is_empty() {
        ui.label("GPU time per stage: no timestamp queries on this device");
    }
    for (stage, ms) in facts.gpu_ms.iter() {
        ui.label(format!("GPU {stage}: {ms:.2} ms"));
    }
    if let Some(m) = &facts.message {
        ui.colored_label(egui::Color32::from_rgb(255, 120, 80), m);
    }
}

/// The pictures to show (the atlas, one light's visibility), the light they show and
/// whether the camera follows it.
fn pictures(ui: &mut egui::Ui, overlays: &mut Overlays, visibility: &mut bool, lights: usize) {
    ui.checkbox(&mut overlays.atlas, "show the shadow atlas (page pool)");
    ui.checkbox(visibility, "show one light's visibility");
    ui.horizontal(|ui| {
        ui.add(egui::DragValue::new(&mut overlays.light).range(0..=lights.saturating_sub(1)));
        ui.label("light");
        let mut following = overlays.follow.is_some();
        if ui.checkbox(&mut following, "follow it").changed() {
            overlays.follow = following.then_some(overlays.light);
        }
    });
    if let Some(f) = overlays.follow.as_mut() {
        *f = overlays.light;
    }
}

/// Says when the device has no pipeline statistics.
fn device_note(ui: &mut egui::Ui, features: wgpu::Features) {
    if !features.contains(wgpu::Features::PIPELINE_STATISTICS_QUERY) {
        ui.label("(no pipeline statistics on this device: benches count less)");
    }
}

/// The atlas picture (the page pool's for virtual maps), top right.
fn atlas_window(ctx: &egui::Context, overlays: &Overlays, fills: Fills) {
    egui::Window::new(if fills == Fills::Pages {
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

/// One light's visibility, at most 240 points wide, bottom right.
fn visibility_window(ctx: &egui::Context, overlays: &Overlays) {
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
