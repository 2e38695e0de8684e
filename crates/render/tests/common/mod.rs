//! Shared helpers of the GPU integration tests.
#![allow(dead_code)]

use glam::{Vec3, Vec4Swizzles};
use manyshadows::scene::builtin;
use manyshadows::scene::{LightKind, Scene};
use manyshadows::{AdapterRequest, GpuContext};

/// The GPU context every GPU test runs on: the adapter `GpuContext::new` picks, narrowed by
/// `WGPU_BACKEND` (CI runs the suite once with `vulkan` and once with `gl`). Never skips: with
/// no adapter the test fails and says what to install.
///
/// On Vulkan (and Metal, DX12) one device per test process, made by the first test that asks
/// and shared (cloned) by every test after it; it is never dropped. NVIDIA's Linux Vulkan
/// driver (580.159.04) crashes or deadlocks now and then when several threads create and
/// destroy devices at once (wgpu issues 8365 and 10010; seen here as a segfault and as a
/// binary stalled after its last check, in `--test-threads 8` runs, never in one-thread
/// runs: docs/benchmarks.md), and one device per test was exactly that. Error scopes are per
/// thread in wgpu, so a test's scoped errors stay its own. On OpenGL every test still makes
/// its own: wgpu's GL device has one context behind a lock that a thread gives up on after
/// 6 s (a panic), and with the device shared a test thread did, once in four runs of
/// analytic.rs on llvmpipe, while another held it.
pub fn context() -> GpuContext {
    static SHARED: std::sync::OnceLock<GpuContext> = std::sync::OnceLock::new();
    let mut made_here = false;
    let shared = SHARED.get_or_init(|| {
        made_here = true;
        new_context()
    });
    if shared.info.backend == manyshadows::wgpu::Backend::Gl && !made_here {
        return new_context();
    }
    shared.clone()
}

fn new_context() -> GpuContext {
    match GpuContext::new(&AdapterRequest::default()) {
        Ok(ctx) => {
            eprintln!(
                "GPU test adapter: {}",
                manyshadows::gpu::context::describe_adapter(&ctx.info)
            );
            ctx
        }
        Err(e) => panic!(
            "GPU tests need a graphics adapter and none was usable: {e}\n\
             Install one: `apt-get install -y mesa-vulkan-drivers` (Vulkan lavapipe) or \
             `apt-get install -y libegl1 libgl1-mesa-dri` (OpenGL llvmpipe)."
        ),
    }
}

/// Held by a test for as long as it makes, uses and drops devices of its own (besides the
/// shared one of [`context`]: `limits.rs`'s smaller devices, `embedding.rs`'s host-made
/// ones), so that one thread at a time creates or destroys a device (the driver trouble
/// [`context`] describes). Take it first in the test, so that it is dropped last.
pub fn own_device_lock() -> std::sync::MutexGuard<'static, ()> {
    static LOCK: std::sync::Mutex<()> = std::sync::Mutex::new(());
    // A test that failed while holding it leaves it poisoned; the next may still run.
    LOCK.lock().unwrap_or_else(|e| e.into_inner())
}

/// Where failing tests write their images.
pub fn artifacts_dir() -> std::path::PathBuf {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../target/test-artifacts");
    std::fs::create_dir_all(&dir).expect("create target/test-artifacts");
    dir
}

/// Ray/box slab test; returns the entry distance.
pub fn ray_box(o: Vec3, d: Vec3, lo: Vec3, hi: Vec3) -> Option<f32> {
    let inv = d.recip();
    let t0 = (lo - o) * inv;
    let t1 = (hi - o) * inv;
    let tmin = t0.min(t1).max_element();
    let tmax = t0.max(t1).min_element();
    (tmax >= tmin.max(0.0)).then_some(tmin.max(0.0))
}

/// How a visibility mask (light 0) agrees with an analytic scene's exact shadow.
#[allow(dead_code)]
pub struct TruthAgreement {
    /// Pixels more than the edge band from any edge, compared.
    pub compared: usize,
    /// Of those, pixels that disagree.
    pub wrong: usize,
    /// Disagreeing pixels anywhere, edges included.
    pub wrong_anywhere: usize,
    /// Compared pixels the truth calls shadowed / lit.
    pub shadowed: usize,
    /// See `shadowed`.
    pub lit: usize,
}

