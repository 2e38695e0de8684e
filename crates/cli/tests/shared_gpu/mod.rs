//! The one GPU context of a CLI test process, for the tests that ask the adapter what it can
//! run (the CLI itself runs in child processes, one device each).

/// The adapter `GpuContext::new` picks, made once per test process, shared (cloned) and never
/// dropped: NVIDIA's Linux Vulkan driver crashes or deadlocks now and then when several
/// threads create and destroy devices at once (wgpu issues 8365 and 10010; see the render
/// crate's tests/common/mod.rs and docs/benchmarks.md).
pub fn context() -> manyshadows::GpuContext {
    static SHARED: std::sync::OnceLock<manyshadows::GpuContext> = std::sync::OnceLock::new();
    SHARED
        .get_or_init(|| {
            manyshadows::GpuContext::new(&Default::default()).unwrap_or_else(|e| {
                panic!(
                    "no usable adapter: {e} (install mesa-vulkan-drivers, or libegl1 + \
                     libgl1-mesa-dri)"
                )
            })
        })
        .clone()
}

/// Whether `ctx`'s device runs ray-traced shadows. Where it does not, the test goes on to check
/// the refusal instead: that is recorded (`manyshadows_testkit::refused`), and fails the test
/// where the test command says the backend must offer ray queries.
#[allow(dead_code)]
#[track_caller]
pub fn rays_here(ctx: &manyshadows::GpuContext) -> bool {
    let unmet = manyshadows::Technique::RAYTRACED.info().unmet(ctx);
    match unmet.first() {
        None => true,
        Some(need) => {
            manyshadows_testkit::refused(
                &need.name(),
                &format!("ray-traced shadows on {}", ctx.describe()),
            );
            false
        }
    }
}
