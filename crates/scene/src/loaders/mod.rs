//! Mesh loaders. STUB.
