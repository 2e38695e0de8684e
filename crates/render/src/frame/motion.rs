//! Motion of instances between frames, for the histories that follow surfaces: the
//! denoiser's (shading/denoise.rs) and the reservoirs' (shading/reuse.rs).
//!
//! Both find last frame's record of a pixel's surface point by projecting the point with the
//! last frame's camera and comparing it with the point kept there. A point on an instance
//! that moved was somewhere else last frame: the G-buffer keeps, per pixel, the instance seen
//! (`GBuffer::instance`, `GBufferViews::MonoMoving`), and [`InstanceMotion::back`] holds per
//! instance the transform from this frame's world back to last frame's (`last · now⁻¹`,
//! the identity for instances that did not move), so the point is taken back to where it
//! was before it is projected and compared. Skinned vertices are not followed (their motion
//! is not an instance's).

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
    /// Instances moved since the last frame recorded, with their transform at that frame.
    pending: Vec<(usize, Mat4)>,
    /// Instances whose `back` is not the identity (moved between the last two frames).
    written: Vec<usize>,
}

impl InstanceMotion {
    /// Identity transforms for `instances` instances.
    pub fn new(ctx: &GpuContext, instances: usize) -> Self {
        use wgpu::util::DeviceExt;
        let identity = vec![Mat4::IDENTITY.to_cols_array(); instances.max(1)];
        let back = ctx
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("motion.back"),
                contents: bytemuck::cast_slice(&identity),
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            });
        // Zero-initialized.
        let still = ctx
            .device
            .create_texture(&wgpu::TextureDescriptor {
                label: Some("motion.still"),
                size: wgpu::Extent3d {
                    width: 1,
                    height: 1,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: crate::frame::gbuffer::INSTANCE_FORMAT,
                usage: wgpu::TextureUsages::TEXTURE_BINDING,
                view_formats: &[],
            })
            .create_view(&Default::default());
        Self {
            back,
            still,
            pending: Vec::new(),
            written: Vec::new(),
        }
    }

    /// Instance `instance`, whose transform was `was`, moves before the next frame (only its
    /// first move since the last frame counts: `was` is then the transform that frame drew).
    pub fn note(&mut self, instance: usize, was: Mat4) {
        if !self.pending.iter().any(|&(i, _)| i == instance) {
            self.pending.push((instance, was));
        }
    }

    /// Before a frame's passes: each instance moved since the last frame gets `last · now⁻¹`
    /// (`now(i)`: its transform this frame), and those moved before it but not since get the
    /// identity again.
    pub fn upload(&mut self, queue: &wgpu::Queue, now: impl Fn(usize) -> Mat4) {
        let write = |i: usize, m: Mat4| {
            queue.write_buffer(
                &self.back,
                (i * std::mem::size_of::<[f32; 16]>()) as u64,
                bytemuck::cast_slice(&m.to_cols_array()),
            );
        };
        for &i in &self.written {
            if !self.pending.iter().any(|&(j, _)| j == i) {
                write(i, Mat4::IDENTITY);
            }
        }
        self.written.clear();
        for (i, was) in self.pending.drain(..) {
            let m = back_transform(was, now(i));
            write(i, m);
            if m != Mat4::IDENTITY {
                self.written.push(i);
            }
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

// Where the surface point `p` was last frame (`back`: `instance_back` of its pixel).
fn last_frame_position(back: mat4x4<f32>, p: vec3<f32>) -> vec3<f32> {
    return (back * vec4<f32>(p, 1.0)).xyz;
}

// Which way the unit normal `n` faced last frame.
fn last_frame_normal(back: mat4x4<f32>, n: vec3<f32>) -> vec3<f32> {
    return normalize((back * vec4<f32>(n, 0.0)).xyz);
}

// Whether a history point whose surface faced `then` may stand for one facing `now` (both
// unit; HISTORY_NORMAL_COS, frame/motion.rs): a surface seen from its other side, or the
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
}
