//! Virtual shadow maps against the exact CPU reference on real geometry: the atrium with 40
//! lights of every type (two mask words per pixel), each bit of the hard visibility mask
//! against a ray traced from the same G-buffer point, scored as `compare` scores it. (The
//! analytic outlines, the one-page pool, caching and frame changes are tested in analytic.rs,
//! caching.rs and frame_changes.rs.)

mod common;

use manyshadows::scene::builtin::{self, BuiltinOptions};
use manyshadows::{Pcf, RenderSettings, Renderer, Technique};

/// Misclassified (false shadow + false light) outside the edge band, as a fraction of the
/// in-reach pairs facing the light (what `compare` reports).
fn misclassified(technique: Technique) -> (f64, common::ReferenceErrors) {
    let (f, e, stats) = misclassified_with(technique, manyshadows::VirtualOptions::default());
    if let Some(stats) = stats {
        assert_eq!(stats.denied, 0, "{stats:?}");
    }
    (f, e)
}

fn misclassified_with(
    technique: Technique,
    options: manyshadows::VirtualOptions,
) -> (
    f64,
    common::ReferenceErrors,
    Option<manyshadows::VirtualStats>,
) {
    let ctx = common::context();
    let scene = atrium_40();
    let settings = RenderSettings::default()
        .with_width(320)
        .with_height(180)
        .with_pcf(Pcf::Off)
        .with_visibility(true)
        .with_technique(technique)
        .with_virtual_maps(options);
    let mut r = Renderer::new(&ctx, &scene, settings).expect("renderer");
    let frame = r.render().expect("frame");
    let vis = frame.visibility.expect("mask");
    assert_eq!(vis.words_per_pixel, 2);
    let e = common::reference_errors(&r, &scene, &vis, 2);
    let c = &e.counts;
    assert!(c.in_reach > 100_000, "degenerate: {c:?}");
    let f = (c.false_shadow + c.false_light) as f64 / c.in_reach as f64;
    eprintln!(
        "atrium, 40 lights, 320x180, {technique}: {:.4} % misclassified; {c:?}",
        f * 100.0
    );
    (f, e, frame.virtual_maps)
}

/// The virtual mask against the reference: under 0.05 % outside the edge band (the issue
/// asked for 0.2 %), and better than the atlas (`traditional`, default maps) on the same
/// frame. Measured (lavapipe and llvmpipe GL): virtual 0.021 % (0.038 % before faces got the
/// atlas floor, `VirtualOptions::atlas_floor`; 0.022 % before spot faces took the atlas's whole
/// bias at their floor, and 0.11 % with every face taking it there), traditional 0.430 % (at
/// 960x540 `compare` measures 0.011 % against 0.412 % with 64 lights: at 320x180 a pixel,
/// hence a page texel, is 3 times wider). Every face at lod 1 (`directed_lod` 1, the default
/// before) gave 0.025 %; every face at lod 0.8 gives 0.221 % (seen failing: the coarser
/// texels' errors are point lights' walls). A whole texel of receiver bias (`bias_scale` 1,
/// the default before) leaks light at contacts: 0.156 %, seen failing.
#[test]
fn virtual_mask_matches_the_reference_better_than_the_atlas() {
    let (virt, _) = misclassified(Technique::VIRTUAL);
    let (atlas, _) = misclassified(Technique::TRADITIONAL);
    assert!(
        virt <= 0.0005,
        "virtual: {:.4} % misclassified",
        virt * 100.0
    );
    assert!(virt < atlas, "virtual {virt} against traditional {atlas}");
}

