//! Motion of instances between frames, for the histories that follow surfaces: the
//! denoiser's (denoise.rs) and the reservoirs' (reuse.rs).
//!
//! Both find last frame's record of a pixel's surface point by projecting the point with the
//! last frame's camera and comparing it with the point kept there. A point on an instance
//! that moved was somewhere else last frame: the G-buffer keeps, per pixel, the instance seen
//! (`GBuffer::instance`, `GBufferViews::MonoMoving`), and [`InstanceMotion::back`] holds per
//! instance the transform from this frame's world back to last frame's (`last · now⁻¹`,
//! the identity for instances that did not move), so the point is taken back to where it
//! was before it is projected and compared. A point on a bent mesh (skinned or morphed) was
//! also elsewhere on its instance: the G-buffer keeps beside the instance the offset to where
//! the mesh held it last frame (gpu_scene/last_positions.rs), added first.

use glam::Mat4;

use crate::gpu::context::GpuContext;

/// Per instance, this frame's world → last frame's, on the GPU; and the instances moved since
/// the last frame recorded.
pub struct InstanceMotion {
    /// `array<mat4x4<f32>>`, one per instance.
    pub back: wgpu::Buffer,
    /// A 1 × 1 instance target holding 0 ("no instance": nothing moves), bound where the
    /// G-buffer keeps no instance (the device cannot hold the target beside the others).
    pub still: wgpu::TextureView,
    table: MotionTable,
}

/// What [`InstanceMotion::back`] holds, kept on the CPU, and the moves it has yet to take in.
#[derive(Debug)]
struct MotionTable {
    /// Per instance, `last · now⁻¹` as `back` holds it.
    mirror: Vec<[f32; 16]>,
    /// Per instance, its transform at the last frame recorded if it moved since.
    was: Vec<Option<Mat4>>,
    /// The instances `was` holds a transform for.
    pending: Vec<usize>,
    /// Instances whose matrix is not the identity (moved between the last two frames).
    written: Vec<usize>,
}

impl MotionTable {
    fn new(instances: usize) -> Self {
        Self {
            mirror: vec![Mat4::IDENTITY.to_cols_array(); instances.max(1)],
            was: vec![None; instances],
            pending: Vec::new(),
            written: Vec::new(),
        }
    }

    /// See [`InstanceMotion::note`].
    fn note(&mut self, instance: usize, was: Mat4) {
        if let Some(slot @ None) = self.was.get_mut(instance) {
            *slot = Some(was);
            self.pending.push(instance);
        }
    }

    /// Takes the moves in (`now(i)`: instance `i`'s transform this frame): each instance
    /// moved since the last frame gets `last · now⁻¹`, each moved before it but not since the
    /// identity again. Returns the range of instances whose matrix changed, if any.
    fn update(&mut self, now: impl Fn(usize) -> Mat4) -> Option<std::ops::Range<usize>> {
        // The lowest and one past the highest instance changed.
        let (mut lo, mut hi) = (usize::MAX, 0);
        let mut set = |mirror: &mut Vec<[f32; 16]>, i: usize, m: Mat4| {
            mirror[i] = m.to_cols_array();
            (lo, hi) = (lo.min(i), hi.max(i + 1));
        };
        for i in std::mem::take(&mut self.written) {
            if self.was[i].is_none() {
                set(&mut self.mirror, i, Mat4::IDENTITY);
            }
        }
        for i in std::mem::take(&mut self.pending) {
            let Some(was) = self.was[i].take() else {
                continue;
            };
            let m = back_transform(was, now(i));
            set(&mut self.mirror, i, m);
            if m != Mat4::IDENTITY {
                self.written.push(i);
            }
        }
        (lo < hi).then_some(lo..hi)
    }
}