/// Compares light 0 of `vis` with `truth` (from [`analytic_truth`], `size`²) away from edges:
/// a pixel counts when every pixel within `edge_band` of it has the same truth. Writes a
/// difference image to `path` (grey = agree, red = false shadow, green = false light) and
/// fails a degenerate test (fewer than 200 shadowed or lit pixels compared).
#[allow(dead_code)]
pub fn agree_with_truth(
    vis: &manyshadows::VisibilityMask,
    truth: &[Option<bool>],
    size: u32,
    edge_band: i32,
    path: &std::path::Path,
) -> TruthAgreement {
    agree_with_truth_of(vis, 0, truth, size, edge_band, path)
}

/// [`agree_with_truth`] for light `light` of the mask.
pub fn agree_with_truth_of(
    vis: &manyshadows::VisibilityMask,
    light: u32,
    truth: &[Option<bool>],
    size: u32,
    edge_band: i32,
    path: &std::path::Path,
) -> TruthAgreement {
    let at = |x: i32, y: i32| truth[(y as u32 * size + x as u32) as usize];
    let mut a = TruthAgreement {
        compared: 0,
        wrong: 0,
        wrong_anywhere: 0,
        shadowed: 0,
        lit: 0,
    };
    let mut diff = vec![0u8; (size * size * 3) as usize];
    for y in 0..size as i32 {
        for x in 0..size as i32 {
            let Some(expected) = at(x, y) else { continue };
            let near_edge = (-edge_band..=edge_band).any(|dy| {
                (-edge_band..=edge_band).any(|dx| {
                    let (nx, ny) = (x + dx, y + dy);
                    nx < 0
                        || ny < 0
                        || nx >= size as i32
                        || ny >= size as i32
                        || at(nx, ny) != Some(expected)
                })
            });
            let got = vis.lit(x as u32, y as u32, light);
            let i = ((y as u32 * size + x as u32) * 3) as usize;
            diff[i..i + 3].copy_from_slice(&match (expected, got) {
                (true, true) => [200, 200, 200],
                (false, false) => [40, 40, 40],
                (true, false) => [255, 0, 0],
                (false, true) => [0, 255, 0],
            });
            a.wrong_anywhere += usize::from(got != expected);
            if near_edge {
                continue;
            }
            a.compared += 1;
            if expected {
                a.lit += 1
            } else {
                a.shadowed += 1
            }
            a.wrong += usize::from(got != expected);
        }
    }
    image::save_buffer(path, &diff, size, size, image::ExtendedColorType::Rgb8).unwrap();
    assert!(
        a.shadowed > 200 && a.lit > 200,
        "{}: degenerate test ({} shadowed, {} lit pixels)",
        path.display(),
        a.shadowed,
        a.lit
    );
    a
}

/// The exact shadow of an analytic scene (`plane-*`: one light over the square occluder) for a
/// `size`² frame of its camera: ray from the camera to the first surface, then a segment from
/// that point to the light against the occluder box.
/// Truth per pixel: `None` = sky, `Some(lit)`.
pub fn analytic_truth(scene: &Scene, size: u32) -> Vec<Option<bool>> {
    let c = builtin::OCCLUDER_CENTER;
    let half = Vec3::new(
        builtin::OCCLUDER_HALF_SIZE,
        builtin::OCCLUDER_THICKNESS * 0.5,
        builtin::OCCLUDER_HALF_SIZE,
    );
    let (lo, hi) = (c - half, c + half);
    let cam = &scene.camera;
    let inv = (cam.projection(1.0) * cam.view()).inverse();
    let light = scene.lights[0];
    let mut out = Vec::new();
    for y in 0..size {
        for x in 0..size {
            let ndc_x = (x as f32 + 0.5) / size as f32 * 2.0 - 1.0;
            let ndc_y = 1.0 - (y as f32 + 0.5) / size as f32 * 2.0;
            let near = inv * glam::Vec4::new(ndc_x, ndc_y, 0.0, 1.0);
            let far = inv * glam::Vec4::new(ndc_x, ndc_y, 1.0, 1.0);
            let o = near.xyz() / near.w;
            let d = (far.xyz() / far.w - o).normalize();
            let t_floor = if d.y < 0.0 { -o.y / d.y } else { f32::INFINITY };
            let t_box = ray_box(o, d, lo, hi).unwrap_or(f32::INFINITY);
            let t = t_floor.min(t_box);
            if !t.is_finite()
                || (o + d * t).x.abs() > 10.0
                || (o + d * t).z.abs() > 10.0 && t == t_floor
            {
                out.push(None);
                continue;
            }
            let p = o + d * t;
            if t_box <= t_floor {
                // The occluder's top face: nothing is above it.
                out.push(Some(true));
                continue;
            }
            let lit = match light.kind {
                LightKind::Directional { direction, .. } => {
                    ray_box(p, -direction, lo, hi).is_none()
                }
                LightKind::Spot {
                    position,
                    direction,
                    cutoff_deg,
                    range,
                } => {
                    let to_p = p - position;
                    let in_cone = to_p.normalize().dot(direction.normalize())
                        >= cutoff_deg.to_radians().cos();
                    in_cone
                        && to_p.length() <= range
                        && ray_box(p, -to_p.normalize(), lo, hi).is_none_or(|t| t > to_p.length())
                }
                LightKind::Point { position, range } => {
                    let to_p = p - position;
                    to_p.length() <= range
                        && ray_box(p, -to_p.normalize(), lo, hi).is_none_or(|t| t > to_p.length())
                }
            };
            out.push(Some(lit));
        }
    }
    out
}

