//! Reflection probes (seed 000's reflection cube maps): a probe's face must be the frame a
//! camera at the probe sees through that face (the same G-buffer, shadows and lighting code,
//! in linear radiance before the tone map); faces are kept while nothing changes and redrawn
//! when a caster moves; reflective materials, and only they, mirror the probe.

mod common;

use glam::Vec3;
use manyshadows::scene::builtin::{self, BuiltinOptions, LightMix};
use manyshadows::scene::texture::linear_to_srgb;
use manyshadows::scene::{Probe, Scene};
use manyshadows::{Exposure, Look, RenderError, RenderSettings, Renderer, Technique, ToneMap};

const SIDE: u32 = 64;

/// The atrium with point lights (their maps do not depend on the camera) and one probe beside
/// the fountain.
fn atrium(mix: LightMix) -> Scene {
    let mut scene = builtin::build(
        "atrium",
        &BuiltinOptions {
            lights: Some(8),
            seed: 2,
            mix,
            shadow_resolution: Some(256),
            ..Default::default()
        },
    )
    .expect("atrium");
    scene.probes = vec![Probe {
        resolution: SIDE,
        ..Probe::new(Vec3::new(6.0, 1.5, 0.0), Vec3::ZERO)
    }];
    scene
}

fn look() -> Look {
    Look {
        shading: None,
        exposure: Some(Exposure::Scale(1.4)),
        tone_map: Some(ToneMap::Exponential),
    }
}

fn settings() -> RenderSettings {
    RenderSettings::default()
        .with_technique(Technique::TRADITIONAL)
        .with_look(look())
}

/// A linear radiance as the frame's exponential tone map and sRGB encoding write it.
fn display(c: f32) -> u8 {
    let v = 1.0 - (-c * 1.4).exp();
    linear_to_srgb(v)
}

fn save(name: &str, rgba: &[u8], w: u32, h: u32) {
    let path = common::artifacts_dir().join(name);
    image::save_buffer(&path, rgba, w, h, image::ColorType::Rgba8).expect("write artifact");
}

#[test]
fn a_probe_face_is_the_frame_a_camera_at_the_probe_sees_through_it() {
    let ctx = common::context();
    let scene = atrium(LightMix::Point);
    let mut r = Renderer::new(&ctx, &scene, settings().with_width(96).with_height(54))
        .expect("renderer with a probe");
    let frame = r.render().expect("frame");
    assert_eq!(frame.probes.map(|p| p.faces_drawn), Some(6));
    let cams = scene.probes[0].face_cameras(scene.camera.near, scene.camera.far);
    let mut worst: f64 = 0.0;
    for (f, cam) in cams.iter().enumerate() {
        let face = r.read_probe_face(0, f).expect("probe face");
        assert_eq!(face.len(), (SIDE * SIDE) as usize);
        let mut mono = scene.clone();
        mono.probes.clear();
        mono.camera = *cam;
        let mut m = Renderer::new(&ctx, &mono, settings().with_width(SIDE).with_height(SIDE))
            .expect("camera at the probe");
        let want = m.render().expect("camera frame").rgba;
        let got: Vec<u8> = face
            .iter()
            .flat_map(|t| [display(t[0]), display(t[1]), display(t[2]), 255])
            .collect();
        // The sky is written as it is, not tone-mapped: a texel matches either way.
        let sky: Vec<u8> = face
            .iter()
            .flat_map(|t| {
                [
                    linear_to_srgb(t[0]),
                    linear_to_srgb(t[1]),
                    linear_to_srgb(t[2]),
                    255,
                ]
            })
            .collect();
        let near = |a: &[u8], b: &[u8]| a.iter().zip(b).all(|(x, y)| x.abs_diff(*y) <= 2);
        let differ = (0..(SIDE * SIDE) as usize)
            .filter(|&k| {
                let t = 4 * k..4 * k + 4;
                !near(&got[t.clone()], &want[t.clone()]) && !near(&sky[t.clone()], &want[t])
            })
            .count();
        let share = differ as f64 / (SIDE * SIDE) as f64;
        eprintln!(
            "face {f}: {differ} texels differ by more than 2 levels ({:.2} %)",
            100.0 * share
        );
        worst = worst.max(share);
        if share > 0.005 {
            save(&format!("probe-face-{f}.png"), &got, SIDE, SIDE);
            save(&format!("probe-face-{f}-camera.png"), &want, SIDE, SIDE);
        }
        // The face is not empty: the atrium surrounds the probe.
        assert!(
            face.iter().filter(|t| t[0] + t[1] + t[2] > 0.0).count() > 100,
            "face {f} is black"
        );
        assert!(
            share <= 0.005,
            "face {f}: {differ} of {} texels differ from the camera's frame by more than 2 \
             levels (images in target/test-artifacts)",
            SIDE * SIDE
        );
    }
    eprintln!(
        "probe faces against cameras: at most {:.2} % of texels differ",
        100.0 * worst
    );
}

