//! The shadow atlas tile allocator. STUB: interface fixed, bodies to be written.

/// A square region of the atlas, in texels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Tile {
    /// Left edge.
    pub x: u32,
    /// Top edge.
    pub y: u32,
    /// Side length.
    pub size: u32,
}

/// What to do when the requested tiles do not fit the largest atlas allowed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum FitPolicy {
    /// Halve every request (keeping their ratios) until everything fits, down to a floor.
    #[default]
    Shrink,
    /// Fail with [`AtlasError::Full`].
    Strict,
}

/// A packed atlas: its side and one tile per request, in request order.
#[derive(Clone, Debug, PartialEq)]
pub struct AtlasLayout {
    /// Side length of the square atlas texture.
    pub size: u32,
    /// One tile per request, same order.
    pub tiles: Vec<Tile>,
    /// How many times every request was halved to fit (0 = as requested).
    pub shrink_steps: u32,
}

/// Why an atlas could not be laid out.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum AtlasError {
    /// The tiles do not fit.
    #[error("shadow atlas full: {requested_texels} texels requested in {tiles} tiles, but the largest atlas is {max_size}x{max_size}; lower the shadow resolution, use fewer shadowed lights, or allow shrinking")]
    Full {
        /// Sum of requested tile areas.
        requested_texels: u64,
        /// Number of tiles.
        tiles: usize,
        /// Largest atlas side allowed.
        max_size: u32,
    },
    /// A request was zero.
    #[error("tile request {index} has size 0")]
    ZeroSize {
        /// Which request.
        index: usize,
    },
}

/// Lays out square tiles (sizes rounded up to powers of two) in the smallest power-of-two atlas
/// no larger than `max_size`.
pub fn layout(requests: &[u32], max_size: u32, policy: FitPolicy) -> Result<AtlasLayout, AtlasError> {
    let _ = (requests, max_size, policy);
    unimplemented!()
}