/// A 20 × 20 floor (a caster) lit by one shadowed light of `kind` reaching `range`.
fn lamp_over_floor(
    kind: manyshadows::scene::LightKind,
    range: f32,
    camera: manyshadows::scene::Camera,
) -> manyshadows::scene::Scene {
    use glam::{Mat4, Vec3};
    use manyshadows::scene::{primitives, Attenuation, Instance, Light, Material, Scene};
    Scene {
        textures: Vec::new(),
        name: "lamp over a floor".into(),
        meshes: vec![primitives::plane(20.0, 20.0, 8)],
        materials: vec![Material::default()],
        instances: vec![Instance::caster(0, 0, Mat4::IDENTITY)],
        lights: vec![Light {
            kind,
            ambient: Vec3::ZERO,
            diffuse: Vec3::ONE,
            specular: Vec3::ZERO,
            attenuation: Attenuation::for_range(range),
            casts_shadows: true,
            shadow_resolution: 256,
            size: 0.0,
        }],
        camera,
        lighting: Default::default(),
        probes: Vec::new(),
        animations: Default::default(),
    }
}

/// A point light above a floor, with the camera seeing every floor point in its reach: the
/// plan lays out all six cube faces, but only the faces the lit samples look through get
/// pages. The light sits 1 above the floor; a floor point in reach R lies at most √(R² − 1)
/// from the foot of the light, and the direction to it is (x, −1, z): the −Y face holds it
/// while |x| ≤ 1 and |z| ≤ 1. Range 1.3 (at most 0.83 away): the −Y face alone. Range 3 (up to
/// 2.83 away): −Y and the four side faces, never +Y (nothing above the light).
#[test]
fn a_point_light_over_a_floor_gets_pages_only_in_the_faces_its_samples_need() {
    use glam::Vec3;
    use manyshadows::scene::{Camera, LightKind};
    let ctx = common::context();
    let scene = |range: f32| {
        lamp_over_floor(
            LightKind::Point {
                position: Vec3::new(0.0, 1.0, 0.0),
                range,
            },
            range,
            Camera::look_at(Vec3::new(0.0, 7.0, 4.0), Vec3::ZERO),
        )
    };
    let settings = RenderSettings::default()
        .with_width(256)
        .with_height(256)
        .with_technique(Technique::VIRTUAL);
    for (range, want) in [(1.3, 1), (3.0, 5)] {
        let mut r = Renderer::new(&ctx, &scene(range), settings.clone()).expect("renderer");
        let stats = r.render().expect("frame").virtual_maps.expect("stats");
        eprintln!("range {range}: {stats:?}");
        assert_eq!(
            stats.fit.faces, 6,
            "the plan has every cube face: {stats:?}"
        );
        assert_eq!(
            stats.faces_in_use, want,
            "range {range}: {} faces in use, want {want}",
            stats.faces_in_use
        );
        assert!(stats.resident >= want, "{stats:?}");
    }
}

/// Spot and directional faces aim for `lod · directed_lod` texels per pixel, point lights'
/// cube faces for `lod`. A light 2 above a floor, seen from nearby: halving `directed_lod`
/// leaves a point light's pages as they were, and gives a spot light a face of half the side
/// whose samples each ask for the level one coarser (the level's texel is the same width,
/// against a pixel now worth half as many texels: log2 of their ratio moves by exactly one),
/// so its finest asked level drops by one. (A lookup or marking still reading the options'
/// `lod` leaves the spot's levels unchanged: seen failing.)
#[test]
fn spot_faces_take_the_directed_level_of_detail_and_cube_faces_keep_theirs() {
    use glam::Vec3;
    use manyshadows::scene::{Camera, LightKind};
    let ctx = common::context();
    let scene = |kind: LightKind| {
        lamp_over_floor(
            kind,
            4.0,
            Camera::look_at(Vec3::new(0.0, 4.0, 2.5), Vec3::ZERO),
        )
    };
    let position = Vec3::new(0.0, 2.0, 0.0);
    let point = LightKind::Point {
        position,
        range: 4.0,
    };
    let spot = LightKind::Spot {
        position,
        direction: Vec3::NEG_Y,
        cutoff_deg: 40.0,
        range: 4.0,
    };
    // (finest asked level, asked per level, the first face's side and level of detail)
    let run = |kind: LightKind, directed: f32| {
        let settings = RenderSettings::default()
            .with_width(768)
            .with_height(768)
            .with_technique(Technique::VIRTUAL)
            .with_virtual_maps(manyshadows::VirtualOptions::default().with_directed_lod(directed));
        let mut r = Renderer::new(&ctx, &scene(kind), settings).expect("renderer");
        let stats = r.render().expect("frame").virtual_maps.expect("stats");
        let face = r.virtual_plan().expect("plan").faces[0];
        eprintln!(
            "{kind:?}, directed {directed}: {stats:?}, face side {}",
            face.table[2]
        );
        let finest = stats
            .asked
            .iter()
            .rposition(|&n| n > 0)
            .expect("pages asked");
        (finest, stats.asked, face.table[2], face.detail[0])
    };
    let (p1, p05) = (run(point, 1.0), run(point, 0.5));
    assert_eq!(p1, p05, "a point light's faces ignore directed_lod");
    assert_eq!(p1.3, 1.0);
    let (s1, s05) = (run(spot, 1.0), run(spot, 0.5));
    assert_eq!((s1.3, s05.3), (1.0, 0.5), "the spot face's level of detail");
    assert_eq!(s05.2 * 2, s1.2, "half the side: {} against {}", s05.2, s1.2);
    assert!(s1.0 >= 2, "the spot must ask for fine levels: {:?}", s1.1);
    assert_eq!(
        s05.0 + 1,
        s1.0,
        "finest asked level: {:?} against {:?}",
        s05.1,
        s1.1
    );
}

