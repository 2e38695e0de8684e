//! The shadow atlas tile allocator: one square tile per shadow view in one depth texture.
//!
//! Why an atlas: seed 000 §19.6 names the limit of layered rendering into a texture array —
//! every layer must have the same size — and points at "a texture atlas that holds multiple
//! depth images" as the way out. An atlas lets each light ask for its own resolution (a
//! 2048² sun cascade beside 256² cube faces), and wgpu, which cannot pick a render-target
//! layer from a vertex shader, can still fill every tile in one pass by remapping clip xy into
//! the view's tile.
//!
//! The allocator is a buddy (quadtree) packing made trivial by two rules:
//!
//! 1. every request is rounded **up** to a power of two, and to at least [`MIN_TILE`] texels;
//! 2. tiles are placed **largest first** along the Z-order (Morton) curve of the atlas.
//!
//! All areas are then powers of four, so each tile's Z-order offset (the sum of the areas
//! before it) is a multiple of its own area, which makes the tile an aligned quadtree block.
//! The packing is therefore perfect: the tiles fit a power-of-two atlas exactly when their
//! total area does and the largest tile is no wider than the atlas. So the fit is decided by
//! arithmetic, the atlas is the smallest power of two that passes, and placement is one sort
//! and one pass (thousands of tiles in microseconds). Rounding up wastes at most 3/4 of a
//! tile's area, and never resolution: a view rendered into a larger tile only gets sharper.
//!
//! When the tiles do not fit the largest atlas allowed, [`FitPolicy`] chooses between an
//! error and halving every request until they do.

use std::cmp::Reverse;

/// Smallest tile side in texels. Requests below it are rounded up: a 3×3 PCF kernel needs a
/// few texels of map, and a tile this small costs next to nothing in the atlas.
pub const MIN_TILE: u32 = 16;

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
    /// Keep the maps of the lights that matter most on screen: the renderer's shadow plan
    /// gives no maps to lights that reach nothing the camera sees, then halves the maps of the
    /// least important lights first (importance = the angle the light's reach subtends at the
    /// camera), and as a last resort leaves the least important lights unshadowed, counting
    /// each kind. [`layout`] alone knows no importance and treats it as [`FitPolicy::Shrink`].
    #[default]
    Prioritize,
    /// Halve every request (keeping their ratios) until everything fits, down to a floor.
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
        /// Sum of requested tile areas (after rounding each side up to a power of two and at
        /// least [`MIN_TILE`]).
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
///
/// Each request becomes a tile of side `max(request, MIN_TILE)` rounded up to a power of two;
/// the atlas side is the smallest power of two that holds them all, at most the largest power
/// of two ≤ `max_size`. If they do not fit, [`FitPolicy::Strict`] fails with
/// [`AtlasError::Full`] and [`FitPolicy::Shrink`] halves every tile (none below [`MIN_TILE`])
/// until they fit, reporting the number of halvings in [`AtlasLayout::shrink_steps`], and fails
/// only when even the floor does not fit. An empty request list gives an empty atlas of side
/// `MIN_TILE` (or `max_size`'s power of two, if smaller), so it is still a valid texture.
pub fn layout(
    requests: &[u32],
    max_size: u32,
    policy: FitPolicy,
) -> Result<AtlasLayout, AtlasError> {
    if let Some(index) = requests.iter().position(|&r| r == 0) {
        return Err(AtlasError::ZeroSize { index });
    }
    // Sides as u64: rounding a request above 2^31 up to a power of two overflows u32.
    let sides: Vec<u64> = requests
        .iter()
        .map(|&r| u64::from(r.max(MIN_TILE)).next_power_of_two())
        .collect();
    let full = || AtlasError::Full {
        requested_texels: sides.iter().map(|s| s * s).sum(),
        tiles: requests.len(),
        max_size,
    };
    if max_size == 0 {
        return Err(full());
    }
    let max_side = u64::from(prev_power_of_two(max_size));
    if sides.is_empty() {
        return Ok(AtlasLayout {
            size: MIN_TILE.min(max_side as u32),
            tiles: Vec::new(),
            shrink_steps: 0,
        });
    }

    let largest = sides.iter().copied().max().unwrap_or(u64::from(MIN_TILE));
    let mut steps = 0u32;
    let (atlas, sides) = loop {
        let shrunk: Vec<u64> = sides
            .iter()
            .map(|&s| (s >> steps).max(u64::from(MIN_TILE)))
            .collect();
        if let Some(atlas) = smallest_atlas(&shrunk, max_side) {
            break (atlas, shrunk);
        }
        // Once the largest tile is at the floor, every tile is: halving changes nothing more.
        if policy == FitPolicy::Strict || (largest >> steps) <= u64::from(MIN_TILE) {
            return Err(full());
        }
        steps += 1;
    };
    if steps > 0 {
        log::info!(
            "shadow atlas: {} tiles halved {steps} time(s) to fit {max_side}x{max_side}",
            sides.len()
        );
    }

    // Largest first (stable, so equal tiles keep request order), each at the Z-order offset
    // equal to the area placed before it.
    let mut order: Vec<usize> = (0..sides.len()).collect();
    order.sort_by_key(|&i| Reverse(sides[i]));
    let mut tiles = vec![
        Tile {
            x: 0,
            y: 0,
            size: 0
        };
        sides.len()
    ];
    let mut offset = 0u64;
    for i in order {
        let (x, y) = morton_decode(offset);
        tiles[i] = Tile {
            x,
            y,
            size: sides[i] as u32,
        };
        offset += sides[i] * sides[i];
    }
    Ok(AtlasLayout {
        size: atlas as u32,
        tiles,
        shrink_steps: steps,
    })
}

