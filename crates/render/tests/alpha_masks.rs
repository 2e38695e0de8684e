//! Alpha-masked casters and textures against exact truth.
//!
//! - The analytic scenes' square occluder becomes a flat card whose texture is a 4 × 4
//!   checkerboard of solid and transparent cells (alpha 255 and 0, 16 texels per cell). The
//!   test computes the exact shadow itself: a ray from the camera to the first surface (the
//!   card where its cell is solid, else the floor), then a segment to the light that is
//!   blocked only where it crosses a solid cell. Every technique's hard visibility must agree
//!   everywhere more than two pixels from an edge, for spot, point and directional lights.
//! - A floor with a checker texture must shade each cell exactly as an untextured floor of
//!   that cell's colour does (the colours of known pixels are known without the texture
//!   path); a flat normal map must change nothing.

mod common;

use glam::{Mat4, Vec2, Vec3, Vec4Swizzles};
use manyshadows::scene::builtin::{self, BuiltinOptions, OCCLUDER_CENTER, OCCLUDER_HALF_SIZE};
use manyshadows::scene::texture::srgb_to_linear;
use manyshadows::scene::{primitives, LightKind, Material, Scene, Texture, TextureRef};
use manyshadows::{Pcf, RenderSettings, Renderer, Technique};

const SIZE: u32 = 256;
const EDGE_BAND_PX: i32 = 2;
/// Checker cells per side of the masked card.
const CELLS: u32 = 4;
/// Texels per side of the mask texture.
const TEXELS: u32 = 64;

fn solid_cell(cx: u32, cy: u32) -> bool {
    (cx + cy).is_multiple_of(2)
}

/// The card's transform: the unit card (x −0.5..0.5, y 0..1, facing +Z) centred, laid flat
/// facing +Y, scaled to the analytic occluder's 2 × 2 m and moved to its centre.
fn card_transform() -> Mat4 {
    Mat4::from_translation(OCCLUDER_CENTER)
        * Mat4::from_rotation_x(-std::f32::consts::FRAC_PI_2)
        * Mat4::from_scale(Vec3::new(
            2.0 * OCCLUDER_HALF_SIZE,
            2.0 * OCCLUDER_HALF_SIZE,
            1.0,
        ))
        * Mat4::from_translation(Vec3::new(0.0, -0.5, 0.0))
}

/// An analytic scene with the checker card instead of the box.
fn checker_scene(name: &str) -> Scene {
    let mut scene = builtin::build(name, &BuiltinOptions::default()).expect("builtin");
    let mask = Texture::from_fn("checker-mask", TEXELS, TEXELS, |x, y| {
        let c = TEXELS / CELLS;
        let a = if solid_cell(x / c, y / c) { 255 } else { 0 };
        [180, 90, 60, a]
    });
    scene.textures = vec![mask];
    scene.meshes[builtin::OCCLUDER_MESH] = primitives::card(1.0, 1.0, Vec2::ONE);
    let occluder = scene
        .instances
        .iter_mut()
        .find(|i| i.mesh == builtin::OCCLUDER_MESH)
        .expect("occluder instance");
    occluder.transform = card_transform();
    let m = occluder.material;
    scene.materials[m] = scene.materials[m].with_texture(0).masked(0.5);
    // Zoom in: at the analytic scenes' 60° the 2 m card is 37 pixels across, its cells 9.
    scene.camera.fov_y_deg = 28.0;
    scene.validate().expect("valid scene");
    scene
}

/// Where the segment `p → p + d·t` (0 < t < t_max) crosses the card plane at a solid cell.
fn blocked(p: Vec3, d: Vec3, t_max: f32, inverse: Mat4) -> Option<f32> {
    if d.y.abs() < 1e-9 {
        return None;
    }
    let t = (OCCLUDER_CENTER.y - p.y) / d.y;
    if !(t > 0.0 && t < t_max) {
        return None;
    }
    let local = inverse.transform_point3(p + d * t);
    // The card's own coordinates: u = x + 0.5, v = 1 − y (v = 0 is the image's top row).
    let (u, v) = (local.x + 0.5, 1.0 - local.y);
    if !(0.0..1.0).contains(&u) || !(0.0..1.0).contains(&v) {
        return None;
    }
    let (cx, cy) = ((u * CELLS as f32) as u32, (v * CELLS as f32) as u32);
    solid_cell(cx, cy).then_some(t)
}

