//! The renderer in a web page: WebGPU through wgpu. A [`WebRenderer`] keeps one scene and
//! renderer alive; each frame is rendered into a texture and copied into the page's canvas
//! through its WebGPU context ([`WebRenderer::present`]). Reading a frame back
//! ([`WebRenderer::read_frame`]) is for the page's tests.
//!
//! Settings travel as a query string (`scene=atrium&technique=layered&lights=64&pcf=3x3`), the
//! same text the page's URL and its controls use; see [`WebSettings`].
//!
//! A user's own model arrives as files (dropped, picked, or fetched by the page for
//! `?model=URL`) and is loaded from memory ([`MemoryFiles`]) by the same loader `render --scene
//! FILE` uses: its URIs resolve only among those files, and the scene gets the same light rig,
//! framing camera and ground. `scene=model` then means that model.
#![cfg(target_arch = "wasm32")]

use manyshadows::scene::animation::Playing;
use manyshadows::scene::builtin::{self, BuiltinOptions, LightMix};
use manyshadows::scene::loaders::{load_scene_from_memory, Ground, LoadOptions, MemoryFiles};
use manyshadows::scene::{Camera, Scene};
use manyshadows::{wgpu, GpuContext, Renderer, Technique};
use wasm_bindgen::prelude::*;

mod score;
mod settings;

use settings::WebSettings;
use wasm_bindgen::JsCast;

fn err(e: impl std::fmt::Display) -> JsValue {
    JsValue::from_str(&e.to_string())
}

/// The `scene` value that names the model opened from files.
const MODEL_SCENE: &str = "model";

/// A model read from files, as loaded (its own or the default lights; `lights=N` replaces them
/// per build).
struct Model {
    scene: Scene,
    /// The model file's name among the files.
    name: String,
    /// What the loader said about it (lights added, extensions ignored, …).
    notes: Vec<String>,
}

impl Model {
    /// Loads `name` among `files` as `render --scene FILE` loads a file (ground `auto`).
    fn load(files: &MemoryFiles, name: &str) -> Result<Self, String> {
        let options = LoadOptions {
            ground: Ground::Auto,
            ..Default::default()
        };
        let loaded = load_scene_from_memory(files, name, &options).map_err(|e| e.to_string())?;
        Ok(Self {
            scene: loaded.scene,
            name: name.to_string(),
            notes: loaded.notes,
        })
    }
}

/// The model file among `files` to open: `wanted` if given, else the only model file; several
/// are refused with their names, none with what the files are.
fn choose_model(files: &MemoryFiles, wanted: Option<&str>) -> Result<String, String> {
    if let Some(w) = wanted {
        return files
            .get(w)
            .map(|_| w.to_string())
            .ok_or_else(|| format!("{w} is not among the files given"));
    }
    let models = files.models();
    match models.as_slice() {
        [one] => Ok(one.to_string()),
        [] => Err(format!(
            "none of the files given ({}) is a model file (.gltf, .glb, .obj, .ply, .ply.gz)",
            files.names().collect::<Vec<_>>().join(", ")
        )),
        several => Err(format!(
            "the files hold {} model files ({}): give one at a time, with the files it uses",
            several.len(),
            several.join(", ")
        )),
    }
}

/// The files of two parallel JS arrays (names, `Uint8Array`s); a `.zip` gives the files in
/// it, in its folder.
fn files_of(names: &js_sys::Array, data: &js_sys::Array) -> Result<MemoryFiles, String> {
    if names.length() != data.length() {
        return Err(format!(
            "{} names for {} files",
            names.length(),
            data.length()
        ));
    }
    let mut files = MemoryFiles::new();
    for (n, d) in names.iter().zip(data.iter()) {
        let name = n.as_string().ok_or("a file name is not a string")?;
        let bytes = d
            .dyn_into::<js_sys::Uint8Array>()
            .map_err(|_| format!("{name}: its content is not a Uint8Array"))?
            .to_vec();
        if name.to_ascii_lowercase().ends_with(".zip") {
            files.insert_zip(&name, &bytes)?;
        } else {
            files.insert(&name, bytes)?;
        }
    }
    Ok(files)
}

