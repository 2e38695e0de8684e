//! Waiting for long GPU work: one wait of wgpu's OpenGL backend ends after about 2.1 s
//! whatever timeout is asked for, and a frame on llvmpipe under load can take longer.
//! `GpuContext::wait_idle` (behind every read-back) must wait for the work, not fail, and not
//! return before it is done. (On llvmpipe's OpenGL the compute work below mostly runs inside
//! `submit`, so this test does not reproduce the 2.1 s fence timeout itself — a clusters test
//! under load did once, "The requested Wait timed out"; it checks that a read-back of 3-5 s of
//! work returns that work's results on both backends.)

mod common;

use std::time::Instant;

use manyshadows::wgpu;

// Each dispatch runs 32,768 turns of a hash per invocation on the buffer's value: llvmpipe
// stops a shader's loops after 65,535 iterations in all (gallivm's guard against endless
// loops), so long work is many dispatches, not one long loop.
const SHADER: &str = r#"
@group(0) @binding(0) var<storage, read_write> out: array<u32>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    var x = out[id.x] ^ id.x;
    for (var i = 0u; i < 32768u; i = i + 1u) {
        x = (x ^ i) * 1664525u + 1013904223u;
    }
    out[id.x] = x;
}
"#;

const INVOCATIONS: u32 = 4096;

/// What invocation `i` holds after `dispatches`, on the CPU.
fn expected(i: u32, dispatches: u32) -> u32 {
    let mut x = 0u32;
    for _ in 0..dispatches {
        x ^= i;
        for k in 0..32768 {
            x = (x ^ k).wrapping_mul(1664525).wrapping_add(1013904223);
        }
    }
    x
}

/// Submits `dispatches` passes in one command buffer, waits for the read-back, and returns
/// the seconds that took and the results.
fn run(ctx: &manyshadows::GpuContext, dispatches: u32) -> (f64, Vec<u32>) {
    let device = &ctx.device;
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("gpu_wait"),
        source: wgpu::ShaderSource::Wgsl(SHADER.into()),
    });
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("gpu_wait"),
        layout: None,
        module: &module,
        entry_point: Some("main"),
        compilation_options: Default::default(),
        cache: None,
    });
    let size = INVOCATIONS as u64 * 4;
    let out = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("gpu_wait.out"),
        size,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let readback = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("gpu_wait.readback"),
        size,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[wgpu::BindGroupEntry {
            binding: 0,
            resource: out.as_entire_binding(),
        }],
    });
    let mut encoder = device.create_command_encoder(&Default::default());
    for _ in 0..dispatches {
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.dispatch_workgroups(INVOCATIONS / 64, 1, 1);
    }
    encoder.copy_buffer_to_buffer(&out, 0, &readback, 0, size);
    let start = Instant::now();
    ctx.queue.submit([encoder.finish()]);
    let bytes = manyshadows::gpu::readback::map_read(ctx, &readback, 0..size).unwrap_or_else(|e| {
        panic!(
            "read-back after {:.1} s: {e}",
            start.elapsed().as_secs_f64()
        )
    });
    let secs = start.elapsed().as_secs_f64();
    (secs, bytemuck::cast_slice(&bytes).to_vec())
}

#[test]
fn a_read_back_waits_for_work_longer_than_one_gl_wait() {
    let ctx = common::context();
    // Grow the work until one submission keeps the GPU busy for over 3 s (the GL backend's
    // single wait gives up after 2.1 s).
    let mut dispatches = 1u32;
    loop {
        let (secs, out) = run(&ctx, dispatches);
        eprintln!("{dispatches} dispatches: {secs:.2} s");
        for i in [0, 1, 777, INVOCATIONS - 1] {
            assert_eq!(
                out[i as usize],
                expected(i, dispatches),
                "invocation {i}: read back before the work finished"
            );
        }
        if secs > 3.0 {
            break;
        }
        assert!(
            dispatches < 4096,
            "could not keep the GPU busy for 3 s ({secs:.2} s with {dispatches} dispatches)"
        );
        // Aim at about 4 s.
        let factor = (4.0 / secs.max(0.01)).clamp(2.0, 64.0);
        dispatches = ((dispatches as f64 * factor) as u32).min(4096);
    }
}