/// A pool with fewer pages than the faces in use: the atrium's 40 lights look through 102
/// faces, a pool of 6 × 6 pages cannot give each one, so every finer level is denied and the
/// last 88 faces share pool pages four to one (level-0 quarter pages, 64² texels over a 90°
/// face). Every face keeps a shadow (none unshadowed), and the mask stays near what such
/// coarse maps give. Measured (lavapipe and llvmpipe GL): 1.55 % misclassified outside the
/// band (2.50 % before faces got the atlas floor), mostly false light where thin casters
/// vanish at 64² (a 10 × 10-page pool, whole level-0 pages for all but 3 faces: 1.31 %, before
/// the floor); quarters read from the wrong place in the pool: 9.96 %. Bound:
/// 4 %.
#[test]
fn faces_on_quarter_pages_keep_their_shadows() {
    let pool = manyshadows::VirtualOptions::default().with_pool_bytes(768 * 768 * 4);
    let (f, _, stats) = misclassified_with(Technique::VIRTUAL, pool);
    let stats = stats.expect("stats");
    eprintln!("36-page pool: {stats:?}");
    assert_eq!(stats.pool_pages, 36);
    assert!(stats.quarter_faces > 0, "{stats:?}");
    assert_eq!(stats.unshadowed_faces, 0, "{stats:?}");
    assert!(f <= 0.04, "{:.4} % misclassified", f * 100.0);
}

