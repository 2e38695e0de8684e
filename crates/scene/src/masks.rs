//! Coverage masks of alpha-tested materials: one bit per texel, "this texel is solid".
//!
//! Why bits and not the texture: a shadow technique asks one question of an alpha-masked
//! caster — is the surface there at this point? — and every technique (five atlas
//! rasterizers, virtual pages, irregular maps) and the CPU reference must answer it the same
//! way, or the comparison between them measures the sampling of alpha instead of the shadows.
//! So the answer is precomputed here, once per material: texel `(x, y)` is covered when its
//! alpha (0..1) times [`Material::base_alpha`](crate::Material) is at least the material's
//! cutoff. Lookups take the nearest texel of the wrapped coordinate
//! ([`Wrap::texel`](crate::texture::Wrap::texel)) at full resolution, no filtering and no mipmaps, in
//! WGSL (`alpha_mask.wgsl`) and in Rust ([`MaskSet::covered`]) with the same arithmetic.
//!
//! Masks whose texels are all covered are dropped (the material is opaque for shadows: no
//! alpha test at all). Materials with the same texture, cutoff and alpha share one mask. The
//! bits of all masks together are held to [`MASK_BUDGET_BYTES`] (the smallest storage binding
//! the renderer accepts): past it the largest masks are halved (alpha averaged over 2×2
//! blocks, then thresholded) until they fit, and [`MaskSet::halved`] says how often.

use std::collections::HashMap;

use glam::Vec2;

use crate::model::Scene;
use crate::texture::Wrap;

/// Most bytes of coverage bits over all masks (4 MiB = 33.5 million texels).
pub const MASK_BUDGET_BYTES: usize = 4 << 20;

/// Record flag: the material is alpha-tested (its bits are meaningful).
pub const FLAG_MASKED: u32 = 1;

/// Where a material's coverage bits are and how to read them; four `u32`s on the GPU.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct MaskRecord {
    /// First word of the mask in [`MaskSet::bits`].
    pub first_word: u32,
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// Bit 0: [`FLAG_MASKED`]; bits 1–2: wrap code along u; bits 3–4: along v
    /// ([`Wrap::code`]).
    pub flags: u32,
}

impl MaskRecord {
    /// True if the material is alpha-tested.
    pub fn masked(&self) -> bool {
        self.flags & FLAG_MASKED != 0
    }

    fn wrap(&self, shift: u32) -> Wrap {
        match (self.flags >> shift) & 3 {
            1 => Wrap::MirroredRepeat,
            2 => Wrap::ClampToEdge,
            _ => Wrap::Repeat,
        }
    }
}

/// The coverage masks of a scene's materials.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MaskSet {
    /// One record per material, in material order (unmasked materials: flags 0).
    pub records: Vec<MaskRecord>,
    /// Every mask's bits, row-major from the top-left texel, 32 texels per word (bit `i % 32`
    /// of word `first_word + i / 32` for texel `i = y · width + x`).
    pub bits: Vec<u32>,
    /// How many times a mask was halved to fit [`MASK_BUDGET_BYTES`].
    pub halved: u32,
}

/// What a mask is made of: the same key gives the same bits.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
struct Key {
    texture: Option<usize>,
    cutoff: u32,
    alpha: u32,
}

