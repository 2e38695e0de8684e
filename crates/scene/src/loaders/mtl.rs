//! OBJ material libraries (`.mtl`, parsed by `tobj`) into this crate's Phong [`Material`]s and
//! [`Texture`]s.
//!
//! Why here and not in tobj: tobj hands texture statements over as raw text (options and all,
//! with whatever path separators the exporter used), and an MTL describes an alpha mask as a
//! separate greyscale image (`map_d`) where the renderer wants one RGBA texture whose alpha is
//! the coverage. The mapping (also in [`super`]'s documentation):
//!
//! - `Kd` → diffuse; `Ka` → ambient, or `Kd` when `Ka` is absent or black (exporters write
//!   `Ka 0 0 0` meaning "no separate ambient colour", which would make shadowed areas black);
//!   `Ks` → specular; `Ns` → shininess (clamped to 0..=1000). Absent values take
//!   [`Material::default`]'s.
//! - `map_Kd` → the base-colour texture.
//! - `map_d` → an alpha mask: the material becomes [`AlphaMode::Mask`] with cutoff 0.5 and
//!   double-sided (foliage cards and chains are seen and cast shadows from both sides). The
//!   coverage is the `map_d` image's alpha where it has transparency (any texel below 255),
//!   else its luminance (Sponza's masks are greyscale, white = solid). It becomes the alpha of
//!   the base-colour texture: `map_Kd`'s colours (the mask resampled to `map_Kd`'s size if the
//!   two differ) or white where there is no `map_Kd`.
//! - `d` / `Tr` (constant dissolve) without `map_d` is ignored: a constant alpha is blending,
//!   which a deferred renderer with one surface per pixel cannot show, and exporters write
//!   `d 1` / `Tr 0` everywhere anyway.
//! - `map_Bump` / `bump` / `norm` → the normal texture, but only if the image has colour (a
//!   tangent-space normal map). A greyscale image is a height map, which this renderer does
//!   not use: ignored, with a note.
//!
//! Texture paths are relative to the MTL's directory and must stay inside the model's folder
//! (unless [`LoadOptions::allow_outside_paths`](super::options::LoadOptions) allows more: a
//! path that leaves it is not opened, and the note says why); backslashes are read as
//! separators, and
//! the statement's options (`-bm 1.0`, `-o u v w`, `-clamp on`, …) are skipped (`-clamp on`
//! selects clamp-to-edge wrapping, everything else repeats). Each image file is decoded once
//! however many materials use it. An image that cannot be read or decoded leaves its material
//! without that texture, with a note: one bad texture should not stop a scene from loading.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use glam::Vec3;

use super::paths::resolve;
use crate::model::Material;
use crate::texture::{AlphaMode, Texture, TextureRef, Wrap};

/// A texture statement's file and the options that matter here.
#[derive(Debug, PartialEq)]
pub(super) struct MapArg {
    /// The file name, backslashes turned into slashes.
    pub file: String,
    /// `-clamp on`.
    pub clamp: bool,
}

/// Parses the rest of a texture statement (after `map_Kd` etc.): options, then the file name
/// (which may contain spaces).
pub(super) fn parse_map(arg: &str) -> MapArg {
    let tokens: Vec<&str> = arg.split_whitespace().collect();
    let number = |t: &str| t.parse::<f32>().is_ok();
    let mut clamp = false;
    let mut i = 0;
    while i < tokens.len() && tokens[i].starts_with('-') && tokens[i].len() > 1 {
        let option = tokens[i].to_ascii_lowercase();
        i += 1;
        match option.as_str() {
            "-blendu" | "-blendv" | "-cc" | "-bm" | "-boost" | "-texres" | "-imfchan" | "-type" => {
                i += 1
            }
            "-clamp" => {
                clamp = tokens.get(i).is_some_and(|t| t.eq_ignore_ascii_case("on"));
                i += 1;
            }
            "-mm" => i += 2,
            // -o / -s / -t take one to three numbers; unknown options, any numbers that follow.
            _ => {
                let mut taken = 0;
                while taken < 3 && tokens.get(i).is_some_and(|t| number(t)) {
                    i += 1;
                    taken += 1;
                }
            }
        }
    }
    MapArg {
        file: tokens
            .get(i..)
            .unwrap_or_default()
            .join(" ")
            .replace('\\', "/"),
        clamp,
    }
}

/// The value of a texture statement: tobj's field, or an unrecognised statement whose keyword
/// matches one of `keys` ignoring case (`map_kd`, `norm`, …).
fn statement<'m>(field: Option<&'m str>, m: &'m tobj::Material, keys: &[&str]) -> Option<&'m str> {
    field.or_else(|| {
        m.unknown_param
            .iter()
            .find(|(k, _)| keys.iter().any(|key| k.eq_ignore_ascii_case(key)))
            .map(|(_, v)| v.as_str())
    })
}

