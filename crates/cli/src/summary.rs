//! What `render` prints and writes about a frame: the summary as JSON, and as text.

use std::time::Duration;

use crate::args::RenderArgs;
use manyshadows::gpu::context::describe_adapter;
use manyshadows::scene::Scene;
use manyshadows::{Frame, GpuContext, Renderer, Technique};

pub(crate) fn summary(
    ctx: &GpuContext,
    scene: &Scene,
    r: &Renderer,
    frame: &Frame,
    estimate: &manyshadows::FrameEstimate,
    args: &RenderArgs,
    total: Duration,
) -> serde_json::Value {
    let count = |t: &str| scene.lights.iter().filter(|l| l.type_name() == t).count();
    let plan = r.plan();
    serde_json::json!({
        "adapter": describe_adapter(&ctx.info),
        "backend": format!("{:?}", ctx.info.backend),
        "scene": scene.name,
        "technique": r.settings().technique.name(),
        "pcf": r.settings().pcf.name(),
        "resolution": [frame.width, frame.height],
        "stereo": r.settings().stereo.map(|st| serde_json::json!({
            "separation": st.separation, "passes": st.passes.name(),
            "eye": [frame.width / 2, frame.height] })),
        "triangles": r.triangles(),
        "instances": scene.instances.len(),
        "lights": { "total": scene.lights.len(), "spot": count("spot"), "point": count("point"), "directional": count("directional"),
                    "shadowed": scene.lights.iter().filter(|l| l.casts_shadows).count(),
                    "sizes": { "radius": size_range(scene, false), "sun_deg": size_range(scene, true) } },
        "shadow_views": r.virtual_plan().map_or(plan.views.len(), |v| v.views.len()),
        "atlas": { "size": plan.layout.size, "fill": plan.fill(), "shrink_steps": plan.layout.shrink_steps, "fit": plan.fit },
        "shadow_work": { "passes": frame.shadow_stats.passes, "draws": frame.shadow_stats.draws, "views_drawn": frame.shadow_stats.views_drawn,
                         "views_stale": frame.shadow_stats.views_stale, "stale_frames": frame.shadow_stats.stale_frames,
                         "views_waiting": frame.shadow_stats.views_waiting,
                         "culled_draws": frame.shadow_stats.culled, "triangles": frame.shadow_stats.triangles },
        "look": look_json(&r.look()),
        "light_loop": r.settings().light_loop.name(),
        "clusters": frame.clusters,
        "probes": frame.probes.map(|p| serde_json::json!({
            "probes": p.probes, "side": p.side, "faces_drawn": p.faces_drawn, "bytes": p.bytes,
            "passes": r.settings().probe_passes.name() })),
        "virtual": frame.virtual_maps,
        "lists": r.irregular_stats(),
        "soft": { "blocker_taps": r.settings().soft.blocker_taps, "filter_taps": r.settings().soft.filter_taps,
                  "max_penumbra": r.max_penumbra(), "area_samples": r.settings().rays.area_samples,
                  "light_samples": r.settings().rays.light_samples, "denoise": r.settings().rays.denoise,
                  "reuse": r.settings().rays.reuse, "spatial": r.settings().rays.spatial.name(),
                  "technique_softens": r.settings().technique.info().soft_shadows },
        "estimate": estimate,
        "estimate_text": describe_estimate(estimate),
        "gpu_ms": frame.timings.gpu_ms,
        "cpu_record_ms": frame.timings.cpu_record_ms,
        "frame_wall_ms": frame.timings.wall_ms,
        "total_wall_ms": total.as_secs_f64() * 1e3,
        "output": args.out,
    })
}

/// The frame's shading model, exposure and tone map.
fn look_json(l: &manyshadows::ResolvedLook) -> serde_json::Value {
    serde_json::json!({
        "shading": l.shading.name(),
        "tone_map": l.tone_map.name(),
        "ev100": l.ev100,
        "exposure_scale": l.exposure_scale,
        "metered": l.metered,
        "description": l.describe(),
    })
}