/// How a renderer's visibility mask compares with the exact CPU reference traced from the same
/// G-buffer points.
#[derive(Debug, Default)]
pub struct ReferenceErrors {
    /// (pixel, light) pairs compared.
    pub pairs: u64,
    /// Pairs the reference sees lit.
    pub lit: u64,
    /// Pairs that differ more than `band` pixels from a reference edge.
    pub wrong: u64,
    /// Pairs that differ within the edge band.
    pub wrong_in_band: u64,
    /// The scores `compare` reports, over all lights: in-reach pairs facing the light, false
    /// shadow and false light outside and inside the edge band.
    pub counts: manyshadows_reference::score::Counts,
}

/// Renders nothing itself: reads `r`'s G-buffer, traces the reference for `scene`'s lights
/// and compares it with `vis` (the frame's mask), errors within `band` pixels of a reference
/// edge apart.
pub fn reference_errors(
    r: &manyshadows::Renderer,
    scene: &Scene,
    vis: &manyshadows::VisibilityMask,
    band: u32,
) -> ReferenceErrors {
    reference_errors_with(r, scene, vis, band, Default::default())
}

/// The surfaces of `r`'s G-buffer, as the CPU reference traces them.
pub fn gbuffer_surfaces(r: &manyshadows::Renderer) -> manyshadows_reference::Surfaces {
    use manyshadows_reference::{SurfacePoint, Surfaces};
    let (w, h) = (r.settings().width, r.settings().height);
    let g = r.read_gbuffer().expect("gbuffer");
    let points = (0..g.position.len())
        .map(|i| {
            g.covered[i].then(|| SurfacePoint {
                position: g.position[i],
                normal: g.normal[i],
            })
        })
        .collect();
    Surfaces::new(w, h, points).expect("surfaces")
}

/// The CPU reference of `scene`'s lights at `surfaces`, single-sided casters shadowing as
/// `rule` says.
pub fn trace_reference(
    scene: &Scene,
    surfaces: &manyshadows_reference::Surfaces,
    rule: manyshadows::SingleSidedShadows,
) -> manyshadows_reference::ReferenceVisibility {
    let tracer = manyshadows_reference::Tracer::with_rule(scene, rule).expect("tracer");
    manyshadows_reference::reference_visibility(
        &tracer,
        &scene.lights,
        surfaces,
        &|| {},
        &Default::default(),
    )
    .expect("reference")
}

/// [`reference_errors`] with single-sided casters shadowing as `rule` says in the reference.
pub fn reference_errors_with(
    r: &manyshadows::Renderer,
    scene: &Scene,
    vis: &manyshadows::VisibilityMask,
    band: u32,
    rule: manyshadows::SingleSidedShadows,
) -> ReferenceErrors {
    let surfaces = gbuffer_surfaces(r);
    let reference = trace_reference(scene, &surfaces, rule);
    errors_against(&reference, &surfaces, vis, band)
}

