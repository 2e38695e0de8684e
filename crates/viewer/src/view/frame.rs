//! One frame of the window: the camera placed (script, fly controls, a followed light), the
//! scene animated (`--animate`, or the file's own animation: `player`), the renderer drawn straight into the surface texture
//! (`Renderer::render_to`), the panel over it, the texture presented, and a line on stdout.

use std::time::Instant;

use glam::{Mat4, Vec3};
use manyshadows::scene::{LightKind, Scene};
use manyshadows::wgpu;

use crate::view::state::State;

impl State {
    /// Draws and presents one frame; `app_scene` is the scene as loaded (the animation moves
    /// from it, the panel's light count rescatters its lights).
    pub(super) fn frame(
        &mut self,
        app_scene: &mut Scene,
        script: Option<&[[f32; 6]]>,
        animate: bool,
    ) {
        let now = Instant::now();
        let dt = (now - self.last_frame).as_secs_f32().min(0.25);
        self.last_frame = now;
        self.move_camera(script, dt);
        if animate {
            self.animate(app_scene, (now - self.started).as_secs_f32());
        }
        if let Some(p) = &mut self.player {
            p.advance(app_scene, dt);
            if let Err(e) = p.apply(&mut self.renderer) {
                self.message = Some(format!("animation: {e}"));
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
        self.render_into(&texture.texture);
        if self.panel {
            self.overlays
                .refresh(&mut self.renderer, self.choice.visibility, &self.egui_ctx);
            self.draw_panel(app_scene, &texture.texture);
        }
        self.ctx.queue.present(texture);
        self.frames += 1;
        self.print_frame_line();
    }

    /// The camera of this frame: the script's line for it (the last line once the script
    /// ends) or the fly controls over `dt` seconds, then at the followed light, if any.
    fn move_camera(&mut self, script: Option<&[[f32; 6]]>, dt: f32) {
        match script {
            Some(cams) => self
                .fly
                .place(cams[(self.frames as usize).min(cams.len() - 1)]),
            None => self.fly.fly(dt),
        }
        if let Some(k) = self.overlays.follow {
            if let Some(l) = self.renderer.scene().lights.get(k) {
                self.fly.follow(l);
            }
        }
        if let Err(e) = self.renderer.set_camera(self.fly.camera) {
            self.message = Some(format!("camera: {e}"));
        }
    }

    /// `--animate` at `t` seconds: the smallest caster circles, and one local light (of two
    /// or more) sways.
    fn animate(&mut self, app_scene: &Scene, t: f32) {
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
            let local = lights
                .iter()
                .position(|l| matches!(l.kind, LightKind::Spot { .. } | LightKind::Point { .. }));
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

    /// The frame drawn into `target`, with the CPU time it took and the shadow views it drew;
    /// the GPU times of an earlier frame are taken when one has finished.
    fn render_into(&mut self, target: &wgpu::Texture) {
        let t0 = Instant::now();
        match self.renderer.render_to(target) {
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
    }

    /// A line per frame on stdout: scripts and tests follow the run by it.
    fn print_frame_line(&self) {
        // The CPU time of the frame's record and submit, timings poll included: no wait for
        // the GPU (acquiring the surface's texture is the loop's only wait).
        let at = self
            .player
            .map(|p| format!("; animation at {:.3} s", p.time))
            .unwrap_or_default();
        println!(
            "presented frame {}: {} of {} shadow views drawn; CPU {:.2} ms; GPU {} (an earlier frame){at}",
            self.frames,
            self.views_drawn,
            self.renderer.shadow_views(),
            self.frame_ms,
            self.gpu_ms
                .total()
                .map_or("not yet".to_string(), |t| format!("{t:.1} ms")),
        );
    }
}
