//! Built-in scenes. STUB.
