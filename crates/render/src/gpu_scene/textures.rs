//! The scene's images on the GPU, for the camera's view: base colours and emissive textures
//! in one sRGB texture array, linear data (normal maps and metallic-roughness maps) in another, every layer the
//! same square side with a full mip chain, and one trilinear sampler.
//!
//! Why arrays of one size: core WebGPU (and so OpenGL and browsers) has no arrays of textures
//! of different sizes in one binding, and binding one texture per material would mean one draw
//! per material with its own bind group. An array needs one binding and the layer index in the
//! material record. The price is resampling: every image is scaled to the array's side (the
//! largest image's side rounded up to a power of two, at most [`MAX_LAYER_SIDE`] and the
//! device's limit, then halved until both arrays fit [`TEXTURE_BUDGET_BYTES`]); the summary
//! says the side. Shadows never read these arrays: alpha-tested casters use the full-resolution
//! coverage bits of [`manyshadows_scene::masks`], so the side chosen here changes how the
//! camera sees a texture, never where a shadow falls.
//!
//! Mipmaps are made on the CPU when the scene is uploaded (2×2 box filter in linear light for
//! colours; normal maps averaged and renormalised). Wrap modes are applied in the shader
//! (`wrap_coord` in common.wgsl, with gradients of the unwrapped coordinate), so one repeating
//! sampler serves every material.

use manyshadows_scene::texture::{linear_to_srgb, srgb_to_linear};
use manyshadows_scene::{Scene, Texture, TextureRef};

use crate::error::RenderError;
use crate::gpu::context::GpuContext;

/// Largest side of a texture-array layer.
pub const MAX_LAYER_SIDE: u32 = 2048;

/// Most bytes of both arrays together, mipmaps included (256 MiB).
pub const TEXTURE_BUDGET_BYTES: u64 = 256 << 20;

/// Format of the base-colour array (sampling returns linear colour, alpha as stored).
pub const COLOUR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;

/// Format of the data array (normal maps, metallic-roughness maps).
pub const NORMAL_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

/// The texture arrays of a scene.
pub struct SceneTextures {
    /// Base colours, one layer per texture some material uses as its base colour.
    pub colour: wgpu::TextureView,
    /// Linear data: one layer per texture some material uses as its normal map, and one per
    /// texture some material uses as its metallic-roughness map.
    pub normal: wgpu::TextureView,
    /// Trilinear, repeating.
    pub sampler: wgpu::Sampler,
    /// Layer of each scene texture in the colour array (`None`: not a base colour).
    pub colour_layers: Vec<Option<u32>>,
    /// Layer of each scene texture in the colour array as an emissive texture.
    pub emissive_layers: Vec<Option<u32>>,
    /// Layer of each scene texture in the data array as a normal map.
    pub normal_layers: Vec<Option<u32>>,
    /// Layer of each scene texture in the data array as a metallic-roughness map.
    pub mr_layers: Vec<Option<u32>>,
    /// Side of every layer in texels (1 when the scene has no textures).
    pub side: u32,
    /// Bytes of both arrays with their mipmaps.
    pub bytes: u64,
}

fn mip_count(side: u32) -> u32 {
    32 - side.leading_zeros()
}

/// Bytes of `layers` layers of `side`² RGBA8 texels with a full mip chain.
fn array_bytes(side: u32, layers: u32) -> u64 {
    (0..mip_count(side))
        .map(|l| ((side >> l).max(1) as u64).pow(2) * 4)
        .sum::<u64>()
        * layers as u64
}

/// The side every layer gets for these images on a device whose 2D textures may be
/// `device_max` texels across.
pub fn layer_side(images: &[&Texture], layers: u32, device_max: u32) -> u32 {
    let Some(largest) = images.iter().map(|t| t.width.max(t.height)).max() else {
        return 1;
    };
    let mut side = largest
        .next_power_of_two()
        .min(MAX_LAYER_SIDE)
        .min(device_max.max(1));
    if !side.is_power_of_two() {
        side = side.next_power_of_two() / 2;
    }
    while side > 1 && array_bytes(side, layers) > TEXTURE_BUDGET_BYTES {
        side /= 2;
    }
    side
}