/// The exact hard shadow of the checker card: `None` = sky, `Some(lit)`.
fn checker_truth(scene: &Scene) -> Vec<Option<bool>> {
    let inverse = card_transform().inverse();
    let cam = &scene.camera;
    let inv = (cam.projection(1.0) * cam.view()).inverse();
    let light = scene.lights[0];
    let mut out = Vec::with_capacity((SIZE * SIZE) as usize);
    for y in 0..SIZE {
        for x in 0..SIZE {
            let ndc_x = (x as f32 + 0.5) / SIZE as f32 * 2.0 - 1.0;
            let ndc_y = 1.0 - (y as f32 + 0.5) / SIZE as f32 * 2.0;
            let near = inv * glam::Vec4::new(ndc_x, ndc_y, 0.0, 1.0);
            let far = inv * glam::Vec4::new(ndc_x, ndc_y, 1.0, 1.0);
            let o = near.xyz() / near.w;
            let d = (far.xyz() / far.w - o).normalize();
            if blocked(o, d, f32::INFINITY, inverse).is_some() {
                // A solid cell of the card, seen from above: nothing is over it.
                out.push(Some(true));
                continue;
            }
            let t = -o.y / d.y;
            let p = o + d * t;
            if d.y >= 0.0 || d.y.is_nan() || p.x.abs() > 10.0 || p.z.abs() > 10.0 {
                out.push(None);
                continue;
            }
            let lit = match light.kind {
                LightKind::Directional { direction, .. } => {
                    blocked(p, -direction, f32::INFINITY, inverse).is_none()
                }
                LightKind::Spot {
                    position,
                    direction,
                    cutoff_deg,
                    range,
                } => {
                    let to_p = p - position;
                    to_p.normalize().dot(direction.normalize()) >= cutoff_deg.to_radians().cos()
                        && to_p.length() <= range
                        && blocked(p, -to_p.normalize(), to_p.length(), inverse).is_none()
                }
                LightKind::Point { position, range } => {
                    let to_p = p - position;
                    to_p.length() <= range
                        && blocked(p, -to_p.normalize(), to_p.length(), inverse).is_none()
                }
            };
            out.push(Some(lit));
        }
    }
    out
}

fn check_all_techniques(name: &str) {
    let ctx = common::context();
    let scene = checker_scene(name);
    let truth = checker_truth(&scene);
    let mut ran = 0;
    for technique in Technique::all() {
        let settings = RenderSettings::default()
            .with_width(SIZE)
            .with_height(SIZE)
            .with_technique(technique)
            .with_pcf(Pcf::Off)
            .with_visibility(true);
        let mut r = match Renderer::new(&ctx, &scene, settings) {
            Ok(r) => r,
            Err(e) => {
                common::check_refusal(&ctx, technique, &e);
                continue;
            }
        };
        let frame = r.render().expect("frame");
        let vis = frame.visibility.as_ref().expect("visibility");
        let path = common::artifacts_dir().join(format!("alpha-checker-{name}-{technique}.png"));
        let a = common::agree_with_truth(vis, &truth, SIZE, EDGE_BAND_PX, &path);
        eprintln!(
            "{name} {technique}: {} of {} pixels away from edges disagree with the exact shadow \
             of the checker card ({} shadowed, {} lit; {})",
            a.wrong,
            a.compared,
            a.shadowed,
            a.lit,
            path.display()
        );
        assert_eq!(
            a.wrong, 0,
            "{name}: {technique} disagrees with the exact shadow of an alpha-masked card"
        );
        ran += 1;
    }
    assert!(ran >= 6, "only {ran} techniques ran");
}

#[test]
fn masked_card_shadow_is_exact_under_a_spot() {
    check_all_techniques("plane-spot");
}

#[test]
fn masked_card_shadow_is_exact_under_a_point_light() {
    check_all_techniques("plane-point");
}

