//! `manyshadows info`: the adapters, the chosen one's limits and features, and what each
//! technique needs of it.

use crate::args::GpuArgs;
use anyhow::Result;
use manyshadows::gpu::context::{describe_adapter, feature_use, list_adapters, requested_backends};
use manyshadows::{GpuContext, Technique};

pub(crate) fn info(args: &GpuArgs) -> Result<()> {
    let req = args.request();
    let backends = requested_backends(&req);
    println!("backends searched: {backends:?}");
    let adapters = list_adapters(&req);
    if adapters.is_empty() {
        println!("adapters: none");
    } else {
        println!("adapters (best first):");
        for a in &adapters {
            println!("  - {}", describe_adapter(a));
        }
    }
    let ctx = GpuContext::new(&req)?;
    println!("chosen: {}", describe_adapter(&ctx.info));
    let l = ctx.limits();
    println!("limits:");
    println!(
        "  max_texture_dimension_2d        {}",
        l.max_texture_dimension_2d
    );
    println!(
        "  max_texture_array_layers        {}",
        l.max_texture_array_layers
    );
    println!(
        "  max_storage_buffer_binding_size {}",
        l.max_storage_buffer_binding_size
    );
    println!("  max_buffer_size                 {}", l.max_buffer_size);
    println!(
        "  max_storage_buffers_per_stage   {}",
        l.max_storage_buffers_per_shader_stage
    );
    println!(
        "  max_compute_workgroup_size      {}x{}x{}",
        l.max_compute_workgroup_size_x,
        l.max_compute_workgroup_size_y,
        l.max_compute_workgroup_size_z
    );
    println!(
        "  max_compute_invocations/group   {}",
        l.max_compute_invocations_per_workgroup
    );
    println!(
        "  max_multiview_view_count        {}",
        l.max_multiview_view_count
    );
    let per_pass = manyshadows::shadows::atlas::multiview::views_per_pass_on(&ctx);
    println!(
        "  views per MULTIVIEW pass        {per_pass}{}",
        if per_pass == 1 && l.max_multiview_view_count > 1 {
            " (this driver loses clipped primitives' view index: one view per pass)"
        } else {
            ""
        }
    );
    println!("optional features:");
    for f in feature_use(ctx.adapter.features()) {
        println!(
            "  [{}] {:<28} {}",
            if f.available { "x" } else { " " },
            f.name,
            f.purpose
        );
    }
    for (f, name) in manyshadows::gpu::context::UNUSED_EXPERIMENTAL {
        println!(
            "  [{}] {:<28} offered by the driver, not used yet",
            if ctx.adapter.features().contains(*f) {
                "x"
            } else {
                " "
            },
            name
        );
    }
    println!(
        "  max_tlas_instance_count         {}",
        l.max_tlas_instance_count
    );
    println!("techniques (what this device lacks for each):");
    for t in Technique::all() {
        let unmet: Vec<String> = t.info().unmet(&ctx).iter().map(|n| n.name()).collect();
        println!(
            "  {:<12} {}",
            t.name(),
            if unmet.is_empty() {
                "runs here".to_string()
            } else {
                format!("needs {}", unmet.join(", "))
            }
        );
    }
    println!(
        "shadow atlas: up to {0}x{0} (default cap {1})",
        l.max_texture_dimension_2d
            .min(manyshadows::DEFAULT_MAX_ATLAS_SIZE),
        manyshadows::DEFAULT_MAX_ATLAS_SIZE
    );
    Ok(())
}