/// Only the pages samples ask for are drawn: their ancestors (marked so that a full pool has a
/// coarser page to fall back to) are drawn only at the admitted level, where the pool's room
/// ends. With the default pool every asked page fits, so the resident pages are exactly the
/// asked ones, fewer than the marked ones. A pool too small for every asked page admits the
/// finest level A whose marked pages fit with the asked pages of the coarser levels (the CPU
/// recomputes A from the counters): asked pages coarser than A and every marked page of A are
/// resident, asked pages finer than A are denied, and the mask stays near the reference
/// (their samples read their ancestor at A). Measured (lavapipe): 328 asked of 348 marked
/// pages; an 18 × 18 pool admits level 3 (its 24 marked pages with the 293 asked coarser
/// ones), denies the 12 of level 4, and misclassifies 0.027 % against the full pool's 0.025 %
/// (bound: 0.05 points more). Marking ancestors as needed, as before, admitted level 2 only.
/// Every face at lod 1 (`directed_lod` 1): with spot faces at the default 0.8, 287 pages are
/// asked, the largest square pool short of them (16 × 16) admits level 1 and denies three
/// finer levels, and the mask's errors are those of maps three levels coarser (0.38 %): the
/// admission rule holds there too, but this bound is for a pool short by one level.
#[test]
fn only_asked_pages_are_drawn_and_a_short_pool_admits_a_whole_level() {
    // Measured without the atlas floor (every face as fine as the atlas's tile at least):
    // with it, at 320 x 180 with 40 lights, the asked pages crowd the finest levels, and a
    // pool short of them denies the floor's pages themselves (0.37 % against 0.021 %), a
    // pool short by much more than one level.
    let lod1 = manyshadows::VirtualOptions::default()
        .with_directed_lod(1.0)
        .with_atlas_floor(false);
    let (full, _, stats) = misclassified_with(Technique::VIRTUAL, lod1);
    let stats = stats.expect("stats");
    eprintln!("default pool: {stats:?}");
    assert_eq!(stats.denied, 0, "{stats:?}");
    assert_eq!(stats.resident, stats.asked_total(), "{stats:?}");
    assert!(stats.asked_total() < stats.needed_total(), "{stats:?}");
    // The largest square pool short of the asked pages.
    let k = ((stats.asked_total() - 1) as f64).sqrt() as u32;
    let page = stats.pool_side / (stats.pool_pages as f64).sqrt() as u32;
    let pool = lod1.with_pool_bytes((k as u64 * page as u64).pow(2) * 4);
    let (short, _, s) = misclassified_with(Technique::VIRTUAL, pool);
    let s = s.expect("stats");
    eprintln!("{k}x{k} pool: {s:?}");
    assert_eq!(s.pool_pages, k * k);
    let a = s.admitted_level() as usize;
    let coarser: u32 = s.asked[..a].iter().sum();
    let finer: u32 = s.asked[a + 1..].iter().sum();
    assert!(finer > 0, "the short pool must deny something: {s:?}");
    assert_eq!(s.resident, coarser + s.needed[a], "level {a}: {s:?}");
    assert_eq!(s.denied, finer, "level {a}: {s:?}");
    assert!(s.resident <= s.pool_pages);
    assert!(
        short <= full + 0.0005,
        "short pool {:.4} % against {:.4} %",
        short * 100.0,
        full * 100.0
    );
}

/// Culling caster clusters by groups first (a merged sphere per 16 clusters, then the
/// clusters of the groups inside a page) must draw exactly what testing every cluster against
/// every page draws: the groups' spheres hold their clusters' spheres, so they only skip work.
/// (A group sphere 30 % too small drops clusters at page borders: the counts differ, seen
/// failing.)
#[test]
fn group_culling_draws_exactly_what_the_flat_cull_draws() {
    let (_, _, grouped) =
        misclassified_with(Technique::VIRTUAL, manyshadows::VirtualOptions::default());
    let (_, _, flat) = misclassified_with(
        Technique::VIRTUAL,
        manyshadows::VirtualOptions::default().with_group_cull(false),
    );
    let (grouped, flat) = (grouped.expect("stats"), flat.expect("stats"));
    eprintln!("grouped: {grouped:?}\nflat: {flat:?}");
    assert_eq!(grouped.drawn, flat.drawn);
    assert!(flat.cluster_draws > 1000, "{flat:?}");
    assert_eq!(
        (grouped.cluster_draws, grouped.triangles),
        (flat.cluster_draws, flat.triangles)
    );
}