#[test]
fn masked_card_shadow_is_exact_under_the_sun() {
    check_all_techniques("plane-directional");
}

/// The cubes' camera over a floor of one material, no shadow caster but the floor, one sun
/// straight down: a pixel's colour depends only on its material's colour.
fn floor_scene(material: Material, textures: Vec<Texture>) -> Scene {
    let mut scene = builtin::build("plane-directional", &BuiltinOptions::default()).unwrap();
    scene.instances.retain(|i| i.mesh == builtin::FLOOR_MESH);
    scene.materials[0] = material;
    scene.textures = textures;
    scene.validate().expect("valid scene");
    scene
}

fn render(scene: &Scene) -> manyshadows::Frame {
    let ctx = common::context();
    let settings = RenderSettings::default().with_width(SIZE).with_height(SIZE);
    Renderer::new(&ctx, scene, settings)
        .expect("renderer")
        .render()
        .expect("frame")
}

#[test]
fn a_checker_texture_shades_each_cell_as_its_colour() {
    // 2 x 2 cells over the 20 m floor (u along +x, v along +z): 10 m cells, far wider than any
    // mip footprint, so pixels away from cell borders sample one colour exactly.
    let colours = [[200u8, 60, 40], [40, 90, 210]];
    let texture = Texture::from_fn("checker", 64, 64, |x, y| {
        let c = colours[((x / 32 + y / 32) % 2) as usize];
        [c[0], c[1], c[2], 255]
    });
    let textured = floor_scene(
        Material::matte(Vec3::ONE).with_texture(0),
        vec![texture.clone()],
    );
    let lin = |c: [u8; 3]| {
        Vec3::new(
            srgb_to_linear(c[0]),
            srgb_to_linear(c[1]),
            srgb_to_linear(c[2]),
        )
    };
    let plain = colours.map(|c| render(&floor_scene(Material::matte(lin(c)), Vec::new())));
    let got = render(&textured);
    // The floor plane (20 m, uv 0..1) under the analytic camera: the pixel's floor point.
    let cam = &textured.camera;
    let inv = (cam.projection(1.0) * cam.view()).inverse();
    let (mut checked, mut off) = ([0usize; 2], 0usize);
    for y in 0..SIZE {
        for x in 0..SIZE {
            let ndc = |dz: f32| {
                let p = inv
                    * glam::Vec4::new(
                        (x as f32 + 0.5) / SIZE as f32 * 2.0 - 1.0,
                        1.0 - (y as f32 + 0.5) / SIZE as f32 * 2.0,
                        dz,
                        1.0,
                    );
                p.xyz() / p.w
            };
            let (o, f) = (ndc(0.0), ndc(1.0));
            let d = (f - o).normalize();
            let p = o + d * (-o.y / d.y);
            let uv = Vec2::new(p.x / 20.0 + 0.5, p.z / 20.0 + 0.5);
            if !(0.0..1.0).contains(&uv.x) || !(0.0..1.0).contains(&uv.y) {
                continue;
            }
            // Away from the cell borders (0.5) by at least 0.5 m.
            if (uv.x - 0.5).abs() < 0.025 || (uv.y - 0.5).abs() < 0.025 {
                continue;
            }
            let cell = (((uv.x * 2.0) as u32 + (uv.y * 2.0) as u32) % 2) as usize;
            let i = ((y * SIZE + x) * 4) as usize;
            let want = &plain[cell].rgba[i..i + 3];
            let have = &got.rgba[i..i + 3];
            checked[cell] += 1;
            if want.iter().zip(have).any(|(a, b)| a.abs_diff(*b) > 1) {
                off += 1;
            }
        }
    }
    eprintln!(
        "checker texture: {} + {} pixels checked, {off} differ by more than one level from the \
         untextured floor of their cell's colour",
        checked[0], checked[1]
    );
    assert!(checked[0] > 5000 && checked[1] > 5000, "{checked:?}");
    assert_eq!(off, 0, "textured cells do not shade as their colour");
}

