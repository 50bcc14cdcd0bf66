//! The layers of ARCHITECTURE.md, checked on the source: between the workspace's crates Cargo
//! refuses an import that points up; inside each crate this test reads every module's paths
//! (`use` trees, and `crate::` / `super::` / `self::` paths in code, test code included) and
//! fails on
//!
//! - an import against the layers: a top-level module may use only the modules of lower layers
//!   (and the leaves every layer may use), never one of its own layer or above;
//! - an import cycle between modules: `a` uses `b` and `b` uses `a`, directly or through others.
//!   A module's use of its own submodules (re-exports, declaring them) is not an edge here: a
//!   child that uses its parent's items and a parent that re-exports the child are one unit.
//!
//! The reader is small on purpose: comments and string literals are blanked, then paths are
//! read token by token. A path is resolved to the longest prefix that names a module file.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// A module path inside one crate, e.g. `["sim", "time_driven", "engine"]`; empty for the root.
type ModPath = Vec<String>;

/// The layers of one crate: top-level module -> layer (lower uses nothing above it); modules in
/// `leaves` may be used by any layer and use nothing of the crate themselves.
struct Layers {
    crate_dir: &'static str,
    layer: &'static [(&'static str, u32)],
    leaves: &'static [&'static str],
}

const CORE: Layers = Layers {
    crate_dir: "crates/core/src",
    layer: &[("physics", 0), ("scene", 1), ("sim", 2), ("observe", 3)],
    leaves: &[],
};

const APP: Layers = Layers {
    crate_dir: "src",
    layer: &[
        ("sweep", 0),
        ("store", 1),
        ("run", 2),
        ("boundary", 2),
        ("cluster", 2),
        ("refine", 3),
        ("report", 3),
        ("cli", 4),
    ],
    leaves: &["output", "terminal"],
};

/// The bench crate has no layers of its own (every figure is a leaf of the binary), but no
/// cycles either.
const BENCH: Layers = Layers {
    crate_dir: "crates/bench/src",
    layer: &[],
    leaves: &[],
};

fn workspace_root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Every `.rs` file under `src`, by module path.
fn module_files(src: &Path) -> BTreeMap<ModPath, PathBuf> {
    let mut out = BTreeMap::new();
    let mut stack = vec![src.to_path_buf()];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).expect("source directory") {
            let p = entry.expect("entry").path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|e| e == "rs") {
                let rel = p.strip_prefix(src).unwrap().with_extension("");
                let mut m: ModPath = rel.iter().map(|s| s.to_string_lossy().into()).collect();
                if matches!(m.last().map(String::as_str), Some("mod" | "lib" | "main")) {
                    m.pop();
                }
                out.insert(m, p);
            }
        }
    }
    out
}

