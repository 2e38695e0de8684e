//! Import floors: the modules of every crate in the workspace import each other without
//! circles, and so do their folders; the techniques never import one another.
//!
//! The check reads `crates/*/src` (beside this crate's manifest) and builds each crate's
//! module graph (`graph.rs`): a file is a module, a folder's `mod.rs` is the folder's module,
//! `lib.rs` (or `main.rs`) the root. An edge `a → b` is a `use crate::…` of, or a `crate::…`
//! path through, module `b` written in `a`. The root is a node like the others: what it
//! re-exports (`pub use`) are its imports, and a name used through it (`crate::Renderer`)
//! imports it, so a module that imports the facade instead of the defining module closes a
//! circle. Comments, string literals and `#[cfg(test)]` items are not imports (`reader.rs`).
//! A set of two or more modules that reach each other (a strongly connected component) is a
//! circle.
//!
//! Relative paths (`self::…`, `super::…`, a child module's name) are imports too: a folder's
//! `mod.rs` that its parts import from (`super::Shared`) while it dispatches to them is a
//! circle; what the parts share lives in a module of its own beside them.
//!
//! Folders are floors: the same graph between folders (a folder and its files are one unit,
//! a file directly in `src/` and the root are units of their own) has no circle either, so
//! each folder sits on one floor. The render crate's floors are printed, by folder and by
//! module.
//!
//! The techniques are read from the registry (`src/registry.rs`'s `TECHNIQUES`): every module
//! that declares a technique (`pub const INFO: TechniqueInfo`) is listed there, only the
//! registry (and the renderer, for one technique's own read-backs) imports a technique's
//! module, and no technique's home (an atlas technique's module, another technique's folder)
//! imports another's.
//!
//! The checker is tested on its own on synthetic crates at the end of this file, so a broken
//! checker cannot pass silently.

mod graph;
mod reader;

use std::collections::BTreeSet;
use std::path::Path;

use graph::{
    circles, circles_of, crate_graph, describe, floors, folder_graph, folder_modules, Graph, ROOT,
};

/// The render crate's registry module: the list of the technique declarations.
const REGISTRY: &str = "registry";
/// The modules that may import a technique's module: the registry, and the crate root, whose
/// facade reads what one technique alone keeps (the virtual maps' page pool and table, the
/// irregular maps' counters). The renderer names none.
const TECHNIQUE_IMPORTERS: [&str; 2] = [REGISTRY, ROOT];
/// The registry's file.
const REGISTRY_FILE: &str = "registry.rs";

// ---------------------------------------------------------------------------------------------
// The workspace.
// ---------------------------------------------------------------------------------------------

fn rust_files(dir: &Path, under: &Path, out: &mut Vec<(String, String)>) {
    let mut entries: Vec<_> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("reading {}: {e}", dir.display()))
        .map(|e| e.expect("directory entry").path())
        .collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            rust_files(&p, under, out);
        } else if p.extension().is_some_and(|e| e == "rs") {
            let rel = p.strip_prefix(under).expect("under src").to_string_lossy();
            let src = std::fs::read_to_string(&p)
                .unwrap_or_else(|e| panic!("reading {}: {e}", p.display()));
            out.push((rel.replace('\\', "/"), src));
        }
    }
}

/// One crate of the workspace, read.
struct Crate {
    name: String,
    /// `(path under src/, source)`.
    files: Vec<(String, String)>,
    /// Through `crate::` paths.
    graph: Graph,
    /// Through relative paths too.
    relative: Graph,
    /// Between folders (from `relative`).
    folders: Graph,
}

fn read_crate(name: String, files: Vec<(String, String)>) -> Crate {
    let graph = crate_graph(&files, false);
    let relative = crate_graph(&files, true);
    let paths: Vec<&str> = files.iter().map(|(p, _)| p.as_str()).collect();
    let folders = folder_graph(&relative, &folder_modules(&paths));
    Crate {
        name,
        files,
        graph,
        relative,
        folders,
    }
}

/// Every crate under `crates/`.
fn workspace() -> Vec<Crate> {
    let crates = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut dirs: Vec<_> = std::fs::read_dir(&crates)
        .expect("the crates folder")
        .map(|e| e.expect("directory entry").path())
        .filter(|p| p.join("src").is_dir())
        .collect();
    dirs.sort();
    dirs.iter()
        .map(|d| {
            let src = d.join("src");
            let mut files = Vec::new();
            rust_files(&src, &src, &mut files);
            let name = d.file_name().expect("crate folder").to_string_lossy();
            read_crate(name.into_owned(), files)
        })
        .collect()
}