/// `[smallest, largest]` size of the directional lights (`suns`: angular diameters, degrees)
/// or of the spot and point lights (radii, world units); null when the scene has none.
fn size_range(scene: &Scene, suns: bool) -> serde_json::Value {
    scene
        .lights
        .iter()
        .filter(|l| (l.type_name() == "directional") == suns)
        .map(|l| l.size)
        .fold(None, |r: Option<(f32, f32)>, x| {
            Some(r.map_or((x, x), |(lo, hi)| (lo.min(x), hi.max(x))))
        })
        .map_or(serde_json::Value::Null, |(lo, hi)| {
            // The f32's shortest decimal (0.53, not 0.5299999713897705), which reads back as
            // the same f32.
            let short = |x: f32| x.to_string().parse::<f64>().unwrap_or(f64::from(x));
            serde_json::json!([short(lo), short(hi)])
        })
}

/// The lights' sizes in words: `all hard (size 0)`, or `sizes: radius 0.16–0.48, sun 0.53°`;
/// empty without lights.
fn describe_sizes(sizes: &serde_json::Value) -> String {
    let range = |key: &str| {
        let r = sizes[key].as_array()?;
        Some((r.first()?.as_f64()?, r.get(1)?.as_f64()?))
    };
    let (radius, sun) = (range("radius"), range("sun_deg"));
    if radius.is_none() && sun.is_none() {
        return String::new();
    }
    if radius.into_iter().chain(sun).all(|(_, hi)| hi == 0.0) {
        return ", all hard (size 0)".into();
    }
    // Three decimals at most: sizes are inputs, not measurements.
    let num = |x: f64| format!("{}", (x * 1000.0).round() / 1000.0);
    let span = |(lo, hi): (f64, f64)| {
        if num(lo) == num(hi) {
            num(lo)
        } else {
            format!("{}–{}", num(lo), num(hi))
        }
    };
    let mut parts = Vec::new();
    if let Some(r) = radius {
        parts.push(format!("radius {}", span(r)));
    }
    if let Some(d) = sun {
        parts.push(format!("sun {}°", span(d)));
    }
    format!(", sizes: {}", parts.join(", "))
}

pub(crate) fn print_summary(s: &serde_json::Value) {
    print_scene(s);
    let technique = s["technique"]
        .as_str()
        .and_then(|t| t.parse::<Technique>().ok());
    let fills = technique.map(|t| t.info().fills);
    print_shadows(s, fills);
    match fills {
        Some(manyshadows::Fills::Pages) => print_virtual(s),
        Some(manyshadows::Fills::Mask) => print_irregular(s),
        Some(manyshadows::Fills::Rays) => print_rays(s),
        _ => print_atlas(s, technique),
    }
    print_clusters(s);
    print_times(s);
}

/// The adapter, the scene and its lights.
fn print_scene(s: &serde_json::Value) {
    let l = &s["lights"];
    println!("adapter      {}", s["adapter"].as_str().unwrap_or("?"));
    println!(
        "scene        {} ({} triangles, {} instances)",
        s["scene"].as_str().unwrap_or("?"),
        s["triangles"],
        s["instances"]
    );
    println!(
        "lights       {} ({} spot, {} point, {} directional; {} shadowed){}",
        l["total"],
        l["spot"],
        l["point"],
        l["directional"],
        l["shadowed"],
        describe_sizes(&l["sizes"])
    );
    if let Some(look) = s["look"]["description"].as_str() {
        println!("look         {look}");
    }
    let pr = &s["probes"];
    if let Some(n) = pr["probes"].as_u64() {
        let side = pr["side"].as_u64().unwrap_or(0);
        println!(
            "probes       {n} reflection probes, {side}x{side} per face ({:.1} MiB); {} faces drawn this frame ({})",
            pr["bytes"].as_f64().unwrap_or(0.0) / (1u64 << 20) as f64,
            pr["faces_drawn"],
            pr["passes"]
                .as_str()
                .and_then(|p| p.parse::<manyshadows::ProbePasses>().ok())
                .map_or("drawn in an unknown way", |p| p.describe())
        );
    }
    let st = &s["stereo"];
    if let Some(passes) = st["passes"].as_str() {
        println!(
            "stereo       two eyes {} apart side by side, each {}x{}; G-buffer {}",
            st["separation"].as_f64().unwrap_or(0.0) as f32,
            st["eye"][0],
            st["eye"][1],
            passes
                .parse::<manyshadows::EyePasses>()
                .map_or("drawn in an unknown way", |p| p.describe())
        );
    }
}

