//! What `render` prints and writes about a frame: the summary as JSON, and as text.

use std::time::Duration;

use crate::args::RenderArgs;
use manyshadows::gpu::context::describe_adapter;
use manyshadows::scene::Scene;
use manyshadows::{Frame, GpuContext, Renderer};

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
    // Where the (last) frame stands in the file's animation.
    let animation = args
        .animation
        .clock(scene, args.frames)
        .ok()
        .flatten()
        .map(|c| {
            let a = &scene.animations;
            serde_json::json!({
                "playing": a.describe(c.playing),
                "time_s": a.wrap(c.playing, c.at(args.frames.saturating_sub(1))),
                "duration_s": a.duration(c.playing),
                "fps": c.fps,
                "moving_instances": a.moving.len(),
                "deformed_meshes": a.deformed_at_rest().len(),
            })
        });
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
        "animation": animation,
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
        "report": frame.report.lines,
        "soft": { "blocker_taps": r.settings().soft.blocker_taps, "filter_taps": r.settings().soft.filter_taps,
                  "max_penumbra": r.max_penumbra(), "area_samples": r.settings().rays.area_samples,
                  "light_samples": r.settings().rays.light_samples, "denoise": r.settings().rays.denoise,
                  "reuse": r.settings().rays.reuse, "spatial": r.settings().rays.spatial.name(),
                  "technique_softens": r.settings().technique.info().soft_shadows,
                  "seed": r.settings().rays.seed,
                  "visibility_from": match r.settings().technique.info().fills {
                      manyshadows::Fills::Rays => "shadow rays",
                      manyshadows::Fills::Atlas => "the shadow atlas",
                      manyshadows::Fills::Pages => "the virtual pages",
                      _ => "the visibility mask",
                  } },
        "estimate": estimate,
        "estimate_text": describe_estimate(estimate),
        "gpu_ms": frame.timings.gpu_ms,
        "cpu_record_ms": frame.timings.cpu_record_ms,
        "frame_wall_ms": frame.timings.wall_ms,
        "total_wall_ms": total.as_secs_f64() * 1e3,
        "peak_resident_bytes": peak_resident_bytes(),
        "output": args.out,
    })
}

/// The most resident memory this process has held so far (Linux: `VmHWM` of
/// /proc/self/status), in bytes; `None` where the system does not say.
pub(crate) fn peak_resident_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 = line
        .trim_start_matches("VmHWM:")
        .trim()
        .trim_end_matches("kB")
        .trim()
        .parse()
        .ok()?;
    Some(kib * 1024)
}

/// Bytes in words: `1.49 GiB`, `312 MiB`.
pub(crate) fn describe_bytes(bytes: u64) -> String {
    let mib = bytes as f64 / (1024.0 * 1024.0);
    if mib >= 1024.0 {
        format!("{:.2} GiB", mib / 1024.0)
    } else {
        format!("{mib:.0} MiB")
    }
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
    // The shadows in the technique's own words (its declaration's report).
    for line in s["report"].as_array().into_iter().flatten() {
        println!(
            "{:<12} {}",
            line["label"].as_str().unwrap_or("?"),
            line["text"].as_str().unwrap_or("")
        );
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
    let a = &s["animation"];
    if let Some(playing) = a["playing"].as_str() {
        let count = |n: u64, one: &str, many: &str| match n {
            1 => format!("1 {one}"),
            n => format!("{n} {many}"),
        };
        let mut what = Vec::new();
        if let Some(n) = a["moving_instances"].as_u64().filter(|&n| n > 0) {
            what.push(count(n, "instance moves", "instances move"));
        }
        if let Some(n) = a["deformed_meshes"].as_u64().filter(|&n| n > 0) {
            what.push(count(n, "mesh deforms", "meshes deform"));
        }
        println!(
            "animation    {playing} at {:.3} s of {:.3} s ({})",
            a["time_s"].as_f64().unwrap_or(0.0),
            a["duration_s"].as_f64().unwrap_or(0.0),
            what.join(", ")
        );
    }
    if let Some(look) = s["look"]["description"].as_str() {
        println!("look         {look}");
    }
    if let Some(line) = describe_sampling(&s["soft"]) {
        println!("sampling     {line}");
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

/// The sampled lights in words (`None` where every light is shaded): how many per pixel, where
/// their visibility comes from, and what reuses or denoises them.
fn describe_sampling(soft: &serde_json::Value) -> Option<String> {
    let k = soft["light_samples"].as_u64().filter(|&k| k > 0)?;
    let mut line = format!(
        "{k} light{} per pixel drawn by importance (seed {}), visibility from {}",
        if k == 1 { "" } else { "s" },
        soft["seed"],
        soft["visibility_from"].as_str().unwrap_or("?")
    );
    if soft["reuse"].as_bool() == Some(true) {
        line.push_str("; reused over frames");
        match soft["spatial"].as_str() {
            Some(mode) if mode != "off" => line.push_str(&format!(" and neighbours ({mode})")),
            _ => {}
        }
    }
    if soft["denoise"].as_bool() == Some(true) {
        line.push_str("; denoised");
    }
    Some(line)
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
    if let Some(peak) = s["peak_resident_bytes"].as_u64() {
        println!(
            "memory       peak resident {} (the whole run: loading, every frame, reading back)",
            describe_bytes(peak)
        );
    }
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
