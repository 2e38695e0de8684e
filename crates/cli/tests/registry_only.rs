//! The programs name no technique themselves: every technique name, default, menu and check
//! of the CLI, the viewer and the web page comes from the renderer's registry
//! (`Technique::all()`, `TechniqueInfo`). This reads their sources (comments aside) and fails
//! on a technique's name in a string literal or in page markup, or a `Technique::NAME`
//! constant, anywhere but in the test files.

use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Rust source without comments (line comments, block comments, doc comments).
fn strip_rust_comments(src: &str) -> String {
    let mut out = String::with_capacity(src.len());
    let b = src.as_bytes();
    let (mut i, mut in_str) = (0, false);
    while i < b.len() {
        let c = b[i] as char;
        if in_str {
            out.push(c);
            if c == '\\' && i + 1 < b.len() {
                out.push(b[i + 1] as char);
                i += 2;
                continue;
            }
            if c == '"' {
                in_str = false;
            }
            i += 1;
        } else if c == '"' {
            in_str = true;
            out.push(c);
            i += 1;
        } else if src[i..].starts_with("//") {
            while i < b.len() && b[i] != b'\n' {
                i += 1;
            }
        } else if src[i..].starts_with("/*") {
            let end = src[i + 2..].find("*/").map_or(b.len(), |e| i + 4 + e);
            i = end;
        } else {
            out.push(c);
            i += 1;
        }
    }
    out
}

/// The string literals of `src` (comments stripped first).
fn string_literals(src: &str) -> Vec<String> {
    let code = strip_rust_comments(src);
    let mut out = Vec::new();
    let mut it = code.split('"');
    it.next();
    while let Some(lit) = it.next() {
        out.push(lit.to_string());
        it.next();
    }
    out
}

/// Where a technique's name stands as a word of a string: alone or before `:`, `@`, `-`…
fn names_a_technique(text: &str, names: &[&str]) -> Option<String> {
    for n in names {
        for (at, _) in text.match_indices(n) {
            let before = text[..at].chars().next_back();
            let after = text[at + n.len()..].chars().next();
            let word = |c: Option<char>| c.is_some_and(|c| c.is_alphanumeric() || c == '_');
            if !word(before) && !word(after) {
                return Some(n.to_string());
            }
        }
    }
    None
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// Benchmark subcommands named after the technique they study, by file, and their name as
/// their output files' prefix (and `bench suite`, which runs `bench layered` by that name).
const BENCH_NAMES: &[(&str, &str)] = &[
    ("bench/layered.rs", "layered"),
    ("bench/irregular.rs", "irregular"),
    ("bench/suite.rs", "layered"),
];

fn technique_names() -> Vec<&'static str> {
    manyshadows::Technique::all()
        .iter()
        .map(|t| t.name())
        // Names that are ordinary words of other options too are checked as constants only.
        .filter(|n| !["compute", "virtual"].contains(n))
        .collect()
}

#[test]
fn the_programs_name_no_technique_outside_the_registry() {
    let names = technique_names();
    let mut files = Vec::new();
    for dir in ["crates/cli/src", "crates/viewer/src", "crates/web/src"] {
        rust_files(&root().join(dir), &mut files);
    }
    assert!(
        files.len() > 10,
        "sources not found under {}",
        root().display()
    );
    let mut found = Vec::new();
    for f in &files {
        let src = std::fs::read_to_string(f).unwrap();
        for lit in string_literals(&src) {
            // Flags of a technique's own knobs (`--irregular-grid`), settings paths
            // (`irregular.hash`), and the benchmarks' subcommand and output names (`bench
            // irregular` writes `bench-irregular/irregular-*.png`) name options and commands,
            // not a choice of technique.
            let command = lit.starts_with("--")
                || lit.starts_with("bench-")
                || lit.starts_with("== bench ")
                || (lit.contains('.') && !lit.contains(' '))
                || BENCH_NAMES
                    .iter()
                    .any(|(file, name)| f.ends_with(file) && lit == *name);
            if command {
                continue;
            }
            if let Some(n) = names_a_technique(&lit, &names) {
                found.push(format!("{}: \"{lit}\" names {n}", f.display()));
            }
        }
        let code = strip_rust_comments(&src);
        for (at, _) in code.match_indices("Technique::") {
            let rest = &code[at + "Technique::".len()..];
            let ident: String = rest
                .chars()
                .take_while(|c| c.is_alphanumeric() || *c == '_')
                .collect();
            if ident.chars().next().is_some_and(|c| c.is_ascii_uppercase()) {
                found.push(format!("{}: Technique::{ident}", f.display()));
            }
        }
    }
    let page = std::fs::read_to_string(root().join("web/index.html")).unwrap();
    let markup: String = page
        .lines()
        .filter(|l| !l.trim_start().starts_with("//") && !l.contains("<!--"))
        .collect::<Vec<_>>()
        .join("\n");
    for n in manyshadows::Technique::all() {
        for form in [format!(">{n}<"), format!("'{n}'"), format!("\"{n}\"")] {
            if markup.contains(&form) {
                found.push(format!("web/index.html: {form}"));
            }
        }
    }
    assert!(
        found.is_empty(),
        "technique names outside the registry:\n{}",
        found.join("\n")
    );
}

/// The check above can fail: it finds a name in a literal, a constant, and page markup.
#[test]
fn the_check_finds_what_it_looks_for() {
    let names = technique_names();
    assert_eq!(
        names_a_technique("cube:traditional", &names).as_deref(),
        Some("traditional")
    );
    assert_eq!(
        names_a_technique("traditional@512", &names).as_deref(),
        Some("traditional")
    );
    assert_eq!(names_a_technique("traditionally", &names), None);
    let lits = string_literals("let a = \"layered\"; // \"gpu-driven\"\nlet b = \"x\";");
    assert_eq!(lits, ["layered", "x"]);
    assert!(strip_rust_comments("/// Technique::LAYERED\nx").trim() == "x");
}
