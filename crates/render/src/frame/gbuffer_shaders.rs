//! The G-buffer pass's WGSL, one composition per way its views are drawn (gbuffer.rs): one
//! camera or two eyes, layered or multiview stereo, probe faces in tiles or layers.

/// Where the G-buffer's views are seen from, for one camera or two eyes.
const EYES_OF_FRAME: &str = "fn eye_position(e: u32) -> vec3<f32> { return frame.eye_pos[e].xyz; }";

/// The pass's WGSL: (with `clip`, clip distances enabled) the common declarations, the
/// pass itself, then `parts` (a way's vertex stage and what it needs).
fn composed(clip: bool, parts: &[&str]) -> String {
    let clip: &[&str] = if clip {
        &["enable clip_distances;"]
    } else {
        &[]
    };
    let base = [crate::gpu::shaders::COMMON, include_str!("gbuffer.wgsl")];
    crate::gpu::shaders::compose(&[clip, &base[..], parts].concat())
}

/// The G-buffer pass's WGSL.
pub fn shader() -> String {
    composed(false, &[EYES_OF_FRAME])
}

/// The same with `vs_faces`: square views in tiles in one layered pass (needs
/// `CLIP_DISTANCES`).
pub fn faces_shader() -> String {
    composed(
        true,
        &[
            include_str!("gbuffer_face_views.wgsl"),
            include_str!("gbuffer_faces.wgsl"),
        ],
    )
}

/// The same with `vs_face_clusters` too: square views in tiles drawn from GPU-culled triangle
/// clusters by indirect multi-draws, the vertices read from storage (needs `CLIP_DISTANCES`).
pub fn face_clusters_shader() -> String {
    composed(
        true,
        &[
            include_str!("gbuffer_face_views.wgsl"),
            include_str!("gbuffer_faces.wgsl"),
            crate::frame::gbuffer_pull::PARAMS_WGSL,
            include_str!("gbuffer_face_clusters.wgsl"),
        ],
    )
}

/// The same with `vs_face_layers`: a probe's six faces in one multiview pass (needs
/// `MULTIVIEW` with six views).
pub fn face_layers_shader() -> String {
    composed(
        false,
        &[
            include_str!("gbuffer_face_views.wgsl"),
            include_str!("gbuffer_face_layers.wgsl"),
        ],
    )
}

/// The same with `vs_multiview`: both eyes of a stereo frame in one multiview pass (needs
/// `MULTIVIEW`).
pub fn multiview_shader() -> String {
    composed(
        false,
        &[include_str!("gbuffer_multiview.wgsl"), EYES_OF_FRAME],
    )
}

/// The same with `vs_layered`: both eyes of a stereo frame in one draw (needs
/// `CLIP_DISTANCES`).
pub fn layered_shader() -> String {
    composed(true, &[include_str!("gbuffer_layered.wgsl"), EYES_OF_FRAME])
}

#[cfg(test)]
mod shader_tests {
    /// Every variant this module composes is WGSL a WebGPU device accepts, with the feature
    /// it enables or needs.
    #[test]
    fn every_variant_validates_for_webgpu() {
        for (name, src, features) in [
            ("gbuffer", super::shader(), wgpu::Features::empty()),
            (
                "gbuffer layered",
                super::layered_shader(),
                wgpu::Features::CLIP_DISTANCES,
            ),
            (
                "gbuffer multiview",
                super::multiview_shader(),
                wgpu::Features::MULTIVIEW,
            ),
            (
                "gbuffer faces",
                super::faces_shader(),
                wgpu::Features::CLIP_DISTANCES,
            ),
            (
                "gbuffer face clusters",
                super::face_clusters_shader(),
                wgpu::Features::CLIP_DISTANCES,
            ),
            (
                "gbuffer face layers",
                super::face_layers_shader(),
                wgpu::Features::MULTIVIEW,
            ),
        ] {
            crate::gpu::shaders::validate_for_webgpu(name, &src, features)
                .unwrap_or_else(|e| panic!("{name}: {e}"));
        }
    }
}
