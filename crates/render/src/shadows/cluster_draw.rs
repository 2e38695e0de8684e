//! Cluster culling and indirect multi-draw in rounds: what `gpu-driven` (atlas tiles) and the
//! virtual maps (pool pages) share. Compute culls caster clusters per view (bounding sphere
//! against the view's frustum, normal cone against the light: `cluster_cull.wgsl`, beside this
//! module) and writes indexed-indirect commands; one multi-draw per round draws the survivors.
//!
//! Views are processed in *rounds*: a round's slots must keep `slot · V` below 2³¹ (the view's
//! batch slot rides in `base_vertex`, V = caster vertices) and its command buffer (clusters ×
//! views × 20 bytes) within the storage-binding limit, so large scenes with many views run
//! several cull + draw rounds instead of truncating. Clusters are split too if even one view's
//! commands would not fit, and alpha-tested clusters never share a round with opaque ones.

/// Bytes of one indexed-indirect command (`wgpu::util::DrawIndexedIndirectArgs`).
pub const COMMAND_SIZE: u64 = std::mem::size_of::<wgpu::util::DrawIndexedIndirectArgs>() as u64;

/// Largest workgroup count per dispatch dimension WebGPU guarantees.
const MAX_GROUPS: u64 = 65535;

/// One cull + draw round: a run of the draw list and a run of the clusters.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Round {
    /// First position in the draw list.
    pub first_view: u32,
    /// Views (batch slots) in the round.
    pub views: u32,
    /// First cluster.
    pub first_cluster: u32,
    /// Clusters.
    pub clusters: u32,
    /// The clusters are alpha-tested ones (a round never mixes them with opaque clusters, so
    /// it is drawn with one pipeline).
    pub masked: bool,
    /// The clusters' triangles are culled by facing when drawn (the rasterizer's back-face
    /// culling: cullable triangles where culling them is the rule).
    pub culled: bool,
}

impl Round {
    /// Command slots of the round.
    pub fn commands(&self) -> u64 {
        self.views as u64 * self.clusters as u64
    }
}

/// Splits `views` listed views × `clusters` clusters into rounds of at most `max_commands`
/// commands whose slots keep `slot · vertices` below 2³¹ (and within dispatch limits). No
/// round straddles `culled` (the clusters before it are drawn culled by facing) or
/// `first_masked` (the first alpha-tested cluster).
pub fn plan_rounds(
    views: u32,
    clusters: u32,
    (culled, first_masked): (u32, u32),
    vertices: u32,
    max_commands: u64,
) -> Vec<Round> {
    if views == 0 || clusters == 0 {
        return Vec::new();
    }
    let max_commands = max_commands.max(1);
    let chunk = (clusters as u64).min(max_commands).min(MAX_GROUPS * 64) as u32;
    // slot · V + (V − 1) must fit an i32 (base_vertex) and the u32 vertex index.
    let by_vertex = (1u64 << 31) / vertices.max(1) as u64;
    let batch = (max_commands / chunk as u64)
        .min(by_vertex)
        .clamp(1, MAX_GROUPS) as u32;
    let split = first_masked.min(clusters);
    let culled = culled.min(split);
    let mut rounds = Vec::new();
    let mut first_view = 0;
    while first_view < views {
        let n = batch.min(views - first_view);
        for (lo, hi) in [(0, culled), (culled, split), (split, clusters)] {
            let mut first_cluster = lo;
            while first_cluster < hi {
                let c = chunk.min(hi - first_cluster);
                rounds.push(Round {
                    first_view,
                    views: n,
                    first_cluster,
                    clusters: c,
                    masked: first_cluster >= split,
                    culled: first_cluster < culled,
                });
                first_cluster += c;
            }
        }
        first_view += n;
    }
    rounds
}

/// Culling whole caster clusters by bounding sphere and normal cone (`gpu-driven`, virtual).
pub const CLUSTER_CULL: &str = include_str!("cluster_cull.wgsl");

#[cfg(test)]
mod tests {
    use super::*;

    fn covered(rounds: &[Round], views: u32, clusters: u32) -> bool {
        let mut seen = vec![0u32; (views * clusters) as usize];
        for r in rounds {
            for v in r.first_view..r.first_view + r.views {
                for c in r.first_cluster..r.first_cluster + r.clusters {
                    seen[(v * clusters + c) as usize] += 1;
                }
            }
        }
        seen.iter().all(|&n| n == 1)
    }

    #[test]
    fn rounds_cover_every_pair_once_within_limits() {
        for &(views, clusters, vertices, max) in &[
            (24u32, 374u32, 30_000u32, u64::MAX),
            (24, 374, 30_000, 1000),
            (24, 374, 30_000, 100),
            (7, 5, 1 << 29, u64::MAX),
            (1, 1, 1, 1),
        ] {
            for split in [0, clusters / 3, clusters] {
                for culled in [0, split / 2, split] {
                    let rounds = plan_rounds(views, clusters, (culled, split), vertices, max);
                    assert!(
                        covered(&rounds, views, clusters),
                        "{views} {clusters} {vertices} {max}"
                    );
                    for r in &rounds {
                        assert!(r.commands() <= max);
                        assert!((r.views as u64) * (vertices as u64) <= 1 << 31);
                        // Alpha-tested clusters never share a round with opaque ones, nor
                        // culled clusters with others.
                        assert_eq!(r.masked, r.first_cluster >= split);
                        assert!(r.masked || r.first_cluster + r.clusters <= split);
                        assert_eq!(r.culled, r.first_cluster < culled);
                        assert!(!r.culled || r.first_cluster + r.clusters <= culled);
                    }
                }
            }
        }
        // One round when everything fits; 2^29 vertices allow four slots per round.
        assert_eq!(plan_rounds(24, 374, (0, 374), 30_000, u64::MAX).len(), 1);
        assert_eq!(plan_rounds(24, 374, (0, 100), 30_000, u64::MAX).len(), 2);
        assert_eq!(plan_rounds(7, 5, (0, 5), 1 << 29, u64::MAX).len(), 2);
        assert!(plan_rounds(0, 5, (0, 5), 10, 10).is_empty());
    }
}