/// How `vis` compares with `reference` (traced at `surfaces`), errors within `band` pixels of
/// a reference edge apart.
pub fn errors_against(
    reference: &manyshadows_reference::ReferenceVisibility,
    surfaces: &manyshadows_reference::Surfaces,
    vis: &manyshadows::VisibilityMask,
    band: u32,
) -> ReferenceErrors {
    use manyshadows_reference::score;
    let (w, h) = (vis.width, vis.height);
    let lights = vis.lights;
    let edge = score::edge_band(&reference.lit, &surfaces.covered(), band);
    let mask = manyshadows_reference::Mask {
        width: vis.width,
        height: vis.height,
        lights: vis.lights,
        words_per_pixel: vis.words_per_pixel,
        words: vis.words.clone(),
    };
    let mut e = ReferenceErrors {
        counts: score::score(reference, &edge, &mask)
            .expect("score")
            .total(|_| true),
        ..Default::default()
    };
    for p in 0..(w * h) as usize {
        for l in 0..lights {
            let want = reference.lit.get(p, l);
            let got = vis.lit(p as u32 % w, p as u32 / w, l);
            e.pairs += 1;
            e.lit += u64::from(want);
            if want != got {
                if edge.get(p, l) {
                    e.wrong_in_band += 1;
                } else {
                    e.wrong += 1;
                }
            }
        }
    }
    e
}

/// Between two frames: pixels that differ, the largest channel difference, and visibility
/// bits that differ (0 when the frames carry no mask).
pub fn frame_differences(a: &manyshadows::Frame, b: &manyshadows::Frame) -> (usize, u8, u32) {
    let px = a
        .rgba
        .chunks(4)
        .zip(b.rgba.chunks(4))
        .filter(|(x, y)| x != y)
        .count();
    let delta = a
        .rgba
        .iter()
        .zip(&b.rgba)
        .map(|(x, y)| x.abs_diff(*y))
        .max()
        .unwrap_or(0);
    let bits = match (&a.visibility, &b.visibility) {
        (Some(va), Some(vb)) => va
            .words
            .iter()
            .zip(&vb.words)
            .map(|(x, y)| (x ^ y).count_ones())
            .sum(),
        (None, None) => 0,
        _ => panic!("one frame has a visibility mask, the other not"),
    };
    (px, delta, bits)
}

/// Pixels whose RGBA differs between two frames; when any do, both frames go to
/// target/test-artifacts as `{stem}_{tag}.png`.
#[allow(dead_code)]
pub fn differing_pixels(
    a: &manyshadows::Frame,
    b: &manyshadows::Frame,
    stem: &str,
    tags: [&str; 2],
) -> usize {
    let differing = a
        .rgba
        .chunks(4)
        .zip(b.rgba.chunks(4))
        .filter(|(x, y)| x != y)
        .count();
    if differing > 0 {
        for (f, tag) in [(a, tags[0]), (b, tags[1])] {
            image::save_buffer(
                artifacts_dir().join(format!("{stem}_{tag}.png")),
                &f.rgba,
                f.width,
                f.height,
                image::ExtendedColorType::Rgba8,
            )
            .expect("write artifact");
        }
    }
    differing
}

/// A ray-traced renderer (`settings` with technique raytraced), or `None` after checking that
/// a device without ray queries refuses the technique by name. Where the test command says the
/// backend must offer ray queries, a refusal fails the test ([`check_refusal`]).
pub fn raytraced(
    ctx: &GpuContext,
    scene: &Scene,
    settings: manyshadows::RenderSettings,
) -> Option<manyshadows::Renderer> {
    let unmet = manyshadows::Technique::RAYTRACED.info().unmet(ctx);
    match manyshadows::Renderer::new(
        ctx,
        scene,
        settings.with_technique(manyshadows::Technique::RAYTRACED),
    ) {
        Ok(r) => {
            assert!(unmet.is_empty(), "rendered without {unmet:?}");
            Some(r)
        }
        Err(e) => {
            check_refusal(ctx, manyshadows::Technique::RAYTRACED, &e);
            None
        }
    }
}

/// The technique the sampled-light tests run on `ctx`: raytraced where the adapter has what
/// shadow rays need (the sampled lights' visibility traced), otherwise traditional shadow maps
/// (the sampled lights' visibility read from the atlas: what the tests check holds for any
/// shadow source, measured against the same technique with every light). Where the test
/// command says the backend must offer ray queries, their absence fails the test instead.
#[track_caller]
pub fn sampling_technique(ctx: &GpuContext) -> manyshadows::Technique {
    let unmet = manyshadows::Technique::RAYTRACED.info().unmet(ctx);
    let Some(need) = unmet.first().map(|n| n.name()) else {
        return manyshadows::Technique::RAYTRACED;
    };
    assert!(
        !manyshadows_testkit::must_offer(&need),
        "no {need}, which the test command says this backend must offer: the sampled lights \
         would be tested through shadow maps only. On Linux the Vulkan run needs Mesa 25's \
         lavapipe (`cargo xtask test` installs it)."
    );
    eprintln!("no {need}: the sampled lights take their visibility from shadow maps (traditional)");
    manyshadows::Technique::TRADITIONAL
}

