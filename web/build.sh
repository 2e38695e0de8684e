#!/usr/bin/env bash
# Builds the web page's module: the renderer for wasm32 and its JavaScript bindings in web/pkg.
# Needs `rustup target add wasm32-unknown-unknown` and
# `cargo install wasm-bindgen-cli --version 0.2.130` (the version of the wasm-bindgen crate).
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release -p manyshadows-web --target wasm32-unknown-unknown
wasm-bindgen --target web --out-dir web/pkg \
    target/wasm32-unknown-unknown/release/manyshadows_web.wasm
echo "built web/pkg; serve it with: python3 web/serve.py 8000 /tmp  (then open http://127.0.0.1:8000/)"
