//! Import floors (issue 25): the modules of every crate in the workspace import each other
//! without circles, and the atlas techniques never import one another.
//!
//! The check reads `crates/*/src` (beside this crate's manifest) and builds each crate's
//! module graph: a file is a module, a folder's `mod.rs` is the folder's module, `lib.rs` (or
//! `main.rs`) the root. An edge `a → b` is a `use crate::…` of, or a `crate::…` path through,
//! module `b` written in `a`; a name the root re-exports (`pub use`, also inside the shim
//! modules written inline in `lib.rs`) counts as what it re-exports. Comments, string literals
//! and `#[cfg(test)]` items are not imports. The root is not a node: it declares every module
//! and holds the crate's error type, which every module may name. A set of two or more modules
//! that reach each other (a strongly connected component) is a circle.
//!
//! Relative paths (`self::…`, `super::…`, a child module's name) are imports too, in every
//! crate: a folder's `mod.rs` that its parts import from (`super::Shared`) while it dispatches
//! to them is a circle; what the parts share lives in a module of its own beside them
//! (`loaders/common.rs`, `builtin/options.rs`). The render crate's floors are printed.
//!
//! The checker is tested on its own on synthetic crates at the end of this file, so a broken
//! checker cannot pass silently.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// The atlas techniques (modules under `shadows/atlas/`). Only the registry creates them;
/// what they share lives in modules they import, never in each other.
const TECHNIQUES: [&str; 5] = [
    "traditional",
    "layered",
    "multiview",
    "gpu_driven",
    "compute",
];
/// The folder of the atlas techniques in the render crate.
const ATLAS: &str = "shadows::atlas";
/// The one module that imports the techniques: the list of their declarations.
const REGISTRY: &str = "shadows::registry";

/// Module → the modules it imports.
type Graph = BTreeMap<String, BTreeSet<String>>;

// ---------------------------------------------------------------------------------------------
// Reading Rust source: comments and literals out, tokens, `#[cfg(test)]` items out.
// ---------------------------------------------------------------------------------------------

fn is_ident_char(c: char) -> bool {
    c.is_alphanumeric() || c == '_'
}

/// The source without comments, with every string and character literal emptied and raw
/// identifiers (`r#virtual`) written plainly.
fn strip_comments_and_literals(src: &str) -> String {
    let c: Vec<char> = src.chars().collect();
    let n = c.len();
    let at = |i: usize| c.get(i).copied().unwrap_or('\0');
    let mut out = String::with_capacity(n);
    let mut i = 0;
    while i < n {
        let ch = c[i];
        let prev_ident = i > 0 && is_ident_char(c[i - 1]);
        if ch == '/' && at(i + 1) == '/' {
            while i < n && c[i] != '\n' {
                i += 1;
            }
        } else if ch == '/' && at(i + 1) == '*' {
            let mut depth = 0;
            while i < n {
                if c[i] == '/' && at(i + 1) == '*' {
                    depth += 1;
                    i += 2;
                } else if c[i] == '*' && at(i + 1) == '/' {
                    depth -= 1;
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    i += 1;
                }
            }
            out.push(' ');
        } else if ch == 'r' && !prev_ident && (at(i + 1) == '#' || at(i + 1) == '"') {
            let mut j = i + 1;
            let mut hashes = 0;
            while at(j) == '#' {
                hashes += 1;
                j += 1;
            }
            if at(j) == '"' {
                // Raw string: ends at a quote followed by as many hashes.
                j += 1;
                while j < n {
                    if c[j] == '"' && (1..=hashes).all(|k| at(j + k) == '#') {
                        j += 1 + hashes;
                        break;
                    }
                    j += 1;
                }
                out.push_str("\"\"");
                i = j;
            } else if hashes == 1 && is_ident_char(at(j)) {
                // Raw identifier: the name without `r#`.
                i = j;
            } else {
                out.push(ch);
                i += 1;
            }
        } else if ch == 'b' && !prev_ident && at(i + 1) == '"' {
            i += 1; // a byte string: the string below
        } else if ch == '"' {
            i += 1;
            while i < n && c[i] != '"' {
                i += if c[i] == '\\' { 2 } else { 1 };
            }
            i += 1;
            out.push_str("\"\"");
        } else if ch == '\'' {
            if at(i + 1) == '\\' {
                // Escaped character literal: up to the closing quote.
                let mut j = i + 2;
                while j < n && c[j] != '\'' {
                    j += 1;
                }
                i = j + 1;
                out.push_str("' '");
            } else if at(i + 2) == '\'' {
                i += 3;
                out.push_str("' '");
            } else {
                out.push(ch); // a lifetime
                i += 1;
            }
        } else {
            out.push(ch);
            i += 1;
        }
    }
    out
}