impl MaskSet {
    /// The masks of `scene` (which must have passed [`Scene::validate`]).
    pub fn new(scene: &Scene) -> Self {
        let mut keys: Vec<Key> = Vec::new();
        let mut by_key: HashMap<Key, usize> = HashMap::new();
        // Per material: the mask it uses (an index into `keys`) and its wrap flags.
        let mut uses: Vec<Option<(usize, u32)>> = Vec::with_capacity(scene.materials.len());
        for m in &scene.materials {
            let Some(cutoff) = m.effective_cutoff() else {
                uses.push(None);
                continue;
            };
            let covered = |a: u8| (a as f32 / 255.0) * m.base_alpha >= cutoff;
            let texture = m.base_color_texture;
            let solid = match texture {
                // A texture whose every texel is covered casts like an opaque surface.
                Some(t) => scene.textures[t.texture]
                    .rgba
                    .chunks_exact(4)
                    .all(|p| covered(p[3])),
                None => covered(255),
            };
            if solid {
                uses.push(None);
                continue;
            }
            let key = Key {
                texture: texture.map(|t| t.texture),
                cutoff: cutoff.to_bits(),
                alpha: m.base_alpha.to_bits(),
            };
            let k = *by_key.entry(key).or_insert_with(|| {
                keys.push(key);
                keys.len() - 1
            });
            let wrap = texture.map_or(0, |t| (t.wrap_s.code() << 1) | (t.wrap_t.code() << 3));
            uses.push(Some((k, wrap)));
        }

        // Sizes, halving the largest until the bits fit the budget.
        let full: Vec<(u32, u32)> = keys
            .iter()
            .map(|k| {
                k.texture.map_or((1, 1), |t| {
                    (scene.textures[t].width, scene.textures[t].height)
                })
            })
            .collect();
        let mut levels = vec![0u32; keys.len()];
        let size = |k: usize, levels: &[u32]| {
            let (w, h) = full[k];
            ((w >> levels[k]).max(1), (h >> levels[k]).max(1))
        };
        let words = |k: usize, levels: &[u32]| {
            let (w, h) = size(k, levels);
            (w as usize * h as usize).div_ceil(32)
        };
        let mut halved = 0;
        while (0..keys.len()).map(|k| words(k, &levels)).sum::<usize>() * 4 > MASK_BUDGET_BYTES {
            let Some(largest) = (0..keys.len())
                .filter(|&k| size(k, &levels) != (1, 1))
                .max_by_key(|&k| words(k, &levels))
            else {
                break;
            };
            levels[largest] += 1;
            halved += 1;
        }

        let mut bits = Vec::new();
        let mut placed = Vec::with_capacity(keys.len());
        for (k, key) in keys.iter().enumerate() {
            let (w, h) = size(k, &levels);
            let first_word = bits.len() as u32;
            bits.resize(bits.len() + words(k, &levels), 0u32);
            let cutoff = f32::from_bits(key.cutoff);
            let alpha = f32::from_bits(key.alpha);
            if let Some(t) = key.texture {
                let tex = &scene.textures[t];
                let (bw, bh) = (tex.width.div_ceil(w), tex.height.div_ceil(h));
                for y in 0..h {
                    for x in 0..w {
                        // Mean alpha of the source block (one texel at full resolution).
                        let (mut sum, mut n) = (0u32, 0u32);
                        for sy in (y * bh)..((y + 1) * bh).min(tex.height) {
                            for sx in (x * bw)..((x + 1) * bw).min(tex.width) {
                                sum += tex.texel(sx, sy)[3] as u32;
                                n += 1;
                            }
                        }
                        let a = if n == 0 {
                            0.0
                        } else {
                            sum as f32 / (255.0 * n as f32)
                        };
                        if a * alpha >= cutoff {
                            let i = (y * w + x) as usize;
                            bits[first_word as usize + i / 32] |= 1 << (i % 32);
                        }
                    }
                }
            }
            placed.push(MaskRecord {
                first_word,
                width: w,
                height: h,
                flags: FLAG_MASKED,
            });
        }
        let records = uses
            .iter()
            .map(|u| match *u {
                None => MaskRecord::default(),
                Some((k, wrap)) => MaskRecord {
                    flags: placed[k].flags | wrap,
                    ..placed[k]
                },
            })
            .collect();
        Self {
            records,
            bits,
            halved,
        }
    }

    /// True if some material is alpha-tested.
    pub fn any(&self) -> bool {
        self.records.iter().any(MaskRecord::masked)
    }

    /// True if `material` is alpha-tested.
    pub fn is_masked(&self, material: usize) -> bool {
        self.records.get(material).is_some_and(MaskRecord::masked)
    }

    /// Whether the surface of `material` exists at texture coordinate `uv` (always true for
    /// materials that are not alpha-tested). The same arithmetic as `mask_covered` in
    /// `alpha_mask.wgsl`.
    pub fn covered(&self, material: usize, uv: Vec2) -> bool {
        let Some(r) = self.records.get(material).filter(|r| r.masked()) else {
            return true;
        };
        let x = r.wrap(1).texel(uv.x, r.width);
        let y = r.wrap(3).texel(uv.y, r.height);
        let i = y * r.width + x;
        (self.bits[(r.first_word + i / 32) as usize] >> (i % 32)) & 1 != 0
    }