fn render() -> Crate {
    workspace()
        .into_iter()
        .find(|c| c.name == "render")
        .unwrap_or_else(|| panic!("the render crate beside {}", env!("CARGO_MANIFEST_DIR")))
}

/// Every circle of `c`: between modules (through `crate::` paths, then through relative ones
/// too) and between folders, each described for a failure message.
fn crate_circles(c: &Crate) -> Vec<String> {
    let mut out = Vec::new();
    let found = circles_of(&c.graph);
    for circle in &found {
        out.push(format!("crate {}: {}", c.name, describe(circle, &c.graph)));
    }
    for circle in circles_of(&c.relative)
        .iter()
        .filter(|x| !found.contains(x))
    {
        out.push(format!(
            "crate {}, relative paths: {}",
            c.name,
            describe(circle, &c.relative)
        ));
    }
    for circle in circles_of(&c.folders) {
        out.push(format!(
            "crate {}, folders: {}",
            c.name,
            describe(&circle, &c.folders)
        ));
    }
    out
}

#[test]
fn no_import_circles_in_any_crate_between_modules_or_folders() {
    let crates = workspace();
    assert!(crates.iter().any(|c| c.name == "render"), "no render crate");
    let mut failures = Vec::new();
    for c in &crates {
        assert!(
            c.graph.contains_key(ROOT),
            "crate {}: its root is no node of the graph",
            c.name
        );
        let found = crate_circles(c);
        println!(
            "crate {}: {} modules, {} imports (with relative paths {}), {} folders; {} circles",
            c.name,
            c.graph.len(),
            c.graph.values().map(BTreeSet::len).sum::<usize>(),
            c.relative.values().map(BTreeSet::len).sum::<usize>(),
            c.folders.len(),
            found.len(),
        );
        if c.name == "render" && found.is_empty() {
            for (f, units) in floors(&c.folders).iter().enumerate() {
                println!("  folder floor {f}: {}", units.join(", "));
            }
            for (f, modules) in floors(&c.relative).iter().enumerate() {
                println!("  module floor {f}: {}", modules.join(", "));
            }
        }
        failures.extend(found);
    }
    assert!(
        failures.is_empty(),
        "import circles (a lower floor imports a higher one, or a module imports through the \
         crate root instead of the defining module; move the shared piece down):\n{}",
        failures.join("\n")
    );
}

/// The render crate's floors as intended, bottom up: each entry is one floor, its units the
/// folders (and files directly in `src/`) that stand on it. A unit imports only units of lower
/// floors, so two folders cannot swap floors unseen, and a new folder fails this test until
/// it is given its floor here (and in ARCHITECTURE.md, which lists the same order). A folder
/// of `shadows/` (a technique's) stands on the techniques' floor by `shadows::*`.
const DECLARED_FLOORS: &[&[&str]] = &[
    &["error"],
    &["gpu"],
    &["gpu_scene"],
    &["frame"],
    &["sampled"],
    &["shadows"],
    // Every technique's folder: a new kind of source stands here without an edit.
    &["shadows::*"],
    &["shading"],
    &["probes"],
    &["settings"],
    &["registry"],
    &["report"],
    &["renderer"],
    &[ROOT],
];

/// Where `unit` stands in [`DECLARED_FLOORS`]: named, or under a folder whose entry ends in
/// `::*` (its subfolders).
fn declared_floor(unit: &str) -> Option<usize> {
    DECLARED_FLOORS.iter().position(|f| {
        f.iter().any(|d| match d.strip_suffix("::*") {
            Some(parent) => unit
                .strip_prefix(parent)
                .and_then(|rest| rest.strip_prefix("::"))
                .is_some_and(|rest| !rest.is_empty() && !rest.contains("::")),
            None => *d == unit,
        })
    })
}

/// The imports of `folders` (a crate's folder graph) that do not go down the declared floors,
/// and the units the declaration does not place.
fn floor_violations(folders: &Graph) -> Vec<String> {
    let mut bad = Vec::new();
    for (from, edges) in folders {
        let Some(a) = declared_floor(from) else {
            bad.push(format!("{from} has no declared floor"));
            continue;
        };
        for to in edges {
            match declared_floor(to) {
                None => bad.push(format!("{to} has no declared floor")),
                Some(b) if b >= a => bad.push(format!(
                    "{from} (floor {a}) imports {to} (floor {b}): only lower floors may be imported"
                )),
                Some(_) => {}
            }
        }
    }
    for floor in DECLARED_FLOORS {
        for unit in floor.iter().filter(|u| !u.ends_with("::*")) {
            if !folders.contains_key(*unit) {
                bad.push(format!("the declared unit {unit} is not in the crate"));
            }
        }
    }
    bad.sort();
    bad.dedup();
    bad
}