/// The technique, its views, how it filters, and what sized lights get from it.
fn print_shadows(s: &serde_json::Value, fills: Option<manyshadows::Fills>) {
    let technique = s["technique"].as_str().unwrap_or("?");
    let sized = s["lights"]["sizes"]
        .as_object()
        .is_some_and(|m| m.values().any(|r| r[1].as_f64().is_some_and(|hi| hi > 0.0)));
    let soft = &s["soft"];
    let (views, filter, softness) = match fills {
        Some(manyshadows::Fills::Mask) => (
            "exact samples in per-light lists".to_string(),
            "no filter (exact, hard)".to_string(),
            "hard: answers at each light's centre, sizes ignored".to_string(),
        ),
        Some(manyshadows::Fills::Rays) => {
            ("no shadow views".to_string(), "no filter".to_string(), {
                let denoise = soft["denoise"].as_bool().unwrap_or(false);
                match soft["light_samples"].as_u64().unwrap_or(0) {
                    0 => format!(
                        "sized lights traced with {0}x{0} samples of their shape per pixel{1}",
                        soft["area_samples"].as_u64().unwrap_or(0).max(1),
                        if denoise {
                            ", new each frame and accumulated over still frames"
                        } else {
                            ""
                        }
                    ),
                    _ => format!(
                        "a sampled sized light is traced at one point of its shape{}{}",
                        if soft["reuse"].as_bool().unwrap_or(false) {
                            ", new each frame, reused across frames"
                        } else if denoise {
                            ", new each frame"
                        } else {
                            ""
                        },
                        if denoise { ", denoised" } else { "" }
                    ),
                }
            })
        }
        _ => (
            format!("{} views", s["shadow_views"]),
            format!("PCF {}", s["pcf"].as_str().unwrap_or("?")),
            format!(
                "sized lights: PCSS, {} blocker and {} filter taps, penumbrae up to {} texels",
                soft["blocker_taps"], soft["filter_taps"], soft["max_penumbra"]
            ),
        ),
    };
    println!("shadows      {views}, technique {technique}, {filter}");
    if sized {
        println!("soft         {softness}");
    }
}