    /// Bytes of coverage bits.
    pub fn bytes(&self) -> usize {
        self.bits.len() * 4
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Material;
    use crate::texture::{Texture, TextureRef};

    fn scene_with(texture: Texture, materials: Vec<Material>) -> Scene {
        Scene {
            textures: vec![texture],
            materials,
            ..Scene::default()
        }
    }

    #[test]
    fn coverage_follows_alpha_and_cutoff() {
        // Left half transparent, right half solid; 4x2 texels.
        let t = Texture::from_fn("half", 4, 2, |x, _| {
            [255, 255, 255, if x < 2 { 0 } else { 255 }]
        });
        let masked = Material::default().with_texture(0).masked(0.5);
        let scene = scene_with(t, vec![Material::default(), masked]);
        let set = MaskSet::new(&scene);
        assert!(!set.is_masked(0));
        assert!(set.is_masked(1));
        assert!(
            set.covered(0, Vec2::new(0.1, 0.1)),
            "opaque materials are always covered"
        );
        assert!(!set.covered(1, Vec2::new(0.1, 0.5)));
        assert!(set.covered(1, Vec2::new(0.9, 0.5)));
        // Repeat wrapping: u = 1.1 is u = 0.1.
        assert!(!set.covered(1, Vec2::new(1.1, 0.5)));
        assert!(set.covered(1, Vec2::new(-0.1, 0.5)));
    }

    #[test]
    fn solid_textures_and_opaque_modes_need_no_mask() {
        let solid = Texture::from_fn("solid", 4, 4, |_, _| [1, 2, 3, 255]);
        let scene = scene_with(solid, vec![Material::default().with_texture(0).masked(0.5)]);
        assert!(!MaskSet::new(&scene).any());
        // No texture, alpha below the cutoff: invisible everywhere.
        let mut m = Material::default().masked(0.5);
        m.base_alpha = 0.25;
        let scene = Scene {
            materials: vec![m],
            ..Scene::default()
        };
        let set = MaskSet::new(&scene);
        assert!(set.is_masked(0) && !set.covered(0, Vec2::new(0.3, 0.3)));
    }

    #[test]
    fn shared_masks_and_clamp_wrapping() {
        let t = Texture::from_fn("stripe", 2, 1, |x, _| {
            [0, 0, 0, if x == 0 { 0 } else { 255 }]
        });
        let mut a = Material::default().with_texture(0).masked(0.5);
        let mut b = a;
        b.base_color_texture = Some(TextureRef {
            texture: 0,
            wrap_s: Wrap::ClampToEdge,
            wrap_t: Wrap::ClampToEdge,
        });
        a.diffuse = glam::Vec3::X;
        let set = MaskSet::new(&scene_with(t, vec![a, b]));
        assert_eq!(set.bits.len(), 1, "one mask for both materials");
        assert!(
            !set.covered(0, Vec2::new(1.25, 0.0)),
            "repeat: 1.25 is 0.25"
        );
        assert!(
            set.covered(1, Vec2::new(1.25, 0.0)),
            "clamp: 1.25 is the last texel"
        );
    }

    #[test]
    fn masks_over_the_budget_are_halved() {
        // 4096 x 4096 texels = 2 MiB of bits each; three of them must shrink to fit 4 MiB.
        let big = || {
            Texture::from_fn("big", 4096, 4096, |x, _| {
                [0, 0, 0, if x % 2 == 0 { 255 } else { 0 }]
            })
        };
        let mut scene = Scene {
            textures: vec![big(), big(), big()],
            ..Scene::default()
        };
        for t in 0..3 {
            scene
                .materials
                .push(Material::default().with_texture(t).masked(0.5));
        }
        let set = MaskSet::new(&scene);
        assert!(set.bytes() <= MASK_BUDGET_BYTES);
        assert!(set.halved >= 1);
        assert!(set.records.iter().any(|r| r.width == 2048));
    }
}