/// Identifiers, `::`, and single punctuation characters.
fn tokenize(code: &str) -> Vec<String> {
    let c: Vec<char> = code.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < c.len() {
        if is_ident_char(c[i]) {
            let start = i;
            while i < c.len() && is_ident_char(c[i]) {
                i += 1;
            }
            out.push(c[start..i].iter().collect());
        } else if c[i] == ':' && c.get(i + 1) == Some(&':') {
            out.push("::".into());
            i += 2;
        } else {
            if !c[i].is_whitespace() {
                out.push(c[i].to_string());
            }
            i += 1;
        }
    }
    out
}

fn is_ident(t: &str) -> bool {
    t.chars()
        .next()
        .is_some_and(|c| c.is_alphabetic() || c == '_')
}

/// Index just past the group that opens at `i` (`{`, `(` or `[`), nesting counted.
fn skip_group(t: &[String], i: usize) -> usize {
    let (open, close) = match t[i].as_str() {
        "{" => ("{", "}"),
        "(" => ("(", ")"),
        _ => ("[", "]"),
    };
    let mut depth = 0;
    let mut j = i;
    while j < t.len() {
        if t[j] == open {
            depth += 1;
        } else if t[j] == close {
            depth -= 1;
            if depth == 0 {
                return j + 1;
            }
        }
        j += 1;
    }
    t.len()
}

/// Removes every item under `#[cfg(test)]`; returns the remaining tokens and the names of
/// file modules declared test-only (`#[cfg(test)] mod name;`).
fn strip_test_items(t: Vec<String>) -> (Vec<String>, Vec<String>) {
    const ATTR: [&str; 7] = ["#", "[", "cfg", "(", "test", ")", "]"];
    let mut out = Vec::with_capacity(t.len());
    let mut test_modules = Vec::new();
    let mut i = 0;
    while i < t.len() {
        if t.len() - i < ATTR.len() || t[i..i + ATTR.len()].iter().zip(ATTR).any(|(a, b)| a != b) {
            out.push(t[i].clone());
            i += 1;
            continue;
        }
        let mut j = i + ATTR.len();
        // Further attributes of the same item.
        while j + 1 < t.len() && t[j] == "#" && t[j + 1] == "[" {
            j = skip_group(&t, j + 1);
        }
        let item_start = j;
        // The item ends at a `;` outside brackets, or with its first `{ … }` (and a `;` after
        // it, as in `use a::{b, c};`).
        while j < t.len() {
            match t[j].as_str() {
                "(" | "[" => j = skip_group(&t, j),
                "{" => {
                    j = skip_group(&t, j);
                    if t.get(j).is_some_and(|s| s == ";") {
                        j += 1;
                    }
                    break;
                }
                ";" => {
                    j += 1;
                    break;
                }
                _ => j += 1,
            }
        }
        let item = &t[item_start..j];
        if let Some(k) = item.iter().position(|s| s == "mod") {
            if item.len() == k + 3 && item[k + 2] == ";" {
                test_modules.push(item[k + 1].clone());
            }
        }
        i = j;
    }
    (out, test_modules)
}

/// One name a `use` brings in: its path, the name it is known by (`None` for a glob).
#[derive(Debug)]
struct UseItem {
    path: Vec<String>,
    name: Option<String>,
}

/// The items of the use tree in `t` (the tokens between `use` and `;`).
fn parse_use_tree(t: &[String], pos: &mut usize, prefix: Vec<String>, out: &mut Vec<UseItem>) {
    let mut path = prefix;
    while *pos < t.len() {
        let tok = t[*pos].as_str();
        match tok {
            "::" => *pos += 1, // a leading `::`
            "{" => {
                *pos += 1;
                while *pos < t.len() && t[*pos] != "}" {
                    parse_use_tree(t, pos, path.clone(), out);
                    if t.get(*pos).is_some_and(|s| s == ",") {
                        *pos += 1;
                    }
                }
                *pos += 1;
                return;
            }
            "*" => {
                *pos += 1;
                out.push(UseItem { path, name: None });
                return;
            }
            _ if is_ident(tok) => {
                *pos += 1;
                if tok != "self" {
                    path.push(tok.to_string());
                }
                if t.get(*pos).is_some_and(|s| s == "::") {
                    *pos += 1;
                    continue;
                }
                let mut name = path.last().cloned();
                if t.get(*pos).is_some_and(|s| s == "as") {
                    name = t.get(*pos + 1).cloned();
                    *pos += 2;
                }
                out.push(UseItem { path, name });
                return;
            }
            _ => {
                *pos += 1;
                return;
            }
        }
    }
}