#[wasm_bindgen]
extern "C" {
    #[wasm_bindgen(js_namespace = console, js_name = error)]
    fn console_error(s: &str);
}

/// Runs when the module is initialised: a panic (a bug: every error the page can meet is
/// returned as a message) is written to the console and to `globalThis.manyshadowsPanic`, so
/// that the page can show it instead of a blank canvas.
#[wasm_bindgen(start)]
fn start() {
    std::panic::set_hook(Box::new(|info| {
        let message = format!("the renderer stopped on a bug: {info}");
        console_error(&message);
        let _ = js_sys::Reflect::set(
            &js_sys::global(),
            &JsValue::from_str("manyshadowsPanic"),
            &JsValue::from_str(&message),
        );
    }));
}

/// The registry's technique names, one per line, the default first: the page's technique menu
/// is made of them.
#[wasm_bindgen]
pub fn technique_names() -> String {
    Technique::all()
        .iter()
        .map(|t| t.name())
        .collect::<Vec<_>>()
        .join("\n")
}

/// `text` as a JSON string (quotes, backslashes and control characters escaped).
fn json_string(text: &str) -> String {
    let mut out = String::from("\"");
    for c in text.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            c if (c as u32) < 0x20 => out.push_str(&format!("\\u{:04x}", c as u32)),
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// One scene on the browser's WebGPU device, rendered on demand.
#[wasm_bindgen]
pub struct WebRenderer {
    ctx: GpuContext,
    settings: WebSettings,
    base_camera: Camera,
    renderer: Renderer,
    target: wgpu::Texture,
    /// The model opened from files, if any (`scene=model`).
    model: Option<Model>,
    /// Shadow views the last frame drew (the others were kept from earlier frames).
    views_drawn: u32,
    /// The newest GPU times read ([`WebRenderer::gpu_times`]).
    last_gpu_times: String,
    /// The score in progress or done ([`WebRenderer::score_start`]).
    score: Option<score::ScoreRun>,
    /// The page's canvas through its WebGPU context, where one is attached.
    canvas: Option<Canvas>,
    /// The animation and time the renderer's scene was last placed at (`None`: as built).
    applied: Option<(Playing, f32)>,
}

/// The page's canvas through its WebGPU context: `rgba8unorm`, written by copying the frame
/// (`rgba8unorm-srgb`: the same bytes) into it.
struct Canvas {
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
}

#[wasm_bindgen]
impl WebRenderer {
    /// Opens the browser's WebGPU adapter and builds the scene `query` describes: with files
    /// (`names` and their `data` as `Uint8Array`s, parallel arrays; empty for a built-in
    /// scene), the model among them (`scene=model` is implied), else the built-in `scene`.
    pub async fn create(
        query: String,
        names: js_sys::Array,
        data: js_sys::Array,
    ) -> Result<WebRenderer, JsValue> {
        let mut settings = WebSettings::parse(&query).map_err(err)?;
        let model = if names.length() > 0 {
            let files = files_of(&names, &data).map_err(err)?;
            let name = choose_model(&files, None).map_err(err)?;
            settings.scene = MODEL_SCENE.into();
            Some(Model::load(&files, &name).map_err(err)?)
        } else {
            None
        };
        let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
        desc.backends = wgpu::Backends::BROWSER_WEBGPU;
        let instance = wgpu::Instance::new(desc);
        let adapter = instance
            .request_adapter(&wgpu::RequestAdapterOptions::default())
            .await
            .map_err(|e| err(format!("no WebGPU adapter: {e}")))?;
        // The optional features the techniques need (from their declarations) and GPU times,
        // where the browser has them; a technique whose needs are missing is refused by name.
        let wanted = Technique::all()
            .iter()
            .fold(wgpu::Features::TIMESTAMP_QUERY, |f, t| {
                f | t.info().features()
            });
        let features = adapter.features() & wanted;
        let (device, queue) = adapter
            .request_device(&wgpu::DeviceDescriptor {
                required_features: features,
                required_limits: adapter.limits(),
                ..Default::default()
            })
            .await
            .map_err(err)?;
        let ctx = GpuContext::from_parts(instance, adapter, device, queue).map_err(err)?;
        // This page is the host: GPU errors outside the renderer's calls are reported through
        // `render`, not thrown by wgpu's default handler.
        ctx.capture_uncaptured_errors();
        let (renderer, base_camera, target) = Self::build(&ctx, &settings, model.as_ref())?;
        Ok(WebRenderer {
            ctx,
            settings,
            base_camera,
            renderer,
            target,
            model,
            views_drawn: 0,
            last_gpu_times: String::new(),
            score: None,
            canvas: None,
            applied: None,
        })
    }

    fn build(
        ctx: &GpuContext,
        s: &WebSettings,
        model: Option<&Model>,
    ) -> Result<(Renderer, Camera, wgpu::Texture), JsValue> {
        let mut scene = if s.scene == MODEL_SCENE {
            let m = model.ok_or_else(|| err("no model is open: drop a model file on the page"))?;
            let mut scene = m.scene.clone();
            if let Some(n) = s.lights {
                manyshadows::scene::loaders::seed_lights(
                    &mut scene,
                    n,
                    s.seed,
                    LightMix::default(),
                    None,
                )
                .map_err(err)?;
            }
            scene
        } else {
            let opts = BuiltinOptions {
                lights: s.lights,
                seed: s.seed,
                ..Default::default()
            };
            builtin::build(&s.scene, &opts).map_err(err)?
        };
        if let Some(n) = s.add_lights {
            manyshadows::scene::loaders::add_seeded_lights(
                &mut scene,
                n,
                s.seed,
                LightMix::default(),
                None,
            )
            .map_err(err)?;
        }
        for l in &mut scene.lights {
            l.size *= s.light_size;
            if matches!(l.kind, manyshadows::scene::LightKind::Directional { .. }) {
                l.size = l.size.min(manyshadows::scene::MAX_ANGULAR_SIZE_DEG * 0.99);
            }
        }
        let base_camera = scene.camera;
        scene.camera = s.view.camera(&base_camera);
        let renderer = Renderer::new(ctx, &scene, s.render_settings()).map_err(err)?;
        let target = ctx.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("web.frame"),
            size: wgpu::Extent3d {
                width: s.width,
                height: s.height,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba8UnormSrgb,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        });
        Ok((renderer, base_camera, target))
    }

    /// Applies new settings. Only the camera changed: the renderer is kept (its shadow plan
    /// follows the camera); anything else rebuilds it. On an error (a technique the device
    /// cannot run, a bad value) the old renderer and settings stay.
    pub fn configure(&mut self, query: String) -> Result<(), JsValue> {
        let next = WebSettings::parse(&query).map_err(err)?;
        let camera_only = WebSettings {
            view: self.settings.view,
            ..next.clone()
        } == self.settings;
        if camera_only {
            self.renderer
                .set_camera(next.view.camera(&self.base_camera))
                .map_err(err)?;
        } else {
            let (renderer, base_camera, target) =
                Self::build(&self.ctx, &next, self.model.as_ref())?;
            self.renderer = renderer;
            self.base_camera = base_camera;
            self.target = target;
            self.applied = None;
        }
        self.settings = next;
        Ok(())
    }

    /// Opens a model from files (`names` and their `data`, parallel arrays: a .glb; a .gltf
    /// with its .bin and images; an .obj with its .mtl and textures; a .ply; a .zip of any of
    /// those): the model file
    /// among them, or `main` where several are. The scene becomes that model, with the other
    /// settings of `query`. Returns the loader's notes, one per line. On an error (naming the
    /// file and what is wrong) the previous scene, model and settings stay.
    pub fn open_files(
        &mut self,
        query: String,
        names: js_sys::Array,
        data: js_sys::Array,
        main: Option<String>,
    ) -> Result<String, JsValue> {
        let mut next = WebSettings::parse(&query).map_err(err)?;
        next.scene = MODEL_SCENE.into();
        let files = files_of(&names, &data).map_err(err)?;
        let name = choose_model(&files, main.as_deref()).map_err(err)?;
        let model = Model::load(&files, &name).map_err(err)?;
        let (renderer, base_camera, target) = Self::build(&self.ctx, &next, Some(&model))?;
        self.renderer = renderer;
        self.base_camera = base_camera;
        self.target = target;
        self.applied = None;
        self.settings = next;
        let notes = self.notes_of(&model);
        self.model = Some(model);
        Ok(notes)
    }

    fn notes_of(&self, model: &Model) -> String {
        model
            .notes
            .iter()
            .map(|n| format!("note: {}: {n}", model.name))
            .collect::<Vec<_>>()
            .join("\n")
    }

    /// The open model's notes (as `open_files` returned them), empty without a model.
    pub fn notes(&self) -> String {
        self.model
            .as_ref()
            .map(|m| self.notes_of(m))
            .unwrap_or_default()
    }

    /// The scene's animations as JSON, `[{"name": …, "duration": …}]` in the file's order
    /// (`[]` when nothing in it moves).
    pub fn animations(&self) -> String {
        let a = &self.renderer.scene().animations;
        if a.is_empty() {
            return "[]".into();
        }
        let clips: Vec<String> = a
            .clips
            .iter()
            .map(|c| {
                format!(
                    "{{\"name\":{},\"duration\":{}}}",
                    json_string(&c.name),
                    c.duration()
                )
            })
            .collect();
        format!("[{}]", clips.join(","))
    }

    /// Places the scene where animation `which` (its number from 0, its name, or `all`) has
    /// it at `t` seconds (looping past its end): moved instances and deformed meshes, as
    /// `render --time` does. Nothing is redone where the scene already stands there, so a
    /// paused animation keeps its shadow maps. Errors: no such animation, a time that is not
    /// finite.
    pub fn set_time(&mut self, which: String, t: f32) -> Result<(), JsValue> {
        if !t.is_finite() {
            return Err(err(format!(
                "animation time {t}: not a finite number of seconds"
            )));
        }
        let a = &self.renderer.scene().animations;
        if a.is_empty() {
            return Ok(());
        }
        let playing = a.choose(&which).map_err(err)?;
        let t = a.wrap(playing, t);
        if self.applied == Some((playing, t)) {
            return Ok(());
        }
        self.renderer.set_time(playing, t).map_err(err)?;
        self.applied = Some((playing, t));
        Ok(())
    }

    /// The open model's file name, empty without one.
    pub fn model_name(&self) -> String {
        self.model
            .as_ref()
            .map(|m| m.name.clone())
            .unwrap_or_default()
    }

    /// Presents every later [`WebRenderer::present`] on `canvas` through its WebGPU context.
    /// Errors: the browser gives the canvas no WebGPU context, or it cannot take the frame's
    /// format (the page says so; WebGPU guarantees canvases `rgba8unorm`).
    pub fn attach_canvas(&mut self, canvas: web_sys::HtmlCanvasElement) -> Result<(), JsValue> {
        let surface = self
            .ctx
            .instance
            .create_surface(wgpu::SurfaceTarget::Canvas(canvas))
            .map_err(|e| err(format!("the canvas has no WebGPU context: {e}")))?;
        let caps = surface.get_capabilities(&self.ctx.adapter);
        let format = wgpu::TextureFormat::Rgba8Unorm;
        if !caps.formats.contains(&format) {
            return Err(err(format!(
                "the canvas cannot take rgba8unorm (it offers {:?})",
                caps.formats
            )));
        }
        let config = wgpu::SurfaceConfiguration {
            usage: wgpu::TextureUsages::COPY_DST | wgpu::TextureUsages::RENDER_ATTACHMENT,
            format,
            width: self.settings.width,
            height: self.settings.height,
            present_mode: wgpu::PresentMode::Fifo,
            desired_maximum_frame_latency: 2,
            alpha_mode: if caps.alpha_modes.contains(&wgpu::CompositeAlphaMode::Opaque) {
                wgpu::CompositeAlphaMode::Opaque
            } else {
                caps.alpha_modes
                    .first()
                    .copied()
                    .unwrap_or(wgpu::CompositeAlphaMode::Auto)
            },
            view_formats: vec![],
            color_space: wgpu::SurfaceColorSpace::Auto,
        };
        self.ctx.device.set_device_lost_callback(|reason, message| {
            console_error(&format!("device lost: {reason:?}: {message}"));
        });
        surface.configure(&self.ctx.device, &config);
        self.canvas = Some(Canvas { surface, config });
        Ok(())
    }

    /// Renders a frame, shows it on the attached canvas (no read-back) and resolves once the
    /// GPU has finished it, so that the page's frame time is the frame's.
    pub async fn present(&mut self) -> Result<(), JsValue> {
        let submitted = self.renderer.render_to(&self.target).map_err(err)?;
        self.views_drawn = submitted.shadow_stats.views_drawn;
        let canvas = self
            .canvas
            .as_mut()
            .ok_or_else(|| err("no canvas is attached"))?;
        let (w, h) = (self.settings.width, self.settings.height);
        if (canvas.config.width, canvas.config.height) != (w, h) {
            canvas.config.width = w;
            canvas.config.height = h;
            canvas.surface.configure(&self.ctx.device, &canvas.config);
        }
        let texture = match canvas.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t)
            | wgpu::CurrentSurfaceTexture::Suboptimal(t) => t,
            other => return Err(err(format!("the canvas gave no texture: {other:?}"))),
        };
        let mut encoder = self.ctx.device.create_command_encoder(&Default::default());
        encoder.copy_texture_to_texture(
            self.target.as_image_copy(),
            texture.texture.as_image_copy(),
            self.target.size(),
        );
        // A 4-byte buffer cleared after the copy: mapping it waits for the frame's work.
        let done = self.ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("frame done"),
            size: 4,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        encoder.clear_buffer(&done, 0, None);
        self.ctx.queue.submit([encoder.finish()]);
        self.ctx.queue.present(texture);
        let (tx, rx) = one_shot();
        done.map_async(wgpu::MapMode::Read, .., move |r| tx(r.is_ok()));
        if !rx.await {
            return Err(err(
                "the GPU did not finish the frame (was the device lost?)",
            ));
        }
        if let Some(e) = self.ctx.take_uncaptured() {
            return Err(err(format!("WebGPU error: {e}")));
        }
        Ok(())
    }

    /// GPU milliseconds per stage of the newest finished frame, `stage ms` per line in the
    /// order they ran, or an empty string where the device has no timestamp queries (or no
    /// frame's times have come back yet). Never waits.
    pub fn gpu_times(&mut self) -> String {
        match self.renderer.poll_gpu_timings() {
            Some(t) if !t.is_empty() => {
                let lines: Vec<String> = t
                    .iter()
                    .map(|(stage, ms)| format!("{}\t{ms:.3}", stage.name()))
                    .collect();
                self.last_gpu_times = lines.join("\n");
            }
            _ => {}
        }
        self.last_gpu_times.clone()
    }

    /// The shadow atlas with its views outlined, or the virtual maps' page pool, as the last
    /// frame left it: an object `{side, rgba, note}` (RGBA8, `side`² pixels, shrunk by a whole
    /// factor to at most `max_side`). Errors: a technique with neither (irregular maps, rays),
    /// or depths over 8192² (their read-back, 4 bytes a texel and 3 for the picture, would
    /// pass 1 GiB of the page's memory; the window viewer shows them).
    pub async fn shadow_picture(&self, max_side: u32) -> Result<js_sys::Object, JsValue> {
        let layout = self.renderer.shadow_layout();
        if layout.side > 8192 {
            return Err(err(format!(
                "the shadow depths ({}) are {}² texels ({} MiB): too large to read back in a web \
                 page; `manyshadows view --show-atlas` shows them",
                layout.fills.describe(),
                layout.side,
                (u64::from(layout.side).pow(2) * 4) >> 20
            )));
        }
        let p = manyshadows::read_deferred(|| self.renderer.shadow_picture())
            .await
            .map_err(err)?;
        let f = p.side.div_ceil(max_side.max(1)).max(1) as usize;
        let side = p.side as usize / f;
        let mut rgba = Vec::with_capacity(side * side * 4);
        for y in 0..side {
            for x in 0..side {
                let i = (y * f * p.side as usize + x * f) * 3;
                rgba.extend_from_slice(&p.rgb[i..i + 3]);
                rgba.push(255);
            }
        }
        let o = js_sys::Object::new();
        let set = |k: &str, v: JsValue| js_sys::Reflect::set(&o, &JsValue::from_str(k), &v);
        set("side", JsValue::from(side as u32))?;
        set("rgba", js_sys::Uint8Array::from(rgba.as_slice()).into())?;
        set(
            "note",
            JsValue::from_str(&if f > 1 {
                format!("{}, shown at {side}² (every {f}th texel)", p.description)
            } else {
                p.description
            }),
        )?;
        Ok(o)
    }

    /// Starts scoring the current view against the exact CPU reference, as `manyshadows
    /// compare` scores a technique (PCF off, the hard visibility mask): renders the view once
    /// more, reads its G-buffer and mask back and builds the BVH. Resolves to what it will
    /// trace, as JSON (`width`, `height`, `lights`, `rays`, `triangles`, `render_ms`,
    /// `bvh_ms`, `soft_samples`); [`WebRenderer::score_step`] then traces it. With
    /// `soft_samples` > 0 and a sized light that casts shadows, the soft reference too, with
    /// that many samples per (pixel, sized light) rounded up to a square (`compare
    /// --soft-samples N`), and the technique's soft visibility is scored against it.
    pub async fn score_start(&mut self, soft_samples: u32) -> Result<String, JsValue> {
        self.score = None;
        if soft_samples > 65_536 {
            return Err(err(format!(
                "{soft_samples} soft samples: at most 65,536 per pair (as compare)"
            )));
        }
        let run = score::ScoreRun::start(
            &self.ctx,
            self.renderer.scene(),
            self.settings.render_settings(),
            soft_samples,
        )
        .await
        .map_err(err)?;
        if let Some(e) = self.ctx.take_uncaptured() {
            return Err(err(format!("WebGPU error: {e}")));
        }
        let plan = run.plan_json();
        self.score = Some(run);
        Ok(plan)
    }

    /// Traces the started score's next rows for about `budget_ms`; returns the fraction of
    /// its rays traced (1 when done: [`WebRenderer::score_result`] then has the numbers).
    pub fn score_step(&mut self, budget_ms: f64) -> Result<f64, JsValue> {
        self.score
            .as_mut()
            .ok_or_else(|| err("no score was started"))?
            .step(budget_ms)
            .map_err(err)
    }

    /// The finished score as JSON (`compare --json`'s names over every light), or an empty
    /// string while it runs.
    pub fn score_result(&self) -> String {
        self.score
            .as_ref()
            .and_then(score::ScoreRun::result_json)
            .unwrap_or_default()
    }

    /// The finished score's misclassified pixels, RGBA to lay over the frame (red = false
    /// shadow, green = false light, darker in the edge band); empty before.
    pub fn score_overlay(&self) -> Vec<u8> {
        self.score
            .as_ref()
            .map(score::ScoreRun::overlay)
            .unwrap_or_default()
    }

    /// Stops and forgets the score.
    pub fn score_stop(&mut self) {
        self.score = None;
    }

    /// The last frame's RGBA8 (sRGB) pixels, row-major from the top-left, read back from the
    /// GPU (the page's tests; showing the frame does not need it).
    pub async fn read_frame(&self) -> Result<Vec<u8>, JsValue> {
        let pixels = read_back(&self.ctx, &self.target).await?;
        if let Some(e) = self.ctx.take_uncaptured() {
            return Err(err(format!("WebGPU error: {e}")));
        }
        Ok(pixels)
    }

    /// Whether frames carry history (sampled lights reused or denoised): still frames converge,
    /// so the page draws a few more after each change.
    pub fn accumulates(&self) -> bool {
        self.settings.reuse || self.settings.denoise
    }

    /// Shadow views the last frame drew; the other views' maps were kept from earlier frames
    /// (while only the camera moves, every map but the cascades that follow the view).
    pub fn shadow_views_drawn(&self) -> u32 {
        self.views_drawn
    }

    /// What the technique fills: `atlas` (shadow views in tiles: the views-drawn count means
    /// something), `pages` (virtual maps: the pages each frame needs), `mask` (irregular
    /// maps: a visibility bit per pixel and light) or `rays`.
    pub fn shadow_fills(&self) -> String {
        match self.renderer.shadow_layout().fills {
            manyshadows::Fills::Atlas => "atlas",
            manyshadows::Fills::Pages => "pages",
            manyshadows::Fills::Mask => "mask",
            manyshadows::Fills::Rays => "rays",
            _ => "other",
        }
        .into()
    }

    /// Shadow views of the frame in all.
    pub fn shadow_views(&self) -> u32 {
        self.renderer.shadow_layout().views as u32
    }

    /// Shadow views that follow the camera (directional lights' cascades), redrawn whenever it
    /// moves.
    pub fn camera_views(&self) -> u32 {
        let scene = self.renderer.scene();
        scene
            .lights
            .iter()
            .filter(|l| l.casts_shadows)
            .map(|l| match l.kind {
                manyshadows::scene::LightKind::Directional { cascades, .. } => cascades,
                _ => 0,
            })
            .sum()
    }

    /// The camera, `px,py,pz,tx,ty,tz` (as `render --camera` takes it).
    pub fn camera(&self) -> String {
        let c = self.renderer.scene().camera;
        [c.position, c.target]
            .iter()
            .flat_map(|v| v.to_array())
            .map(|x| format!("{x}"))
            .collect::<Vec<_>>()
            .join(",")
    }

    /// Frame width in pixels.
    pub fn width(&self) -> u32 {
        self.settings.width
    }

    /// Frame height in pixels.
    pub fn height(&self) -> u32 {
        self.settings.height
    }

    /// One line per technique of the registry: its name, a tab, and what this device lacks
    /// for it (empty where it runs). The page disables the ones it cannot run.
    pub fn technique_status(&self) -> String {
        Technique::all()
            .iter()
            .map(|t| {
                let unmet: Vec<String> =
                    t.info().unmet(&self.ctx).iter().map(|n| n.name()).collect();
                format!("{}\t{}", t.name(), unmet.join(", "))
            })
            .collect::<Vec<_>>()
            .join("\n")
    }

    /// A few lines for the page: adapter, lights, shadow views, atlas and what the device lacks.
    pub fn info(&self) -> String {
        let layout = self.renderer.shadow_layout();
        // What the techniques need that this device lacks (from their declarations), and the
        // measurements the page could show.
        let mut lacks: Vec<String> = Technique::all()
            .iter()
            .filter_map(|t| {
                let unmet: Vec<String> =
                    t.info().unmet(&self.ctx).iter().map(|n| n.name()).collect();
                (!unmet.is_empty()).then(|| format!("{} (technique {t})", unmet.join(", ")))
            })
            .collect();
        for (f, what) in [
            (
                wgpu::Features::PIPELINE_STATISTICS_QUERY,
                "pipeline statistics (primitive counters)",
            ),
            (
                wgpu::Features::TIMESTAMP_QUERY,
                "timestamp queries (GPU times)",
            ),
        ] {
            if !self.ctx.has(f) {
                lacks.push(what.into());
            }
        }
        // Browsers hide the adapter's name from wgpu; the page prints what it may know.
        let adapter = self.ctx.describe();
        format!(
            "adapter: {}\nscene {}: {} lights, {} shadow views, {} {}²{}\n\
             technique {}, {} point shadows, PCF {}, {} light loop{}\n{}\nthis device lacks: {}",
            if self.ctx.info.name.is_empty() {
                "the browser's WebGPU (see above)".to_string()
            } else {
                adapter
            },
            if self.settings.scene == MODEL_SCENE {
                self.model_name()
            } else {
                self.settings.scene.clone()
            },
            self.renderer.scene().lights.len(),
            layout.views,
            layout.fills.describe(),
            layout.side,
            layout
                .atlas_fill
                .map(|f| format!(" ({:.0} % filled)", f * 100.0))
                .unwrap_or_default(),
            self.settings.technique.name(),
            self.settings.point_shadows.name(),
            self.settings.pcf.name(),
            self.settings.light_loop.name(),
            match self.settings.light_samples {
                0 => String::new(),
                k => format!(
                    "; {k} light{} sampled per pixel{}{}",
                    if k == 1 { "" } else { "s" },
                    if self.settings.reuse { ", reused" } else { "" },
                    if self.settings.denoise {
                        ", denoised"
                    } else {
                        ""
                    }
                ),
            },
            self.renderer.look().describe(),
            if lacks.is_empty() {
                "nothing the renderer uses".into()
            } else {
                lacks.join(", ")
            }
        )
    }
}

