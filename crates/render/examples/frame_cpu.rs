//! CPU time to record and submit a frame: the atrium with N seeded lights, every shadow view
//! redrawn each frame (no caching, rasterization discarded), each frame read back before the next so the GPU's work
//! does not overlap the timed recording.
//!
//! `cargo run --release -p manyshadows --example frame_cpu -- [TECHNIQUES] [LIGHTS] [FRAMES]`
//! e.g. `-- layered,gpu-driven,compute 32,256 40`; prints the median and quartiles of
//! [`manyshadows::SubmittedFrame::cpu_record_ms`] per configuration.

use manyshadows::scene::builtin;
use manyshadows::{AdapterRequest, GpuContext, RenderSettings, Renderer, Technique};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let techniques = args
        .get(1)
        .map_or("traditional,layered,multiview,gpu-driven,compute", |s| s);
    let lights = args.get(2).map_or("32,256", |s| s);
    let frames: usize = args.get(3).map_or(Ok(40), |s| s.parse())?;
    let ctx = GpuContext::new(&AdapterRequest::default())?;
    println!("adapter: {}", ctx.info.name);
    let t0 = std::time::Instant::now();
    let (w, h) = (320, 180);
    for n in lights.split(',') {
        let n: usize = n.parse()?;
        let mut scene = builtin::build(
            &std::env::var("SCENE").unwrap_or("atrium".into()),
            &Default::default(),
        )?;
        scene.lights = builtin::scatter_lights(&scene, n, 1, Default::default(), Some(128));
        for t in techniques.split(',') {
            let technique: Technique = t.parse()?;
            // Rasterization skipped (scissor 0): the same commands are recorded, and
            // software adapters finish a frame in reasonable time.
            let settings = RenderSettings::default()
                .with_width(w)
                .with_height(h)
                .with_technique(technique)
                .with_shadow(manyshadows::ShadowOptions::default().with_discard_raster(true));
            let mut renderer = match Renderer::new(&ctx, &scene, settings) {
                Ok(r) => r,
                Err(e) => {
                    println!("{t:>12} {n:>5} lights: {e}");
                    continue;
                }
            };
            let mut ms = Vec::new();
            for f in 0..frames + 2 {
                let frame = renderer.render()?;
                if f >= 2 {
                    ms.push(frame.timings.cpu_record_ms);
                }
            }
            ms.sort_by(f64::total_cmp);
            let q = |p: f64| ms[((ms.len() - 1) as f64 * p).round() as usize];
            println!(
                "{t:>12} {n:>5} lights, {:>4} views: cpu_record_ms median {:.3} (q1 {:.3}, q3 {:.3})",
                renderer.plan().views.len(),
                q(0.5),
                q(0.25),
                q(0.75)
            );
            eprintln!("  ({:.1} s so far)", t0.elapsed().as_secs_f64());
        }
    }
    Ok(())
}
