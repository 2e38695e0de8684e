//! Everything that can go wrong while building, loading or checking a scene.

use std::path::PathBuf;

/// Everything that can go wrong while building, loading or checking a scene.
///
/// Each variant's message says what was wrong and, where it helps, what to do about it.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// A file could not be read.
    #[error("cannot read {path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating system's reason.
        source: std::io::Error,
    },
    /// A file was read but its contents are not valid for its format.
    #[error("{path}: {reason}")]
    Parse {
        /// The file.
        path: PathBuf,
        /// What is wrong, in the parser's words where possible.
        reason: String,
    },
    /// The file's extension names no format we load.
    #[error("{path}: unsupported mesh format (expected .obj, .gltf, .glb, .ply or .ply.gz)")]
    UnsupportedFormat {
        /// The file.
        path: PathBuf,
    },
    /// A file is larger than the loader accepts.
    #[error("{path}: {reason}")]
    TooLarge {
        /// The file.
        path: PathBuf,
        /// Which limit it broke.
        reason: String,
    },
    /// A mesh has out-of-range indices, non-finite coordinates or mismatched arrays.
    #[error("mesh '{mesh}' is invalid: {reason}")]
    InvalidMesh {
        /// Mesh name.
        mesh: String,
        /// What is wrong.
        reason: String,
    },
    /// An instance refers to something missing or has an unusable transform.
    #[error("instance {index} is invalid: {reason}")]
    InvalidInstance {
        /// Instance index.
        index: usize,
        /// What is wrong.
        reason: String,
    },
    /// A material has non-finite or negative values.
    #[error("material {index} is invalid: {reason}")]
    InvalidMaterial {
        /// Material index.
        index: usize,
        /// What is wrong.
        reason: String,
    },
    /// A light has an unusable parameter.
    #[error("light {index} is invalid: {reason}")]
    InvalidLight {
        /// Light index.
        index: usize,
        /// What is wrong.
        reason: String,
    },
    /// A reflection probe with a bad position, size or resolution.
    #[error("probe {index} is invalid: {reason}")]
    InvalidProbe {
        /// Index into `Scene::probes`.
        index: usize,
        /// What is wrong.
        reason: String,
    },
    /// A texture has no pixels, too many, or a data length that does not match its size.
    #[error("texture {index} is invalid: {reason}")]
    InvalidTexture {
        /// Texture index.
        index: usize,
        /// What is wrong.
        reason: String,
    },
    /// The camera cannot produce an image.
    #[error("camera is invalid: {0}")]
    InvalidCamera(String),
    /// A built-in scene name that does not exist.
    #[error("unknown built-in scene '{name}' (built-in scenes: {known})")]
    UnknownScene {
        /// The name asked for.
        name: String,
        /// The names that exist, comma-separated.
        known: String,
    },
    /// A request the scene builder cannot honour (e.g. too many lights).
    #[error("{0}")]
    InvalidRequest(String),
}
