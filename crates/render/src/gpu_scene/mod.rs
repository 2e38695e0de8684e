//! What the GPU holds of the scene, above [`crate::gpu`]: the instances' buffers
//! ([`instances`]: positions, normals, texture coordinates, indices, instances, materials),
//! the materials' images ([`textures`]), skinned and morphed meshes bent on the GPU
//! ([`deform`]), the positions the last frame drew where meshes bend
//! ([`last_positions`]), skinning ([`skinning`]) and the world-space
//! shadow-caster geometry every shadow technique reads ([`casters`], with the alpha-mask tail
//! and its WGSL beside it).

pub mod caster_layout;
pub mod casters;
pub mod deform;
pub mod instances;
pub mod last_positions;
pub mod skinning;
pub mod textures;