/// The text with comments, string and character literals replaced by spaces (lifetimes and
/// labels kept), so that paths inside them are not read.
fn blank_comments_and_literals(text: &str) -> String {
    let b: Vec<char> = text.chars().collect();
    let mut out = String::with_capacity(text.len());
    let mut i = 0;
    while i < b.len() {
        let c = b[i];
        let next = b.get(i + 1).copied();
        if c == '/' && next == Some('/') {
            while i < b.len() && b[i] != '\n' {
                i += 1;
            }
        } else if c == '/' && next == Some('*') {
            let mut depth = 0;
            while i < b.len() {
                if b[i] == '/' && b.get(i + 1) == Some(&'*') {
                    depth += 1;
                    i += 2;
                } else if b[i] == '*' && b.get(i + 1) == Some(&'/') {
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
        } else if c == 'r' && (next == Some('"') || next == Some('#')) && !ident_before(&b, i) {
            // Raw string: r"..." or r#"..."#.
            let mut j = i + 1;
            let mut hashes = 0;
            while b.get(j) == Some(&'#') {
                hashes += 1;
                j += 1;
            }
            if b.get(j) != Some(&'"') {
                out.push(c);
                i += 1;
                continue;
            }
            j += 1;
            'raw: while j < b.len() {
                if b[j] == '"' && (0..hashes).all(|k| b.get(j + 1 + k) == Some(&'#')) {
                    j += 1 + hashes;
                    break 'raw;
                }
                j += 1;
            }
            i = j;
            out.push(' ');
        } else if c == '"' {
            i += 1;
            while i < b.len() && b[i] != '"' {
                if b[i] == '\\' {
                    i += 1;
                }
                i += 1;
            }
            i += 1;
            out.push(' ');
        } else if c == '\'' && is_char_literal(&b, i) {
            i += 1;
            while i < b.len() && b[i] != '\'' {
                if b[i] == '\\' {
                    i += 1;
                }
                i += 1;
            }
            i += 1;
            out.push(' ');
        } else {
            out.push(c);
            i += 1;
        }
    }
    out
}

fn ident_before(b: &[char], i: usize) -> bool {
    i > 0 && (b[i - 1].is_alphanumeric() || b[i - 1] == '_')
}

/// `'x'` or `'\n'` rather than a lifetime `'a`.
fn is_char_literal(b: &[char], i: usize) -> bool {
    matches!(
        (b.get(i + 1), b.get(i + 2)),
        (Some('\\'), _) | (Some(_), Some('\''))
    )
}

/// Tokens: identifiers, `::`, and single punctuation characters.
fn tokens(text: &str) -> Vec<String> {
    let b: Vec<char> = text.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        let c = b[i];
        if c.is_alphanumeric() || c == '_' {
            let start = i;
            while i < b.len() && (b[i].is_alphanumeric() || b[i] == '_') {
                i += 1;
            }
            out.push(b[start..i].iter().collect());
        } else if c == ':' && b.get(i + 1) == Some(&':') {
            out.push("::".into());
            i += 2;
        } else if c.is_whitespace() {
            i += 1;
        } else {
            out.push(c.to_string());
            i += 1;
        }
    }
    out
}

/// The paths of a `use` tree starting at `toks[*i]`, each with `prefix` in front; stops after
/// the tree (at `;`, `,` or `}` of the enclosing group, not consumed).
fn use_tree(toks: &[String], i: &mut usize, prefix: &[String], out: &mut Vec<Vec<String>>) {
    let mut path = prefix.to_vec();
    while *i < toks.len() {
        let t = toks[*i].as_str();
        match t {
            "::" => *i += 1,
            "{" => {
                *i += 1;
                loop {
                    use_tree(toks, i, &path, out);
                    match toks.get(*i).map(String::as_str) {
                        Some(",") => *i += 1,
                        Some("}") => {
                            *i += 1;
                            break;
                        }
                        _ => break,
                    }
                }
                return;
            }
            ";" | "," | "}" => break,
            "as" => {
                *i += 2;
                break;
            }
            "*" => {
                *i += 1;
                break;
            }
            _ => {
                path.push(t.to_string());
                *i += 1;
            }
        }
    }
    out.push(path);
}

/// Every path the module's text names that may point into the crate (`crate::`, `super::`,
/// `self::` paths, and the paths of `use` trees), each with the inline modules (`mod tests {`)
/// it sits in.
fn paths_in(text: &str) -> Vec<(Vec<String>, Vec<String>)> {
    let toks = tokens(&blank_comments_and_literals(text));
    let mut out = Vec::new();
    let mut inline: Vec<(String, usize)> = Vec::new();
    let mut depth = 0usize;
    let here = |inline: &[(String, usize)]| inline.iter().map(|(n, _)| n.clone()).collect();
    let mut i = 0;
    while i < toks.len() {
        let t = toks[i].as_str();
        match t {
            "{" => depth += 1,
            "}" => {
                depth -= 1;
                if inline.last().is_some_and(|&(_, d)| d > depth) {
                    inline.pop();
                }
            }
            "mod" if toks.get(i + 2).is_some_and(|n| n == "{") => {
                inline.push((toks[i + 1].clone(), depth + 1));
                depth += 1;
                i += 3;
                continue;
            }
            "use" => {
                i += 1;
                let mut trees = Vec::new();
                use_tree(&toks, &mut i, &[], &mut trees);
                out.extend(trees.into_iter().map(|p| (here(&inline), p)));
                continue;
            }
            _ => {}
        }
        let starts_path = matches!(t, "crate" | "super" | "self")
            && toks.get(i + 1).is_some_and(|n| n == "::")
            && (i == 0 || toks[i - 1] != "::");
        if starts_path {
            let mut path = vec![t.to_string()];
            let mut j = i + 1;
            while toks.get(j).is_some_and(|n| n == "::")
                && toks
                    .get(j + 1)
                    .is_some_and(|n| n.chars().all(|c| c.is_alphanumeric() || c == '_'))
            {
                path.push(toks[j + 1].clone());
                j += 2;
            }
            out.push((here(&inline), path));
            i = j;
        } else {
            i += 1;
        }
    }
    out
}