/// Copies `target` into a mappable buffer and waits (asynchronously) for its pixels.
async fn read_back(ctx: &GpuContext, target: &wgpu::Texture) -> Result<Vec<u8>, JsValue> {
    let (width, height) = (target.width(), target.height());
    // Rows padded to 256 bytes, as copies require.
    let row = (width * 4).next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
    let buffer = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("web.readback"),
        size: row as u64 * height as u64,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    encoder.copy_texture_to_buffer(
        target.as_image_copy(),
        wgpu::TexelCopyBufferInfo {
            buffer: &buffer,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(row),
                rows_per_image: None,
            },
        },
        target.size(),
    );
    ctx.queue.submit([encoder.finish()]);
    let (tx, rx) = one_shot();
    buffer.map_async(wgpu::MapMode::Read, .., move |r| {
        if let Err(e) = &r {
            console_error(&format!("mapping the frame for reading: {e}"));
        }
        tx(r.is_ok())
    });
    if !rx.await {
        return Err(err("mapping the frame for reading failed"));
    }
    let data = buffer.get_mapped_range(..).map_err(err)?;
    let mut out = Vec::with_capacity((width * height * 4) as usize);
    for y in 0..height as usize {
        out.extend_from_slice(&data[y * row as usize..y * row as usize + width as usize * 4]);
    }
    Ok(out)
}

/// A one-shot channel as a JS promise (no extra crate): resolved by the map callback.
fn one_shot() -> (
    impl FnOnce(bool) + 'static,
    impl std::future::Future<Output = bool>,
) {
    let mut resolve_fn = None;
    let promise = js_sys::Promise::new(&mut |resolve, _| resolve_fn = Some(resolve));
    let resolve = resolve_fn.expect("Promise::new runs its executor at once");
    let send = move |ok: bool| {
        let _ = resolve.call1(&JsValue::NULL, &JsValue::from_bool(ok));
    };
    let fut = async move {
        wasm_bindgen_futures::JsFuture::from(promise)
            .await
            .ok()
            .and_then(|v| v.as_bool())
            .unwrap_or(false)
    };
    (send, fut)
}
