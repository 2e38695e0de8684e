//! The `manyshadows` program: everything is in the library (`src/lib.rs`).

fn main() {
    manyshadows_cli::main();
}