/// The module a path named in module `from` points into: `crate::`, `self::`, `super::` paths,
/// and relative paths that start with one of `from`'s own submodules.
fn resolve(
    from: &ModPath,
    path: &[String],
    modules: &BTreeMap<ModPath, PathBuf>,
) -> Option<ModPath> {
    let first = path.first()?;
    let (mut base, mut rest): (ModPath, &[String]) = match first.as_str() {
        "crate" => (vec![], &path[1..]),
        "self" => (from.clone(), &path[1..]),
        "super" => {
            let mut b = from.clone();
            b.pop();
            (b, &path[1..])
        }
        _ => {
            let mut child = from.clone();
            child.push(first.clone());
            if !modules.contains_key(&child) {
                return None;
            }
            (from.clone(), path)
        }
    };
    while rest.first().is_some_and(|s| s == "super") {
        base.pop();
        rest = &rest[1..];
    }
    let mut full = base;
    full.extend(rest.iter().cloned());
    (0..=full.len())
        .rev()
        .map(|k| full[..k].to_vec())
        .find(|m| modules.contains_key(m))
}

/// Module -> modules it uses (itself excluded).
fn use_graph(src: &Path) -> BTreeMap<ModPath, BTreeSet<ModPath>> {
    let modules = module_files(src);
    let mut graph = BTreeMap::new();
    for (m, file) in &modules {
        let text = std::fs::read_to_string(file).expect("source file");
        let used: BTreeSet<ModPath> = paths_in(&text)
            .iter()
            .filter_map(|(inline, p)| {
                let mut from = m.clone();
                from.extend(inline.iter().cloned());
                resolve(&from, p, &modules)
            })
            .filter(|d| d != m)
            .collect();
        graph.insert(m.clone(), used);
    }
    graph
}

fn name(m: &ModPath) -> String {
    if m.is_empty() {
        "(crate root)".into()
    } else {
        m.join("::")
    }
}

/// The imports of `graph` against `layers`, as `"a::b -> c::d"`.
fn layer_violations(graph: &BTreeMap<ModPath, BTreeSet<ModPath>>, layers: &Layers) -> Vec<String> {
    let layer_of = |m: &ModPath| {
        m.first()
            .and_then(|top| layers.layer.iter().find(|(n, _)| n == top))
            .map(|&(_, l)| l)
    };
    let is_leaf = |m: &ModPath| {
        m.first()
            .is_some_and(|t| layers.leaves.contains(&t.as_str()))
    };
    let mut out = Vec::new();
    for (from, used) in graph {
        for to in used {
            if from.first() == to.first() || from.is_empty() {
                continue;
            }
            let bad = if is_leaf(from) {
                true
            } else if is_leaf(to) {
                false
            } else {
                match (layer_of(from), layer_of(to)) {
                    (Some(a), Some(b)) => b >= a,
                    // A top-level module the layer table does not name: add it to the table.
                    _ => !layers.layer.is_empty(),
                }
            };
            if bad {
                out.push(format!("{} -> {}", name(from), name(to)));
            }
        }
    }
    out
}