/// Images decoded so far and the scene textures made from them.
#[derive(Default)]
struct Images {
    decoded: HashMap<PathBuf, Result<Texture, String>>,
    /// Scene textures by (colour image, mask image).
    made: HashMap<(Option<PathBuf>, Option<PathBuf>), usize>,
    textures: Vec<Texture>,
}

impl Images {
    fn image(&mut self, file: &Path, shown: &str) -> Result<Texture, String> {
        self.decoded
            .entry(file.to_path_buf())
            .or_insert_with(|| {
                super::common::read_limited(file)
                    .map_err(|e| e.to_string())
                    .and_then(|bytes| Texture::decode(shown, &bytes))
            })
            .clone()
    }

    fn texture(
        &mut self,
        key: (Option<PathBuf>, Option<PathBuf>),
        make: impl FnOnce() -> Texture,
    ) -> usize {
        if let Some(&t) = self.made.get(&key) {
            return t;
        }
        self.textures.push(make());
        let t = self.textures.len() - 1;
        self.made.insert(key, t);
        t
    }
}

/// The coverage (0–255) of each texel of a `map_d` image: its alpha if it has transparency,
/// else its luminance.
fn coverage(mask: &Texture) -> Vec<u8> {
    let alpha = mask.has_alpha();
    mask.rgba
        .chunks_exact(4)
        .map(|t| {
            if alpha {
                t[3]
            } else {
                (0.2126 * t[0] as f32 + 0.7152 * t[1] as f32 + 0.0722 * t[2] as f32)
                    .round()
                    .clamp(0.0, 255.0) as u8
            }
        })
        .collect()
}

/// `colour`'s texels (or white at the mask's size) with the mask's coverage as alpha.
fn masked_texture(colour: Option<&Texture>, mask: &Texture) -> Texture {
    let cover = coverage(mask);
    let as_alpha = Texture {
        name: mask.name.clone(),
        width: mask.width,
        height: mask.height,
        rgba: cover.iter().flat_map(|&c| [255, 255, 255, c]).collect(),
    };
    let (width, height) = colour.map_or((mask.width, mask.height), |c| (c.width, c.height));
    let alpha = as_alpha.resized(width, height);
    let rgba: Vec<u8> = match colour {
        Some(c) => c
            .rgba
            .chunks_exact(4)
            .zip(alpha.rgba.chunks_exact(4))
            .flat_map(|(c, a)| [c[0], c[1], c[2], a[3]])
            .collect(),
        None => alpha.rgba.to_vec(),
    };
    Texture {
        name: match colour {
            Some(c) => format!("{} + {}", c.name, mask.name),
            None => mask.name.clone(),
        },
        width,
        height,
        rgba: rgba.into(),
    }
}

/// Whether every texel is grey (red = green = blue): a height map, not a normal map.
fn is_greyscale(t: &Texture) -> bool {
    t.rgba.chunks_exact(4).all(|p| p[0] == p[1] && p[1] == p[2])
}

fn wrap(clamp: bool) -> Wrap {
    if clamp {
        Wrap::ClampToEdge
    } else {
        Wrap::Repeat
    }
}

