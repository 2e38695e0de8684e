//! Meshes as scanners deliver them: the Stanford dragon (`dragon_vrip_res3.ply.gz`) has 4,188
//! directed edges used twice — triangles wound against their neighbours — and 67 vertices whose
//! face normals cancel. Its vertex normals (area-weighted, as every loader computes them) still
//! point outwards, but a reversed triangle is a *back face* to the rasterizer. Shading must not
//! depend on winding: a reversed triangle seen from outside is the outside of the surface.
//!
//! The test mesh is generated here (no download): a bumpy sphere with one triangle in 7 wound
//! the other way, rendered beside the same sphere wound consistently. The speckles of the
//! dragon (reversed triangles shaded with their normal turned away from the camera: black) made
//! 476 of the sphere's 3,400 pixels (14 %) face away in the G-buffer and 453 (13 %) much
//! darker than on the consistent sphere; since the G-buffer orients normals by the triangle's
//! plane both are 0 (Vulkan and OpenGL).

mod common;

use glam::{Mat4, Vec3};
use manyshadows::scene::{
    primitives, Attenuation, Camera, Instance, Light, LightKind, Material, Mesh, Scene,
};
use manyshadows::{RenderSettings, Renderer};

/// A sphere of radius ~1 with bumps (so normals vary), centred 1.2 above the floor; one
/// triangle in `flip_every` wound the other way.
fn bumpy_sphere(flip_every: Option<usize>) -> Mesh {
    let mut m = primitives::uv_sphere(1.0, 96, 48);
    for p in &mut m.positions {
        *p *= 1.0 + 0.04 * (7.0 * p.x).sin() * (5.0 * p.y).cos() * (6.0 * p.z).sin();
    }
    if let Some(k) = flip_every {
        for (i, t) in m.indices.chunks_exact_mut(3).enumerate() {
            if i % k == 3 {
                t.swap(1, 2);
            }
        }
    }
    m.compute_normals();
    m
}

fn scene(sphere: Mesh) -> Scene {
    let light = |position: Vec3, range: f32| Light {
        kind: LightKind::Spot {
            position,
            direction: (Vec3::new(0.0, 1.2, 0.0) - position).normalize(),
            cutoff_deg: 40.0,
            range,
        },
        ambient: Vec3::splat(0.02),
        diffuse: Vec3::splat(0.9),
        specular: Vec3::splat(0.3),
        attenuation: Attenuation::for_range(range),
        casts_shadows: true,
        shadow_resolution: 1024,
        size: 0.0,
    };
    Scene {
        textures: Vec::new(),
        name: "scanned".into(),
        meshes: vec![primitives::plane(8.0, 8.0, 1), sphere],
        materials: vec![Material::default()],
        instances: vec![
            Instance::caster(0, 0, Mat4::IDENTITY),
            Instance::caster(1, 0, Mat4::from_translation(Vec3::new(0.0, 1.2, 0.0))),
        ],
        lights: vec![
            light(Vec3::new(2.5, 4.0, 3.0), 12.0),
            light(Vec3::new(-3.0, 3.0, 1.5), 12.0),
        ],
        camera: Camera {
            position: Vec3::new(0.0, 2.0, 4.0),
            target: Vec3::new(0.0, 1.2, 0.0),
            ..Default::default()
        },
        lighting: Default::default(),
        probes: Vec::new(),
        animations: Default::default(),
    }
}

fn render(sphere: Mesh) -> (Vec<u8>, manyshadows::GBufferData) {
    let ctx = common::context();
    let s = scene(sphere);
    let mut r = Renderer::new(
        &ctx,
        &s,
        RenderSettings::default().with_width(200).with_height(150),
    )
    .unwrap();
    let frame = r.render().unwrap();
    (frame.rgba, r.read_gbuffer().unwrap())
}

#[test]
fn reversed_triangles_shade_like_the_rest_of_the_surface() {
    let (good_rgba, good_g) = render(bumpy_sphere(None));
    let (scan_rgba, scan_g) = render(bumpy_sphere(Some(7)));
    let eye = Vec3::new(0.0, 2.0, 4.0);
    // Sphere pixels: covered, above the floor.
    let sphere: Vec<usize> = (0..scan_g.covered.len())
        .filter(|&i| scan_g.covered[i] && scan_g.position[i].y > 0.05)
        .collect();
    assert!(sphere.len() > 2500, "{} sphere pixels", sphere.len());
    // 1. G-buffer normals face the camera (what two-sided shading promises).
    let away = |g: &manyshadows::GBufferData| {
        sphere
            .iter()
            .filter(|&&i| g.normal[i].dot((eye - g.position[i]).normalize()) < -0.2)
            .count()
    };
    let (away_good, away_scan) = (away(&good_g), away(&scan_g));
    eprintln!(
        "normals facing away: consistent {away_good}, reversed {away_scan} of {}",
        sphere.len()
    );
    // 2. The lit image: no pixel much darker than on the consistent sphere. (The two meshes'
    // vertex normals differ a little near reversed triangles — their face normals enter the
    // sum negated — so the images are close, not equal.)
    let luma = |p: &[u8]| 0.3 * p[0] as f32 + 0.59 * p[1] as f32 + 0.11 * p[2] as f32;
    let darker = sphere
        .iter()
        .filter(|&&i| {
            let (g, s) = (
                luma(&good_rgba[4 * i..4 * i + 4]),
                luma(&scan_rgba[4 * i..4 * i + 4]),
            );
            g > 30.0 && s < 0.5 * g
        })
        .count();
    eprintln!("much darker pixels: {darker} of {}", sphere.len());
    assert_eq!(away_good, 0);
    assert_eq!(away_scan, 0, "reversed triangles shade as seen from inside");
    assert_eq!(darker, 0, "dark speckles on reversed triangles");
}