/// The import cycles of `graph` (strongly connected components of more than one module), not
/// counting a module's edges into its own submodules.
fn cycles(graph: &BTreeMap<ModPath, BTreeSet<ModPath>>) -> Vec<Vec<String>> {
    let edges: BTreeMap<&ModPath, Vec<&ModPath>> = graph
        .iter()
        .map(|(m, used)| {
            let own = |d: &&ModPath| d.len() > m.len() && d[..m.len()] == m[..];
            (m, used.iter().filter(|d| !own(d)).collect())
        })
        .collect();
    // Tarjan's strongly connected components, iteratively over a small graph.
    struct Tarjan<'a> {
        edges: &'a BTreeMap<&'a ModPath, Vec<&'a ModPath>>,
        index: BTreeMap<&'a ModPath, usize>,
        low: BTreeMap<&'a ModPath, usize>,
        stack: Vec<&'a ModPath>,
        on_stack: BTreeSet<&'a ModPath>,
        found: Vec<Vec<String>>,
    }
    impl<'a> Tarjan<'a> {
        fn visit(&mut self, v: &'a ModPath) {
            let n = self.index.len();
            self.index.insert(v, n);
            self.low.insert(v, n);
            self.stack.push(v);
            self.on_stack.insert(v);
            for &w in self.edges.get(v).into_iter().flatten() {
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
                let mut comp = Vec::new();
                while let Some(w) = self.stack.pop() {
                    self.on_stack.remove(w);
                    comp.push(name(w));
                    if w == v {
                        break;
                    }
                }
                if comp.len() > 1 {
                    comp.sort();
                    self.found.push(comp);
                }
            }
        }
    }
    let mut t = Tarjan {
        edges: &edges,
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        on_stack: BTreeSet::new(),
        found: Vec::new(),
    };
    for m in graph.keys() {
        if !t.index.contains_key(m) {
            t.visit(m);
        }
    }
    t.found
}

#[test]
fn no_module_imports_against_the_layers() {
    let mut bad = Vec::new();
    for layers in [&CORE, &APP, &BENCH] {
        let graph = use_graph(&workspace_root().join(layers.crate_dir));
        for v in layer_violations(&graph, layers) {
            bad.push(format!("{}: {v}", layers.crate_dir));
        }
    }
    assert!(
        bad.is_empty(),
        "imports against the layers:\n{}",
        bad.join("\n")
    );
}

#[test]
fn no_import_cycles_inside_a_crate() {
    let mut bad = Vec::new();
    for layers in [&CORE, &APP, &BENCH] {
        let graph = use_graph(&workspace_root().join(layers.crate_dir));
        for c in cycles(&graph) {
            bad.push(format!("{}: {}", layers.crate_dir, c.join(" <-> ")));
        }
    }
    assert!(bad.is_empty(), "import cycles:\n{}", bad.join("\n"));
}

/// The reader itself, on source whose graph is known: a `use` tree with groups and renames, a
/// path in code, paths inside comments and strings that must not count, a child using its
/// parent, and a cycle between two siblings.
#[test]
fn the_reader_finds_the_edges_of_a_known_source() {
    let dir = tempfile::tempdir().unwrap();
    let src = dir.path();
    let write = |p: &str, t: &str| {
        let f = src.join(p);
        std::fs::create_dir_all(f.parent().unwrap()).unwrap();
        std::fs::write(f, t).unwrap();
    };
    write("lib.rs", "pub mod low;\npub mod high;\n");
    write(
        "low/mod.rs",
        "pub mod a;\npub mod b;\npub use a::A;\n// crate::high is only named here\nconst S: &str = \"crate::high\";\nconst R: &str = r#\"crate::high\"#;\n",
    );
    write(
        "low/a.rs",
        "use super::{b::{B as Bee, self}, *};\npub struct A<'x>(&'x u8);\n",
    );
    write(
        "low/b.rs",
        "pub struct B;\nfn f() -> char { let _ = super::a::A(&0); '\\'' }\nmod tests { use super::*; }\n",
    );
    write("high.rs", "fn g() { let _ = crate::low::b::B; }\n");
    let graph = use_graph(src);
    let m = |s: &str| -> ModPath { s.split("::").map(String::from).collect() };
    assert_eq!(graph[&m("low::a")], BTreeSet::from([m("low"), m("low::b")]));
    assert_eq!(graph[&m("low::b")], BTreeSet::from([m("low::a")]));
    assert_eq!(graph[&m("high")], BTreeSet::from([m("low::b")]));
    assert_eq!(graph[&m("low")], BTreeSet::from([m("low::a")]));
    let layers = Layers {
        crate_dir: "",
        layer: &[("low", 0), ("high", 1)],
        leaves: &[],
    };
    assert!(layer_violations(&graph, &layers).is_empty());
    let flipped = Layers {
        crate_dir: "",
        layer: &[("low", 1), ("high", 0)],
        leaves: &[],
    };
    assert_eq!(layer_violations(&graph, &flipped), vec!["high -> low::b"]);
    assert_eq!(cycles(&graph), vec![vec!["low::a", "low::b"]]);
}
