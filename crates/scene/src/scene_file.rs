//! TOML scene files. STUB.
