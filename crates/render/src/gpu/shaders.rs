//! WGSL's one way of sharing code: composition. `common.wgsl` (struct declarations beside
//! this module, kept in sync with [`crate::gpu::types`]) is prepended to the shaders that need
//! it; every other WGSL file lies beside the module that owns it, which composes its own
//! shaders with [`compose`] and makes the module with [`module`]. Each owner validates what it
//! composes against WebGPU's capabilities in its tests (`validate_for_webgpu`), so broken
//! WGSL fails `cargo test` without a GPU.

/// Struct declarations shared by all shaders.
pub const COMMON: &str = include_str!("common.wgsl");

/// Concatenates shader parts in order.
pub fn compose(parts: &[&str]) -> String {
    parts.join("\n")
}

/// Creates a shader module from composed WGSL.
pub fn module(device: &wgpu::Device, label: &str, source: &str) -> wgpu::ShaderModule {
    device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    })
}

/// Parses and validates `source` as a WebGPU device with `features` would: naga's
/// capabilities from WebGPU's core (a fully compliant downlevel, no optional feature) plus
/// those `features` bring, as wgpu maps them. A shader that relies on more fails here, not in
/// a browser.
#[cfg(test)]
pub(crate) fn validate_for_webgpu(
    name: &str,
    source: &str,
    features: wgpu::Features,
) -> Result<(), String> {
    use wgpu::naga;
    let module = naga::front::wgsl::parse_str(source)
        .map_err(|e| format!("{name}: {}", e.emit_to_string(source)))?;
    let caps = wgpu_naga_bridge::features_to_naga_capabilities(
        features,
        wgpu::DownlevelFlags::compliant(),
    );
    naga::valid::Validator::new(naga::valid::ValidationFlags::all(), caps)
        .validate(&module)
        .map(|_| ())
        .map_err(|e| {
            format!("{name} does not validate with WebGPU's capabilities + {features:?}: {e:?}")
        })
}

#[cfg(test)]
mod tests {
    /// The check above can fail: a shader that enables clip distances is refused without the
    /// feature and accepted with it.
    #[test]
    fn webgpu_validation_refuses_a_feature_the_shader_was_not_given() {
        let src = "enable clip_distances;\nstruct O { @builtin(position) p: vec4<f32>, @builtin(clip_distances) c: array<f32, 1> }\n@vertex fn vs() -> O { return O(vec4<f32>(0.0), array<f32, 1>(1.0)); }";
        assert!(super::validate_for_webgpu("probe", src, wgpu::Features::empty()).is_err());
        super::validate_for_webgpu("probe", src, wgpu::Features::CLIP_DISTANCES)
            .unwrap_or_else(|e| panic!("{e}"));
    }
}