/// A renderer of `settings` with [`sampling_technique`]: shadow rays where the adapter traces
/// them, shadow maps elsewhere (OpenGL). Any error fails the test.
#[track_caller]
pub fn sampler(
    ctx: &GpuContext,
    scene: &Scene,
    settings: manyshadows::RenderSettings,
) -> manyshadows::Renderer {
    let technique = sampling_technique(ctx);
    manyshadows::Renderer::new(ctx, scene, settings.with_technique(technique))
        .unwrap_or_else(|e| panic!("{technique}: {e}"))
}

/// `e` is `technique`'s refusal on `ctx`'s device: the device lacks one of its needs, and the
/// refusal names it. The refusal is recorded as a test that checked a refusal instead of
/// running, and fails the test where the test command says the backend must offer the need
/// (`manyshadows_testkit::refused`).
#[track_caller]
pub fn check_refusal(
    ctx: &GpuContext,
    technique: manyshadows::Technique,
    e: &manyshadows::RenderError,
) {
    let unmet = technique.info().unmet(ctx);
    assert!(
        !unmet.is_empty() && e.is_unsupported(),
        "{technique} failed on an adapter that has all it needs: {e}"
    );
    let need = unmet[0].name();
    assert!(
        e.to_string().contains(&need),
        "the refusal of {technique} names {need}: {e}"
    );
    manyshadows_testkit::refused(&need, &format!("technique {technique}: {e}"));
}

/// Renders with `settings` on `ctx`, or `None` where the device refuses its technique for a
/// need it lacks (checked and recorded by [`check_refusal`]). Any other error fails the test.
#[track_caller]
pub fn renderer_or_refusal(
    ctx: &GpuContext,
    scene: &Scene,
    settings: manyshadows::RenderSettings,
) -> Option<manyshadows::Renderer> {
    let technique = settings.technique;
    match manyshadows::Renderer::new(ctx, scene, settings) {
        Ok(r) => {
            let unmet = technique.info().unmet(ctx);
            assert!(unmet.is_empty(), "{technique} rendered without {unmet:?}");
            Some(r)
        }
        Err(e) => {
            check_refusal(ctx, technique, &e);
            None
        }
    }
}

/// Root-mean-square difference of two frames' sRGB channels, 0..255.
pub fn rmse(a: &manyshadows::Frame, b: &manyshadows::Frame) -> f64 {
    let n = a.rgba.len() as f64;
    let s: f64 = a
        .rgba
        .iter()
        .zip(&b.rgba)
        .map(|(&x, &y)| (f64::from(x) - f64::from(y)).powi(2))
        .sum();
    (s / n).sqrt()
}

/// The cubes under 48 seeded lights of every type (the built-in default sizes): each pixel has
/// far more candidate lights than one sample (the sampled-ray tests' scene).
pub fn cubes_under_48_lights() -> Scene {
    let mut scene = builtin::build("cubes", &builtin::BuiltinOptions::default()).expect("scene");
    scene.lights = builtin::scatter_lights(&scene, 48, 3, builtin::LightMix::All, None);
    scene
}

/// Each of `settings` is refused as an invalid option naming `option`, on any device.
pub fn refused_naming(scene: &Scene, settings: &[manyshadows::RenderSettings], option: &str) {
    let ctx = context();
    for s in settings {
        match manyshadows::Renderer::new(&ctx, scene, s.clone()) {
            Err(e @ manyshadows::RenderError::InvalidOption { .. }) => {
                assert!(e.to_string().contains(option), "{e}");
            }
            Err(e) => panic!("refused for another reason: {e}"),
            Ok(_) => panic!("{option}: accepted where it cannot apply"),
        }
    }
}

/// Depth difference that counts as a different texel where the rasterizer's arithmetic is the
/// same IEEE arithmetic in every pass (lavapipe, llvmpipe): a few ULPs of depth near 1.
pub const ATLAS_DEPTH_TOL: f32 = 2e-6;
/// Depth difference beyond which two texels hold different surfaces (or one holds none).
pub const ATLAS_COVERAGE_TOL: f32 = 1e-4;