/// What one file refers to.
#[derive(Debug, Default)]
struct Refs {
    /// `use` items, each with the inline modules (`mod x { … }`) it is written in.
    uses: Vec<(Vec<String>, UseItem)>,
    /// Paths of two or more segments outside `use`, with their inline modules.
    paths: Vec<(Vec<String>, Vec<String>)>,
    /// File modules declared under `#[cfg(test)]`.
    test_modules: Vec<String>,
}

fn refs(src: &str) -> Refs {
    let (t, test_modules) = strip_test_items(tokenize(&strip_comments_and_literals(src)));
    let mut r = Refs {
        test_modules,
        ..Default::default()
    };
    let mut scope: Vec<(String, usize)> = Vec::new();
    let mut depth = 0usize;
    let mut i = 0;
    while i < t.len() {
        let tok = t[i].as_str();
        let names = |scope: &[(String, usize)]| scope.iter().map(|s| s.0.clone()).collect();
        if tok == "mod" && t.get(i + 2).is_some_and(|s| s == "{") && is_ident(&t[i + 1]) {
            scope.push((t[i + 1].clone(), depth));
            depth += 1;
            i += 3;
        } else if tok == "{" {
            depth += 1;
            i += 1;
        } else if tok == "}" {
            depth = depth.saturating_sub(1);
            if scope.last().is_some_and(|s| s.1 == depth) {
                scope.pop();
            }
            i += 1;
        } else if tok == "use" {
            let end = (i..t.len()).find(|&j| t[j] == ";").unwrap_or(t.len());
            let mut items = Vec::new();
            let mut pos = 0;
            parse_use_tree(&t[i + 1..end], &mut pos, Vec::new(), &mut items);
            let here: Vec<String> = names(&scope);
            r.uses.extend(items.into_iter().map(|u| (here.clone(), u)));
            i = end + 1;
        } else if is_ident(tok)
            && (i == 0 || t[i - 1] != "::")
            && t.get(i + 1).is_some_and(|s| s == "::")
            && t.get(i + 2).is_some_and(|s| is_ident(s))
        {
            let mut segs = vec![tok.to_string()];
            let mut j = i;
            while t.get(j + 1).is_some_and(|s| s == "::")
                && t.get(j + 2).is_some_and(|s| is_ident(s))
            {
                segs.push(t[j + 2].clone());
                j += 2;
            }
            r.paths.push((names(&scope), segs));
            i = j + 1;
        } else {
            i += 1;
        }
    }
    r
}

// ---------------------------------------------------------------------------------------------
// One crate's module graph.
// ---------------------------------------------------------------------------------------------

fn split(m: &str) -> Vec<String> {
    if m.is_empty() {
        Vec::new()
    } else {
        m.split("::").map(str::to_string).collect()
    }
}

/// The module a file under `src/` is (`""` for the root); `None` for files that are no
/// module of the library or binary (`src/bin/…`, `main.rs` beside a `lib.rs`).
fn module_of(rel: &str, has_lib: bool) -> Option<String> {
    let rel = rel.strip_suffix(".rs")?;
    let parts: Vec<&str> = rel.split('/').collect();
    match parts.as_slice() {
        ["lib"] => Some(String::new()),
        ["main"] => (!has_lib).then(String::new),
        ["bin", ..] => None,
        [dirs @ .., "mod"] => Some(dirs.join("::")),
        _ => Some(parts.join("::")),
    }
}

struct CrateGraph {
    modules: BTreeSet<String>,
    /// Names the root re-exports: path from the root (`shadow::ShadowInput`) → its target.
    aliases: BTreeMap<String, Vec<String>>,
}