#[test]
fn faces_are_kept_while_nothing_changes_and_redrawn_when_a_caster_moves() {
    let ctx = common::context();
    let scene = atrium(LightMix::Spot);
    let mut r = Renderer::new(&ctx, &scene, settings().with_width(96).with_height(54))
        .expect("renderer with a probe");
    assert_eq!(r.render().unwrap().probes.unwrap().faces_drawn, 6);
    let before: Vec<Vec<[f32; 4]>> = (0..6).map(|f| r.read_probe_face(0, f).unwrap()).collect();
    assert_eq!(
        r.render().unwrap().probes.unwrap().faces_drawn,
        0,
        "nothing changed"
    );
    // The fountain (at the origin, beside the probe) moves up by a metre.
    let fountain = scene
        .instances
        .iter()
        .position(|i| scene.meshes[i.mesh].name == "fountain")
        .expect("the atrium's fountain");
    let t = scene.instances[fountain].transform;
    r.set_instance_transform(fountain, glam::Mat4::from_translation(Vec3::Y) * t)
        .unwrap();
    assert_eq!(
        r.render().unwrap().probes.unwrap().faces_drawn,
        6,
        "a caster moved"
    );
    let changed: usize = (0..6)
        .map(|f| {
            let after = r.read_probe_face(0, f).unwrap();
            after.iter().zip(&before[f]).filter(|(a, b)| a != b).count()
        })
        .sum();
    assert!(
        changed > 100,
        "the moved fountain changed only {changed} texels"
    );
}

#[test]
fn reflective_materials_and_only_they_mirror_the_probe() {
    let ctx = common::context();
    let with = atrium(LightMix::Spot);
    let mut without = with.clone();
    without.probes.clear();
    let frame = |scene: &Scene| {
        let mut r = Renderer::new(&ctx, scene, settings().with_width(160).with_height(90))
            .expect("renderer");
        let f = r.render().expect("frame");
        (f.rgba, r.read_gbuffer().expect("G-buffer"))
    };
    let (a, g) = frame(&with);
    let (b, _) = frame(&without);
    let (mut mirrors, mut mirrored, mut matte_changed) = (0, 0, 0);
    let mut brighter = 0i64;
    for (k, (pa, pb)) in a.chunks_exact(4).zip(b.chunks_exact(4)).enumerate() {
        if !g.covered[k] {
            continue;
        }
        let reflective = with.materials[g.material[k] as usize].reflect > 0.0;
        if reflective {
            mirrors += 1;
            mirrored += usize::from(pa != pb);
            brighter += (0..3)
                .map(|c| i64::from(pa[c]) - i64::from(pb[c]))
                .sum::<i64>();
        } else if pa != pb {
            matte_changed += 1;
        }
    }
    eprintln!(
        "{mirrored} of {mirrors} reflective pixels changed, {:.2} levels brighter on average",
        brighter as f64 / (3 * mirrors.max(1)) as f64
    );
    assert_eq!(matte_changed, 0, "surfaces that reflect nothing changed");
    assert!(
        mirrors > 1000,
        "too few reflective pixels in view ({mirrors})"
    );
    // Mirrored light adds: the reflective pixels are brighter (a dark room's reflections
    // change some dark pixels by less than one level).
    assert!(
        mirrored * 5 > mirrors && brighter > 0,
        "only {mirrored} of {mirrors} reflective pixels show the probe ({brighter} levels)"
    );
}

#[test]
fn bad_probes_and_unsupported_techniques_are_refused_by_name() {
    let ctx = common::context();
    let mut scene = atrium(LightMix::Spot);
    let refused = |scene: &Scene, technique: Technique| {
        Renderer::new(
            &ctx,
            scene,
            settings()
                .with_technique(technique)
                .with_width(32)
                .with_height(18),
        )
        .err()
    };
    match refused(&scene, Technique::IRREGULAR) {
        Some(RenderError::NotImplemented { .. }) => {}
        other => panic!("irregular with probes: {other:?}"),
    }
    let good = scene.probes[0];
    for bad in [
        Probe {
            resolution: 0,
            ..good
        },
        Probe {
            resolution: 4096,
            ..good
        },
        Probe {
            position: Vec3::NAN,
            ..good
        },
        Probe {
            size: Vec3::new(1.0, -1.0, 1.0),
            ..good
        },
    ] {
        scene.probes = vec![bad];
        let err = refused(&scene, Technique::TRADITIONAL);
        assert!(
            err.as_ref()
                .is_some_and(|e| e.to_string().contains("probe 0 is invalid")),
            "{bad:?}: {err:?}"
        );
    }
    scene.probes = vec![
        Probe {
            resolution: 8,
            ..good
        };
        Probe::MAX_COUNT + 1
    ];
    let err = refused(&scene, Technique::TRADITIONAL);
    assert!(
        err.as_ref()
            .is_some_and(|e| e.to_string().contains("at most 64")),
        "too many probes: {err:?}"
    );
}
