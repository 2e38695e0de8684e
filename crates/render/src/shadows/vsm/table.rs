//! The page table as the page passes of the virtual shadow maps share it ([`super::pages`]
//! records them in order: [`super::carry`], [`super::mark`] or [`super::tiles`],
//! [`super::alloc`]). `vsm_table.wgsl` is the WGSL piece every stage's shader composes before
//! its own: the table's bindings, the states of its entries, the frame's counters and the
//! walks through a face's mip chain of page grids. Here are the same buffers on the CPU side
//! (`TableBuffers`), the words the table holds per entry and the counters' size, and the
//! dispatch of one thread per entry or block of entries.

/// The table's WGSL declarations, composed before each stage's own.
pub(crate) const PAGE_TABLE: &str = include_str!("vsm_table.wgsl");

/// Words of the page table per entry: the entry, its receiver depth key and its cell mask.
pub(crate) const TABLE_WORDS: u64 = 3;

/// Words of the counters buffer (see `vsm_table.wgsl`).
pub(crate) const COUNTERS: usize = 34;

/// The buffers `vsm_table.wgsl` binds (owned by [`super::pages`]).
pub(crate) struct TableBuffers<'a> {
    /// `VsmUniforms` (binding 7).
    pub uniforms: &'a wgpu::Buffer,
    /// `array<VirtualFace>` (binding 8).
    pub faces: &'a wgpu::Buffer,
    /// The page table with its receiver bounds (binding 9).
    pub table: &'a wgpu::Buffer,
    /// The frame's counters (binding 10).
    pub counters: &'a wgpu::Buffer,
    /// Last frame's page table (binding 14).
    pub prev_table: &'a wgpu::Buffer,
}

/// Workgroups of 64 threads for `threads` threads: along x up to 65,535, rows past that (the
/// shaders read the index as `x + y · groups.x · 64`).
pub(crate) fn entry_groups(threads: u64) -> (u32, u32) {
    let n = threads.div_ceil(64);
    (n.min(65535) as u32, n.div_ceil(65535) as u32)
}