impl InstanceMotion {
    /// Identity transforms for `instances` instances.
    pub fn new(ctx: &GpuContext, instances: usize) -> Self {
        use wgpu::util::DeviceExt;
        let table = MotionTable::new(instances);
        let back = ctx
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("motion.back"),
                contents: bytemuck::cast_slice(&table.mirror),
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            });
        Self {
            back,
            still: crate::gpu::pipelines::one_texel_view(
                &ctx.device,
                "motion.still",
                crate::frame::gbuffer::INSTANCE_FORMAT,
            ),
            table,
        }
    }

    /// Instance `instance`, whose transform was `was`, moves before the next frame (only its
    /// first move since the last frame counts: `was` is then the transform that frame drew).
    pub fn note(&mut self, instance: usize, was: Mat4) {
        self.table.note(instance, was);
    }

    /// Before a frame's passes: each instance moved since the last frame gets `last · now⁻¹`
    /// (`now(i)`: its transform this frame), and those moved before it but not since get the
    /// identity again; the range of instances that changed is written in one copy (nothing
    /// when nothing moved).
    pub fn upload(&mut self, queue: &wgpu::Queue, now: impl Fn(usize) -> Mat4) {
        if let Some(range) = self.table.update(now) {
            queue.write_buffer(
                &self.back,
                (range.start * std::mem::size_of::<[f32; 16]>()) as u64,
                bytemuck::cast_slice(&self.table.mirror[range]),
            );
        }
    }

    /// The instance target to bind: the G-buffer's, or [`Self::still`] where it has none.
    pub fn instance_view(&self, gbuffer: &crate::frame::gbuffer::GBuffer) -> wgpu::TextureView {
        gbuffer.instance.as_ref().map_or_else(
            || self.still.clone(),
            |t| t.create_view(&Default::default()),
        )
    }
}

/// World now → world then, for an instance drawn with `then` last frame and `now` this frame:
/// exactly the identity when it did not move (so a still surface's point is not rounded).
pub fn back_transform(then: Mat4, now: Mat4) -> Mat4 {
    if then == now {
        Mat4::IDENTITY
    } else {
        then * now.inverse()
    }
}

/// The WGSL both histories use: per pixel `px`, the instance's motion back to the last frame
/// (`instance_back`, the identity where the pixel's instance did not move or none is kept),
/// and a point's and a normal's place through it. Needs `gbuf_instance: texture_2d<u32>` and
/// `motion_back: array<mat4x4<f32>>` declared by the includer. (The normal is turned by the
/// matrix itself: right for rigid motions and uniform scaling, which is what moves; a
/// non-uniform scale would want its inverse transpose.)
pub const WGSL: &str = "
fn instance_back(px: vec2<u32>) -> mat4x4<f32> {
    // The stand-in target is 1 x 1 (motion.rs `still`).
    let at = min(px, textureDimensions(gbuf_instance) - vec2<u32>(1u));
    let k = textureLoad(gbuf_instance, vec2<i32>(at), 0).x;
    if (k == 0u) {
        return mat4x4<f32>(vec4<f32>(1.0, 0.0, 0.0, 0.0), vec4<f32>(0.0, 1.0, 0.0, 0.0),
                           vec4<f32>(0.0, 0.0, 1.0, 0.0), vec4<f32>(0.0, 0.0, 0.0, 1.0));
    }
    return motion_back[k - 1u];
}

// Where the surface point `p` of pixel `px` was last frame (`back`: `instance_back` of the
// pixel): where its bent mesh held it (the offset the G-buffer keeps beside the instance,
// zero where no mesh bends: gbuffer.rs `MOTION_FORMAT`), then taken by its instance's motion.
fn last_frame_position(px: vec2<u32>, back: mat4x4<f32>, p: vec3<f32>) -> vec3<f32> {
    return (back * vec4<f32>(p + bent_offset(px), 1.0)).xyz;
}

// The offset from pixel `px`'s point to where its bent mesh held it last frame. An
// `INSTANCE_FORMAT` target (no mesh bends) reads (0, 0, 1) in yzw: 1 is the bits of the least
// denormal, taken as 0.
fn bent_offset(px: vec2<u32>) -> vec3<f32> {
    let at = min(px, textureDimensions(gbuf_instance) - vec2<u32>(1u));
    let bits = textureLoad(gbuf_instance, vec2<i32>(at), 0).yzw;
    return select(bitcast<vec3<f32>>(bits), vec3<f32>(0.0), bits == vec3<u32>(0u, 0u, 1u));
}

