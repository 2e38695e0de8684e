//! Reflection probes (seed 000's reflection cube maps): a probe's face must be the frame a
//! camera at the probe sees through that face (the same G-buffer, shadows and lighting code,
//! in linear radiance before the tone map); faces are kept while nothing changes and redrawn
//! when a caster moves; reflective materials, and only they, mirror the probe.

mod common;

use glam::Vec3;
use manyshadows::scene::builtin::{self, BuiltinOptions, LightMix};
use manyshadows::scene::texture::linear_to_srgb;
use manyshadows::scene::{Probe, Scene};
use manyshadows::{Exposure, Look, RenderSettings, Renderer, Technique, ToneMap};

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
fn bad_probes_are_refused_by_name_and_a_mask_technique_leaves_them_out() {
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
    // Irregular maps' mask holds the camera's pixels only: the probes are left out (warned).
    let mut r = Renderer::new(
        &ctx,
        &scene,
        settings()
            .with_technique(Technique::IRREGULAR)
            .with_width(32)
            .with_height(18),
    )
    .expect("irregular leaves the probes out");
    assert_eq!(r.render().expect("frame").probes, None);
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
    // 64 probes of 1024² need 3 GiB of faces: made where the device has the memory, else
    // refused naming the probes (lavapipe: out of memory), never a later validation error.
    scene.probes = vec![
        Probe {
            resolution: 1024,
            ..good
        };
        Probe::MAX_COUNT
    ];
    if let Some(e) = refused(&scene, Technique::TRADITIONAL) {
        assert!(
            e.to_string().contains("faces of 64 probes"),
            "3 GiB of faces: {e}"
        );
    }
}

