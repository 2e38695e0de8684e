// One round of the probe faces' cluster cull and its draw (gbuffer_pull.rs), shared by the
// cull (probes/clusters.wgsl) and the G-buffer's vertex shader
// (gbuffer_face_clusters.wgsl).
struct FaceDrawParams {
    // first face of the round, faces in the round, first cluster of the round, clusters in it
    round: vec4<u32>,
    // S (slot stride), V (scene vertices), 1 = compact commands, unused
    stride: vec4<u32>,
}
