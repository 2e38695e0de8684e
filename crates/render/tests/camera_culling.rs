//! Single-sided materials (glTF's `doubleSided: false`, `Material::cull_back_faces`) show the
//! camera their front faces only: a toon outline, an inverted hull around a model, shows at
//! the silhouette and nowhere else; a double-sided card shows both faces; materials that do
//! not ask (the built-in scenes', TOML's) stay two-sided.

mod common;

use glam::{Mat4, Vec3};
use manyshadows::scene::{primitives, Attenuation, Camera, Instance, Light, LightKind};
use manyshadows::scene::{Material, Mesh, Scene};
use manyshadows::{RenderSettings, Renderer};

const W: u32 = 160;
const H: u32 = 120;

fn light() -> Light {
    Light {
        kind: LightKind::Point {
            position: Vec3::new(3.0, 4.0, 5.0),
            range: 30.0,
        },
        ambient: Vec3::splat(0.3),
        diffuse: Vec3::ONE,
        specular: Vec3::ZERO,
        attenuation: Attenuation::for_range(30.0),
        casts_shadows: false,
        shadow_resolution: 256,
        size: 0.0,
    }
}

fn material(colour: Vec3, cull_back_faces: bool, double_sided: bool) -> Material {
    Material {
        ambient: colour,
        diffuse: colour,
        specular: Vec3::ZERO,
        cull_back_faces,
        double_sided,
        ..Default::default()
    }
}

/// A mesh with every triangle wound the other way (its faces turned inside out).
fn inverted(mut m: Mesh) -> Mesh {
    for t in m.indices.chunks_exact_mut(3) {
        t.swap(1, 2);
    }
    for n in &mut m.normals {
        *n = -*n;
    }
    m
}

/// Whether a pixel is mostly red (widened: `2 * u8` wraps in a release build).
fn is_red(p: &[u8]) -> bool {
    p[0] > 80 && u16::from(p[0]) > 2 * u16::from(p[1].max(p[2]))
}

/// Pixels that show mostly red (the card), and pixels of anything.
fn red_and_covered(rgba: &[u8]) -> (usize, usize) {
    let mut red = 0;
    let mut covered = 0;
    for p in rgba.chunks_exact(4) {
        if p[0] > 60 || p[1] > 60 || p[2] > 60 {
            covered += 1;
        }
        if is_red(p) {
            red += 1;
        }
    }
    (red, covered)
}

/// A white cube inside a red inverted hull 15 % larger: with the hull single-sided, its faces
/// towards the camera are back faces and are culled, its far faces hide behind the cube: red
/// shows only outside the cube's own silhouette (a rim); two-sided (the default), the hull
/// covers the cube.
#[test]
fn an_inverted_hull_shows_only_at_the_silhouette() {
    let ctx = common::context();
    let scene = |hull: Option<bool>| Scene {
        name: "outline".into(),
        meshes: vec![
            primitives::cuboid(Vec3::ONE),
            inverted(primitives::cuboid(Vec3::splat(1.15))),
        ],
        materials: vec![
            material(Vec3::ONE, false, false),
            material(Vec3::new(1.0, 0.0, 0.0), hull.unwrap_or(false), false),
        ],
        instances: std::iter::once(Instance::caster(0, 0, Mat4::IDENTITY))
            .chain(hull.map(|_| Instance::caster(1, 1, Mat4::IDENTITY)))
            .collect(),
        lights: vec![light()],
        camera: Camera {
            position: Vec3::new(2.2, 1.8, 2.6),
            target: Vec3::ZERO,
            up: Vec3::Y,
            fov_y_deg: 50.0,
            near: 0.1,
            far: 20.0,
        },
        ..Default::default()
    };
    let render = |hull: Option<bool>| {
        Renderer::new(&ctx, &scene(hull), RenderSettings::new(W, H))
            .expect("renderer")
            .render()
            .expect("frame")
            .rgba
    };
    let cube = render(None);
    let two_sided = render(Some(false));
    let outline = render(Some(true));
    let _ = image::save_buffer(
        common::artifacts_dir().join("outline-cube.png"),
        &cube,
        W,
        H,
        image::ColorType::Rgba8,
    );
    let _ = image::save_buffer(
        common::artifacts_dir().join("outline-shell.png"),
        &outline,
        W,
        H,
        image::ColorType::Rgba8,
    );
    let covered = |p: &[u8]| p[0] > 60 || p[1] > 60 || p[2] > 60;
    let (mut inside, mut rim, mut cube_pixels, mut hidden) = (0, 0, 0, 0);
    for ((c, o), t) in cube
        .chunks_exact(4)
        .zip(outline.chunks_exact(4))
        .zip(two_sided.chunks_exact(4))
    {
        if covered(c) {
            cube_pixels += 1;
            inside += usize::from(is_red(o));
            hidden += usize::from(is_red(t));
        } else {
            rim += usize::from(is_red(o));
        }
    }
    eprintln!(
        "cube {cube_pixels} pixels; single-sided hull: {inside} red inside it, {rim} around it; \
         two-sided: {hidden} red inside"
    );
    assert!(cube_pixels > 1000);
    // Two-sided, the hull covers the cube.
    assert_eq!(hidden, cube_pixels, "a two-sided hull must hide the cube");
    // Single-sided: the cube shows whole, the hull only around it.
    assert_eq!(inside, 0, "the single-sided hull covered the cube");
    assert!(rim > 100, "no silhouette rim ({rim} pixels)");
}

/// A card seen from behind: a double-sided one (or one whose material does not ask for
/// culling) shows; a single-sided one does not, and a mirrored instance of it shows its other
/// face (its winding turns with the determinant).
#[test]
fn a_card_from_behind_shows_unless_single_sided() {
    let ctx = common::context();
    // A plane facing +Y; the camera looks at it from below.
    let frame = |cull: bool, double_sided: bool, transform: Mat4| {
        let scene = Scene {
            name: "card".into(),
            meshes: vec![primitives::plane(2.0, 2.0, 1)],
            materials: vec![material(Vec3::new(1.0, 0.0, 0.0), cull, double_sided)],
            instances: vec![Instance::caster(0, 0, transform)],
            lights: vec![Light {
                kind: LightKind::Point {
                    position: Vec3::new(0.0, -3.0, 0.5),
                    range: 30.0,
                },
                ..light()
            }],
            camera: Camera {
                position: Vec3::new(0.0, -3.0, 0.3),
                target: Vec3::ZERO,
                up: Vec3::Z,
                fov_y_deg: 50.0,
                near: 0.1,
                far: 20.0,
            },
            ..Default::default()
        };
        let rgba = Renderer::new(&ctx, &scene, RenderSettings::new(W, H))
            .expect("renderer")
            .render()
            .expect("frame")
            .rgba;
        red_and_covered(&rgba).0
    };
    let two_sided = frame(false, false, Mat4::IDENTITY);
    let double_sided = frame(false, true, Mat4::IDENTITY);
    let single_sided = frame(true, false, Mat4::IDENTITY);
    // Mirrored in y: its front face now points down, at the camera.
    let mirrored = frame(true, false, Mat4::from_scale(Vec3::new(1.0, -1.0, 1.0)));
    eprintln!("red pixels: {two_sided} / {double_sided} / {single_sided} / {mirrored}");
    assert!(two_sided > 2000 && double_sided == two_sided);
    assert_eq!(single_sided, 0, "a single-sided card's back showed");
    assert!(mirrored > 2000, "the mirrored card's front did not show");
}