/// A mirror sphere in a room whose six walls glow in six colours, each wall's two halves in
/// two shades, the probe at the room's centre standing for the room: each of the sphere's
/// pixels must show the colour of the wall and half its reflected view ray reaches, found on
/// the CPU from the pixel's G-buffer point and normal by a ray-box crossing. This is
/// independent of the probe's faces, their order and orientation, and the box projection: a
/// wrong face, a mirrored face or a plain direction lookup shows another colour.
#[test]
fn a_mirror_shows_the_wall_its_reflected_ray_reaches() {
    use glam::Mat4;
    use manyshadows::scene::{primitives, Camera, Instance, Material};
    let ctx = common::context();
    let h = 4.0f32;
    let colours = [
        Vec3::new(0.6, 0.05, 0.05),
        Vec3::new(0.05, 0.6, 0.05),
        Vec3::new(0.05, 0.05, 0.6),
        Vec3::new(0.6, 0.6, 0.05),
        Vec3::new(0.05, 0.6, 0.6),
        Vec3::new(0.6, 0.05, 0.6),
    ];
    // Wall `w` (+X, −X, +Y, −Y, +Z, −Z), half `b` (1: the half where the next axis is
    // positive, in a darker shade).
    let shade = |w: usize, b: usize| colours[w] * if b == 1 { 0.3 } else { 1.0 };
    let black = Material {
        ambient: Vec3::ZERO,
        diffuse: Vec3::ZERO,
        specular: Vec3::ZERO,
        ..Material::default()
    };
    let mut materials = Vec::new();
    let mut instances = Vec::new();
    for w in 0..6 {
        let (axis, sign) = (w / 2, if w % 2 == 0 { 1.0 } else { -1.0 });
        let next = (axis + 1) % 3;
        for b in 0..2 {
            materials.push(Material {
                emissive: shade(w, b),
                ..black
            });
            // A thin slab: the wall's half, as a box (no rotation needed).
            let mut size = Vec3::splat(2.0 * h);
            size[axis] = 0.02;
            size[next] = h;
            let mut at = Vec3::ZERO;
            at[axis] = sign * (h + 0.01);
            at[next] = if b == 1 { 0.5 * h } else { -0.5 * h };
            let t = Mat4::from_translation(at) * Mat4::from_scale(size);
            instances.push(Instance::caster(0, materials.len() - 1, t));
        }
    }
    materials.push(Material { ..black }.reflecting(1.0));
    let mirror = materials.len() - 1;
    let centre = Vec3::new(1.0, -1.0, 0.5);
    instances.push(Instance::caster(1, mirror, Mat4::from_translation(centre)));
    let mut camera = Camera::look_at(Vec3::new(-2.5, 1.5, -2.5), centre);
    camera.fov_y_deg = 40.0;
    let scene = Scene {
        name: "mirror room".into(),
        meshes: vec![
            primitives::cuboid(Vec3::ONE),
            primitives::uv_sphere(1.0, 64, 32),
        ],
        materials,
        instances,
        camera,
        probes: vec![Probe {
            resolution: 128,
            ..Probe::new(Vec3::ZERO, Vec3::splat(2.0 * h))
        }],
        ..Default::default()
    };
    let (w, hh) = (160u32, 120u32);
    let mut r =
        Renderer::new(&ctx, &scene, settings().with_width(w).with_height(hh)).expect("mirror room");
    let frame = r.render().expect("frame");
    let g = r.read_gbuffer().expect("G-buffer");
    let (mut compared, mut wrong) = (0usize, 0usize);
    let mut halves = [0usize; 2];
    let mut diff = frame.rgba.clone();
    for k in 0..(w * hh) as usize {
        diff[4 * k..4 * k + 3].copy_from_slice(&[0, 0, 0]);
        if !g.covered[k] || g.material[k] as usize != mirror {
            continue;
        }
        let (p, n) = (g.position[k], g.normal[k]);
        let v = (scene.camera.position - p).normalize();
        if n.dot(v) < 0.2 {
            continue;
        }
        let ray = 2.0 * n.dot(v) * n - v;
        // Where the reflected ray leaves the room.
        let far = ((Vec3::splat(h) - p) / ray).max((Vec3::splat(-h) - p) / ray);
        let axis = if far.x <= far.y && far.x <= far.z {
            0
        } else if far.y <= far.z {
            1
        } else {
            2
        };
        let hit = p + ray * far[axis];
        let next = (axis + 1) % 3;
        // Away from the walls' edges and the halves' border (bilinear taps, faces' seams).
        let off_edge = (0..3).all(|a| a == axis || hit[a].abs() < h - 0.3) && hit[next].abs() > 0.3;
        // The probe sees that wall point past the sphere (a probe sees the room from its
        // centre: where the sphere stands between them it sees the sphere, unlit, instead).
        let d = hit.normalize();
        let along = centre.dot(d);
        let past = along < 0.0 || (centre - d * along).length() > 1.1;
        if !off_edge || !past {
            continue;
        }
        let wall = 2 * axis + usize::from(ray[axis] < 0.0);
        let half = usize::from(hit[next] > 0.0);
        let want: Vec<u8> = (0..3).map(|c| display(shade(wall, half)[c])).collect();
        let got = &frame.rgba[4 * k..4 * k + 3];
        compared += 1;
        halves[half] += 1;
        if got.iter().zip(&want).any(|(a, b)| a.abs_diff(*b) > 3) {
            wrong += 1;
            diff[4 * k..4 * k + 3].copy_from_slice(&[255, 0, 0]);
        } else {
            diff[4 * k..4 * k + 3].copy_from_slice(&[128, 128, 128]);
        }
    }
    eprintln!(
        "mirror: {wrong} of {compared} compared pixels show another colour ({halves:?} per half)"
    );
    if wrong * 100 > compared || std::env::var("SAVE").is_ok() {
        save("probe-mirror.png", &frame.rgba, w, hh);
        save("probe-mirror-diff.png", &diff, w, hh);
    }
    assert!(
        compared > 1000 && halves.iter().all(|&n| n > 200),
        "too few mirror pixels compared ({compared}, {halves:?} per half)"
    );
    assert!(
        wrong * 100 <= compared,
        "{wrong} of {compared} mirror pixels show another wall's colour (images in \
         target/test-artifacts)"
    );
}

