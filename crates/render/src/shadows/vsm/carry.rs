//! Caching of the virtual shadow maps: what a frame carries over from the last one. On the
//! CPU (`PageCache`), which faces may keep last frame's pages (their view and virtual side
//! unchanged: `VirtualFace::table.w`), where casters moved in them (`VirtualFace::dirty`, from
//! [`super::moved`]), and whether the frame marks incrementally: with the camera, the lights
//! and every face as last frame (only casters moved), last frame's needs carry over and only
//! the pixels the moved casters may cover are marked again. On the GPU (`CarryPass`,
//! `vsm_carry.wgsl`), that carrying over: every page resident or denied last frame is asked
//! again. Which pages keep their pool page and depth is the allocation's call
//! ([`super::alloc`], `cs_retain`).

use std::collections::HashMap;

use glam::{Mat4, Vec3};
use manyshadows_scene::light_space::ViewKind;
use manyshadows_scene::Scene;

use crate::gpu::pipelines::{
    bind_group_layout, compute_pipeline, pipeline_layout, storage_entry, storage_rw_entry,
    uniform_entry, whole_entry,
};
use crate::gpu::shaders::{compose, module, COMMON};
use crate::shadows::vsm::moved::{camera_matrix, moved_rect, screen_rect, union};
use crate::shadows::vsm::plan::{VirtualPlan, NOTHING_MOVED};
use crate::shadows::vsm::table::{entry_groups, TableBuffers, PAGE_TABLE};
use crate::shadows::vsm::types::VirtualFace;
use crate::shadows::vsm::types::VSM_TYPES;

/// Carrying last frame's needs over: `cs_carry`.
pub(crate) fn shader() -> String {
    compose(&[
        COMMON,
        VSM_TYPES,
        PAGE_TABLE,
        include_str!("vsm_carry.wgsl"),
    ])
}

/// How a frame marks the pages its samples need.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Marking {
    /// Every pixel marks.
    Full,
    /// Last frame's needs carry over; the pixels of this rectangle (x0, y0, x1, y1; none when
    /// nothing moved) mark again.
    Carry(Option<[u32; 4]>),
}

/// A face of the last recorded frame, by (light, view kind).
#[derive(Clone, Copy, Debug)]
struct LastFace {
    view_proj: [[f32; 4]; 4],
    side: u32,
    first: u32,
}

/// What page marking depends on, besides the G-buffer under moved casters.
#[derive(Clone, Debug)]
struct SceneKey {
    camera: manyshadows_scene::Camera,
    lights: Vec<manyshadows_scene::Light>,
    /// Transforms of the instances that cast no shadow (their moves are not noted as moves).
    others: Vec<Mat4>,
}

impl SceneKey {
    /// True if `scene` has this camera, these lights and these non-casting instances.
    fn matches(&self, scene: &Scene) -> bool {
        self.camera == scene.camera
            && self.lights == scene.lights
            && self.others.iter().copied().eq(scene
                .instances
                .iter()
                .filter(|i| !i.casts_shadows)
                .map(|i| i.transform))
    }

    fn of(scene: &Scene) -> Self {
        Self {
            camera: scene.camera,
            lights: scene.lights.clone(),
            others: scene
                .instances
                .iter()
                .filter(|i| !i.casts_shadows)
                .map(|i| i.transform)
                .collect(),
        }
    }
}

/// What a frame takes from the last one ([`PageCache::frame`]).
pub(crate) struct Carried {
    /// The plan's faces with what each may keep (`table.w`, `dirty`), for the faces buffer.
    pub faces: Vec<VirtualFace>,
    pub marking: Marking,
    /// `VsmUniforms::prev.x`: page-table entries of the last recorded frame (what last
    /// frame's table holds).
    pub prev_entries: u32,
    /// `VsmUniforms::prev.y`: pages drawn now may be kept later, so they get room to spare.
    pub spare: bool,
    /// Whether a face may keep its pages: only then is last frame's table read.
    pub copy_prev: bool,
}

/// The CPU side of the caching: last frame's faces, the casters moved since, and what the
/// marking depended on.
pub(crate) struct PageCache {
    /// Page-table entries of the last recorded frame (what `prev_table` receives).
    prev_entries: u32,
    /// The faces of the last recorded frame; empty when nothing may be kept.
    last: HashMap<(usize, ViewKind), LastFace>,
    /// Caster bounding spheres moved since the last frame (old and new).
    moves: Vec<[(Vec3, f32); 2]>,
    /// What the marking depends on besides the G-buffer under moved casters: the camera, the
    /// lights and the non-casting instances, as of the last [`Self::update`].
    key: SceneKey,
    /// Bumped whenever `key` changes.
    key_gen: u64,
    /// `key_gen` of the last recorded frame (its table holds that state's needs).
    marked_gen: u64,
    /// Camera world → clip, for the screen rectangle of moved casters.
    camera: Mat4,
}

impl PageCache {
    /// Nothing to keep yet, for `scene` seen on a `size` screen.
    pub(crate) fn new(scene: &Scene, size: (u32, u32)) -> Self {
        Self {
            prev_entries: 0,
            last: Default::default(),
            moves: Vec::new(),
            key: SceneKey::of(scene),
            key_gen: 1,
            marked_gen: 0,
            camera: camera_matrix(scene, size),
        }
    }

    /// Follows a changed frame (camera, lights).
    pub(crate) fn update(&mut self, scene: &Scene, size: (u32, u32)) {
        // Compared in place: a caster moving every frame costs no copy of thousands of lights.
        if !self.key.matches(scene) {
            self.key = SceneKey::of(scene);
            self.key_gen += 1;
        }
        self.camera = camera_matrix(scene, size);
    }

