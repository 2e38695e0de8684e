//! Everything that can go wrong in the reference.

/// Everything that can go wrong in the reference. Each message says what to do.
#[derive(Debug, thiserror::Error)]
pub enum ReferenceError {
    /// The scene is invalid (the same checks the renderer makes).
    #[error(transparent)]
    Scene(#[from] manyshadows_scene::SceneError),
    /// Two images or masks that must describe the same frame do not.
    #[error("{what}: expected {expected}, found {found}; score masks of the same frame and scene")]
    Mismatch {
        /// What differs.
        what: &'static str,
        /// The size or count expected.
        expected: String,
        /// The size or count found.
        found: String,
    },
}
