//! Drawing the reflection probes' faces (seed 000's reflection cube maps) through the frame's
//! own passes: each face is a small frame of its own (`Probe::face_cameras`: 90°, square),
//! drawn into one G-buffer sized to a face and lit, one face after another, with the frame's
//! lights and its shadow source (the same maps the camera's pixels read), straight into its
//! layer of [`ProbeMaps::faces`] (linear radiance), which the frame's lighting then samples
//! for reflections.
//!
//! **Per face** only the face's uniforms differ: they are copied, in the encoder, from a
//! staging buffer that holds every face's into the one uniform buffer both passes read, so the
//! faces' passes run in order in one submission.
//!
//! **What a face is not**: it has no light clusters (its pixels loop over every light: a
//! face is at most a few hundred texels on a side) and no reflections of its own (one bounce);
//! `FrameUniforms::view` stays the camera's, so a directional light's cascade is chosen by the
//! camera's depth of the point, as the cascades were fitted to the camera.
//!
//! **Kept while nothing changes** (as shadow views are cached): the faces are redrawn in a
//! frame only when a light, a caster or the light count changed since they were drawn, or the
//! camera moved where the shadows depend on it (directional lights' cascades, virtual pages).

use manyshadows_scene::light_space;
use manyshadows_scene::Scene;

use crate::error::RenderError;
use crate::frame::clusters::LightClusters;
use crate::frame::gbuffer::{GBuffer, GBufferViews};
use crate::gpu::context::GpuContext;
use crate::gpu::timing::{GpuTimer, Span};
use crate::gpu::types::FrameUniforms;
use crate::gpu_scene::instances::GpuScene;
use crate::probes::maps::{FaceView, ProbeMaps, ProbePasses, ProbeStats};
use crate::shading::inputs::FrameInputs;
use crate::shading::lighting::{LightingInputs, LightingPass};
use crate::shading::look::ShadingConsts;
use crate::shadows::source::ShadowSource;

use crate::probes::clusters::FaceClusters;

/// Byte stride of the staging buffer's per-face uniforms: `FrameUniforms` rounded up to 256
/// (the copy offset alignment is 4; 256 keeps each block aligned as a dynamic uniform offset
/// would want).
const STRIDE: u64 = (std::mem::size_of::<FrameUniforms>() as u64).next_multiple_of(256);

/// The faces' G-buffers drawn into the tiles of one atlas: in one layered pass
/// ([`ProbePasses::Layered`]) or from GPU-culled clusters ([`ProbePasses::Clusters`]).
struct LayeredFaces {
    /// `FrameUniforms` of the atlas (its viewport is the atlas's size).
    uniforms: wgpu::Buffer,
    /// `array<FaceView>`.
    views: wgpu::Buffer,
    atlas: GBuffer,
    /// Tiles per row.
    cols: u32,
    /// Drawn GPU-driven: the clusters and their cull.
    clusters: Option<FaceClusters>,
}

/// The probes' faces and the passes that draw them.
pub(crate) struct ProbeFrame {
    /// What the frame's lighting samples.
    pub(crate) maps: ProbeMaps,
    /// `FrameUniforms` of the face being drawn.
    uniforms: wgpu::Buffer,
    /// Every face's `FrameUniforms`, `STRIDE` apart.
    staging: wgpu::Buffer,
    gbuffer: GBuffer,
    clusters: LightClusters,
    lighting: LightingPass,
    /// Drawn layered: every face's G-buffer in one pass into its tile of this atlas.
    layered: Option<LayeredFaces>,
    /// Drawn multiview: the faces' views and the six-layer G-buffer of one probe's pass.
    multiview: Option<(wgpu::Buffer, GBuffer)>,
    /// Per face, per draw, whether its bounding sphere meets the face's frustum (the others
    /// are not drawn into that face).
    visible: Vec<Vec<bool>>,
    /// The same by draw then face (`draw · faces + face`), for the layered pass.
    visible_by_draw: Vec<bool>,
    /// The faces must be drawn in the next frame.
    pub(crate) dirty: bool,
    /// Faces drawn by the last frame.
    pub(crate) faces_drawn: u32,
}