#[test]
fn the_render_crate_keeps_its_declared_floors() {
    let render = render();
    let bad = floor_violations(&render.folders);
    assert!(
        bad.is_empty(),
        "the render crate's folders against DECLARED_FLOORS (bottom up: {:?}):\n{}",
        DECLARED_FLOORS,
        bad.join("\n")
    );
}

#[test]
fn checker_finds_a_swap_of_two_declared_floors() {
    // `frame` importing `shading` is a circle-free graph (so the circle check passes it), but
    // it puts frame above shading: the declared floors fail it.
    let mut folders: Graph = DECLARED_FLOORS
        .iter()
        .flat_map(|f| f.iter())
        .map(|u| u.replace("::*", "::vsm"))
        .map(|u| (u, BTreeSet::new()))
        .collect();
    folders
        .get_mut(ROOT)
        .expect("root")
        .extend(["renderer".to_string(), "error".to_string()]);
    assert!(
        floor_violations(&folders).is_empty(),
        "{:?}",
        floor_violations(&folders)
    );
    folders
        .get_mut("frame")
        .expect("frame")
        .insert("shading".to_string());
    assert!(circles_of(&folders).is_empty());
    let bad = floor_violations(&folders);
    assert!(
        bad.len() == 1 && bad[0].starts_with("frame (floor 3) imports shading"),
        "{bad:?}"
    );
    folders.insert("newcomer".to_string(), BTreeSet::new());
    assert!(floor_violations(&folders)
        .iter()
        .any(|b| b.contains("newcomer has no declared floor")));
    // A new technique's folder stands on the techniques' floor without an edit.
    assert_eq!(
        declared_floor("shadows::cones"),
        declared_floor("shadows::vsm")
    );
    assert_eq!(declared_floor("shadows::cones::deeper"), None);
}

/// The modules that declare a technique (`pub const INFO: TechniqueInfo`).
fn technique_modules(c: &Crate) -> BTreeSet<String> {
    c.files
        .iter()
        .filter(|(_, src)| {
            reader::strip_comments_and_literals(src).contains("pub const INFO: TechniqueInfo")
        })
        .map(|(p, _)| {
            p.strip_suffix(".rs")
                .expect("a Rust file")
                .trim_end_matches("/mod")
                .replace('/', "::")
        })
        .collect()
}

/// The modules the registry lists in `TECHNIQUES` (entries `&path::INFO`), resolved through
/// its `use` items.
fn registered(c: &Crate) -> Vec<String> {
    let (_, src) = c
        .files
        .iter()
        .find(|(p, _)| p == REGISTRY_FILE)
        .expect("the registry's file");
    let code = reader::strip_comments_and_literals(src);
    let start = code
        .find("TECHNIQUES: &[&TechniqueInfo] = &[")
        .expect("the registry's TECHNIQUES list");
    let list = &code[start..code[start..].find("];").expect("the list's end") + start];
    let uses = reader::refs(src).uses;
    list.split('&')
        .filter_map(|e| e.trim().trim_end_matches(',').strip_suffix("::INFO"))
        .map(|entry| {
            let mut segs = entry.split("::");
            let first = segs.next().expect("a path");
            let (_, item) = uses
                .iter()
                .find(|(_, u)| u.name.as_deref() == Some(first))
                .unwrap_or_else(|| panic!("the registry's entry {entry} is not imported"));
            let base = item.path.iter().skip_while(|s| *s == "crate").cloned();
            base.chain(segs.map(str::to_string))
                .collect::<Vec<_>>()
                .join("::")
        })
        .collect()
}

/// A technique's home: an atlas technique's own module (they share the atlas folder), or the
/// folder of any other technique's declaration.
fn home(technique: &str) -> String {
    match technique.rsplit_once("::") {
        Some(("shadows::atlas", _)) => technique.to_string(),
        Some((folder, _)) => folder.to_string(),
        None => technique.to_string(),
    }
}

/// Imports that break the technique rules in `graph`: only [`TECHNIQUE_IMPORTERS`] import a
/// technique's module, and no module in one technique's home imports another's home.
fn technique_imports(graph: &Graph, techniques: &BTreeSet<String>) -> Vec<String> {
    let homes: BTreeSet<String> = techniques.iter().map(|t| home(t)).collect();
    let home_of = |m: &str| {
        homes
            .iter()
            .find(|h| m == h.as_str() || m.starts_with(&format!("{h}::")))
            .cloned()
    };
    let mut bad = Vec::new();
    for (m, edges) in graph {
        for t in edges {
            if techniques.contains(t) && !TECHNIQUE_IMPORTERS.contains(&m.as_str()) {
                bad.push(format!("{m} imports the technique {t}"));
            } else if let (Some(a), Some(b)) = (home_of(m), home_of(t)) {
                if a != b {
                    bad.push(format!("{m} ({a}) imports {t} ({b})"));
                }
            }
        }
    }
    bad.sort();
    bad.dedup();
    bad
}