// Which way the unit normal `n` faced last frame.
fn last_frame_normal(back: mat4x4<f32>, n: vec3<f32>) -> vec3<f32> {
    return normalize((back * vec4<f32>(n, 0.0)).xyz);
}

// Whether a history point whose surface faced `then` may stand for one facing `now` (both
// unit; HISTORY_NORMAL_COS, motion.rs): a surface seen from its other side, or the
// other face of a crease, starts anew.
fn same_facing(then: vec3<f32>, now: vec3<f32>) -> bool {
    return dot(then, now) >= HISTORY_NORMAL_COS;
}
";

/// The cosine of the widest angle between the normal a history was kept for and a point's
/// normal (taken back to last frame) for the history to stand for the point (the denoiser's
/// and the reservoirs': disocclusion by normal, beside the test of position).
pub const HISTORY_NORMAL_COS: f32 = 0.9;

/// [`WGSL`] with the constant it reads.
pub fn wgsl() -> String {
    format!("const HISTORY_NORMAL_COS: f32 = {HISTORY_NORMAL_COS:?}f;\n{WGSL}")
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{Quat, Vec3};

    /// A point on an instance, carried by its motion, is taken back to where it was.
    #[test]
    fn back_transform_returns_a_moved_point_to_where_it_was() {
        let then = Mat4::from_scale_rotation_translation(
            Vec3::splat(2.0),
            Quat::from_rotation_y(0.3),
            Vec3::new(1.0, 0.0, -2.0),
        );
        let now = Mat4::from_rotation_translation(Quat::from_rotation_x(0.7), Vec3::Y) * then;
        let object = Vec3::new(0.25, -0.5, 1.0);
        let back = back_transform(then, now);
        let was = then.transform_point3(object);
        let p = now.transform_point3(object);
        assert!(p.distance(was) > 0.5, "the motion must move the point");
        assert!(back.transform_point3(p).distance(was) < 1e-5);
        assert_eq!(back_transform(now, now), Mat4::IDENTITY);
    }

    /// An instance's matrix is its move since the last frame while it moves, the identity
    /// again the frame after it stops; its first move between two frames is the one that
    /// counts; and only the instances that changed are written.
    #[test]
    fn the_table_follows_moves_and_stops() {
        let at = |x: f32| Mat4::from_translation(Vec3::X * x);
        let mut t = MotionTable::new(4);
        let now = |i: usize| if i == 2 { at(3.0) } else { Mat4::IDENTITY };
        assert_eq!(t.update(now), None, "nothing moved");
        // Instance 2 moves twice before the frame: from 0 (what the last frame drew) to 3.
        t.note(2, at(0.0));
        t.note(2, at(1.0));
        assert_eq!(t.update(now), Some(2..3));
        let back = Mat4::from_cols_array(&t.mirror[2]);
        assert!(back
            .transform_point3(Vec3::new(3.0, 0.0, 0.0))
            .abs_diff_eq(Vec3::ZERO, 1e-6));
        assert_eq!(t.mirror[1], Mat4::IDENTITY.to_cols_array());
        // It stops: the identity again, once.
        assert_eq!(t.update(now), Some(2..3));
        assert_eq!(t.mirror[2], Mat4::IDENTITY.to_cols_array());
        assert_eq!(t.update(now), None);
        // Two instances, one set back where it was: the range spans both, the identity kept.
        t.note(0, Mat4::IDENTITY);
        t.note(3, at(5.0));
        assert_eq!(
            t.update(|i| if i == 3 { at(5.0) } else { at(-1.0) }),
            Some(0..4)
        );
        assert_eq!(t.mirror[3], Mat4::IDENTITY.to_cols_array());
        assert_eq!(t.written, vec![0]);
        // An unknown instance is ignored.
        t.note(9, at(1.0));
        assert_eq!(t.update(now), Some(0..1));
    }
}