/// Receiver bounds skip only casters that no sample reading the page can see. Depth: each
/// sample's shadow test is `receiver <= stored`, and a caster deeper than every receiver leaves
/// it true. Extent: a page is cleared and drawn only over the rectangle its samples' filter
/// taps reach. So the hard visibility mask and the image (PCF 2x2) are the same, with fewer
/// triangles drawn, but for rounding: triangles are clipped at the rectangle's sides, and a
/// clipped triangle's new corners interpolate depths that can differ in the last bit from the
/// whole triangle's, enough to flip a comparison whose receiver sits that close to a surface
/// (with the virtual maps' half-texel bias: on lavapipe 1 pixel by 2 of 255 levels, on
/// llvmpipe GL 1 mask bit of 2.3 M; clipping at the page's sides instead gives identical
/// masks and images on both, seen, but rasterizes more). So at most 2 mask bits and 2 pixels
/// may differ, the pixels by at most 4 levels. (Bounding a page by half its farthest receiver
/// changes 22,584 mask words; a rectangle without the taps' reach, 31 pixels: seen failing.)
#[test]
fn casters_beyond_a_pages_farthest_receiver_are_skipped_without_changing_a_pixel() {
    let ctx = common::context();
    let scene = atrium_40();
    let render = |receiver_cull: bool| {
        virtual_frame(
            &ctx,
            &scene,
            manyshadows::VirtualOptions::default().with_receiver_cull(receiver_cull),
        )
    };
    let (bounded, all) = (render(true), render(false));
    let (b, a) = (
        bounded.virtual_maps.expect("stats"),
        all.virtual_maps.expect("stats"),
    );
    eprintln!("bounded: {b:?}\nall: {a:?}");
    assert_eq!((b.drawn, b.denied), (a.drawn, a.denied));
    assert!(
        b.triangles * 10 < a.triangles * 9,
        "receiver bounds should save over a tenth of the triangles: {} of {}",
        b.triangles,
        a.triangles
    );
    let (differing, largest, bits) = common::frame_differences(&bounded, &all);
    // (Writes both images as artifacts when any pixel differs.)
    common::differing_pixels(&bounded, &all, "virtual_receiver_cull", ["bounded", "all"]);
    eprintln!("mask bits that differ: {bits}; pixels: {differing}");
    assert!(bits <= 2, "{bits} mask bits differ");
    assert!(
        differing <= 2 && largest <= 4,
        "{differing} pixels differ, by up to {largest} levels"
    );
}

/// Where the adapter counts draws on the GPU, page drawing expands (cluster, page) pairs into
/// the triangles that touch the page, in an index buffer of `expand_bytes`; when a round's
/// triangles exceed it, the pairs past it are drawn whole. An index buffer of 1,000 triangles
/// overflows in every round of the atrium and must give the same image and mask as the
/// default 2 M. (Drawing nothing past the buffer: 62,630 mask words differ, seen failing.)
/// Drawn whole, the pairs also skip the expansion's per-triangle culls, so this checks those
/// against drawing everything: a triangle between texel centres writes no texel (skipping
/// triangles that reach 0.3 texel past a centre fails here, seen). On adapters without
/// GPU-counted draws both draw whole clusters and agree trivially.
#[test]
fn an_overflowing_triangle_expansion_draws_the_same_shadows() {
    let ctx = common::context();
    let scene = atrium_40();
    // Without the atlas floor: with it, 2 pixels of the PCF image differ by one level of 255
    // (the mask is the same), and that is the expansion's back-face cull, which whole draws
    // do not do: at a closed caster's silhouette a texel centre can fall inside a back face
    // and outside every front face, so whole draws write the back face's depth there and the
    // expansion leaves it clear (either is a valid rasterization of the silhouette; with the
    // back-face cull turned off the two agree, seen). Not the texel-centre cull, the receiver
    // bounds or the tile marking (each turned off or widened, the 2 pixels stay).
    let render = |expand_bytes: u64| {
        virtual_frame(
            &ctx,
            &scene,
            manyshadows::VirtualOptions::default()
                .with_expand_bytes(expand_bytes)
                .with_atlas_floor(false),
        )
    };
    let (small, full) = (render(12 * 1000), render(24 << 20));
    let (s, f) = (
        small.virtual_maps.expect("stats"),
        full.virtual_maps.expect("stats"),
    );
    eprintln!(
        "GPU-counted draws: {}; triangles kept: {} (small), {} (full)",
        ctx.device
            .features()
            .contains(wgpu::Features::MULTI_DRAW_INDIRECT_COUNT),
        s.triangles,
        f.triangles
    );
    assert!(f.triangles > 10_000, "{f:?}");
    assert_eq!(s.drawn, f.drawn);
    assert_same_shadows(&small, &full, "virtual_expand_overflow", ["small", "full"]);
}