/// Whether the adapter rasterizes on the CPU (lavapipe, llvmpipe: the adapters CI runs), where
/// two passes over the same triangles agree to a few ULPs and the equivalence tests hold each
/// technique to a measured handful of texels. A hardware rasterizer is held to what Vulkan
/// fixes: depth interpolation precision and the snapping of clipped or guard-band vertices are
/// the implementation's, so drawing through another viewport transform (an atlas-wide viewport,
/// multiview, a compute shader) moves depths in their last bits and tips edge texels. Measured
/// on NVIDIA's driver (H200, 580.159): depths up to 2e-5 apart (1e-4 in the compute
/// rasterizer) and up to 0.35 % of covered texels tipped on edges (slivers and huge triangles).
pub fn cpu_rasterizer(ctx: &GpuContext) -> bool {
    ctx.info.device_type == wgpu::DeviceType::Cpu
}

/// How two square depth atlases of the same views differ.
#[derive(Debug, Default, Clone)]
pub struct AtlasDiff {
    /// Texels covered (depth < 1) in either.
    pub covered: usize,
    /// Texels whose depth differs by more than [`ATLAS_DEPTH_TOL`].
    pub differing: usize,
    /// Of those, texels differing by more than [`ATLAS_COVERAGE_TOL`]: different surfaces or
    /// coverage.
    pub coverage: usize,
    /// Of those, texels inside a surface: the reference's 3 x 3 neighbourhood all covered (or
    /// all empty) and one plane. A rasterization rule may tip a texel on an edge, never one
    /// inside a triangle.
    pub coverage_inside: usize,
    /// Largest difference below [`ATLAS_COVERAGE_TOL`]: the same surface, rounded differently.
    pub max_rounding: f32,
}

impl AtlasDiff {
    /// What a hardware rasterizer is held to (see [`cpu_rasterizer`]): every surface where the
    /// reference has it. Edge texels may tip (at most 1 % of the covered texels) and a handful
    /// inside surfaces (1 in 100,000 covered: NVIDIA's compute-rasterized atrium, 18 of 11 M);
    /// a lost triangle, view or tile, or a misplaced one, tips whole surfaces.
    pub fn within_hardware_rules(&self) -> bool {
        self.coverage * 100 <= self.covered && self.coverage_inside * 100_000 <= self.covered
    }
}

impl std::fmt::Display for AtlasDiff {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} of {} covered texels differ by more than {ATLAS_DEPTH_TOL:e}, {} by more than \
             {ATLAS_COVERAGE_TOL:e} (coverage; {} inside a surface), the others by at most {:e}",
            self.differing, self.covered, self.coverage, self.coverage_inside, self.max_rounding
        )
    }
}

/// Compares `got` with `reference`, square depth atlases (cleared to 1.0), texel by texel.
pub fn atlas_diff(reference: &[f32], got: &[f32]) -> AtlasDiff {
    assert_eq!(reference.len(), got.len(), "atlases of different sizes");
    let side = (reference.len() as f64).sqrt() as usize;
    assert_eq!(side * side, reference.len(), "atlas not square");
    let at = |x: isize, y: isize| -> Option<f32> {
        (x >= 0 && y >= 0 && (x as usize) < side && (y as usize) < side)
            .then(|| reference[y as usize * side + x as usize])
    };
    let mut d = AtlasDiff::default();
    for (i, (&r, &g)) in reference.iter().zip(got).enumerate() {
        d.covered += usize::from(r < 1.0 || g < 1.0);
        let e = (r - g).abs();
        if e <= ATLAS_DEPTH_TOL {
            continue;
        }
        d.differing += 1;
        if e <= ATLAS_COVERAGE_TOL {
            d.max_rounding = d.max_rounding.max(e);
            continue;
        }
        d.coverage += 1;
        // An edge: a neighbour in the reference uncovered where this texel is covered (or the
        // other way), or a neighbourhood that is not one plane (depth is affine in window
        // coordinates across a triangle, so across one the second differences vanish).
        let (x, y) = ((i % side) as isize, (i / side) as isize);
        let coverage_edge = (-1..=1).any(|dy| {
            (-1..=1).any(|dx| at(x + dx, y + dy).is_some_and(|n| (n < 1.0) != (r < 1.0)))
        });
        let bent = [(1, 0), (0, 1), (1, 1), (1, -1)].iter().any(|&(dx, dy)| {
            match (at(x - dx, y - dy), at(x + dx, y + dy)) {
                (Some(a), Some(b)) => (a + b - 2.0 * r).abs() > ATLAS_COVERAGE_TOL,
                _ => false,
            }
        });
        let edge = coverage_edge || bent;
        d.coverage_inside += usize::from(!edge);
    }
    d
}
