//! Reading the G-buffer back: per pixel the world position and normal the frame shaded.
//!
//! The exact CPU reference (`manyshadows-reference`) casts its shadow rays from these points,
//! so the reference and every technique judge the very same surface samples. The targets hold
//! `f32` bit patterns in `Rgba32Uint` texels (see [`crate::frame::gbuffer`]); they are read back as
//! bits and reinterpreted, so nothing is rounded on the way.

use glam::Vec3;

use crate::error::RenderError;
use crate::frame::gbuffer::GBuffer;
use crate::gpu::context::GpuContext;

/// The G-buffer of the last rendered frame on the CPU, row-major from the top-left pixel.
#[derive(Clone, Debug, PartialEq)]
pub struct GBufferData {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// World position per pixel (meaningless where `covered` is false).
    pub position: Vec<Vec3>,
    /// Unit normal per pixel, on the side of its triangle the camera sees (the G-buffer pass
    /// turns it by the triangle's plane, whatever the winding).
    pub normal: Vec<Vec3>,
    /// Material index per pixel.
    pub material: Vec<u32>,
    /// Whether the pixel saw geometry.
    pub covered: Vec<bool>,
    /// The surface's albedo per pixel: sRGB-encoded red, green, blue and 255 (white for
    /// untextured surfaces).
    pub albedo: Vec<[u8; 4]>,
}

/// Bytes per texel of the G-buffer targets (four 32-bit channels).
const TEXEL_BYTES: u32 = 16;

fn texels(bytes: &[u8]) -> impl Iterator<Item = [u32; 4]> + '_ {
    bytes.chunks_exact(TEXEL_BYTES as usize).map(|t| {
        let w = |i: usize| u32::from_le_bytes([t[4 * i], t[4 * i + 1], t[4 * i + 2], t[4 * i + 3]]);
        [w(0), w(1), w(2), w(3)]
    })
}

impl GBufferData {
    /// Reads `gbuffer` back ([`crate::Renderer::read_gbuffer`]).
    pub(crate) fn read(ctx: &GpuContext, gbuffer: &GBuffer) -> Result<Self, RenderError> {
        ctx.scoped("reading the G-buffer", || {
            let position = crate::gpu::readback::read_texture(ctx, &gbuffer.position, TEXEL_BYTES)?;
            let normal = crate::gpu::readback::read_texture(ctx, &gbuffer.normal, TEXEL_BYTES)?;
            let (width, height) = (gbuffer.position.width(), gbuffer.position.height());
            let pixels = width as usize * height as usize;
            if position.len() != pixels * TEXEL_BYTES as usize
                || normal.len() != pixels * TEXEL_BYTES as usize
            {
                return Err(RenderError::Readback {
                    what: "the G-buffer",
                    reason: format!(
                        "{} and {} bytes came back for {width}x{height} pixels",
                        position.len(),
                        normal.len()
                    ),
                });
            }
            let f = f32::from_bits;
            let mut out = GBufferData {
                width,
                height,
                position: Vec::with_capacity(pixels),
                normal: Vec::with_capacity(pixels),
                material: Vec::with_capacity(pixels),
                covered: Vec::with_capacity(pixels),
                albedo: Vec::with_capacity(pixels),
            };
            for (p, n) in texels(&position).zip(texels(&normal)) {
                out.position.push(Vec3::new(f(p[0]), f(p[1]), f(p[2])));
                // w is the packed albedo on geometry, the clear value 0 elsewhere
                // (`has_geometry` in common.wgsl).
                out.covered.push(p[3] != 0);
                out.albedo.push(p[3].to_le_bytes());
                out.normal
                    .push(Vec3::new(f(n[0]), f(n[1]), f(n[2])).normalize_or_zero());
                // Bits 16-31 hold a metallic-roughness texel (gbuffer.wgsl).
                out.material.push(n[3] & 0xffff);
            }
            Ok(out)
        })
    }
}