/// Tile marking (the default) must ask for exactly the pages per-pixel marking asks for: a
/// tile marks a light's page only where it proved that every sample needing a page of the
/// light needs that one (or a pixel checked that it does), and hands everything uncertain on
/// to per-pixel marking. So the asked and marked pages per level are equal, and with the
/// pages drawn whole (no receiver bounds) the image and visibility mask are equal bit for
/// bit; with receiver bounds (a tile's are those of its box of samples, at least as wide as
/// its pixels') only rounding at the drawn rectangle's sides may differ, as in
/// `casters_beyond_a_pages_farthest_receiver_are_skipped_without_changing_a_pixel`. Once with
/// the visibility mask (pages for samples facing away too) and once for the lighting alone
/// (facing tests on), on the atrium (every light type), the terrain (cascades over long
/// slopes), the atrium moved 3,000 units from the origin (coordinates rounding 300 times
/// coarser: the tiles' margins grow with them) and the atrium with every other light sized
/// (their tiles show only where no sample needs a page; the rest is marked per pixel). Each of the tiles' ways (no page, one page marked once, a known page checked per
/// pixel, per pixel) must have been taken; in the atrium's lighting-only frames some tiles also
/// find the jobs' room full and do their per-pixel work themselves (seen with a counter). The
/// page tables are compared entry by entry: the same pages in the same pool places. (Seen failing: the level margin at -0.2, the asked
/// pages differ; the facing proof without the box's angular radius, 27 pixels by up to 114
/// levels; the uv margin at -0.01, 24 mask bits, its cells too small. Not caught, even entry
/// by entry: dropping the bias's half-texel growth of the box, the margins' growth with the
/// coordinates (the far atrium passes without it) or a uv margin of -0.002 leave the page
/// tables identical — a page one tile's samples would miss is asked by their neighbours — so
/// only a per-tile check could see them.)
#[test]
fn tile_marking_asks_exactly_the_pages_per_pixel_marking_asks() {
    let ctx = common::context();
    let terrain = builtin::build(
        "terrain",
        &BuiltinOptions {
            lights: Some(24),
            light_sizes: manyshadows::scene::light_size::LightSizes::HARD,
            ..Default::default()
        },
    )
    .expect("terrain");
    // The atrium 3,000 units from the world's origin: samples' coordinates round 300 times
    // coarser, which the tiles' margins must cover (the per-pixel path rounds as it will).
    let mut far = atrium_40();
    let offset = glam::Vec3::new(3000.0, 0.0, -2000.0);
    for i in &mut far.instances {
        i.transform = glam::Mat4::from_translation(offset) * i.transform;
    }
    for l in &mut far.lights {
        match &mut l.kind {
            manyshadows::scene::LightKind::Spot { position, .. }
            | manyshadows::scene::LightKind::Point { position, .. } => *position += offset,
            _ => {}
        }
    }
    far.camera.position += offset;
    far.camera.target += offset;
    // Every other spot and point light sized: their samples are marked per pixel (their
    // filters reach pages beside their own) but for tiles no sample of which needs a page.
    let mut sized = atrium_40();
    for (k, l) in sized.lights.iter_mut().enumerate() {
        if k % 2 == 0 && l.type_name() != "directional" {
            l.size = 0.1;
        }
    }
    assert!(sized.lights.iter().any(|l| l.size > 0.0));
    for (name, scene) in [
        ("atrium", atrium_40()),
        ("terrain", terrain),
        ("far atrium", far),
        ("half-sized atrium", sized),
    ] {
        for visibility in [true, false] {
            for receiver_cull in [false, true] {
                if name == "far atrium" && receiver_cull {
                    continue;
                }
                let render = |tiles: bool| {
                    let settings = RenderSettings::default()
                        .with_width(320)
                        .with_height(180)
                        .with_visibility(visibility)
                        .with_technique(Technique::VIRTUAL)
                        .with_virtual_maps(
                            manyshadows::VirtualOptions::default()
                                .with_tile_marking(tiles)
                                .with_receiver_cull(receiver_cull),
                        );
                    let mut r = Renderer::new(&ctx, &scene, settings).expect("renderer");
                    let frame = r.render().expect("frame");
                    let table = r.read_page_table().expect("page table");
                    (frame, table)
                };
                let ((tiles, t_table), (pixels, p_table)) = (render(true), render(false));
                let (t, p) = (
                    tiles.virtual_maps.expect("stats"),
                    pixels.virtual_maps.expect("stats"),
                );
                let case =
                    format!("{name}, visibility {visibility}, receiver cull {receiver_cull}");
                eprintln!("{case}: tiles {:?}\npixels {:?}", t.tiles, p.tiles);
                assert_eq!(p.tiles, manyshadows::TileMarking::default(), "{case}");
                let m = t.tiles;
                assert!(
                    m.empty > 0 && m.one_page > 0 && m.known_page > 0 && m.per_pixel > 0,
                    "{case}: every way of the tiles should be taken: {m:?}"
                );
                assert_eq!((t.asked, t.needed), (p.asked, p.needed), "{case}");
                // Entry by entry: the same pages, in the same pool places.
                let entries = t.fit.table_entries as usize;
                assert_eq!(p.fit.table_entries as usize, entries, "{case}");
                let differing = (0..entries).filter(|&k| t_table[k] != p_table[k]).count();
                assert_eq!(differing, 0, "{case}: page-table entries that differ");
                assert!(t.asked_total() > 50, "{case}: {t:?}");
                assert_eq!((t.drawn, t.denied), (p.drawn, p.denied), "{case}");
                if !receiver_cull {
                    assert_eq!(t.triangles, p.triangles, "{case}");
                    if visibility {
                        assert_same_shadows(
                            &tiles,
                            &pixels,
                            "virtual_tile_marking",
                            ["tiles", "pixels"],
                        );
                    } else {
                        assert_eq!(
                            common::differing_pixels(
                                &tiles,
                                &pixels,
                                "virtual_tile_marking",
                                ["tiles", "pixels"]
                            ),
                            0,
                            "{case}: pixels that differ"
                        );
                    }
                } else {
                    let (differing, largest, bits) = common::frame_differences(&tiles, &pixels);
                    assert!(bits <= 2, "{case}: {bits} mask bits differ");
                    assert!(
                        differing <= 2 && largest <= 4,
                        "{case}: {differing} pixels differ, by up to {largest} levels"
                    );
                }
            }
        }
    }
}

