//! Recording the G-buffer pass: the camera's view (mono, or stereo in one pass or one per
//! eye), and the probes' faces (one pass per face, layered, multiview with a copy into the
//! faces' layers, or GPU-driven clusters), each timed where asked.

use crate::frame::eyes::EyePasses;
use crate::frame::gbuffer::GBuffer;
use crate::gpu::timing::{GpuTimer, Span};
use crate::gpu_scene::instances::{CameraCull, GpuScene};

impl GBuffer {
    /// Records the pass: every instance, no culling (the camera sees a handful of instances
    /// fewer at most; the shadow passes are where culling pays). Stereo: one pass per eye, or
    /// one pass drawing both (`EyePasses`).
    pub fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        scene: &GpuScene,
        timer: &GpuTimer,
        span: Option<Span>,
    ) {
        if let Some(n) = self.faces {
            self.record_pass(encoder, scene, (timer, span, true, true), None, (n, 0..n));
            return;
        }
        self.record_views(encoder, scene, timer, span);
    }

    /// A probe's six faces (`GBufferViews::FaceLayers`): probe `probe`'s multiview pass into
    /// the six-layer targets (draw instances `probe · instances + i`), beginning the span when
    /// `begin`; [`Self::copy_layer`] then hands each face on.
    pub(crate) fn record_face_layers(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        scene: &GpuScene,
        (timer, span, begin): (&GpuTimer, Option<Span>, bool),
        probe: u32,
    ) {
        let Some(mv) = &self.multiview else {
            debug_assert!(false, "face layers are drawn into multiview targets");
            return;
        };
        let base = probe * scene.draws.len() as u32;
        let writes = (timer, span, begin, false);
        self.record_into(
            encoder,
            scene,
            &mv.views,
            writes,
            (true, None, None),
            (1, base..base + 1),
        );
    }

    /// Copies layer `layer` of the face-layer targets (position, normal, emission) into `into`.
    pub(crate) fn copy_layer(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        layer: u32,
        into: &GBuffer,
    ) {
        let Some(mv) = &self.multiview else {
            return;
        };
        // The layers' textures are position, normal, depth, emission (see `new`).
        let pairs = [(0, &into.position), (1, &into.normal)]
            .into_iter()
            .chain(into.emission.as_ref().map(|e| (3, e)));
        for (i, target) in pairs {
            let Some(layers) = mv.textures.get(i) else {
                continue;
            };
            encoder.copy_texture_to_texture(
                wgpu::TexelCopyTextureInfo {
                    texture: layers,
                    mip_level: 0,
                    origin: wgpu::Origin3d {
                        x: 0,
                        y: 0,
                        z: layer,
                    },
                    aspect: wgpu::TextureAspect::All,
                },
                target.as_image_copy(),
                wgpu::Extent3d {
                    width: target.width(),
                    height: target.height(),
                    depth_or_array_layers: 1,
                },
            );
        }
    }

    /// Square views in tiles (`GBufferViews::Faces`) in their one pass, which begins the span
    /// (passes recorded after it end it); `visible[draw · views + view]` false leaves that
    /// instance out of that view (consecutive views still drawn, one draw per run).
    pub(crate) fn record_faces_begin(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        scene: &GpuScene,
        (timer, span): (&GpuTimer, Option<Span>),
        visible: Option<&[bool]>,
    ) {
        let n = self.faces.unwrap_or(1);
        let writes = (timer, span, true, false);
        self.record_into(
            encoder,
            scene,
            &self.views,
            writes,
            (true, None, visible),
            (n, 0..n),
        );
    }

    fn record_views(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        scene: &GpuScene,
        timer: &GpuTimer,
        span: Option<Span>,
    ) {
        match self.stereo {
            None => {
                self.record_pass(encoder, scene, (timer, span, true, true), None, (1, 0..1));
            }
            Some(EyePasses::PerEye) => {
                let eye_width = self.size.0 / 2;
                for eye in 0..2u32 {
                    let rect = [eye * eye_width, 0, eye_width, self.size.1];
                    let writes = (timer, span, eye == 0, eye == 1);
                    self.record_pass(encoder, scene, writes, Some(rect), (2, eye..eye + 1));
                }
            }
            Some(EyePasses::Layered) => {
                self.record_pass(encoder, scene, (timer, span, true, true), None, (2, 0..2));
            }
            Some(EyePasses::Multiview) => self.record_multiview(encoder, scene, timer, span),
        }
    }

    /// Both eyes in one multiview pass into the two-layer targets, then each layer copied
    /// into its eye's half (the depth is not needed after the pass).
    fn record_multiview(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        scene: &GpuScene,
        timer: &GpuTimer,
        span: Option<Span>,
    ) {
        let Some(mv) = &self.multiview else {
            debug_assert!(false, "multiview targets are made with the pipelines");
            return;
        };
        let writes = (timer, span, true, true);
        self.record_into(
            encoder,
            scene,
            &mv.views,
            writes,
            (true, None, None),
            (1, 0..1),
        );
        let eye_width = self.size.0 / 2;
        // The layers' textures are position, normal, depth, emission (see `new`).
        let pairs = [(0, &self.position), (1, &self.normal)]
            .into_iter()
            .chain(self.emission.as_ref().map(|e| (3, e)));
        for (i, target) in pairs {
            let layers = &mv.textures[i];
            for eye in 0..2u32 {
                encoder.copy_texture_to_texture(
                    wgpu::TexelCopyTextureInfo {
                        texture: layers,
                        mip_level: 0,
                        origin: wgpu::Origin3d { x: 0, y: 0, z: eye },
                        aspect: wgpu::TextureAspect::All,
                    },
                    wgpu::TexelCopyTextureInfo {
                        texture: target,
                        mip_level: 0,
                        origin: wgpu::Origin3d {
                            x: eye * eye_width,
                            y: 0,
                            z: 0,
                        },
                        aspect: wgpu::TextureAspect::All,
                    },
                    wgpu::Extent3d {
                        width: eye_width,
                        height: self.size.1,
                        depth_or_array_layers: 1,
                    },
                );
            }
        }
    }

    /// One render pass: the first (`writes.2`) clears; `rect` limits it to one eye's half;
    /// each scene instance `i` is drawn as draw instances `eyes·i + copies`.
    fn record_pass(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        scene: &GpuScene,
        (timer, span, first, last): (&GpuTimer, Option<Span>, bool, bool),
        rect: Option<[u32; 4]>,
        (eyes, copies): (u32, std::ops::Range<u32>),
    ) {
        let writes = (timer, span, first, last);
        self.record_into(
            encoder,
            scene,
            &self.views,
            writes,
            (first, rect, None),
            (eyes, copies),
        );
    }

    /// A mono pass that clears and writes the span's first (`begin`) and last (`end`)
    /// timestamps as asked: several frames' G-buffers drawn into the same targets one after
    /// another (a reflection probe's faces), timed as one span; `visible` (by draw) leaves out
    /// the draws it marks false (culled by the caller against the view's frustum).
    pub(crate) fn record_timed(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        scene: &GpuScene,
        (timer, span): (&GpuTimer, Option<Span>),
        (begin, end): (bool, bool),
        visible: Option<&[bool]>,
    ) {
        let writes = (timer, span, begin, end);
        self.record_into(
            encoder,
            scene,
            &self.views,
            writes,
            (true, None, visible),
            (1, 0..1),
        );
    }

    /// [`Self::record_pass`] into `views` (position, normal, depth, emission): the frame's
    /// targets, or the multiview pass's two-layer ones.
    fn record_into(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        scene: &GpuScene,
        views: &[wgpu::TextureView],
        (timer, span, first, last): (&GpuTimer, Option<Span>, bool, bool),
        (clear, rect, visible): (bool, Option<[u32; 4]>, Option<&[bool]>),
        (eyes, copies): (u32, std::ops::Range<u32>),
    ) {
        let mut pass = self.begin_pass(encoder, views, (timer, span, first, last), clear);
        if let Some([x, y, w, h]) = rect {
            pass.set_viewport(x as f32, y as f32, w as f32, h as f32, 0.0, 1.0);
            pass.set_scissor_rect(x, y, w, h);
        }
        pass.set_bind_group(0, &self.bind_group, &[]);
        pass.set_vertex_buffer(0, scene.positions.slice(..));
        pass.set_vertex_buffer(1, scene.normals.slice(..));
        pass.set_vertex_buffer(2, scene.uvs.slice(..));
        if self.instance.is_some() {
            // The moving pipelines' last positions: this frame's where no mesh bends.
            let last = scene
                .last_positions
                .as_ref()
                .map_or(&scene.positions, |l| &l.buffer);
            pass.set_vertex_buffer(3, last.slice(..));
        }
        pass.set_index_buffer(scene.indices.slice(..), wgpu::IndexFormat::Uint32);
        // Opaque surfaces first (early depth testing), then the alpha-tested ones.
        for masked in [false, true] {
            let mut set = None;
            for (k, d) in scene.draws.iter().enumerate() {
                if d.masked != masked {
                    continue;
                }
                // The draw's copies (views) to draw: all, or the runs `visible` marks (index
                // `draw · eyes + copy`).
                let shown = |c: u32| {
                    visible.is_none_or(|v| {
                        v.get(k * eyes as usize + c as usize)
                            .copied()
                            .unwrap_or(true)
                    })
                };
                let mut c = copies.start;
                while c < copies.end {
                    if !shown(c) {
                        c += 1;
                        continue;
                    }
                    let run = c;
                    while c < copies.end && shown(c) {
                        c += 1;
                    }
                    let key = (masked, d.camera_cull);
                    if set != Some(key) {
                        pass.set_pipeline(&self.pipelines[&key]);
                        set = Some(key);
                    }
                    let m = d.mesh;
                    pass.draw_indexed(
                        m.first_index..m.first_index + m.index_count,
                        m.base_vertex,
                        eyes * d.instance + run..eyes * d.instance + c,
                    );
                }
            }
        }
    }

    /// One round of GPU-culled clusters (`GBufferViews::FaceClusters`): a pass into the
    /// atlas (cleared when `clear`; the span's timestamps as `first` and `last` say) with the
    /// pipeline of `key` (alpha test, face culling) and `pull` bound at `offset`, in which
    /// `draw` records the round's indirect multi-draw.
    pub(crate) fn record_face_clusters(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        (timer, span, first, last): (&GpuTimer, Option<Span>, bool, bool),
        clear: bool,
        (pull, offset): (&wgpu::BindGroup, u32),
        key: (bool, CameraCull),
        draw: impl FnOnce(&mut wgpu::RenderPass<'_>),
    ) {
        let mut pass = self.begin_pass(encoder, &self.views, (timer, span, first, last), clear);
        let Some(pipeline) = self.pipelines.get(&key) else {
            debug_assert!(false, "no G-buffer pipeline for {key:?}");
            return;
        };
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, &self.bind_group, &[]);
        pass.set_bind_group(1, pull, &[offset]);
        draw(&mut pass);
    }

    /// A pass into `views` (position, normal, depth, then emission and instance where the
    /// G-buffer has them), cleared when `clear`, its
    /// timestamps as `first` and `last` say.
    fn begin_pass<'e>(
        &self,
        encoder: &'e mut wgpu::CommandEncoder,
        views: &[wgpu::TextureView],
        (timer, span, first, last): (&GpuTimer, Option<Span>, bool, bool),
        clear: bool,
    ) -> wgpu::RenderPass<'e> {
        let (pv, nv, dv) = (&views[0], &views[1], &views[2]);
        let load = if clear {
            wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT)
        } else {
            wgpu::LoadOp::Load
        };
        let target = |view| {
            Some(wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load,
                    store: wgpu::StoreOp::Store,
                },
            })
        };
        encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("gbuffer.pass"),
            // Then the emission and instance targets, where the G-buffer has them.
            color_attachments: &[target(pv), target(nv)]
                .into_iter()
                .chain(views[3..].iter().map(target))
                .collect::<Vec<_>>(),
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: dv,
                depth_ops: Some(wgpu::Operations {
                    // The first pass clears the whole image, the second eye's loads it.
                    load: if clear {
                        wgpu::LoadOp::Clear(1.0)
                    } else {
                        wgpu::LoadOp::Load
                    },
                    store: if last {
                        wgpu::StoreOp::Discard
                    } else {
                        wgpu::StoreOp::Store
                    },
                }),
                stencil_ops: None,
            }),
            timestamp_writes: timer.render_writes(span, first, last),
            occlusion_query_set: None,
            multiview_mask: self
                .multiview
                .as_ref()
                .and_then(|mv| std::num::NonZeroU32::new((1 << mv.layers) - 1)),
        })
    }
}