#[test]
fn techniques_come_from_the_registry_and_never_import_each_other() {
    let render = render();
    let declared = technique_modules(&render);
    let listed = registered(&render);
    assert!(
        listed.len() >= 8,
        "the registry lists {} techniques: {listed:?}",
        listed.len()
    );
    let listed_set: BTreeSet<String> = listed.iter().cloned().collect();
    assert_eq!(
        listed_set, declared,
        "every module declaring a technique is in the registry, and only those"
    );
    for t in &listed {
        assert!(
            render.relative.contains_key(t),
            "technique module {t} not found"
        );
    }
    let bad = technique_imports(&render.relative, &declared);
    assert!(
        bad.is_empty(),
        "techniques share code through modules they import, not through each other (only \
         {REGISTRY} names them):\n{}",
        bad.join("\n")
    );
}

// ---------------------------------------------------------------------------------------------
// The checker on synthetic crates.
// ---------------------------------------------------------------------------------------------

fn synthetic(files: &[(&str, &str)]) -> Crate {
    let files = files
        .iter()
        .map(|(p, s)| (p.to_string(), s.to_string()))
        .collect();
    read_crate("synthetic".into(), files)
}

#[test]
fn checker_finds_a_two_module_circle() {
    let found = circles(&[("a", vec!["b"]), ("b", vec!["a"]), ("c", vec!["a"])]);
    assert_eq!(found, vec![vec!["a".to_string(), "b".to_string()]]);
    let chain = circles(&[("a", vec!["b"]), ("b", vec!["c"]), ("c", vec![])]);
    assert!(chain.is_empty(), "{chain:?}");
    let three = circles(&[
        ("a", vec!["b"]),
        ("b", vec!["c"]),
        ("c", vec!["a"]),
        ("d", vec![]),
    ]);
    assert_eq!(three.len(), 1);
    assert_eq!(three[0], ["a", "b", "c"]);
}

#[test]
fn checker_reads_imports_like_rustc() {
    let files = [
        (
            "lib.rs",
            "pub mod a; pub mod b; pub mod c; pub mod f;\n\
             /// Old path.\n pub mod old { pub use crate::b::Thing; }\n\
             pub use c::Other;\n\
             #[derive(Debug, thiserror::Error)] pub enum E { #[error(\"{x} {{\")] X { x: u32 } }",
        ),
        // Comments, strings and test items are no imports.
        (
            "a.rs",
            "use crate::b::Thing; // crate::c::X\n\
             /* crate::c::Y */ fn f() -> &'static str { let _c = '{'; \"crate::c::Z\" }\n\
             #[cfg(test)]\nmod tests { use crate::c::Other; }",
        ),
        (
            "b.rs",
            "pub struct Thing; fn g() { let _ = crate::c::Other; }",
        ),
        (
            "c.rs",
            "pub struct Other; use super::f::{self, inner::{Deep as D}};",
        ),
        ("f/mod.rs", "pub mod inner; fn h() { inner::Deep; }"),
        (
            "f/inner.rs",
            "pub struct Deep; #[cfg(test)] mod t { use crate::a; }",
        ),
    ];
    let c = synthetic(&files);
    let edges = |g: &Graph, m: &str| g[m].iter().cloned().collect::<Vec<_>>();
    assert_eq!(edges(&c.relative, "a"), ["b"]);
    assert_eq!(edges(&c.relative, "b"), ["c"]);
    assert_eq!(edges(&c.relative, "c"), ["f", "f::inner"]);
    assert_eq!(edges(&c.relative, "f"), ["f::inner"]);
    assert!(edges(&c.relative, "f::inner").is_empty());
    // The root's re-exports and shims are its imports.
    assert_eq!(edges(&c.relative, ROOT), ["b", "c"]);
    assert!(crate_circles(&c).is_empty(), "{:?}", crate_circles(&c));
    // Through `crate::` paths only, the relative ones are no edges (but the root's).
    assert_eq!(edges(&c.graph, "b"), ["c"]);
    assert!(edges(&c.graph, "c").is_empty() && edges(&c.graph, "f").is_empty());
    // Folders: `f` and its file are one unit.
    assert_eq!(edges(&c.folders, "c"), ["f"]);
    assert!(!c.folders.contains_key("f::inner"));

    // A name used through the root (its re-export, or a shim module in it) imports the root,
    // which imports the defining module back: a circle.
    for through in ["crate::Other", "crate::old::Thing"] {
        let a = format!("fn f(_: {through}) {{}}");
        let c = synthetic(&[
            (
                "lib.rs",
                "pub mod a; pub mod c; pub mod b; pub use c::Other; pub mod old { pub use crate::b::Thing; }",
            ),
            ("a.rs", &a),
            ("b.rs", "pub struct Thing;"),
            ("c.rs", "pub struct Other; use crate::a::f;"),
        ]);
        let found = circles_of(&c.graph);
        assert_eq!(found.len(), 1, "{through}: {found:?}");
        assert!(found[0].contains(&ROOT.to_string()), "{through}: {found:?}");
        assert!(describe(&found[0], &c.graph).contains(&format!("a → {ROOT}")));
    }
}