impl CrateGraph {
    /// `segs` written in file module `m` inside its inline modules `scope`, as a path from
    /// the crate root; `None` for paths into other crates and local items.
    fn absolute(&self, m: &[String], scope: &[String], segs: &[String]) -> Option<Vec<String>> {
        let here: Vec<String> = m.iter().chain(scope).cloned().collect();
        let first = segs.first()?.as_str();
        match first {
            "crate" => Some(segs[1..].to_vec()),
            "self" => Some(here.into_iter().chain(segs[1..].iter().cloned()).collect()),
            "super" => {
                let mut base = here;
                let mut k = 0;
                while segs.get(k).is_some_and(|s| s == "super") {
                    base.pop()?;
                    k += 1;
                }
                Some(base.into_iter().chain(segs[k..].iter().cloned()).collect())
            }
            _ => {
                let child: Vec<String> = m.iter().cloned().chain([first.to_string()]).collect();
                (scope.is_empty() && self.modules.contains(&child.join("::")))
                    .then(|| m.iter().chain(segs).cloned().collect())
            }
        }
    }

    /// The module an absolute path lands in: its longest prefix that is a module, else
    /// through the root's re-exports; `""` for the root's own items.
    fn module(&self, abs: &[String], hops: usize) -> String {
        for k in (1..=abs.len()).rev() {
            let m = abs[..k].join("::");
            if self.modules.contains(&m) {
                return m;
            }
        }
        if hops < 8 {
            for k in (1..=abs.len()).rev() {
                if let Some(target) = self.aliases.get(&abs[..k].join("::")) {
                    let next: Vec<String> = target.iter().chain(&abs[k..]).cloned().collect();
                    return self.module(&next, hops + 1);
                }
            }
        }
        String::new()
    }
}

/// The module graph of one crate from its files (`(path under src/, source)`): edges from
/// `crate::` paths, and with `relative` from `self::`, `super::` and child paths too.
fn crate_graph(files: &[(String, String)], relative: bool) -> Graph {
    let has_lib = files.iter().any(|(p, _)| p == "lib.rs");
    let parsed: Vec<(String, Refs)> = files
        .iter()
        .filter_map(|(p, src)| Some((module_of(p, has_lib)?, refs(src))))
        .collect();
    // Test-only file modules (and what is under them) are left out.
    let test_only: BTreeSet<String> = parsed
        .iter()
        .flat_map(|(m, r)| {
            r.test_modules.iter().map(move |t| {
                if m.is_empty() {
                    t.clone()
                } else {
                    format!("{m}::{t}")
                }
            })
        })
        .collect();
    let excluded = |m: &str| {
        test_only
            .iter()
            .any(|t| m == t || m.starts_with(&format!("{t}::")))
    };
    let parsed: Vec<(String, Refs)> = parsed.into_iter().filter(|(m, _)| !excluded(m)).collect();
    let mut g = CrateGraph {
        modules: parsed.iter().map(|(m, _)| m.clone()).collect(),
        aliases: BTreeMap::new(),
    };
    if let Some((_, root)) = parsed.iter().find(|(m, _)| m.is_empty()) {
        for (scope, u) in &root.uses {
            let (Some(name), Some(target)) = (&u.name, g.absolute(&[], scope, &u.path)) else {
                continue;
            };
            let key: Vec<String> = scope.iter().cloned().chain([name.clone()]).collect();
            g.aliases.insert(key.join("::"), target);
        }
    }
    let mut graph = Graph::new();
    for (m, r) in &parsed {
        if m.is_empty() {
            continue;
        }
        let ms = split(m);
        let targets = r
            .uses
            .iter()
            .map(|(scope, u)| (scope, &u.path))
            .chain(r.paths.iter().map(|(scope, p)| (scope, p)));
        let edges = graph.entry(m.clone()).or_default();
        for (scope, path) in targets {
            if !relative && path.first().is_none_or(|s| s != "crate") {
                continue;
            }
            if let Some(abs) = g.absolute(&ms, scope, path) {
                let target = g.module(&abs, 0);
                if !target.is_empty() && target != *m {
                    edges.insert(target);
                }
            }
        }
    }
    graph
}