/// The smallest power-of-two side ≤ `max_side` whose square holds tiles of power-of-two
/// `sides` (largest-first Z-order packing is perfect, so area and width decide), if any.
fn smallest_atlas(sides: &[u64], max_side: u64) -> Option<u64> {
    let area: u64 = sides.iter().map(|s| s * s).sum();
    let mut side = sides.iter().copied().max()?;
    while side * side < area {
        side *= 2;
    }
    (side <= max_side).then_some(side)
}

/// The largest power of two ≤ `n` (`n` > 0).
fn prev_power_of_two(n: u32) -> u32 {
    1 << (31 - n.leading_zeros())
}

/// Texel `(x, y)` at Z-order index `i` (x from the even bits, y from the odd bits).
fn morton_decode(i: u64) -> (u32, u32) {
    fn compact(mut v: u64) -> u32 {
        v &= 0x5555_5555_5555_5555;
        v = (v | (v >> 1)) & 0x3333_3333_3333_3333;
        v = (v | (v >> 2)) & 0x0f0f_0f0f_0f0f_0f0f;
        v = (v | (v >> 4)) & 0x00ff_00ff_00ff_00ff;
        v = (v | (v >> 8)) & 0x0000_ffff_0000_ffff;
        v = (v | (v >> 16)) & 0x0000_0000_ffff_ffff;
        v as u32
    }
    (compact(i), compact(i >> 1))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A small deterministic generator (xorshift64).
    struct Rng(u64);
    impl Rng {
        fn below(&mut self, n: u32) -> u32 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            (self.0 % u64::from(n)) as u32
        }
    }

    /// Every tile inside the atlas, no two overlapping (sweep over x-sorted tiles), sides
    /// powers of two ≥ MIN_TILE and ≥ the (unshrunk) request.
    fn check(requests: &[u32], atlas: &AtlasLayout) {
        assert_eq!(atlas.tiles.len(), requests.len());
        assert!(atlas.size.is_power_of_two());
        for (t, &r) in atlas.tiles.iter().zip(requests) {
            assert!(t.size.is_power_of_two() && t.size >= MIN_TILE, "{t:?}");
            assert!(
                t.x + t.size <= atlas.size && t.y + t.size <= atlas.size,
                "{t:?} outside {}",
                atlas.size
            );
            if atlas.shrink_steps == 0 {
                assert!(
                    t.size >= r && t.size < 2 * r.max(MIN_TILE),
                    "request {r} got {t:?}"
                );
            }
        }
        let mut by_x: Vec<&Tile> = atlas.tiles.iter().collect();
        by_x.sort_by_key(|t| t.x);
        for (i, a) in by_x.iter().enumerate() {
            for b in &by_x[i + 1..] {
                if b.x >= a.x + a.size {
                    break;
                }
                let overlap = b.y < a.y + a.size && a.y < b.y + b.size;
                assert!(!overlap, "{a:?} overlaps {b:?}");
            }
        }
    }

    fn area(atlas: &AtlasLayout) -> u64 {
        atlas.tiles.iter().map(|t| u64::from(t.size).pow(2)).sum()
    }

    #[test]
    fn random_requests_never_overlap_and_stay_inside() {
        let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
        for _ in 0..200 {
            let n = 1 + rng.below(60) as usize;
            let requests: Vec<u32> = (0..n).map(|_| 1 + rng.below(1500)).collect();
            let atlas = layout(&requests, 16384, FitPolicy::Strict).unwrap();
            check(&requests, &atlas);
        }
    }

    #[test]
    fn atlas_is_the_smallest_that_holds_the_tiles() {
        let mut rng = Rng(12345);
        for _ in 0..200 {
            let n = 1 + rng.below(40) as usize;
            let requests: Vec<u32> = (0..n).map(|_| 1 + rng.below(3000)).collect();
            let atlas = layout(&requests, 1 << 15, FitPolicy::Strict).unwrap();
            check(&requests, &atlas);
            let largest = atlas.tiles.iter().map(|t| t.size).max().unwrap();
            let half = u64::from(atlas.size / 2);
            assert!(
                half < u64::from(largest) || half * half < area(&atlas),
                "{} would also hold {requests:?}",
                atlas.size / 2
            );
        }
    }

    #[test]
    fn mixed_sizes_are_placed() {
        let requests = [2048, 512, 512, 512, 512, 512, 512, 1024, 1024, 1024];
        let atlas = layout(&requests, 8192, FitPolicy::Strict).unwrap();
        check(&requests, &atlas);
        // 2048² + 3·1024² + 6·512² = 8.5 M texels: more than 2048², at most 4096².
        assert_eq!(atlas.size, 4096);
        assert_eq!(atlas.shrink_steps, 0);
        assert_eq!(
            atlas.tiles[0],
            Tile {
                x: 0,
                y: 0,
                size: 2048
            }
        );
        // Requests that are not powers of two round up; tiny ones up to MIN_TILE.
        let atlas = layout(&[1000, 3, 17], 4096, FitPolicy::Strict).unwrap();
        check(&[1000, 3, 17], &atlas);
        let sizes: Vec<u32> = atlas.tiles.iter().map(|t| t.size).collect();
        assert_eq!(sizes, [1024, MIN_TILE, 32]);
        assert_eq!(atlas.size, 2048);
    }

    #[test]
    fn max_size_need_not_be_a_power_of_two() {
        // 3000 allows 2048 at most: one 2048 tile fits, two do not.
        assert_eq!(layout(&[2048], 3000, FitPolicy::Strict).unwrap().size, 2048);
        assert!(layout(&[2048, 2048], 3000, FitPolicy::Strict).is_err());
    }

    #[test]
    fn full_atlas_is_an_error_in_strict_mode() {
        let err = layout(&[4096, 4096, 1024], 8192 - 1, FitPolicy::Strict).unwrap_err();
        assert_eq!(
            err,
            AtlasError::Full {
                requested_texels: 2 * 4096 * 4096 + 1024 * 1024,
                tiles: 3,
                max_size: 8191,
            }
        );
        let message = err.to_string();
        assert!(
            message.contains("8191x8191") && message.contains("3 tiles"),
            "{message}"
        );
        assert!(message.contains("allow shrinking"), "{message}");
        // A tile wider than the atlas is full however little the total area.
        assert!(matches!(
            layout(&[5000], 4096, FitPolicy::Strict),
            Err(AtlasError::Full { .. })
        ));
        // Smaller than the smallest tile.
        assert!(matches!(
            layout(&[1], 8, FitPolicy::Shrink),
            Err(AtlasError::Full { .. })
        ));
    }

    #[test]
    fn shrink_halves_every_request_until_it_fits() {
        // 8 × 2048² = 32 M texels needs 8192²; in 4096² every tile must halve once.
        let requests = [2048; 8];
        let atlas = layout(&requests, 4096, FitPolicy::Shrink).unwrap();
        check(&requests, &atlas);
        assert_eq!(atlas.shrink_steps, 1);
        assert_eq!(atlas.size, 4096);
        assert!(atlas.tiles.iter().all(|t| t.size == 1024));
        // Ratios are kept: 4096 + 1024s in 2048 → halved twice.
        let requests = [4096, 1024, 1024, 1024];
        let atlas = layout(&requests, 2048, FitPolicy::Shrink).unwrap();
        check(&requests, &atlas);
        assert_eq!(atlas.shrink_steps, 2);
        let sizes: Vec<u32> = atlas.tiles.iter().map(|t| t.size).collect();
        assert_eq!(sizes, [1024, 256, 256, 256]);
        // Halving stops at MIN_TILE for the small ones while the large ones keep shrinking.
        let requests = [1024, 16, 16];
        let atlas = layout(&requests, 256, FitPolicy::Shrink).unwrap();
        assert_eq!(atlas.shrink_steps, 3);
        let sizes: Vec<u32> = atlas.tiles.iter().map(|t| t.size).collect();
        assert_eq!(sizes, [128, 16, 16]);
        // Too many tiles even at the floor: Full.
        let err = layout(&vec![64; 300], 256, FitPolicy::Shrink).unwrap_err();
        assert!(
            matches!(
                err,
                AtlasError::Full {
                    tiles: 300,
                    max_size: 256,
                    ..
                }
            ),
            "{err}"
        );
    }

    #[test]
    fn zero_request_is_an_error() {
        assert_eq!(
            layout(&[256, 0, 128], 4096, FitPolicy::Shrink),
            Err(AtlasError::ZeroSize { index: 1 })
        );
        assert!(layout(&[0], 4096, FitPolicy::Strict)
            .unwrap_err()
            .to_string()
            .contains("request 0"));
    }

    #[test]
    fn empty_request_list_gives_a_small_valid_atlas() {
        let atlas = layout(&[], 4096, FitPolicy::Strict).unwrap();
        assert_eq!(
            (atlas.size, atlas.tiles.len(), atlas.shrink_steps),
            (MIN_TILE, 0, 0)
        );
    }

    #[test]
    fn thousands_of_small_tiles_pack() {
        // 6000 views (1000 point lights × 6 faces) at mixed small sizes. (Speed is not asserted
        // here: timed tests flake; the packing is linear in the number of tiles.)
        let mut rng = Rng(42);
        let requests: Vec<u32> = (0..6000).map(|_| 16 << rng.below(4)).collect();
        let atlas = layout(&requests, 16384, FitPolicy::Strict).unwrap();
        check(&requests, &atlas);
        let half = u64::from(atlas.size / 2);
        assert!(half * half < area(&atlas));
    }
}