/// Two folders that import each other are a circle even when their modules are not: the
/// upward import the floors test must catch.
#[test]
fn checker_finds_folders_that_import_each_other() {
    let files = [
        ("lib.rs", "pub mod low; pub mod high;"),
        ("low/mod.rs", "pub mod base; pub mod extra;"),
        ("low/base.rs", "pub struct Base;"),
        ("high/mod.rs", "pub mod top;"),
        ("high/top.rs", "use crate::low::base::Base; pub struct Top;"),
        ("low/extra.rs", "pub struct Extra;"),
    ];
    let c = synthetic(&files);
    assert!(crate_circles(&c).is_empty(), "{:?}", crate_circles(&c));
    // The root only declares the modules: it imports nothing.
    assert_eq!(floors(&c.folders), [vec![ROOT, "low"], vec!["high"]]);
    // One upward import from a module nothing in `high` imports: no module circle, a folder
    // circle.
    let mut upward = files;
    upward[5] = (
        "low/extra.rs",
        "use crate::high::top::Top; pub struct Extra;",
    );
    let c = synthetic(&upward);
    assert!(circles_of(&c.relative).is_empty());
    let found = crate_circles(&c);
    assert_eq!(found.len(), 1, "{found:?}");
    assert!(
        found[0].contains("folders: circle of 2 modules: high, low"),
        "{found:?}"
    );
}

#[test]
fn checker_catches_a_technique_importing_another() {
    let c = synthetic(&[
        ("lib.rs", "pub mod shadows; pub mod registry;"),
        (
            "shadows/mod.rs",
            "pub mod atlas; pub mod source; pub mod vsm;",
        ),
        (
            "shadows/atlas/mod.rs",
            "pub mod layered; pub mod traditional; pub mod shared;",
        ),
        (
            "shadows/source.rs",
            "use crate::shadows::atlas::layered::L;",
        ),
        ("shadows/atlas/shared.rs", "pub fn depth() {}"),
        ("shadows/atlas/traditional.rs", "use super::shared::depth;"),
        (
            "shadows/atlas/layered.rs",
            "use crate::shadows::atlas::traditional::T;",
        ),
        ("shadows/vsm/mod.rs", "pub mod pages; pub mod source;"),
        (
            "shadows/vsm/pages.rs",
            "use crate::shadows::atlas::shared::depth;",
        ),
        (
            "shadows/vsm/source.rs",
            "use crate::shadows::atlas::layered::L;",
        ),
        (
            "registry.rs",
            "use crate::shadows::atlas::{layered, traditional}; use crate::shadows::vsm;",
        ),
    ]);
    let techniques: BTreeSet<String> = [
        "shadows::atlas::layered",
        "shadows::atlas::traditional",
        "shadows::vsm::source",
    ]
    .into_iter()
    .map(String::from)
    .collect();
    assert_eq!(
        technique_imports(&c.relative, &techniques),
        [
            "shadows::atlas::layered imports the technique shadows::atlas::traditional",
            "shadows::source imports the technique shadows::atlas::layered",
            "shadows::vsm::source imports the technique shadows::atlas::layered",
        ]
    );
}

#[test]
fn checker_orders_floors() {
    let mut g = Graph::new();
    g.insert("top".into(), ["mid".to_string(), "low".to_string()].into());
    g.insert("mid".into(), ["low".to_string()].into());
    g.insert("low".into(), BTreeSet::new());
    g.insert("side".into(), ["low".to_string()].into());
    assert_eq!(floors(&g), [vec!["low"], vec!["mid", "side"], vec!["top"]]);
}