impl ProbeFrame {
    /// The faces of `scene`'s probes (at least one) and their passes, lit with `lights` and
    /// `source`'s shadows as `consts` shade the frame.
    pub(crate) fn new(
        ctx: &GpuContext,
        scene: &Scene,
        gpu_scene: &GpuScene,
        lights: &wgpu::Buffer,
        source: &dyn ShadowSource,
        consts: ShadingConsts,
        passes: ProbePasses,
    ) -> Result<Self, RenderError> {
        let maps = ProbeMaps::new(ctx, scene)?;
        let layered = match passes {
            ProbePasses::Layered => Some(LayeredFaces::new(ctx, gpu_scene, &maps, None)?),
            ProbePasses::Clusters => {
                let clusters = FaceClusters::new(ctx)?;
                Some(LayeredFaces::new(ctx, gpu_scene, &maps, Some(clusters))?)
            }
            _ => None,
        };
        let multiview = match passes {
            ProbePasses::Multiview => Some(face_layers(ctx, gpu_scene, &maps)?),
            _ => None,
        };
        let side = maps.side;
        let device = &ctx.device;
        let size = std::mem::size_of::<FrameUniforms>() as u64;
        let uniforms = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("probes.uniforms"),
            size,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let staging = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("probes.staging"),
            size: STRIDE * 6 * maps.count as u64,
            usage: wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let gbuffer = GBuffer::new(ctx, gpu_scene, &uniforms, (side, side), GBufferViews::Mono);
        // No clusters (their uniforms stay zero: every light); the lighting pass binds their
        // buffers all the same.
        let clusters = LightClusters::new(
            ctx,
            (side, side),
            scene.lights.len(),
            Default::default(),
            false,
            None,
        )?;
        let consts = ShadingConsts {
            emission_texture: gbuffer.emission.is_some(),
            linear_out: true,
            ..consts
        };
        let lighting = LightingPass::new(
            ctx,
            &Self::inputs(&uniforms, lights, gpu_scene, &gbuffer, &clusters, source),
            (side, side),
            &consts,
        );
        Ok(Self {
            maps,
            uniforms,
            staging,
            gbuffer,
            clusters,
            lighting,
            layered,
            multiview,
            visible: Vec::new(),
            visible_by_draw: Vec::new(),
            dirty: true,
            faces_drawn: 0,
        })
    }