/// The circles of `graph`: its strongly connected components of two or more modules
/// (Tarjan), each sorted, in sorted order.
fn circles(graph: &[(&str, Vec<&str>)]) -> Vec<Vec<String>> {
    struct Tarjan<'g> {
        edges: BTreeMap<&'g str, Vec<&'g str>>,
        index: BTreeMap<&'g str, usize>,
        low: BTreeMap<&'g str, usize>,
        stack: Vec<&'g str>,
        on_stack: BTreeSet<&'g str>,
        out: Vec<Vec<String>>,
    }
    impl<'g> Tarjan<'g> {
        fn visit(&mut self, v: &'g str) {
            let i = self.index.len();
            self.index.insert(v, i);
            self.low.insert(v, i);
            self.stack.push(v);
            self.on_stack.insert(v);
            for w in self.edges.get(v).cloned().unwrap_or_default() {
                if !self.index.contains_key(w) {
                    self.visit(w);
                    let lw = self.low[w];
                    let lv = self.low.get_mut(v).unwrap();
                    *lv = (*lv).min(lw);
                } else if self.on_stack.contains(w) {
                    let iw = self.index[w];
                    let lv = self.low.get_mut(v).unwrap();
                    *lv = (*lv).min(iw);
                }
            }
            if self.low[v] == self.index[v] {
                let mut component = Vec::new();
                while let Some(w) = self.stack.pop() {
                    self.on_stack.remove(w);
                    component.push(w.to_string());
                    if w == v {
                        break;
                    }
                }
                if component.len() > 1 {
                    component.sort();
                    self.out.push(component);
                }
            }
        }
    }
    let mut t = Tarjan {
        edges: graph.iter().map(|(m, e)| (*m, e.clone())).collect(),
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        on_stack: BTreeSet::new(),
        out: Vec::new(),
    };
    let nodes: BTreeSet<&str> = graph
        .iter()
        .flat_map(|(m, e)| std::iter::once(*m).chain(e.iter().copied()))
        .collect();
    for v in nodes {
        if !t.index.contains_key(v) {
            t.visit(v);
        }
    }
    t.out.sort();
    t.out
}

fn circles_of(graph: &Graph) -> Vec<Vec<String>> {
    let pairs: Vec<(&str, Vec<&str>)> = graph
        .iter()
        .map(|(m, e)| (m.as_str(), e.iter().map(String::as_str).collect()))
        .collect();
    circles(&pairs)
}

/// A circle for a failure message: its modules, and the imports that close it.
fn describe(circle: &[String], graph: &Graph) -> String {
    let inside: BTreeSet<&String> = circle.iter().collect();
    let edges: Vec<String> = circle
        .iter()
        .flat_map(|m| {
            graph[m]
                .iter()
                .filter(|t| inside.contains(t))
                .map(move |t| format!("{m} → {t}"))
        })
        .collect();
    format!(
        "circle of {} modules: {}\n    imports: {}",
        circle.len(),
        circle.join(", "),
        edges.join(", ")
    )
}

/// The modules of an acyclic graph by floor: a module's floor is one above the highest floor
/// it imports (0 for modules that import none).
fn floors(graph: &Graph) -> Vec<Vec<String>> {
    fn floor(m: &str, graph: &Graph, memo: &mut BTreeMap<String, usize>) -> usize {
        if let Some(&f) = memo.get(m) {
            return f;
        }
        memo.insert(m.to_string(), 0); // a circle (reported elsewhere) ends here
        let f = graph
            .get(m)
            .map(|e| {
                e.iter()
                    .map(|t| floor(t, graph, memo) + 1)
                    .max()
                    .unwrap_or(0)
            })
            .unwrap_or(0);
        memo.insert(m.to_string(), f);
        f
    }
    let mut memo = BTreeMap::new();
    let mut out: Vec<Vec<String>> = Vec::new();
    for m in graph.keys() {
        let f = floor(m, graph, &mut memo);
        if out.len() <= f {
            out.resize(f + 1, Vec::new());
        }
        out[f].push(m.clone());
    }
    out
}

/// Modules that import an atlas technique they may not: a technique importing another
/// technique, or anything but the registry (`shadows::registry`) importing a technique.
fn technique_imports(graph: &Graph) -> Vec<String> {
    let technique = |m: &str| TECHNIQUES.iter().any(|t| m == format!("{ATLAS}::{t}"));
    let mut bad = Vec::new();
    for (m, edges) in graph {
        if m == REGISTRY {
            continue;
        }
        for t in edges.iter().filter(|t| technique(t)) {
            bad.push(format!("{m} imports {t}"));
        }
    }
    bad
}

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

/// Every crate under `crates/` with its module graphs: through `crate::` paths, and through
/// relative paths too.
fn workspace() -> Vec<(String, Graph, Graph)> {
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
            let name = d
                .file_name()
                .expect("crate folder")
                .to_string_lossy()
                .into_owned();
            (name, crate_graph(&files, false), crate_graph(&files, true))
        })
        .collect()
}