/// Virtual maps: faces, pages, marking and the drawing's work.
fn print_virtual(s: &serde_json::Value) {
    let v = &s["virtual"];
    if !v.is_object() {
        return;
    }
    let fit = &v["fit"];
    let capped = fit["capped_side"].as_u64().unwrap_or(0);
    let prev = v["prev_table_bytes"].as_u64().unwrap_or(0);
    println!(
        "virtual      {} faces of {} lights ({} off screen, no faces; {} faces needed by a sample, the rest get no pages), page table {} entries ({} KiB{}){}",
        fit["faces"], fit["lights"], fit["off_screen"], v["faces_in_use"], fit["table_entries"],
        v["table_bytes"].as_u64().unwrap_or(0) / 1024,
        if prev > 0 { format!(", and {} KiB for last frame's, kept for caching", prev / 1024) } else { String::new() },
        if capped > 0 { format!(", virtual sides capped at {capped}² to fit it") } else { String::new() }
    );
    let per_level = |key: &str| -> String {
        v[key]
            .as_array()
            .map(|a| a.iter().map(|x| x.to_string()).collect::<Vec<_>>())
            .unwrap_or_default()
            .join("/")
    };
    let denied = v["denied"].as_u64().unwrap_or(0);
    let unshadowed = v["unshadowed_faces"].as_u64().unwrap_or(0);
    let quarter = v["quarter_faces"].as_u64().unwrap_or(0);
    let mut tail = String::new();
    if denied > 0 {
        tail +=
            &format!("; {denied} pages did not fit the pool, their samples used coarser levels");
    }
    if quarter > 0 {
        tail += &format!("; {quarter} faces share pool pages four to one at half resolution (the pool has fewer pages than faces in use)");
    }
    if unshadowed > 0 {
        tail += &format!(
            "; {unshadowed} faces had no room even for a quarter page: unshadowed; raise --page-pool"
        );
    }
    println!(
        "pages        {} resident in a pool of {} ({} drawn, {} kept from the last frame; {}x{} texels, {} MiB); asked by samples per level (coarsest first) {} (with their ancestors {}){tail}",
        v["resident"], v["pool_pages"], v["drawn"], v["kept"], v["pool_side"], v["pool_side"],
        v["pool_bytes"].as_u64().unwrap_or(0) >> 20,
        per_level("asked"),
        per_level("needed"),
    );
    let t = &v["tiles"];
    let count = |k: &str| t[k].as_u64().unwrap_or(0);
    if count("empty") + count("one_page") + count("known_page") + count("per_pixel") > 0 {
        println!(
            "marking      by 4x4-pixel tiles, (tile, light) pairs: {} need no page, {} one page marked once, {} a known page checked per pixel, {} marked per pixel ({} tiles whole)",
            count("empty"),
            count("one_page"),
            count("known_page"),
            count("per_pixel"),
            count("whole_tiles"),
        );
    }
    // Pages are chosen, culled and drawn on the GPU: their counts are the pages line's.
    println!(
        "shadow work  {} pages drawn ({} kept from the last frame): {} (cluster, page) pairs \
         past the cluster cull, {} triangles drawn (culled per page on the GPU: clusters, then \
         triangles where the adapter counts draws)",
        v["drawn"], v["kept"], v["cluster_draws"], v["triangles"]
    );
}

/// Irregular maps: their own work, no atlas and no passes of shadow maps.
fn print_irregular(s: &serde_json::Value) {
    let i = &s["lists"];
    if !i.is_object() {
        return;
    }
    println!(
        "lists        {} batch(es) of lights, the largest holding {} of {} list nodes (camera \
         samples in light-space lists); up to {} 8x8-texel tiles queued for the triangle \
         tests{}",
        i["batches"],
        i["peak_nodes"],
        i["node_capacity"],
        i["peak_tiles"],
        match i["unmapped"].as_u64().unwrap_or(0) {
            0 => String::new(),
            n => format!("; {n} samples outside every view of their light (counted lit)"),
        }
    );
}

/// Shadow rays: the acceleration structure's rebuilds, no map.
fn print_rays(s: &serde_json::Value) {
    println!(
        "shadow work  no shadow map: rays per pixel and light of its cluster (or per sampled \
         light) in the lighting pass; {} top-level structure build(s)",
        s["shadow_work"]["passes"]
    );
}

/// The atlas and the passes that filled it.
fn print_atlas(s: &serde_json::Value, technique: Option<Technique>) {
    let a = &s["atlas"];
    let w = &s["shadow_work"];
    let shrink = a["shrink_steps"].as_u64().unwrap_or(0);
    println!(
        "atlas        {0}x{0}, {1:.0}% filled{2}",
        a["size"],
        a["fill"].as_f64().unwrap_or(0.0) * 100.0,
        if shrink > 0 {
            format!(", maps shrunk {}x per side to fit", 1u64 << shrink)
        } else {
            String::new()
        }
    );
    let fit = &a["fit"];
    if fit["reduced"].as_u64().unwrap_or(0)
        + fit["unshadowed"].as_u64().unwrap_or(0)
        + fit["off_screen"].as_u64().unwrap_or(0)
        > 0
    {
        println!(
            "shadow fit   {} lights at full resolution, {} with smaller maps, {} unshadowed (no room), {} off screen (no maps needed)",
            fit["full"], fit["reduced"], fit["unshadowed"], fit["off_screen"]
        );
    }
    // What the triangle count is: drawn (after instance culling), or handed to a stage that
    // culls each (triangle, view) itself.
    let what = match technique.map(|t| t.info().culling) {
        Some(manyshadows::Culling::VertexStage) => {
            "triangle-views submitted (each culled per view in the vertex stage)"
        }
        Some(manyshadows::Culling::Threads) => {
            "triangle-views submitted (each culled per view by its setup thread)"
        }
        Some(manyshadows::Culling::Clusters) => {
            "triangle-views submitted (clusters culled per view in compute before drawing)"
        }
        _ => "triangles drawn",
    };
    println!(
        "shadow work  {} passes, {} draws ({} instance-views culled on the CPU), {} {what}",
        w["passes"], w["draws"], w["culled_draws"], w["triangles"]
    );
}