    /// What a face's lighting reads: the face's G-buffer and clusters, the frame's lights,
    /// materials and shadows; no sampled lights and no reflections of its own (one bounce).
    fn inputs<'a>(
        uniforms: &'a wgpu::Buffer,
        lights: &'a wgpu::Buffer,
        gpu_scene: &'a GpuScene,
        gbuffer: &'a GBuffer,
        clusters: &'a LightClusters,
        source: &'a dyn ShadowSource,
    ) -> LightingInputs<'a> {
        let mut parts = crate::sampled::lighting_parts(None, None, None);
        parts.push(crate::probes::maps::lighting_part(None));
        LightingInputs {
            frame: FrameInputs {
                frame: uniforms,
                lights,
                materials: &gpu_scene.materials,
                gbuffer,
                clusters,
                shadows: source.output(),
            },
            parts,
            wants: None,
        }
    }

    /// After the frame's buffers or shadows were replaced (`Renderer::prepare`): binds them,
    /// rewrites every face's uniforms from the frame's, and (when `redraw`) marks the faces
    /// for drawing. `frame` is the camera's `FrameUniforms`.
    pub(crate) fn update(
        &mut self,
        ctx: &GpuContext,
        scene: &Scene,
        gpu_scene: &GpuScene,
        (lights, source): (&wgpu::Buffer, &dyn ShadowSource),
        frame: &FrameUniforms,
        redraw: bool,
    ) -> Result<(), RenderError> {
        let inputs = Self::inputs(
            &self.uniforms,
            lights,
            gpu_scene,
            &self.gbuffer,
            &self.clusters,
            source,
        );
        self.lighting.rebind(ctx, &inputs);
        let side = self.maps.side;
        let mut bytes = vec![0u8; (STRIDE * 6 * self.maps.count as u64) as usize];
        for (k, probe) in scene.probes.iter().enumerate() {
            for (f, cam) in probe
                .face_cameras(scene.camera.near, scene.camera.far)
                .iter()
                .enumerate()
            {
                let view_proj = (cam.projection(1.0) * cam.view()).to_cols_array_2d();
                let pos = cam.position.extend(1.0).to_array();
                let s = side as f32;
                let u = FrameUniforms {
                    view_proj,
                    camera_pos: pos,
                    viewport: [s, s, 1.0 / s, 1.0 / s],
                    eye_view_proj: [view_proj; 2],
                    eye_pos: [pos; 2],
                    eyes: [s, 1.0, 0.0, 0.0],
                    ..*frame
                };
                let at = (STRIDE as usize) * (6 * k + f);
                bytes[at..at + std::mem::size_of::<FrameUniforms>()]
                    .copy_from_slice(bytemuck::bytes_of(&u));
            }
        }
        ctx.queue.write_buffer(&self.staging, 0, &bytes);
        // Per-face culling of whole instances on the CPU (one pass per face draws only what it
        // sees, the layered pass each instance only into the faces it meets); multiview culls
        // nothing and GPU-driven faces cull clusters on the GPU.
        let per_face = self.layered.is_none() && self.multiview.is_none();
        let layered = self.layered.as_ref().is_some_and(|l| l.clusters.is_none());
        self.visible.clear();
        self.visible_by_draw.clear();
        if !(per_face || layered) {
            return self.update_ways(ctx, scene, gpu_scene, frame, redraw);
        }
        self.visible = scene
            .probes
            .iter()
            .flat_map(|p| p.face_cameras(scene.camera.near, scene.camera.far))
            .map(|cam| {
                let planes = light_space::frustum_planes(cam.projection(1.0) * cam.view());
                gpu_scene
                    .draws
                    .iter()
                    .map(|d| light_space::sphere_in_planes(&planes, d.sphere.0, d.sphere.1))
                    .collect()
            })
            .collect();
        if layered {
            let faces = self.visible.len();
            self.visible_by_draw = (0..gpu_scene.draws.len() * faces)
                .map(|i| self.visible[i % faces][i / faces])
                .collect();
        }
        self.update_ways(ctx, scene, gpu_scene, frame, redraw)
    }

    /// The layered (or GPU-driven) atlas's and the multiview pass's views, and the redraw
    /// mark (the rest of [`Self::update`]).
    fn update_ways(
        &mut self,
        ctx: &GpuContext,
        scene: &Scene,
        gpu_scene: &GpuScene,
        frame: &FrameUniforms,
        redraw: bool,
    ) -> Result<(), RenderError> {
        let side = self.maps.side;
        if let Some(l) = &mut self.layered {
            l.update(ctx, scene, gpu_scene, frame, side)?;
        }
        if let Some((views, _)) = &self.multiview {
            let records = face_views(scene, side, 1, gpu_scene.draws.len() as u32);
            ctx.queue
                .write_buffer(views, 0, bytemuck::cast_slice(&records));
        }
        self.dirty |= redraw;
        Ok(())
    }

    /// Draws every face when they must be, timed as `span`; returns the faces drawn.
    pub(crate) fn record(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        gpu_scene: &GpuScene,
        timer: &GpuTimer,
        span: Option<Span>,
    ) -> u32 {
        if !std::mem::take(&mut self.dirty) {
            self.faces_drawn = 0;
            return 0;
        }
        let faces = 6 * self.maps.count;
        let size = std::mem::size_of::<FrameUniforms>() as u64;
        if let Some(l) = &self.layered {
            if let Some(c) = &l.clusters {
                c.record_begin(encoder, gpu_scene, &l.atlas, (timer, span));
            } else {
                let visible = Some(self.visible_by_draw.as_slice());
                l.atlas
                    .record_faces_begin(encoder, gpu_scene, (timer, span), visible);
            }
        }
        for face in 0..faces {
            encoder.copy_buffer_to_buffer(
                &self.staging,
                STRIDE * face as u64,
                &self.uniforms,
                0,
                size,
            );
            let first = face == 0;
            let last = face + 1 == faces;
            match (&self.layered, &self.multiview) {
                (Some(l), _) => l.copy_tile(encoder, face as u32, &self.gbuffer, self.maps.side),
                (None, Some((_, layers))) => {
                    if face % 6 == 0 {
                        let probe = (face / 6) as u32;
                        layers.record_face_layers(encoder, gpu_scene, (timer, span, first), probe);
                    }
                    layers.copy_layer(encoder, (face % 6) as u32, &self.gbuffer);
                }
                (None, None) => {
                    let writes = (first, false);
                    let visible = self.visible.get(face).map(|v| v.as_slice());
                    self.gbuffer
                        .record_timed(encoder, gpu_scene, (timer, span), writes, visible);
                }
            }
            let target = &self.maps.face_views[face];
            self.lighting
                .record_into(encoder, target, (timer, span), (false, last));
        }
        self.faces_drawn = faces as u32;
        self.faces_drawn
    }

    /// Drawn GPU-driven: of the last frame that drew the faces, the cluster-face pairs the
    /// cull kept and those it was offered (a read-back, for tests).
    pub(crate) fn clusters_kept(
        &self,
        ctx: &GpuContext,
    ) -> Result<Option<(u64, u64)>, RenderError> {
        match self.face_clusters() {
            Some(c) => c.kept(ctx).map(Some),
            None => Ok(None),
        }
    }

    /// Drawn GPU-driven: the clusters and their cull.
    pub(crate) fn face_clusters(&self) -> Option<&FaceClusters> {
        self.layered.as_ref().and_then(|l| l.clusters.as_ref())
    }

    /// The same, to change (test hooks).
    #[cfg(feature = "test-hooks")]
    pub(crate) fn face_clusters_mut(&mut self) -> Option<&mut FaceClusters> {
        self.layered.as_mut().and_then(|l| l.clusters.as_mut())
    }

    /// What the last frame did.
    pub(crate) fn stats(&self) -> ProbeStats {
        ProbeStats {
            probes: self.maps.count as u32,
            side: self.maps.side,
            faces_drawn: self.faces_drawn,
            bytes: self.maps.bytes(),
        }
    }
}

