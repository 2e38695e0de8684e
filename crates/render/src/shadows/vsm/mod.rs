//! Virtual shadow maps (seed 002: Olsson et al., "Efficient Virtual Shadow Maps for Many
//! Lights", I3D 2014; the page pool and page table as Unreal Engine 5 builds them, since wgpu
//! has no sparse textures).
//!
//! **Faces** ([`plan`]). Every shadow view of the plan — a spot's frustum, each of a point
//! light's six cube faces, each cascade — is a *face* with a virtual map of up to 16,384²
//! texels, cut into [`PAGE_SIZE`](plan::PAGE_SIZE)² pages. A face is a mip chain of page grids:
//! level `l` has `2^l × 2^l` pages, level 0 covers the whole face with one page, the finest
//! level has `side / PAGE_SIZE` pages per side. The CPU picks each face's virtual side from the
//! light's importance (the largest texel density any visible point in its reach can ask for;
//! directional lights and lights around the camera get the maximum) and lays out one
//! page-table entry per page of every level ([`VirtualPlan`](plan::VirtualPlan)); lights that
//! reach nothing the camera sees get no faces.
//!
//! **Pages on the GPU, every frame** ([`pages`] records the stages in order, after the G-buffer
//! and the light clusters; what they share of the page table is [`table`], `vsm_table.wgsl`):
//! 1. *mark* ([`mark`], `vsm_mark.wgsl`): each pixel visits its cluster's lights; for each
//!    light that reaches it (and faces it), the sample asks for the level whose texel matches
//!    its pixel footprint ([`VirtualOptions::lod`](plan::VirtualOptions::lod) texels per
//!    pixel): that page is marked *asked* and its ancestors *above*. By default 4×4-pixel
//!    tiles do this once per light where the bounds of their samples prove that every sample
//!    needing a page needs the same one, and hand the rest to per-pixel marking: the same
//!    pages ([`VirtualOptions::tile_marking`](plan::VirtualOptions::tile_marking); [`tiles`],
//!    `vsm_tiles.wgsl`). With caching, when the camera, the lights and every face are as last
//!    frame (only casters moved), last frame's pages carry over ([`carry`], `vsm_carry.wgsl`)
//!    and only the pixels under the moved casters' old and new bounds ([`moved`]) are marked
//!    again. Under sampled lights each pixel marks only the lights its samples ask about
//!    (noted by the lighting pass's choose pass, `crate::sampled::pages`), and pages asked
//!    within the last frames stay asked ([`sampled`]);
//! 2. *allocate* ([`alloc`], `vsm_alloc.wgsl`): the *admitted level* A is the finest level
//!    whose marked pages fit the pool together with the asked pages of every coarser level.
//!    Asked pages coarser than A and every marked page of A get pool pages in page-table order
//!    (ranks from per-block counts and a prefix sum, so the frame never depends on thread
//!    order). With room for every asked page, only those are drawn: an ancestor nobody asked
//!    for is never read. Otherwise asked pages finer than A are *denied* and their lookups fall
//!    back to their ancestor at A — a coarser shadow, never a wrong or missing one — and the
//!    frame's [`VirtualStats`](plan::VirtualStats) count them. A pool with fewer pages than
//!    faces in use gives the last faces quarter pages (four faces' level 0 at 64² in one pool
//!    page, `quarter_faces`), so every face keeps a shadow up to four faces per pool page; only
//!    past that are faces left unshadowed (counted too). With caching
//!    ([`crate::settings::RenderSettings::cache_shadows`]) a page resident last frame in a face
//!    whose view did not change keeps its pool page and its depth unless a caster moved within
//!    it (the moved bounding spheres, old and new, projected onto the face: only the pages
//!    under them are invalidated, not the face) or its samples now reach past the receiver
//!    bounds it was drawn with; only the other pages get free pool pages and are drawn;
//! 3. *render* ([`draw`], `vsm_draw.wgsl`): every page drawn this frame is an ordinary shadow
//!    view (the face's projection cropped to the page, one tile of the pool), drawn the
//!    `gpu-driven` way: compute culls caster clusters against each page's frustum slice (and by
//!    normal cone) — groups of 16 clusters by a merged sphere first, then the clusters of the
//!    groups inside the page, each by its sphere, its box and its quarters' boxes — against
//!    the page's receiver bounds (the farthest depth its samples compare against and the
//!    rectangle their filter taps reach, both kept by the marking), then, where draws are
//!    counted on the GPU, expands the surviving (cluster, page) pairs to the triangles that
//!    touch the page; one draw per round ([`crate::shadows::cluster_draw`]) renders them,
//!    clipped to the page's drawn rectangle.
//!
//! **Lookups** (`vsm_lookup.wgsl` after `vsm_common.wgsl`, composed into the lighting and
//! visibility passes) repeat the marking's level and page choice with the same code, read the
//! page table and sample the pool; PCF taps are clamped to the page.
//!
//! [`source`] is the frame's shadow source made of them (its output: the pool and its table).

pub mod alloc;
pub mod carry;
pub mod draw;
pub mod mark;
pub mod moved;
pub mod pages;
pub mod plan;
pub mod sampled;
pub mod source;
pub mod table;
pub mod tiles;
pub mod types;
