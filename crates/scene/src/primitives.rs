//! Procedural meshes. STUB.