/// The probes' faces drawn in one layered pass (each instance once per face, into its tile of
/// an atlas G-buffer), one multiview pass per probe (each face in its layer, at the origin) or
/// GPU-driven (triangle clusters culled per face in compute, indirect multi-draws into the
/// layered way's tiles) against one pass per face: the same texels but where a triangle's edge
/// or a shadow's edge tips under the tile offset (the rasterizer's rounding), a measured
/// handful, bounded here; multiview draws each face as one pass would.
#[test]
fn faces_drawn_in_one_pass_match_faces_drawn_one_pass_each() {
    use manyshadows::ProbePasses;
    let ctx = common::context();
    let mut scene = atrium(LightMix::Spot);
    scene.probes.push(Probe {
        resolution: SIDE,
        ..Probe::new(Vec3::new(-8.0, 3.0, 0.0), Vec3::new(20.0, 12.0, 16.0))
    });
    let faces = |passes: ProbePasses| {
        let settings = settings()
            .with_width(64)
            .with_height(36)
            .with_probe_passes(passes);
        let mut r = match Renderer::new(&ctx, &scene, settings) {
            Err(e @ manyshadows::RenderError::MissingFeature { .. })
                if passes != ProbePasses::PerFace =>
            {
                let why = Renderer::probe_passes_unmet(&ctx, passes).expect("refused for a lack");
                let need = ["MULTIVIEW", "CLIP_DISTANCES", "INDIRECT_EXECUTION"]
                    .into_iter()
                    .find(|n| why.contains(n))
                    .unwrap_or_else(|| panic!("{passes}: an unknown need: {why}"));
                manyshadows_testkit::refused(need, &format!("probe faces {passes}: {e}"));
                return None;
            }
            other => other.expect("renderer"),
        };
        assert_eq!(r.render().expect("frame").probes.unwrap().faces_drawn, 12);
        Some(
            (0..2)
                .flat_map(|k| (0..6).map(move |f| (k, f)))
                .map(|(k, f)| r.read_probe_face(k, f).expect("face"))
                .collect::<Vec<_>>(),
        )
    };
    let one = faces(ProbePasses::PerFace).expect("per face");
    // Where the device has the features: layered and GPU-driven everywhere here (Vulkan and
    // GL), multiview on Vulkan.
    let expected = if ctx.info.backend == manyshadows::wgpu::Backend::Vulkan {
        3
    } else {
        2
    };
    let mut compared = 0;
    for passes in [
        ProbePasses::Layered,
        ProbePasses::Multiview,
        ProbePasses::Clusters,
    ] {
        let Some(other) = faces(passes) else {
            continue;
        };
        compared += 1;
        let (mut texels, mut differ) = (0usize, 0usize);
        for (a, b) in one.iter().zip(&other) {
            for (x, y) in a.iter().zip(b) {
                texels += 1;
                let off = (0..3).any(|c| display(x[c]).abs_diff(display(y[c])) > 2);
                differ += usize::from(off);
            }
        }
        let share = differ as f64 / texels as f64;
        eprintln!(
            "{passes} faces: {differ} of {texels} texels differ by more than 2 levels ({:.3} %)",
            100.0 * share
        );
        assert!(
            share <= 0.005,
            "{passes} faces differ from per-face ones in {:.2} % of texels",
            100.0 * share
        );
    }
    assert_eq!(
        compared, expected,
        "a way was refused where the device has it"
    );
}

/// A single-sided-able grid of `n` × `n` quads in the plane x = 0 (y, z in 0..1), its front
/// (counter-clockwise winding, normals) facing +x.
fn grid(n: u32) -> manyshadows::scene::Mesh {
    let (mut positions, mut indices) = (Vec::new(), Vec::new());
    for j in 0..=n {
        for i in 0..=n {
            positions.push(Vec3::new(0.0, j as f32 / n as f32, i as f32 / n as f32));
        }
    }
    for j in 0..n {
        for i in 0..n {
            let a = j * (n + 1) + i;
            let (b, c, d) = (a + n + 1, a + 1, a + n + 2);
            // (b − a) × (c − a) = +y × +z = +x.
            indices.extend([a, b, c, c, b, d]);
        }
    }
    manyshadows::scene::Mesh {
        name: "grid".into(),
        normals: vec![Vec3::X; positions.len()],
        uvs: Vec::new(),
        positions,
        indices,
    }
}

