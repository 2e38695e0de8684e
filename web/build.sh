#!/usr/bin/env bash
# Builds the web page's module: the renderer for wasm32 and its JavaScript bindings, into
# web/pkg (or the folder given as the first argument).
# Needs `rustup target add wasm32-unknown-unknown` and
# `cargo install wasm-bindgen-cli --version 0.2.130` (the version of the wasm-bindgen crate).
set -euo pipefail
cd "$(dirname "$0")/.."
out="${1:-web/pkg}"
cargo build --release -p manyshadows-web --target wasm32-unknown-unknown
wasm-bindgen --target web --out-dir "$out" \
    "${CARGO_TARGET_DIR:-target}/wasm32-unknown-unknown/release/manyshadows_web.wasm"
echo "built $out; serve web/ with any static server (cargo xtask web builds and serves it at http://127.0.0.1:8000/)"