/// Sized lights through the tile marking: a tile all of whose samples need one page marks it
/// once, and with it the pages beside that every sample's soft filter reaches (the corners of
/// its reach, when each falls in one page for the whole tile). On frames so small that each
/// page is needed by only a few tiles, so that a page or a bound one tile misses shows in
/// the page table (on the 320×180 frame of the test above other samples ask for every page
/// beside: there, a tile marking nothing at all for a sized light changed no entry), every
/// entry must equal per-pixel marking's. Seen failing: the pages beside not marked by tiles
/// (a frame's entries differ), nothing marked by a sized light's tile.
#[test]
fn sized_lights_tiles_ask_the_pages_their_filters_reach() {
    let ctx = common::context();
    // Every light sized (the built-in sizes: 2 % of each range, the sun 0.53°).
    let scene = builtin::build(
        "atrium",
        &BuiltinOptions {
            lights: Some(40),
            ..Default::default()
        },
    )
    .expect("atrium");
    assert!(scene.lights.iter().all(|l| l.size > 0.0));
    let (mut whole_tiles, mut bounded) = (0, 0);
    for (width, height) in [(16, 16), (40, 24), (96, 54), (160, 90)] {
        for max_penumbra in [32.0, 64.0] {
            let render = |tiles: bool| {
                let settings = RenderSettings::default()
                    .with_width(width)
                    .with_height(height)
                    .with_technique(Technique::VIRTUAL)
                    .with_soft(manyshadows::SoftShadows::default().with_max_penumbra(max_penumbra))
                    .with_virtual_maps(
                        manyshadows::VirtualOptions::default().with_tile_marking(tiles),
                    );
                let mut r = Renderer::new(&ctx, &scene, settings).expect("renderer");
                let frame = r.render().expect("frame");
                let table = r.read_page_table().expect("page table");
                (frame.virtual_maps.expect("stats"), table)
            };
            let ((t, t_table), (p, p_table)) = (render(true), render(false));
            let case = format!("{width}x{height}, penumbrae up to {max_penumbra} texels");
            eprintln!("{case}: {:?}, {} pages asked", t.tiles, t.asked_total());
            whole_tiles += t.tiles.one_page;
            assert_eq!((t.asked, t.needed), (p.asked, p.needed), "{case}");
            let entries = t.fit.table_entries as usize;
            assert_eq!(p.fit.table_entries as usize, entries, "{case}");
            let differing = (0..entries).filter(|&k| t_table[k] != p_table[k]).count();
            assert_eq!(differing, 0, "{case}: page-table entries that differ");
            assert_eq!((t.drawn, t.denied), (p.drawn, p.denied), "{case}");
            // The receiver bounds after the entries (vsm_table.wgsl: each page's farthest
            // depth key, then its cells): a tile's bound its samples' box, so at least what
            // the samples themselves ask (keys are positive floats: their bits order them).
            assert!(
                t_table.len() >= 3 * entries,
                "{case}: entries, keys and cells"
            );
            let short = (0..entries)
                .filter(|&k| {
                    let (tk, pk) = (t_table[entries + k], p_table[entries + k]);
                    let (tc, pc) = (t_table[2 * entries + k], p_table[2 * entries + k]);
                    tk < pk || pc & !tc != 0
                })
                .count();
            bounded += (0..entries)
                .filter(|&k| p_table[2 * entries + k] != 0)
                .count();
            assert_eq!(
                short, 0,
                "{case}: pages whose tile bounds miss what samples ask"
            );
        }
    }
    assert!(
        whole_tiles > 0,
        "no sized light's tile marked its pages once"
    );
    assert!(bounded > 100, "only {bounded} pages bounded");
}