/// A gable roof with the normals its file gives (outwards), wound outwards or inwards (as
/// imported models often are). Under a sun the winding must change nothing: the same lit image
/// and visibility, byte for byte, and every roof pixel lit (nothing is above the roof). Before
/// the G-buffer oriented normals by the triangle's plane, the inward-wound roof was shaded from
/// inside and its receivers were biased into the roof (self-shadowing stripes).
#[test]
fn roof_winding_changes_nothing() {
    let roof = |inward: bool| {
        let s = std::f32::consts::FRAC_1_SQRT_2;
        let (south, north) = (Vec3::new(0.0, s, s), Vec3::new(0.0, s, -s));
        let mut m = Mesh {
            name: "roof".into(),
            // South slope (z 1 → 0, y 1 → 2), then north slope (z 0 → −1, y 2 → 1).
            positions: vec![
                Vec3::new(-1.5, 1.0, 1.0),
                Vec3::new(1.5, 1.0, 1.0),
                Vec3::new(1.5, 2.0, 0.0),
                Vec3::new(-1.5, 2.0, 0.0),
                Vec3::new(-1.5, 2.0, 0.0),
                Vec3::new(1.5, 2.0, 0.0),
                Vec3::new(1.5, 1.0, -1.0),
                Vec3::new(-1.5, 1.0, -1.0),
            ],
            normals: vec![south, south, south, south, north, north, north, north],
            uvs: Vec::new(),
            indices: vec![0, 1, 2, 0, 2, 3, 4, 5, 6, 4, 6, 7],
        };
        if inward {
            for t in m.indices.chunks_exact_mut(3) {
                t.swap(1, 2);
            }
        }
        m
    };
    let render = |inward: bool| {
        let ctx = common::context();
        let mut s = scene(roof(inward));
        s.instances[1].transform = Mat4::IDENTITY;
        s.lights = vec![Light {
            kind: LightKind::Directional {
                direction: Vec3::new(0.3, -1.0, -0.6).normalize(),
                cascades: 2,
                split_lambda: 0.5,
                cascade_resolution_scale: 1.0,
            },
            ambient: Vec3::splat(0.02),
            diffuse: Vec3::splat(0.9),
            specular: Vec3::splat(0.3),
            attenuation: Attenuation::NONE,
            casts_shadows: true,
            shadow_resolution: 1024,
            size: 0.0,
        }];
        s.camera.position = Vec3::new(2.5, 3.0, 4.0);
        s.camera.target = Vec3::new(0.0, 1.4, 0.0);
        let mut r = Renderer::new(
            &ctx,
            &s,
            RenderSettings::default()
                .with_width(200)
                .with_height(150)
                .with_visibility(true),
        )
        .unwrap();
        let frame = r.render().unwrap();
        let g = r.read_gbuffer().unwrap();
        (frame, g)
    };
    let (out_frame, out_g) = render(false);
    let (in_frame, _) = render(true);
    let roof_pixels: Vec<usize> = (0..out_g.covered.len())
        .filter(|&i| out_g.covered[i] && out_g.position[i].y > 1.01)
        .collect();
    assert!(
        roof_pixels.len() > 2000,
        "{} roof pixels",
        roof_pixels.len()
    );
    let (vo, vi) = (
        out_frame.visibility.as_ref().unwrap(),
        in_frame.visibility.as_ref().unwrap(),
    );
    let w = vo.width;
    let px = |i: usize| ((i as u32) % w, (i as u32) / w);
    let shadowed = |v: &manyshadows::VisibilityMask| {
        roof_pixels
            .iter()
            .filter(|&&i| !v.lit(px(i).0, px(i).1, 0))
            .count()
    };
    let (so, si) = (shadowed(vo), shadowed(vi));
    eprintln!(
        "roof pixels in shadow: outward-wound {so}, inward-wound {si} of {}",
        roof_pixels.len()
    );
    assert_eq!(so, 0, "the outward-wound roof shadows itself");
    assert_eq!(si, 0, "the inward-wound roof shadows itself");
    assert!(vo == vi, "visibility depends on winding");
    let differing = out_frame
        .rgba
        .chunks_exact(4)
        .zip(in_frame.rgba.chunks_exact(4))
        .filter(|(a, b)| a != b)
        .count();
    assert_eq!(differing, 0, "lit image depends on winding");
}