/// The light clusters.
fn print_clusters(s: &serde_json::Value) {
    let c = &s["clusters"];
    if !c.is_object() {
        println!("clusters     off (every pixel loops over every light)");
        return;
    }
    let overflow = c["overflowed"].as_u64().unwrap_or(0);
    println!(
        "clusters     {}x{}x{} grid ({} px tiles), {} occupied, lights per cluster {:.1} mean / {} max, {} of {} lights in view{}",
        c["tiles"][0], c["tiles"][1], c["slices"], c["tile"], c["occupied"],
        c["mean_lights"].as_f64().unwrap_or(0.0), c["max_lights"], c["lights_in_view"], s["lights"]["total"],
        if overflow > 0 {
            format!("; {overflow} clusters overflowed the {} KiB list pool and looped over every light", c["pool_bytes"].as_u64().unwrap_or(0) / 1024)
        } else {
            String::new()
        }
    );
}

/// GPU and CPU times, and the file written.
fn print_times(s: &serde_json::Value) {
    match s["gpu_ms"].as_object() {
        Some(m) if !m.is_empty() => {
            let parts: Vec<String> = m
                .iter()
                .map(|(k, v)| format!("{k} {:.2} ms", v.as_f64().unwrap_or(0.0)))
                .collect();
            println!("GPU time     {}", parts.join(", "));
        }
        _ => println!("GPU time     (no timestamp queries on this adapter)"),
    }
    if let Some(e) = s["estimate_text"].as_str() {
        println!("estimate     {e}, before the first frame");
    }
    println!(
        "CPU record   {:.2} ms; frame wall {:.1} ms; total {:.1} s",
        s["cpu_record_ms"].as_f64().unwrap_or(0.0),
        s["frame_wall_ms"].as_f64().unwrap_or(0.0),
        s["total_wall_ms"].as_f64().unwrap_or(0.0) / 1e3
    );
    println!("wrote        {}", s["output"].as_str().unwrap_or("?"));
}

/// An estimate in words: `~3.2 min on this adapter (G-buffer 0.1 s, shadows 3.0 min, lighting
/// 9.4 s)`, saying where the costs come from when the adapter is not a CPU one.
pub(crate) fn describe_estimate(e: &manyshadows::FrameEstimate) -> String {
    let t = |ms: f64| {
        if ms >= 60_000.0 {
            format!("{:.1} min", ms / 60_000.0)
        } else if ms >= 1_000.0 {
            format!("{:.1} s", ms / 1e3)
        } else {
            format!("{ms:.0} ms")
        }
    };
    format!(
        "~{} {} (G-buffer {}, shadows {}, lighting {}{})",
        t(e.total_ms()),
        if e.calibrated {
            "on this adapter"
        } else {
            "at lavapipe's costs (this adapter is no CPU: likely far less)"
        },
        t(e.gbuffer_ms + e.clusters_ms),
        t(e.shadows_ms),
        t(e.lighting_ms),
        if e.probes_ms > 0.0 {
            format!(", probes {}", t(e.probes_ms))
        } else {
            String::new()
        }
    )
}