/// GPU-driven faces cull per face on the GPU, and only what a face cannot show: six 90° faces
/// split the directions around the probe, so a cluster (a piece of a mesh) lies in one face's
/// frustum, or two or three where it straddles their edges, and the cull keeps well under half
/// of every cluster × every face. A grid of 8,192 triangles stands beside the probe, its front
/// facing away: single-sided, each of its clusters faces away from the probe and is dropped
/// from every face (at least one pair per cluster fewer kept). And the faces stay those one
/// pass per face draws with the same materials (which culls whole instances and back faces),
/// also after the fountain moves from the probe's −x face into its +z face (the clusters'
/// spheres follow their instance on the GPU).
#[test]
fn gpu_driven_faces_keep_only_the_clusters_a_face_can_show() {
    use manyshadows::ProbePasses;
    let ctx = common::context();
    let grid_triangles: u64 = 2 * 64 * 64;
    let run = |single_sided: bool, passes: ProbePasses| {
        let mut scene = atrium(LightMix::Spot);
        for m in &mut scene.materials {
            m.cull_back_faces = single_sided;
        }
        scene.meshes.push(grid(64));
        let transform = glam::Mat4::from_translation(Vec3::new(7.5, 0.5, -1.0))
            * glam::Mat4::from_scale(Vec3::splat(2.0));
        scene.instances.push(manyshadows::scene::Instance::caster(
            scene.meshes.len() - 1,
            0,
            transform,
        ));
        let settings = settings()
            .with_width(64)
            .with_height(36)
            .with_probe_passes(passes);
        let mut r = Renderer::new(&ctx, &scene, settings).expect("renderer");
        r.render().expect("frame");
        let read = |r: &Renderer| -> Vec<Vec<[f32; 4]>> {
            (0..6)
                .map(|f| r.read_probe_face(0, f).expect("face"))
                .collect()
        };
        let mut faces = read(&r);
        let kept = r.probe_clusters_kept().expect("read-back");
        let fountain = scene
            .instances
            .iter()
            .position(|i| scene.meshes[i.mesh].name == "fountain")
            .expect("the atrium's fountain");
        let t = scene.instances[fountain].transform;
        r.set_instance_transform(
            fountain,
            glam::Mat4::from_translation(Vec3::new(6.0, 0.0, 4.0)) * t,
        )
        .expect("move");
        assert_eq!(r.render().expect("frame").probes.unwrap().faces_drawn, 6);
        faces.extend(read(&r));
        (kept, faces)
    };
    let mut kept = Vec::new();
    for single_sided in [false, true] {
        let (counts, faces) = run(single_sided, ProbePasses::Clusters);
        let (k, offered) = counts.expect("drawn GPU-driven");
        eprintln!("single-sided {single_sided}: the cull kept {k} of {offered} cluster-face pairs");
        assert!(offered > 0 && offered % 6 == 0, "offered {offered}");
        assert!(
            k > 0 && 2 * k < offered,
            "kept {k} of {offered}: a cluster lies in a few of the six faces"
        );
        kept.push(k);
        let (none, one) = run(single_sided, ProbePasses::PerFace);
        assert_eq!(none, None, "per-face draws no clusters");
        let (mut texels, mut differ) = (0usize, 0usize);
        for (a, b) in faces.iter().zip(&one) {
            for (x, y) in a.iter().zip(b) {
                texels += 1;
                differ += usize::from((0..3).any(|c| display(x[c]).abs_diff(display(y[c])) > 2));
            }
        }
        eprintln!("  {differ} of {texels} texels differ from per-face by more than 2 levels");
        assert!(
            differ * 200 <= texels,
            "single-sided {single_sided}: {differ} of {texels} texels differ from per-face"
        );
    }
    // The grid's clusters: at most 256 triangles each (probes/clusters.rs).
    let grid_clusters = grid_triangles.div_ceil(256);
    assert!(
        kept[1] + grid_clusters <= kept[0],
        "single-sided, the grid's {grid_clusters} clusters face away from the probe and are \
         dropped from every face (kept {} against {})",
        kept[1],
        kept[0]
    );
}

/// GPU-driven faces split over many cull + draw rounds (each round some faces, or some of a
/// pipeline's clusters: what many probes or a large scene need within the device's limits)
/// draw the faces one round per pipeline draws (the test hook caps the commands of a round).
#[test]
fn gpu_driven_faces_in_many_rounds_match_few_rounds() {
    use manyshadows::ProbePasses;
    let ctx = common::context();
    let mut scene = atrium(LightMix::Spot);
    scene.probes.push(Probe {
        resolution: SIDE,
        ..Probe::new(Vec3::new(-8.0, 3.0, 0.0), Vec3::new(20.0, 12.0, 16.0))
    });
    let settings = settings()
        .with_width(64)
        .with_height(36)
        .with_probe_passes(ProbePasses::Clusters);
    let read = |r: &Renderer| -> Vec<Vec<[f32; 4]>> {
        (0..2)
            .flat_map(|k| (0..6).map(move |f| (k, f)))
            .map(|(k, f)| r.read_probe_face(k, f).expect("face"))
            .collect()
    };
    let mut r = Renderer::new(&ctx, &scene, settings.clone()).expect("renderer");
    r.render().expect("frame");
    let few = r.probe_cluster_rounds().expect("drawn GPU-driven");
    let (_, offered) = r.probe_clusters_kept().expect("read-back").expect("counts");
    let clusters = offered / 12;
    let want = read(&r);
    // Two faces' commands of every cluster per round, then rounds that split the clusters.
    for cap in [2 * clusters, clusters / 3 + 1] {
        let mut r = Renderer::new(&ctx, &scene, settings.clone()).expect("renderer");
        assert!(r.cap_probe_cluster_rounds(cap));
        r.render().expect("frame");
        let rounds = r.probe_cluster_rounds().expect("drawn GPU-driven");
        assert!(
            rounds >= few + 4,
            "{rounds} rounds of at most {cap} commands against {few}"
        );
        let got = read(&r);
        let (mut texels, mut differ) = (0usize, 0usize);
        for (a, b) in want.iter().zip(&got) {
            for (x, y) in a.iter().zip(b) {
                texels += 1;
                differ += usize::from((0..3).any(|c| display(x[c]).abs_diff(display(y[c])) > 2));
            }
        }
        eprintln!(
            "{rounds} rounds of at most {cap} commands ({few} uncapped): {differ} of {texels} \
             texels differ by more than 2 levels"
        );
        assert!(
            differ * 200 <= texels,
            "{differ} of {texels} texels differ between {rounds} rounds and {few}"
        );
    }
}
