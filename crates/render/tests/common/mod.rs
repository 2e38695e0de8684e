//! Shared helpers of the GPU integration tests.
#![allow(dead_code)]

use manyshadows::{AdapterRequest, GpuContext};

/// The GPU context every GPU test runs on: the adapter `GpuContext::new` picks, narrowed by
/// `WGPU_BACKEND` (CI runs the suite once with `vulkan` and once with `gl`). Never skips: with
/// no adapter the test fails and says what to install.
pub fn context() -> GpuContext {
    match GpuContext::new(&AdapterRequest::default()) {
        Ok(ctx) => {
            eprintln!(
                "GPU test adapter: {}",
                manyshadows::context::describe_adapter(&ctx.info)
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

/// Where failing tests write their images.
pub fn artifacts_dir() -> std::path::PathBuf {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../target/test-artifacts");
    std::fs::create_dir_all(&dir).expect("create target/test-artifacts");
    dir
}
