//! One crate's module graph from its files, the circles in it ([`circles_of`]), its floors,
//! and the same graph between folders ([`folder_graph`]).

use std::collections::{BTreeMap, BTreeSet};

use crate::reader::{refs, Refs};

/// Module → the modules it imports.
pub type Graph = BTreeMap<String, BTreeSet<String>>;

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

/// The crate root (`lib.rs`, or `main.rs` without one) as a node: what it re-exports are its
/// imports, and a module that names something through it (`crate::Renderer` for
/// `crate::renderer::Renderer`) imports it. A crate whose root re-exports its modules (a
/// facade) has no circle only if its modules import the defining modules.
pub const ROOT: &str = "(root)";

struct CrateGraph {
    modules: BTreeSet<String>,
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

    /// The module an absolute path lands in: its longest prefix that is a file module, else
    /// the root (its own items, its inline modules and what it re-exports).
    fn module(&self, abs: &[String]) -> String {
        (1..=abs.len())
            .rev()
            .map(|k| abs[..k].join("::"))
            .find(|m| self.modules.contains(m))
            .unwrap_or_else(|| ROOT.to_string())
    }
}

/// The module graph of one crate from its files (`(path under src/, source)`): edges from
/// `crate::` paths, and with `relative` from `self::`, `super::` and child paths too. The root
/// is the node [`ROOT`].
pub fn crate_graph(files: &[(String, String)], relative: bool) -> Graph {
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
    let g = CrateGraph {
        modules: parsed
            .iter()
            .map(|(m, _)| m.clone())
            .filter(|m| !m.is_empty())
            .collect(),
    };
    let mut graph = Graph::new();
    for (m, r) in &parsed {
        let ms = split(m);
        let node = if m.is_empty() {
            ROOT.to_string()
        } else {
            m.clone()
        };
        let targets = r
            .uses
            .iter()
            .map(|(scope, u)| (scope, &u.path))
            .chain(r.paths.iter().map(|(scope, p)| (scope, p)));
        let edges = graph.entry(node.clone()).or_default();
        for (scope, path) in targets {
            // The root's re-exports name its children without `crate::`.
            if !relative && !m.is_empty() && path.first().is_none_or(|s| s != "crate") {
                continue;
            }
            if let Some(abs) = g.absolute(&ms, scope, path) {
                let target = g.module(&abs);
                if target != node {
                    edges.insert(target);
                }
            }
        }
    }
    graph
}

/// The folder a module lives in, as the unit of [`folder_graph`]: a folder's `mod.rs` and
/// every file in it are the folder (`shadows::atlas` for `shadows/atlas/layered.rs`); a file
/// directly in `src/` is a unit of its own, and so is the root.
pub fn folder_of(module: &str, folder_modules: &BTreeSet<String>) -> String {
    if module == ROOT || folder_modules.contains(module) {
        return module.to_string();
    }
    match module.rsplit_once("::") {
        Some((parent, _)) => parent.to_string(),
        None => module.to_string(),
    }
}

/// The modules that are folders (`dir/mod.rs`), from the crate's file paths under `src/`.
pub fn folder_modules(paths: &[&str]) -> BTreeSet<String> {
    paths
        .iter()
        .filter_map(|p| p.strip_suffix("/mod.rs"))
        .map(|d| d.replace('/', "::"))
        .collect()
}

/// `graph` between folders: an edge `a → b` where a module in folder `a` imports one in
/// folder `b`. A circle here is two folders importing each other, even without a circle of
/// modules: a folder that cannot be read as one floor.
pub fn folder_graph(graph: &Graph, folder_modules: &BTreeSet<String>) -> Graph {
    let mut out = Graph::new();
    for (m, edges) in graph {
        let from = folder_of(m, folder_modules);
        let entry = out.entry(from.clone()).or_default();
        for t in edges {
            let to = folder_of(t, folder_modules);
            if to != from {
                entry.insert(to);
            }
        }
    }
    out
}

/// The circles of `graph`: its strongly connected components of two or more modules
/// (Tarjan), each sorted, in sorted order.
pub fn circles(graph: &[(&str, Vec<&str>)]) -> Vec<Vec<String>> {
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

pub fn circles_of(graph: &Graph) -> Vec<Vec<String>> {
    let pairs: Vec<(&str, Vec<&str>)> = graph
        .iter()
        .map(|(m, e)| (m.as_str(), e.iter().map(String::as_str).collect()))
        .collect();
    circles(&pairs)
}

/// A circle for a failure message: its modules, and the imports that close it.
pub fn describe(circle: &[String], graph: &Graph) -> String {
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
pub fn floors(graph: &Graph) -> Vec<Vec<String>> {
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