impl LayeredFaces {
    /// The atlas of `maps`' faces (a grid of tiles as square as it goes) and its pass (from
    /// `clusters`, when given); needs `CLIP_DISTANCES`, and an atlas within the device's
    /// largest texture.
    fn new(
        ctx: &GpuContext,
        gpu_scene: &GpuScene,
        maps: &ProbeMaps,
        clusters: Option<FaceClusters>,
    ) -> Result<Self, RenderError> {
        if !ctx.has(wgpu::Features::CLIP_DISTANCES) {
            return Err(RenderError::missing_feature(
                ctx,
                "probe faces drawn into one atlas (layered or GPU-driven)",
                "CLIP_DISTANCES (to keep each face's copy of a triangle in its tile)",
                "draw the probes' faces one pass per face",
            ));
        }
        let faces = 6 * maps.count as u32;
        let cols = (faces as f64).sqrt().ceil() as u32;
        let rows = faces.div_ceil(cols);
        let (w, h) = (cols * maps.side, rows * maps.side);
        let max = ctx.limits().max_texture_dimension_2d;
        if w.max(h) > max {
            return Err(RenderError::TooLarge {
                what: format!(
                    "an atlas of {faces} probe faces of {}² ({w}x{h}) to draw them layered",
                    maps.side
                ),
                needed: u64::from(w.max(h)),
                limit: u64::from(max),
                unit: "texels per side",
                limit_name: "max_texture_dimension_2d",
            });
        }
        let device = &ctx.device;
        let uniforms = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("probes.atlas_uniforms"),
            size: std::mem::size_of::<FrameUniforms>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let views = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("probes.face_views"),
            size: u64::from(faces) * std::mem::size_of::<FaceView>() as u64,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let drawn = match &clusters {
            Some(c) => GBufferViews::FaceClusters {
                views: &views,
                count: faces,
                pull: &c.pull_layout,
            },
            None => GBufferViews::Faces {
                views: &views,
                count: faces,
            },
        };
        let atlas = GBuffer::new(ctx, gpu_scene, &uniforms, (w, h), drawn);
        Ok(Self {
            uniforms,
            views,
            atlas,
            cols,
            clusters,
        })
    }