#[test]
fn no_import_circles_in_any_crate() {
    let crates = workspace();
    assert!(
        crates.iter().any(|(name, ..)| name == "render"),
        "the render crate was not found beside {}",
        env!("CARGO_MANIFEST_DIR")
    );
    let mut failures = Vec::new();
    for (name, graph, relative) in &crates {
        let found = circles_of(graph);
        let imports: usize = graph.values().map(BTreeSet::len).sum();
        let with_relative = circles_of(relative);
        println!(
            "crate {name}: {} modules, {imports} imports, {} circles; with relative paths {} \
             imports, {} circles",
            graph.len() + 1,
            found.len(),
            relative.values().map(BTreeSet::len).sum::<usize>(),
            with_relative.len(),
        );
        for c in &found {
            failures.push(format!("crate {name}: {}", describe(c, graph)));
        }
        if name == "render" && with_relative.is_empty() {
            for (f, modules) in floors(relative).iter().enumerate() {
                println!("  floor {f}: {}", modules.join(", "));
            }
        }
        for c in with_relative.iter().filter(|c| !found.contains(c)) {
            failures.push(format!(
                "crate {name}, relative paths: {}",
                describe(c, relative)
            ));
        }
    }
    assert!(
        failures.is_empty(),
        "import circles (a lower floor imports a higher one; move the shared piece down):\n{}",
        failures.join("\n")
    );
}

#[test]
fn atlas_techniques_never_import_each_other() {
    let crates = workspace();
    let (_, _, render) = crates
        .iter()
        .find(|(name, ..)| name == "render")
        .expect("the render crate");
    for t in TECHNIQUES {
        let m = format!("{ATLAS}::{t}");
        assert!(render.contains_key(&m), "technique module {m} not found");
    }
    assert!(render.contains_key(REGISTRY), "{REGISTRY} not found");
    let bad = technique_imports(render);
    assert!(
        bad.is_empty(),
        "atlas techniques share code through modules they import, not through each other \
         (only {REGISTRY} names them):\n{}",
        bad.join("\n")
    );
}

// ---------------------------------------------------------------------------------------------
// The checker on synthetic crates.
// ---------------------------------------------------------------------------------------------

fn synthetic(files: &[(&str, &str)], relative: bool) -> Graph {
    let files: Vec<(String, String)> = files
        .iter()
        .map(|(p, s)| (p.to_string(), s.to_string()))
        .collect();
    crate_graph(&files, relative)
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
        // A path through a root shim counts as its target; comments, strings and test items
        // are no imports.
        (
            "a.rs",
            "use crate::old::Thing; // crate::c::X\n\
             /* crate::c::Y */ fn f() -> &'static str { let _c = '{'; \"crate::c::Z\" }\n\
             #[cfg(test)]\nmod tests { use crate::c::Other; }",
        ),
        ("b.rs", "pub struct Thing; fn g() { let _ = crate::Other; }"),
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
    let g = synthetic(&files, true);
    let edges = |m: &str| g[m].iter().cloned().collect::<Vec<_>>();
    assert_eq!(edges("a"), ["b"]);
    assert_eq!(edges("b"), ["c"], "crate::Other is c's");
    assert_eq!(edges("c"), ["f", "f::inner"]);
    assert_eq!(edges("f"), ["f::inner"]);
    assert!(edges("f::inner").is_empty());
    assert!(circles_of(&g).is_empty());
    // Through `crate::` paths only, the relative ones are no edges.
    let g = synthetic(&files, false);
    let edges = |m: &str| g[m].iter().cloned().collect::<Vec<_>>();
    assert_eq!(edges("b"), ["c"]);
    assert!(edges("c").is_empty() && edges("f").is_empty());

    // One import back closes a circle, found through the shim module.
    let g = synthetic(
        &[
            (
                "lib.rs",
                "pub mod a; pub mod b; pub mod old { pub use crate::a::A; }",
            ),
            ("a.rs", "pub struct A; use crate::b::B;"),
            ("b.rs", "pub struct B; fn f(_: crate::old::A) {}"),
        ],
        false,
    );
    assert_eq!(circles_of(&g), vec![vec!["a".to_string(), "b".to_string()]]);
    assert!(describe(&circles_of(&g)[0], &g).contains("a → b, b → a"));
}

#[test]
fn checker_catches_a_technique_importing_another() {
    let g = synthetic(
        &[
            ("lib.rs", "pub mod shadows;"),
            (
                "shadows/mod.rs",
                "pub mod atlas; pub mod registry; pub mod source;",
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
            (
                "shadows/registry.rs",
                "use crate::shadows::atlas::{layered, traditional};",
            ),
        ],
        true,
    );
    assert_eq!(
        technique_imports(&g),
        [
            "shadows::atlas::layered imports shadows::atlas::traditional",
            "shadows::source imports shadows::atlas::layered"
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