/// Converts tobj's materials; `dirs[i]` is the directory material `i`'s library lives in;
/// `(root, allow_outside)`: the model's folder, and whether texture paths may leave it.
pub(super) fn convert(
    materials: &[tobj::Material],
    dirs: &[PathBuf],
    (root, allow_outside): (&Path, bool),
    notes: &mut Vec<String>,
) -> (Vec<Material>, Vec<crate::texture::Texture>) {
    let mut images = Images::default();
    let mut height_maps = Vec::new();
    let mut out = Vec::with_capacity(materials.len());
    let default = Material::default();
    for (i, m) in materials.iter().enumerate() {
        let dir = dirs.get(i).map_or(Path::new("."), PathBuf::as_path);
        let name = if m.name.is_empty() {
            format!("material {i}")
        } else {
            m.name.clone()
        };
        let diffuse = m.diffuse.map_or(default.diffuse, Vec3::from);
        let ambient = m
            .ambient
            .map(Vec3::from)
            .filter(|a| *a != Vec3::ZERO)
            .unwrap_or(diffuse);
        let mut material = Material {
            ambient,
            diffuse,
            specular: m.specular.map_or(default.specular, Vec3::from),
            shininess: m
                .shininess
                .filter(|s| s.is_finite())
                .map_or(default.shininess, |s| s.clamp(0.0, 1000.0)),
            ..default
        };

        // Opens the image of a texture statement, or says (in a note) why not.
        let mut open = |what: &str, arg: Option<&str>, images: &mut Images| {
            let arg = parse_map(arg?);
            if arg.file.is_empty() {
                notes.push(format!("material '{name}': {what} names no file: ignored"));
                return None;
            }
            let found = resolve(
                root,
                dir,
                &arg.file,
                &format!("{what} '{}'", arg.file),
                allow_outside,
            )
            .and_then(|file| images.image(&file, &arg.file).map(|t| (file, t)));
            match found {
                Ok((file, t)) => Some((file, t, arg.clamp)),
                Err(reason) => {
                    notes.push(format!(
                        "material '{name}': {what} '{}' could not be used ({reason}): ignored",
                        arg.file
                    ));
                    None
                }
            }
        };
        let colour = open(
            "map_Kd",
            statement(m.diffuse_texture.as_deref(), m, &["map_Kd"]),
            &mut images,
        );
        let mask = open(
            "map_d",
            statement(m.dissolve_texture.as_deref(), m, &["map_d"]),
            &mut images,
        );
        let bump = open(
            "bump map",
            statement(
                m.normal_texture.as_deref(),
                m,
                &["map_Bump", "bump", "norm", "map_norm"],
            ),
            &mut images,
        );

        match (&colour, &mask) {
            (_, Some((mask_file, mask_tex, mask_clamp))) => {
                let key = (
                    colour.as_ref().map(|c| c.0.clone()),
                    Some(mask_file.clone()),
                );
                let t = images.texture(key, || {
                    masked_texture(colour.as_ref().map(|c| &c.1), mask_tex)
                });
                let clamp = colour.as_ref().map_or(*mask_clamp, |c| c.2);
                material.base_color_texture = Some(TextureRef {
                    texture: t,
                    wrap_s: wrap(clamp),
                    wrap_t: wrap(clamp),
                });
                material.alpha_mode = AlphaMode::Mask;
                material.alpha_cutoff = 0.5;
                material.double_sided = true;
            }
            (Some((file, tex, clamp)), None) => {
                let t = images.texture((Some(file.clone()), None), || tex.clone());
                material.base_color_texture = Some(TextureRef {
                    texture: t,
                    wrap_s: wrap(*clamp),
                    wrap_t: wrap(*clamp),
                });
            }
            (None, None) => {}
        }
        if let Some((file, tex, clamp)) = bump {
            if is_greyscale(&tex) {
                height_maps.push(name.clone());
            } else {
                let t = images.texture((Some(file), None), || tex);
                material.normal_texture = Some(TextureRef {
                    texture: t,
                    wrap_s: wrap(clamp),
                    wrap_t: wrap(clamp),
                });
            }
        }
        out.push(material);
    }
    if !height_maps.is_empty() {
        let shown: Vec<&str> = height_maps.iter().take(4).map(String::as_str).collect();
        notes.push(format!(
            "{} material(s) have greyscale bump maps (height maps, not tangent-space normal \
             maps): ignored ('{}'{})",
            height_maps.len(),
            shown.join("', '"),
            if height_maps.len() > shown.len() {
                ", …"
            } else {
                ""
            }
        ));
    }
    (out, images.textures)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn texture_statement_options_are_skipped() {
        let p = |s: &str| parse_map(s);
        assert_eq!(p("tex.png").file, "tex.png");
        assert_eq!(p("-bm 1.0 textures\\bump.png").file, "textures/bump.png");
        assert_eq!(p("-o 0.5 0.5 -s 2 2 1 my tex.png").file, "my tex.png");
        assert_eq!(p("-mm 0 1 -blendu off a.jpg").file, "a.jpg");
        let c = p("-clamp on leaf.png");
        assert_eq!((c.file.as_str(), c.clamp), ("leaf.png", true));
        assert_eq!(p("-o 1 x.png").file, "x.png");
        assert_eq!(p("").file, "");
        assert_eq!(p("-bm").file, "");
    }

    #[test]
    fn mask_from_luminance_or_alpha() {
        let grey = Texture::from_fn("g", 2, 1, |x, _| {
            [x as u8 * 200, x as u8 * 200, x as u8 * 200, 255]
        });
        assert_eq!(coverage(&grey), vec![0, 200]);
        let alpha = Texture::from_fn("a", 2, 1, |x, _| [255, 255, 255, 100 + x as u8]);
        assert_eq!(coverage(&alpha), vec![100, 101]);
        let colour = Texture::from_fn("c", 2, 1, |_, _| [10, 20, 30, 255]);
        let m = masked_texture(Some(&colour), &grey);
        assert_eq!(&m.rgba[..], &[10, 20, 30, 0, 10, 20, 30, 200]);
    }
}