    /// Last frame's table went with its buffer: keep no pages next time.
    pub(crate) fn table_replaced(&mut self) {
        self.last.clear();
    }

    /// Notes that a shadow caster's bounding sphere moved from `old` to `new`.
    pub(crate) fn note_moved(&mut self, old: (Vec3, f32), new: (Vec3, f32)) {
        self.moves.push([old, new]);
    }

    /// Keeps no page at the next frame (caster geometry or culling decisions changed).
    pub(crate) fn forget(&mut self) {
        self.last.clear();
        self.key_gen += 1;
    }

    /// What the next frame of `plan` (on a `viewport` screen) carries over: with `keep`,
    /// faces whose view and virtual side did not change may keep their pages, except where
    /// casters moved. Notes the faces as the last frame's and forgets the moves.
    pub(crate) fn frame(
        &mut self,
        plan: &VirtualPlan,
        keep: bool,
        viewport: (u32, u32),
    ) -> Carried {
        // Which faces may keep last frame's pages: `table.w` = their first entry then + 1, and
        // where in them casters moved (`dirty`): only the kept pages there are drawn anew (and
        // those whose samples now reach past the receiver bound they were drawn with).
        let mut faces = plan.faces.clone();
        for (face, view) in faces.iter_mut().zip(&plan.views) {
            face.table[3] = 0;
            face.dirty = NOTHING_MOVED;
            let Some(last) = self.last.get(&(view.light, view.kind)) else {
                continue;
            };
            if !(keep && last.view_proj == face.view_proj && last.side == face.table[2]) {
                continue;
            }
            face.table[3] = last.first + 1;
            for &(c, r) in self.moves.iter().flatten() {
                if view.sphere_visible(c, r) {
                    face.dirty = union(face.dirty, moved_rect(view.view_proj, c, r));
                }
            }
        }
        self.last = faces
            .iter()
            .zip(&plan.views)
            .map(|(f, v)| {
                let last = LastFace {
                    view_proj: f.view_proj,
                    side: f.table[2],
                    first: f.table[0],
                };
                ((v.light, v.kind), last)
            })
            .collect();
        // Incremental marking: with the camera, lights and every face as last frame (only
        // casters moved), last frame's needs carry over and only the pixels the moved casters
        // may cover (old and new places) are marked again.
        let incremental = keep
            && self.marked_gen == self.key_gen
            && self.prev_entries == plan.fit.table_entries
            && faces.iter().all(|f| f.table[3] != 0);
        let marking = if incremental {
            let rect = self
                .moves
                .iter()
                .flatten()
                .map(|&(c, r)| screen_rect(self.camera, viewport, c, r))
                .reduce(|a, b| {
                    [
                        a[0].min(b[0]),
                        a[1].min(b[1]),
                        a[2].max(b[2]),
                        a[3].max(b[3]),
                    ]
                });
            Marking::Carry(rect.filter(|r| r[0] < r[2] && r[1] < r[3]))
        } else {
            Marking::Full
        };
        // Pages drawn now may be kept later, so they get room to spare (not in a renderer's
        // first frame: a single image pays nothing for it). Not when marking incrementally
        // either: carried pages' needs are the bounds they were drawn with, room included, and
        // widening those again would grow a page under a caster that moves every frame until
        // it covers the whole page.
        let spare = keep && self.prev_entries > 0 && !incremental;
        self.moves.clear();
        // Last frame's table is read only where a face may keep its pages.
        let copy_prev = faces.iter().any(|f| f.table[3] != 0);
        Carried {
            faces,
            marking,
            prev_entries: self.prev_entries,
            spare,
            copy_prev,
        }
    }

    /// Notes that a frame of `entries` page-table entries was recorded.
    pub(crate) fn recorded(&mut self, entries: u32) {
        self.prev_entries = entries;
        self.marked_gen = self.key_gen;
    }
}

/// The carrying pass: its layout, pipeline and bind group.
pub(crate) struct CarryPass {
    layout: wgpu::BindGroupLayout,
    carry: wgpu::ComputePipeline,
    group: Option<wgpu::BindGroup>,
}

impl CarryPass {
    pub(crate) fn new(device: &wgpu::Device) -> Self {
        let cs = wgpu::ShaderStages::COMPUTE;
        let layout = bind_group_layout(
            device,
            "vsm.carry_layout",
            &[
                uniform_entry(7, cs),
                storage_entry(8, cs),
                storage_rw_entry(9, cs),
                storage_entry(14, cs),
            ],
        );
        let code = module(device, "vsm.carry_shader", &shader());
        let pl = pipeline_layout(device, "vsm.carry_pipeline_layout", &[&layout]);
        Self {
            carry: compute_pipeline(device, "vsm.carry", &pl, &code, "cs_carry"),
            layout,
            group: None,
        }
    }

    /// Builds the bind group (whenever a buffer it holds was replaced).
    pub(crate) fn bind(&mut self, device: &wgpu::Device, table: &TableBuffers<'_>) {
        self.group = Some(device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("vsm.carry_group"),
            layout: &self.layout,
            entries: &[
                whole_entry(7, table.uniforms),
                whole_entry(8, table.faces),
                whole_entry(9, table.table),
                whole_entry(14, table.prev_table),
            ],
        }));
    }

    /// Asks again, in a table of `entries` entries, for the pages last frame had resident or
    /// denied in the faces that keep theirs.
    pub(crate) fn record(&self, pass: &mut wgpu::ComputePass<'_>, entries: u32) {
        let Some(group) = &self.group else {
            return;
        };
        let (x, y) = entry_groups(entries as u64);
        pass.set_bind_group(0, group, &[]);
        pass.set_pipeline(&self.carry);
        pass.dispatch_workgroups(x, y, 1);
    }
}