    /// The faces' views and tiles, the atlas's uniforms (the frame's, its viewport the atlas)
    /// and, drawn GPU-driven, the clusters of `gpu_scene`.
    fn update(
        &mut self,
        ctx: &GpuContext,
        scene: &Scene,
        gpu_scene: &GpuScene,
        frame: &FrameUniforms,
        side: u32,
    ) -> Result<(), RenderError> {
        let views = face_views(scene, side, self.cols, 0);
        ctx.queue
            .write_buffer(&self.views, 0, bytemuck::cast_slice(&views));
        if let Some(c) = &mut self.clusters {
            c.prepare(ctx, scene, gpu_scene, (views.len() as u32, &self.views))?;
        }
        let (w, h) = (self.atlas.position.width(), self.atlas.position.height());
        let (w, h) = (w as f32, h as f32);
        let u = FrameUniforms {
            viewport: [w, h, 1.0 / w, 1.0 / h],
            ..*frame
        };
        ctx.queue
            .write_buffer(&self.uniforms, 0, bytemuck::bytes_of(&u));
        Ok(())
    }

    /// Copies face `face`'s tile of the atlas into `into`, the face G-buffer its lighting
    /// reads.
    fn copy_tile(&self, encoder: &mut wgpu::CommandEncoder, face: u32, into: &GBuffer, side: u32) {
        let (x, y) = ((face % self.cols) * side, (face / self.cols) * side);
        let pairs = [
            (&self.atlas.position, &into.position),
            (&self.atlas.normal, &into.normal),
        ]
        .into_iter()
        .chain(self.atlas.emission.as_ref().zip(into.emission.as_ref()));
        for (from, to) in pairs {
            encoder.copy_texture_to_texture(
                wgpu::TexelCopyTextureInfo {
                    texture: from,
                    mip_level: 0,
                    origin: wgpu::Origin3d { x, y, z: 0 },
                    aspect: wgpu::TextureAspect::All,
                },
                to.as_image_copy(),
                wgpu::Extent3d {
                    width: side,
                    height: side,
                    depth_or_array_layers: 1,
                },
            );
        }
    }
}

/// Every probe face's view, its tile in an atlas of `cols` tiles per row of `side`², and
/// `instances` in `tile.w` (the multiview pass's instance encoding).
fn face_views(scene: &Scene, side: u32, cols: u32, instances: u32) -> Vec<FaceView> {
    let mut views = Vec::new();
    for probe in &scene.probes {
        for cam in probe.face_cameras(scene.camera.near, scene.camera.far) {
            let f = views.len() as u32;
            let (x, y) = ((f % cols) * side, (f / cols) * side);
            views.push(FaceView {
                view_proj: (cam.projection(1.0) * cam.view()).to_cols_array_2d(),
                eye: cam.position.extend(1.0).to_array(),
                tile: [x as f32, y as f32, side as f32, instances as f32],
            });
        }
    }
    views
}

/// The faces' views and the six-layer G-buffer a probe's multiview pass draws into; needs six
/// views per multiview pass.
fn face_layers(
    ctx: &GpuContext,
    gpu_scene: &GpuScene,
    maps: &ProbeMaps,
) -> Result<(wgpu::Buffer, GBuffer), RenderError> {
    let per_pass = ctx.multiview_views_per_pass();
    if per_pass < 6 {
        return Err(RenderError::missing_feature(
            ctx,
            "probe faces drawn multiview",
            format!("MULTIVIEW with six views per pass (this device: {per_pass})"),
            "draw the probes' faces one pass per face, or layered",
        ));
    }
    let views = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("probes.face_views"),
        size: 6 * maps.count as u64 * std::mem::size_of::<FaceView>() as u64,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let side = maps.side;
    let layers = GBuffer::new(
        ctx,
        gpu_scene,
        // The faces' passes read no frame uniforms but the binding's.
        &ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("probes.layers_uniforms"),
            size: std::mem::size_of::<FrameUniforms>() as u64,
            usage: wgpu::BufferUsages::UNIFORM,
            mapped_at_creation: false,
        }),
        (side, side),
        GBufferViews::FaceLayers { views: &views },
    );
    Ok((views, layers))
}