#[test]
fn a_flat_normal_map_changes_nothing() {
    let flat = Texture::from_fn("flat-normal", 16, 16, |_, _| [128, 128, 255, 255]);
    let bumpy = Texture::from_fn("tilted-normal", 16, 16, |_, _| [200, 128, 200, 255]);
    let mut mapped = Material::matte(Vec3::splat(0.8));
    mapped.normal_texture = Some(TextureRef::repeat(0));
    let plain = render(&floor_scene(Material::matte(Vec3::splat(0.8)), Vec::new()));
    let with_flat = render(&floor_scene(mapped, vec![flat]));
    let with_tilt = render(&floor_scene(mapped, vec![bumpy]));
    let differing = |a: &manyshadows::Frame, b: &manyshadows::Frame, tol: u8| {
        a.rgba
            .chunks(4)
            .zip(b.rgba.chunks(4))
            .filter(|(x, y)| x.iter().zip(y.iter()).any(|(p, q)| p.abs_diff(*q) > tol))
            .count()
    };
    let flat_off = differing(&plain, &with_flat, 1);
    let tilt_off = differing(&plain, &with_tilt, 1);
    eprintln!(
        "normal maps: flat {flat_off} pixels off by more than a level, tilted {tilt_off} pixels"
    );
    assert_eq!(flat_off, 0, "a flat normal map changed the shading");
    // A map tilting every normal by ~30° must show (the sun is straight-ish down).
    assert!(
        tilt_off > 10_000,
        "a tilted normal map changed only {tilt_off} pixels"
    );
}

/// A glTF file written with one light of each type (KHR_lights_punctual) and a camera renders
/// with those lights and that camera: each light's hard shadow of the analytic box agrees with
/// the exact one computed from the geometry, and the camera is the file's.
#[test]
fn a_gltf_file_renders_with_its_own_lights_and_camera() {
    use manyshadows::scene::builtin::AnalyticLight;
    let ctx = common::context();
    let mut scene = builtin::build("plane-spot", &BuiltinOptions::default()).unwrap();
    scene.lights = [
        AnalyticLight::Spot,
        AnalyticLight::Point,
        AnalyticLight::Directional,
    ]
    .map(|l| l.light(None))
    .to_vec();
    let dir = common::artifacts_dir().join("gltf-lights");
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("three-lights.gltf");
    manyshadows::scene::loaders::write_gltf(&scene, &path).expect("write glTF");
    let loaded = manyshadows::scene::loaders::load_scene(&path).expect("load glTF");
    let file = loaded.scene;
    assert_eq!(file.lights.len(), 3, "notes: {:?}", loaded.notes);
    for (a, b) in file.lights.iter().zip(&scene.lights) {
        assert_eq!(a.type_name(), b.type_name());
    }
    let (c, d) = (file.camera, scene.camera);
    assert!(
        c.position.distance(d.position) < 1e-3
            && (c.target - c.position)
                .normalize()
                .dot((d.target - d.position).normalize())
                > 0.99999
            && (c.fov_y_deg - d.fov_y_deg).abs() < 1e-3,
        "the file's camera {c:?} is not the one written {d:?}"
    );
    let settings = RenderSettings::default()
        .with_width(SIZE)
        .with_height(SIZE)
        .with_pcf(Pcf::Off)
        .with_visibility(true);
    let mut r = Renderer::new(&ctx, &file, settings).expect("renderer");
    let frame = r.render().expect("frame");
    let vis = frame.visibility.as_ref().expect("visibility");
    for (k, light) in file.lights.iter().enumerate() {
        // The exact shadow of the box for this light alone, from the file's camera.
        let one = Scene {
            lights: vec![*light],
            ..file.clone()
        };
        let truth = common::analytic_truth(&one, SIZE);
        let out = dir.join(format!("light{k}-{}.png", light.type_name()));
        let a = common::agree_with_truth_of(vis, k as u32, &truth, SIZE, EDGE_BAND_PX, &out);
        eprintln!(
            "glTF light {k} ({}): {} of {} pixels away from edges disagree ({} shadowed, {} lit)",
            light.type_name(),
            a.wrong,
            a.compared,
            a.shadowed,
            a.lit
        );
        assert_eq!(
            a.wrong,
            0,
            "light {k} ({}) of the glTF file",
            light.type_name()
        );
    }
}