/// The mip chain of one colour layer (`side`² at level 0), as RGBA8 sRGB bytes per level.
fn colour_mips(texture: &Texture, side: u32) -> Vec<Vec<u8>> {
    let base = texture.resized(side, side);
    let mut linear: Vec<[f32; 4]> = base
        .rgba
        .chunks_exact(4)
        .map(|t| {
            [
                srgb_to_linear(t[0]),
                srgb_to_linear(t[1]),
                srgb_to_linear(t[2]),
                t[3] as f32 / 255.0,
            ]
        })
        .collect();
    let mut levels = vec![base.rgba.to_vec()];
    let coverage = |v: &[[f32; 4]], scale: f32| {
        v.iter().filter(|c| c[3] * scale >= ALPHA_REFERENCE).count() as f32 / v.len() as f32
    };
    let wanted = coverage(&linear, 1.0);
    let has_alpha = linear.iter().any(|c| c[3] < 1.0);
    let mut s = side;
    while s > 1 {
        linear = halve(&linear, s);
        s /= 2;
        if has_alpha {
            preserve_coverage(&mut linear, wanted, coverage);
        }
        levels.push(
            linear
                .iter()
                .flat_map(|c| {
                    [
                        linear_to_srgb(c[0]),
                        linear_to_srgb(c[1]),
                        linear_to_srgb(c[2]),
                        (c[3].clamp(0.0, 1.0) * 255.0).round() as u8,
                    ]
                })
                .collect(),
        );
    }
    levels
}

/// The alpha cutoff mipmaps keep the coverage for (glTF's default, and every built-in
/// masked material's).
const ALPHA_REFERENCE: f32 = 0.5;