/// The atrium with 40 hard lights of every type (two mask words per pixel): these tests
/// check which pages are drawn and what they hold, where sized lights' soft filters would also
/// read pages beside the asked ones (soft virtual maps: `soft_shadows.rs`).
fn atrium_40() -> manyshadows::scene::Scene {
    builtin::build(
        "atrium",
        &BuiltinOptions {
            lights: Some(40),
            light_sizes: manyshadows::scene::light_size::LightSizes::HARD,
            ..Default::default()
        },
    )
    .expect("atrium")
}

/// One virtual-map frame of `scene` at 320x180 with PCF 2x2 and the hard visibility mask.
fn virtual_frame(
    ctx: &manyshadows::GpuContext,
    scene: &manyshadows::scene::Scene,
    options: manyshadows::VirtualOptions,
) -> manyshadows::Frame {
    let settings = RenderSettings::default()
        .with_width(320)
        .with_height(180)
        .with_visibility(true)
        .with_technique(Technique::VIRTUAL)
        .with_virtual_maps(options);
    let mut r = Renderer::new(ctx, scene, settings).expect("renderer");
    r.render().expect("frame")
}

/// Image and visibility mask equal bit for bit (differing images are written as artifacts).
fn assert_same_shadows(
    a: &manyshadows::Frame,
    b: &manyshadows::Frame,
    stem: &str,
    tags: [&str; 2],
) {
    let words = |f: &manyshadows::Frame| f.visibility.as_ref().expect("mask").words.clone();
    let (wa, wb) = (words(a), words(b));
    assert_eq!(wa.len(), wb.len());
    let differing = wa.iter().zip(&wb).filter(|(x, y)| x != y).count();
    assert_eq!(differing, 0, "mask words that differ");
    assert_eq!(
        common::differing_pixels(a, b, stem, tags),
        0,
        "pixels that differ"
    );
}