/// Scales a mip level's alpha so that the share of texels at or above [`ALPHA_REFERENCE`] is
/// the full-resolution level's (Castaño's coverage-preserving mipmaps): averaging thin wires
/// or leaves with the holes between them would otherwise drop them below the cutoff, and an
/// alpha-tested fence would vanish with distance.
fn preserve_coverage(
    level: &mut [[f32; 4]],
    wanted: f32,
    coverage: impl Fn(&[[f32; 4]], f32) -> f32,
) {
    let (mut lo, mut hi) = (0.0f32, 64.0f32);
    for _ in 0..24 {
        let mid = 0.5 * (lo + hi);
        if coverage(level, mid) < wanted {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    for c in level.iter_mut() {
        c[3] = (c[3] * hi).min(1.0);
    }
}

/// The mip chain of one normal-map layer: vectors averaged and renormalised.
fn normal_mips(texture: &Texture, side: u32) -> Vec<Vec<u8>> {
    // Resample the encoded vectors directly (they are linear data, not colours).
    let base = resize_linear(texture, side);
    let encode = |v: &[[f32; 4]]| -> Vec<u8> {
        v.iter()
            .flat_map(|c| {
                let n = glam::Vec3::new(c[0] * 2.0 - 1.0, c[1] * 2.0 - 1.0, c[2] * 2.0 - 1.0)
                    .normalize_or(glam::Vec3::Z);
                let e = |x: f32| ((x * 0.5 + 0.5).clamp(0.0, 1.0) * 255.0).round() as u8;
                [e(n.x), e(n.y), e(n.z), 255]
            })
            .collect()
    };
    let mut level = base;
    let mut levels = vec![encode(&level)];
    let mut s = side;
    while s > 1 {
        level = halve(&level, s);
        s /= 2;
        levels.push(encode(&level));
    }
    levels
}

/// The mip chain of one metallic-roughness layer: the values averaged as they are (they are
/// factors, not colours).
fn data_mips(texture: &Texture, side: u32) -> Vec<Vec<u8>> {
    let encode = |v: &[[f32; 4]]| -> Vec<u8> {
        v.iter()
            .flat_map(|c| c.map(|x| (x.clamp(0.0, 1.0) * 255.0).round() as u8))
            .collect()
    };
    let mut level = resize_linear(texture, side);
    let mut levels = vec![encode(&level)];
    let mut s = side;
    while s > 1 {
        level = halve(&level, s);
        s /= 2;
        levels.push(encode(&level));
    }
    levels
}

/// `texture` resampled to `side`² without any colour conversion, as floats in 0..1.
fn resize_linear(texture: &Texture, side: u32) -> Vec<[f32; 4]> {
    let src = image::RgbaImage::from_raw(texture.width, texture.height, texture.rgba.to_vec())
        .expect("a validated texture holds width·height texels");
    let out = image::imageops::resize(&src, side, side, image::imageops::FilterType::Triangle);
    out.pixels()
        .map(|p| p.0.map(|c| c as f32 / 255.0))
        .collect()
}

/// One 2×2 box-filter step of a square image `side` texels across.
fn halve(src: &[[f32; 4]], side: u32) -> Vec<[f32; 4]> {
    let half = (side / 2).max(1);
    let at = |x: u32, y: u32| src[(y.min(side - 1) * side + x.min(side - 1)) as usize];
    let mut out = Vec::with_capacity((half * half) as usize);
    for y in 0..half {
        for x in 0..half {
            let q = [
                at(2 * x, 2 * y),
                at(2 * x + 1, 2 * y),
                at(2 * x, 2 * y + 1),
                at(2 * x + 1, 2 * y + 1),
            ];
            out.push(std::array::from_fn(|c| {
                (q[0][c] + q[1][c] + q[2][c] + q[3][c]) * 0.25
            }));
        }
    }
    out
}

impl SceneTextures {
    /// Whether any material's emission comes from a texture.
    pub fn has_emissive(&self) -> bool {
        self.emissive_layers.iter().any(Option::is_some)
    }

    /// Uploads the textures `scene`'s materials use. Fails when there are more layers than
    /// the device's array-layer limit.
    pub fn new(ctx: &GpuContext, scene: &Scene) -> Result<Self, RenderError> {
        let n = scene.textures.len();
        let mut colour_layers = vec![None; n];
        let mut normal_layers = vec![None; n];
        let mut mr_layers = vec![None; n];
        let mut emissive_layers = vec![None; n];
        let (mut colours, mut normals) = (0u32, 0u32);
        // Texture `t`'s layer in `layers`, the array's next one (counted in `count`) if it has none.
        let assign = |layers: &mut [Option<u32>], t: Option<TextureRef>, count: &mut u32| {
            if let Some(t) = t {
                layers[t.texture].get_or_insert_with(|| {
                    *count += 1;
                    *count - 1
                });
            }
        };
        for m in &scene.materials {
            assign(&mut colour_layers, m.base_color_texture, &mut colours);
            assign(&mut normal_layers, m.normal_texture, &mut normals);
        }
        // Metallic-roughness maps after the normal maps, in the same (linear) array; emissive
        // textures after the base colours (sRGB colours too; a texture used as both keeps its
        // base-colour layer).
        for m in &scene.materials {
            if let Some(t) = m.emissive_texture {
                if emissive_layers[t.texture].is_none() {
                    emissive_layers[t.texture] = colour_layers[t.texture];
                }
            }
            assign(&mut emissive_layers, m.emissive_texture, &mut colours);
            assign(&mut mr_layers, m.metallic_roughness_texture, &mut normals);
        }
        let limits = ctx.limits();
        let max_layers = limits.max_texture_array_layers;
        if colours.max(normals) > max_layers {
            return Err(RenderError::TooLarge {
                what: format!(
                    "the materials' {colours} base-colour and {normals} normal-map and \
                     metallic-roughness textures"
                ),
                needed: u64::from(colours.max(normals)),
                limit: u64::from(max_layers),
                unit: "texture-array layers",
                limit_name: "max_texture_array_layers",
            });
        }
        let used: Vec<&Texture> = scene
            .textures
            .iter()
            .enumerate()
            .filter(|(i, _)| {
                colour_layers[*i].is_some()
                    || emissive_layers[*i].is_some()
                    || normal_layers[*i].is_some()
                    || mr_layers[*i].is_some()
            })
            .map(|(_, t)| t)
            .collect();
        let side = layer_side(&used, colours + normals, limits.max_texture_dimension_2d);
        // At least two layers: OpenGL reads zeros from an array view of a one-layer texture;
        // and never a multiple of six: wgpu's OpenGL backend takes those for cube maps.
        let layer_count = |layers: u32| {
            let n = layers.max(2);
            if n.is_multiple_of(6) {
                n + 1
            } else {
                n
            }
        };
        let make = |label: &str, format: wgpu::TextureFormat, layers: u32| {
            ctx.device.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size: wgpu::Extent3d {
                    width: side,
                    height: side,
                    depth_or_array_layers: layer_count(layers),
                },
                mip_level_count: mip_count(side),
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
                view_formats: &[],
            })
        };
        let colour = make("textures.colour", COLOUR_FORMAT, colours);
        let normal = make("textures.normal", NORMAL_FORMAT, normals);
        let upload = |target: &wgpu::Texture, layer: u32, levels: Vec<Vec<u8>>| {
            for (level, bytes) in levels.iter().enumerate() {
                let s = (side >> level).max(1);
                ctx.queue.write_texture(
                    wgpu::TexelCopyTextureInfo {
                        texture: target,
                        mip_level: level as u32,
                        origin: wgpu::Origin3d {
                            x: 0,
                            y: 0,
                            z: layer,
                        },
                        aspect: wgpu::TextureAspect::All,
                    },
                    bytes,
                    wgpu::TexelCopyBufferLayout {
                        offset: 0,
                        bytes_per_row: Some(4 * s),
                        rows_per_image: Some(s),
                    },
                    wgpu::Extent3d {
                        width: s,
                        height: s,
                        depth_or_array_layers: 1,
                    },
                );
            }
        };
        for (i, t) in scene.textures.iter().enumerate() {
            if let Some(layer) = colour_layers[i] {
                upload(&colour, layer, colour_mips(t, side));
            }
            if let Some(layer) = emissive_layers[i].filter(|&l| Some(l) != colour_layers[i]) {
                upload(&colour, layer, colour_mips(t, side));
            }
            if let Some(layer) = normal_layers[i] {
                upload(&normal, layer, normal_mips(t, side));
            }
            if let Some(layer) = mr_layers[i] {
                upload(&normal, layer, data_mips(t, side));
            }
        }
        let view = |t: &wgpu::Texture| {
            t.create_view(&wgpu::TextureViewDescriptor {
                dimension: Some(wgpu::TextureViewDimension::D2Array),
                ..Default::default()
            })
        };
        let sampler = ctx.device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("textures.sampler"),
            address_mode_u: wgpu::AddressMode::Repeat,
            address_mode_v: wgpu::AddressMode::Repeat,
            address_mode_w: wgpu::AddressMode::ClampToEdge,
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            mipmap_filter: wgpu::MipmapFilterMode::Linear,
            ..Default::default()
        });
        Ok(Self {
            colour: view(&colour),
            normal: view(&normal),
            sampler,
            colour_layers,
            emissive_layers,
            normal_layers,
            mr_layers,
            side,
            bytes: array_bytes(side, colours) + array_bytes(side, normals),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn side_follows_the_largest_image_and_the_budget() {
        let t = |w, h| Texture::from_fn("t", w, h, |_, _| [0, 0, 0, 255]);
        let (a, b) = (t(300, 100), t(64, 64));
        assert_eq!(layer_side(&[&a, &b], 2, 8192), 512);
        assert_eq!(layer_side(&[&b], 1, 8192), 64);
        assert_eq!(layer_side(&[], 0, 8192), 1);
        let big = t(4096, 4096);
        assert_eq!(layer_side(&[&big], 1, 8192), MAX_LAYER_SIDE);
        assert_eq!(
            layer_side(&[&big], 1, 1000),
            512,
            "a power of two within the device"
        );
        // 100 layers of 2048² with mips would be 2.2 GiB: halved until under 256 MiB.
        let side = layer_side(&[&big], 100, 8192);
        assert!(
            array_bytes(side, 100) <= TEXTURE_BUDGET_BYTES && side == 512,
            "{side}"
        );
    }

    #[test]
    fn mips_keep_alpha_coverage() {
        // Thin wires: one texel in four solid. Plain averaging gives alpha 0.25 everywhere at
        // level 2 (below the 0.5 cutoff: the wires vanish); the kept coverage is 25 %.
        let t = Texture::from_fn("wires", 16, 16, |x, _| {
            [0, 0, 0, if x % 4 == 0 { 255 } else { 0 }]
        });
        let levels = colour_mips(&t, 16);
        let solid = |l: &Vec<u8>| {
            l.chunks_exact(4).filter(|p| p[3] >= 128).count() as f32 / (l.len() / 4) as f32
        };
        assert_eq!(solid(&levels[0]), 0.25);
        for l in &levels[1..4] {
            assert!(solid(l) >= 0.24, "{}", solid(l));
        }
    }

    #[test]
    fn mips_average_in_linear_light() {
        // A 2x2 checker of black and white averages to linear 0.5 (sRGB 188), not sRGB 128.
        let t = Texture::from_fn("c", 2, 2, |x, y| {
            let v = if (x + y) % 2 == 0 { 255 } else { 0 };
            [v, v, v, 255]
        });
        let levels = colour_mips(&t, 2);
        assert_eq!(levels.len(), 2);
        assert_eq!(levels[1], vec![188, 188, 188, 255]);
    }
}
