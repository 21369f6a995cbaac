//! The workspace's module graph: no two modules of a crate need each other, directly or
//! through others. When two files need each other, the shared part is a third module (a
//! model, a layout, a constant's home), so dependencies point one way.
//!
//! The check lives here, in the root package's `techniques` test binary, beside the tests of
//! the shared kernels and the techniques whose modules make up most of the graph (`cli` and
//! `report` test what the command line and the reports do). The root package's
//! `CARGO_MANIFEST_DIR` is the workspace's root, so it reads every crate's sources in place
//! (`scenes`, `instrumentation`, `methods`, `analysis`, `reports`, `bench` with its binary, and
//! the CLI's `src/`) with no test binary of its own and no path out of a crate.
//!
//! How the sources are read (a small lexer, no compiler):
//!
//! - A crate's modules are the files its root (`lib.rs`, `main.rs`) reaches through `mod x;`
//!   declarations, `x.rs` or `x/mod.rs`, nested modules included (`methods::gpu::frame`,
//!   `methods::spsm::classify`). A `mod` declaration is not an edge.
//! - A module depends on the modules its code names by `crate::`, `super::` or `self::` paths,
//!   `use` groups included (`use crate::{a, b::c}`): a path names the deepest module file it
//!   runs through (`crate::spsm::Spsm` names `spsm`, `super::texel::Tri` the sibling `texel`).
//!   Inside an inline module (`mod tests { use super::*; }`) `super::` and `self::` start from
//!   that module.
//! - A name a module re-exports (`pub use`, `pub(crate) use`) names the module it comes from,
//!   through further re-exports: `crate::gpu::GpuError` names `gpu::error`. So a `mod.rs` that
//!   re-exports its children's items is no hub of false cycles, and a re-export left at an
//!   item's old place does not hide where the item lives. A re-export is an edge itself only
//!   when written with `crate::`, `super::` or `self::`; globs (`pub use x::*`) are not
//!   followed.
//! - Other paths are not read: another crate's (`scenes::Mesh`), or a parent's own children
//!   (`raster::rasterize_conservative` in `spsm`). A parent is its children's front: they name
//!   what it defines with `super::`, it runs them; read both ways, every such parent would be
//!   a cycle with its children (`scenes::io`, `methods::afsm`, `methods::gpu::pan09`).
//! - Comments (`//`, `///`, `//!`, `/* */`) and string and character literals are skipped:
//!   doc links name modules a module does not use (the GPU path's docs point to
//!   `crate::registry`), and read as code they made false cycles through most of `methods`.

use std::collections::{BTreeMap, BTreeSet, VecDeque};
use std::path::{Path, PathBuf};

/// The crates of the workspace: the name their modules are printed under, the source folder
/// and the crate root. `bench` has a library and a binary, two crates of one folder.
const CRATES: &[(&str, &str, &str)] = &[
    ("scenes", "scenes/src", "lib.rs"),
    ("instrumentation", "instrumentation/src", "lib.rs"),
    ("methods", "methods/src", "lib.rs"),
    ("analysis", "analysis/src", "lib.rs"),
    ("reports", "reports/src", "lib.rs"),
    ("bench", "bench/src", "lib.rs"),
    ("embree-side-by-side", "bench/src", "main.rs"),
    ("shadowbench", "src", "main.rs"),
];

/// What the lexer keeps of a source: identifiers, `::`, and single punctuation characters.
fn tokens(src: &str) -> Vec<&str> {
    let b = src.as_bytes();
    let ident = |c: u8| c.is_ascii_alphanumeric() || c == b'_';
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        let c = b[i];
        let rest = &b[i..];
        if c.is_ascii_whitespace() || !c.is_ascii() {
            i += 1;
        } else if rest.starts_with(b"//") {
            i += rest.iter().position(|&c| c == b'\n').unwrap_or(rest.len());
        } else if rest.starts_with(b"/*") {
            let mut depth = 0;
            while i < b.len() {
                if b[i..].starts_with(b"/*") {
                    depth += 1;
                    i += 2;
                } else if b[i..].starts_with(b"*/") {
                    depth -= 1;
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    i += 1;
                }
            }
        } else if let Some(hashes) = raw_string_start(rest).filter(|_| i == 0 || !ident(b[i - 1])) {
            // r"..", r#".."#, br"..": ends at the quote followed by as many hashes.
            let open = rest.iter().position(|&c| c == b'"').unwrap_or(0) + 1;
            let close: Vec<u8> = std::iter::once(b'"').chain(vec![b'#'; hashes]).collect();
            let end = rest[open..].windows(close.len()).position(|w| w == close.as_slice());
            i += open + end.map_or(rest.len() - open, |e| e + close.len());
        } else if c == b'"' || rest.starts_with(b"b\"") {
            i += if c == b'"' { 1 } else { 2 };
            while i < b.len() && b[i] != b'"' {
                i += if b[i] == b'\\' { 2 } else { 1 };
            }
            i += 1;
        } else if c == b'\'' {
            // A character literal ('x', '\n', '\u{..}', '·') or a lifetime ('a, '_).
            if rest.get(1) == Some(&b'\\') {
                i += 3 + rest[3..].iter().position(|&c| c == b'\'').map_or(0, |e| e + 1);
            } else {
                let len = src[i + 1..].chars().next().map_or(1, char::len_utf8);
                i += if b.get(i + 1 + len) == Some(&b'\'') { len + 2 } else { 1 };
            }
        } else if ident(c) && !c.is_ascii_digit() {
            let len = rest.iter().position(|&c| !ident(c)).unwrap_or(rest.len());
            out.push(&src[i..i + len]);
            i += len;
        } else if c.is_ascii_digit() {
            // 1, 0x1f, 1.5e3, 2u32; a `.` only before a digit (`0..n` is a range).
            i += 1;
            while i < b.len()
                && (ident(b[i]) || (b[i] == b'.' && b.get(i + 1).is_some_and(u8::is_ascii_digit)))
            {
                i += 1;
            }
        } else if rest.starts_with(b"::") {
            out.push("::");
            i += 2;
        } else {
            out.push(&src[i..i + 1]);
            i += 1;
        }
    }
    out
}

/// The number of `#` of a raw string literal starting at `s` (`r"`, `r#"`, `br"`), if one does.
fn raw_string_start(s: &[u8]) -> Option<usize> {
    let s = s.strip_prefix(b"b").unwrap_or(s).strip_prefix(b"r")?;
    let hashes = s.iter().take_while(|&&c| c == b'#').count();
    (s.get(hashes) == Some(&b'"')).then_some(hashes)
}

/// Whether a token is an identifier.
fn is_ident(t: &str) -> bool {
    t.bytes().next().is_some_and(|c| c.is_ascii_alphabetic() || c == b'_')
}

/// A path as a `use` tree or an expression names it: its segments, and for a `use` member the
/// name it is given (`as y`; `*` for a glob), if not its last segment.
type Named = (Vec<String>, Option<String>);

/// Reads the path or `use` tree starting at `toks[i]`, segments after `prefix`; pushes every
/// full path it names (a group `{a, b::c}` names each member) and returns the index after it.
fn path_tree(toks: &[&str], mut i: usize, prefix: &[String], out: &mut Vec<Named>) -> usize {
    let mut segs = prefix.to_vec();
    while i < toks.len() && is_ident(toks[i]) {
        segs.push(toks[i].to_owned());
        i += 1;
        if toks.get(i) != Some(&"::") {
            break;
        }
        i += 1;
        match toks.get(i) {
            Some(&"{") => {
                i += 1;
                while i < toks.len() && toks[i] != "}" {
                    i = path_tree(toks, i, &segs, out);
                    while i < toks.len() && toks[i] != "," && toks[i] != "}" {
                        i += 1;
                    }
                    if toks.get(i) == Some(&",") {
                        i += 1;
                    }
                }
                return i + 1;
            }
            Some(&"*") => {
                out.push((segs, Some("*".to_owned())));
                return i + 1;
            }
            _ => {}
        }
    }
    let alias = match (toks.get(i), toks.get(i + 1)) {
        (Some(&"as"), Some(name)) if is_ident(name) => {
            i += 2;
            Some(name.to_string())
        }
        _ => None,
    };
    if segs.len() > prefix.len() {
        out.push((segs, alias));
    }
    i
}

/// What one file says about modules: its `mod x;` children, every `crate::`, `super::` or
/// `self::` path it names, and what it re-exports.
#[derive(Debug, Default)]
struct FileRefs {
    /// Modules declared as files (`mod x;`).
    children: Vec<String>,
    /// The inline modules (`mod tests { .. }`) around a path, and the path's segments.
    paths: Vec<(Vec<String>, Vec<String>)>,
    /// The names the file's own `pub use` (any `pub(..)` too) gives, with the paths they name.
    reexports: BTreeMap<String, Vec<String>>,
}

/// Reads a source file's children, paths and re-exports.
fn file_refs(src: &str) -> FileRefs {
    let toks = tokens(src);
    let mut refs = FileRefs::default();
    // Inline modules open here, with the brace depth they opened at.
    let mut inline: Vec<(String, usize)> = Vec::new();
    let mut depth = 0;
    let mut i = 0;
    while i < toks.len() {
        let t = toks[i];
        let next = toks.get(i + 1).copied();
        let path_start = matches!(t, "crate" | "super" | "self")
            && next == Some("::")
            && (i == 0 || toks[i - 1] != "::");
        match t {
            "mod" if next.is_some_and(is_ident) => {
                match toks.get(i + 2).copied() {
                    Some(";") if inline.is_empty() => refs.children.push(toks[i + 1].to_owned()),
                    Some("{") => {
                        inline.push((toks[i + 1].to_owned(), depth));
                        depth += 1;
                    }
                    _ => {}
                }
                i += 3;
            }
            _ if t == "use" || path_start => {
                // `pub use`, `pub(crate) use`: a re-export.
                let public = (i >= 1 && toks[i - 1] == "pub")
                    || (i >= 4 && toks[i - 4] == "pub" && toks[i - 3] == "(" && toks[i - 1] == ")");
                let mut found = Vec::new();
                i = path_tree(&toks, if t == "use" { i + 1 } else { i }, &[], &mut found);
                let around: Vec<String> = inline.iter().map(|(n, _)| n.clone()).collect();
                for (segs, alias) in found {
                    let name = alias.or_else(|| segs.last().cloned()).unwrap_or_default();
                    if t == "use" && public && inline.is_empty() && is_ident(&name) {
                        refs.reexports.insert(name, segs.clone());
                    }
                    if matches!(segs[0].as_str(), "crate" | "super" | "self") {
                        refs.paths.push((around.clone(), segs));
                    }
                }
            }
            "{" => {
                depth += 1;
                i += 1;
            }
            "}" => {
                depth -= 1;
                if inline.last().is_some_and(|(_, d)| *d == depth) {
                    inline.pop();
                }
                i += 1;
            }
            _ => i += 1,
        }
    }
    refs
}

/// Every module file of the crate rooted at `dir/root`, by module path (the root is empty),
/// with what it says.
fn crate_modules(dir: &Path, root: &str) -> BTreeMap<Vec<String>, FileRefs> {
    let mut modules = BTreeMap::new();
    // (module path, file, the folder its children are in)
    let mut todo = vec![(Vec::new(), dir.join(root), dir.to_path_buf())];
    while let Some((path, file, children_dir)) = todo.pop() {
        let src = std::fs::read_to_string(&file).unwrap_or_else(|e| panic!("{file:?}: {e}"));
        let refs = file_refs(&src);
        for c in &refs.children {
            let flat = children_dir.join(format!("{c}.rs"));
            let (file, sub) = if flat.exists() {
                (flat, children_dir.join(c))
            } else {
                (children_dir.join(c).join("mod.rs"), children_dir.join(c))
            };
            assert!(file.exists(), "`mod {c};` in {path:?} of {dir:?}: no {c}.rs or {c}/mod.rs");
            let mut child: Vec<String> = path.clone();
            child.push(c.clone());
            todo.push((child, file, sub));
        }
        modules.insert(path, refs);
    }
    modules
}

/// The module a path names from module `at` (its file's path, then the inline modules
/// around it): the deepest module file the path runs through, or, for a name that module
/// re-exports, the module the name comes from.
fn resolve(
    modules: &BTreeMap<Vec<String>, FileRefs>,
    at: &[String],
    segs: &[String],
) -> Vec<String> {
    resolve_within(modules, at, segs, 0)
}

/// [`resolve`], `hops` re-exports deep (a loop of re-exports stops after a few).
fn resolve_within(
    modules: &BTreeMap<Vec<String>, FileRefs>,
    at: &[String],
    segs: &[String],
    hops: usize,
) -> Vec<String> {
    let (mut full, rest): (Vec<String>, &[String]) = match segs.first().map(String::as_str) {
        Some("crate") => (Vec::new(), &segs[1..]),
        Some("self") => (at.to_vec(), &segs[1..]),
        _ => {
            let supers = segs.iter().take_while(|s| *s == "super").count();
            (at[..at.len().saturating_sub(supers)].to_vec(), &segs[supers..])
        }
    };
    full.extend(rest.iter().filter(|s| *s != "self").cloned());
    let k = (0..=full.len()).rev().find(|&k| modules.contains_key(&full[..k])).unwrap_or(0);
    let module = full[..k].to_vec();
    let reexport = full.get(k).and_then(|name| modules.get(&module)?.reexports.get(name));
    let Some(target) = reexport.filter(|_| hops < 8) else {
        return module;
    };
    // `pub use child::Item` names the child; `pub use other_crate::Item` stays here.
    let mut child = module.clone();
    child.push(target[0].clone());
    if matches!(target[0].as_str(), "crate" | "super" | "self") {
        resolve_within(modules, &module, target, hops + 1)
    } else if modules.contains_key(&child) {
        resolve_within(modules, &child, &target[1..], hops + 1)
    } else {
        module
    }
}

/// Every module of the workspace (`crate::a::b`, the root as `crate`) with the modules of its
/// crate that its code names.
fn module_graph() -> BTreeMap<String, BTreeSet<String>> {
    let workspace = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let mut graph = BTreeMap::new();
    for (name, dir, root) in CRATES {
        let modules = crate_modules(&workspace.join(dir), root);
        let label = |p: &[String]| {
            std::iter::once(*name)
                .chain(p.iter().map(String::as_str))
                .collect::<Vec<_>>()
                .join("::")
        };
        for (path, refs) in &modules {
            let named = refs
                .paths
                .iter()
                .map(|(around, segs)| {
                    let at: Vec<String> = path.iter().chain(around).cloned().collect();
                    resolve(&modules, &at, segs)
                })
                .filter(|m| m != path)
                .map(|m| label(&m))
                .collect();
            graph.insert(label(path), named);
        }
    }
    graph
}

/// The cycles of `graph`: in every strongly connected component of more than one module, the
/// shortest cycle through each of its modules, each cycle once.
fn cycles(graph: &BTreeMap<String, BTreeSet<String>>) -> Vec<Vec<String>> {
    // Tarjan's strongly connected components.
    struct Tarjan<'a> {
        graph: &'a BTreeMap<String, BTreeSet<String>>,
        index: BTreeMap<&'a str, (usize, usize)>,
        stack: Vec<&'a str>,
        components: Vec<BTreeSet<&'a str>>,
    }
    impl<'a> Tarjan<'a> {
        fn visit(&mut self, m: &'a str) -> usize {
            let n = self.index.len();
            self.index.insert(m, (n, n));
            self.stack.push(m);
            let mut low = n;
            for next in self.graph.get(m).into_iter().flatten() {
                low = match self.index.get(next.as_str()) {
                    None => low.min(self.visit(next)),
                    Some(&(k, _)) if self.stack.contains(&next.as_str()) => low.min(k),
                    Some(_) => low,
                };
            }
            self.index.insert(m, (n, low));
            if low == n {
                let at = self.stack.iter().rposition(|s| *s == m).unwrap_or(0);
                self.components.push(self.stack.drain(at..).collect());
            }
            low
        }
    }
    let mut t = Tarjan { graph, index: BTreeMap::new(), stack: Vec::new(), components: Vec::new() };
    for m in graph.keys() {
        if !t.index.contains_key(m.as_str()) {
            t.visit(m);
        }
    }
    let mut found = BTreeSet::new();
    for component in t.components.iter().filter(|c| c.len() > 1) {
        for &start in component {
            if let Some(mut cycle) = shortest_cycle(graph, component, start) {
                // One way of writing each cycle: from its first module in name order.
                cycle.pop();
                let first = (0..cycle.len()).min_by_key(|&k| &cycle[k]).unwrap_or(0);
                cycle.rotate_left(first);
                cycle.push(cycle[0].clone());
                found.insert(cycle);
            }
        }
    }
    found.into_iter().collect()
}

/// The shortest way from `start` back to it inside `component`, breadth-first, as the
/// modules on it (`start` first and last).
fn shortest_cycle(
    graph: &BTreeMap<String, BTreeSet<String>>,
    component: &BTreeSet<&str>,
    start: &str,
) -> Option<Vec<String>> {
    let mut came_from: BTreeMap<&str, &str> = BTreeMap::new();
    let mut queue = VecDeque::from([start]);
    while let Some(m) = queue.pop_front() {
        for next in graph.get(m).into_iter().flatten().map(String::as_str) {
            if next == start {
                let mut cycle = vec![start.to_owned(), m.to_owned()];
                let mut at = m;
                while at != start {
                    at = came_from[at];
                    cycle.push(at.to_owned());
                }
                cycle.reverse();
                return Some(cycle);
            }
            if component.contains(next) && !came_from.contains_key(next) {
                came_from.insert(next, m);
                queue.push_back(next);
            }
        }
    }
    None
}

/// No module of any crate needs another that needs it back, directly or through others.
#[test]
fn modules_form_no_cycle() {
    let graph = module_graph();
    let edges: usize = graph.values().map(BTreeSet::len).sum();
    let depends = |a: &str, b: &str| graph.get(a).is_some_and(|n| n.contains(b));
    // A reader that saw nothing would find no cycle: it must see the workspace, every kind of
    // path (`super::` groups, nested `crate::` groups, a re-export followed).
    assert!(graph.len() >= 100 && edges >= 300, "{} modules, {edges} edges", graph.len());
    for (a, b) in [
        ("methods::spsm::classify", "methods::spsm::texel"),
        ("methods::registry", "methods::spsm"),
        ("methods::gpu::spsm::pack", "methods::spsm::texel"),
        ("scenes::registry", "scenes::scene_file"),
        ("reports::sweep", "reports::model"),
        ("methods::gpu::spsm::pack", "methods::gpu::spsm::raster"),
        ("methods::gpu::frame", "methods::gpu::context"),
    ] {
        assert!(depends(a, b), "{a} should depend on {b}: {:?}", graph.get(a));
    }
    let found = cycles(&graph);
    let lines: Vec<String> = found.iter().map(|c| c.join(" -> ")).collect();
    assert!(found.is_empty(), "{} import cycles:\n{}", found.len(), lines.join("\n"));
}

/// The reader on a made-up crate: groups, `super::` from a child and from an inline module,
/// `self::`, re-exports followed to where their names come from, and what it must not read
/// (comments, strings, other crates' paths, `mod` lines); the cycle finder on a loop through
/// three modules.
#[test]
fn module_reader_sees_paths_reexports_and_long_cycles() {
    let src = r##"
        //! Names crate::c in a comment.
        use crate::{a, b::{self, x as y}, d::*};
        /* crate::c */ mod child;
        fn f() -> &'static str { let _ = '{'; scenes::Mesh; self::g(); "crate::c {" }
        #[cfg(test)] mod tests { use super::*; use super::super::z; }
    "##;
    let refs = file_refs(src);
    assert_eq!(refs.children, ["child"]);
    let paths: Vec<String> = refs.paths.iter().map(|(a, p)| format!("{a:?}{p:?}")).collect();
    assert_eq!(
        paths,
        [
            r#"[]["crate", "a"]"#,
            r#"[]["crate", "b", "self"]"#,
            r#"[]["crate", "b", "x"]"#,
            r#"[]["crate", "d"]"#,
            r#"[]["self", "g"]"#,
            r#"["tests"]["super"]"#,
            r#"["tests"]["super", "super", "z"]"#,
        ]
    );
    assert!(refs.reexports.is_empty());

    let s = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
    let root = "pub use b::x::Thing as Other; pub(crate) use self::a::A; pub use glam::DVec3;";
    let modules: BTreeMap<Vec<String>, FileRefs> =
        [(&[][..], root), (&["a"], ""), (&["b"], "pub use x::*;"), (&["b", "x"], "")]
            .iter()
            .map(|(p, src)| (s(p), file_refs(src)))
            .collect();
    assert_eq!(modules[&s(&[])].reexports.len(), 3);
    for (at, path, named) in [
        (&["b", "x"][..], &["super", "super", "a", "T"][..], &["a"][..]),
        (&["b", "tests"], &["super", "x"], &["b", "x"]),
        (&["a"], &["crate", "b", "self"], &["b"]),
        (&["a"], &["crate", "Other", "new"], &["b", "x"]),
        (&["b", "x"], &["crate", "A"], &["a"]),
        (&["a"], &["crate", "DVec3"], &[]),
        (&["a"], &["crate", "b", "Thing"], &["b"]),
    ] {
        assert_eq!(resolve(&modules, &s(at), &s(path)), s(named), "{path:?} from {at:?}");
    }

    let graph: BTreeMap<String, BTreeSet<String>> =
        [("a", "b"), ("b", "c"), ("c", "a"), ("d", "a"), ("e", "e")]
            .iter()
            .map(|(m, n)| (m.to_string(), BTreeSet::from([n.to_string()])))
            .collect();
    assert_eq!(cycles(&graph), [s(&["a", "b", "c", "a"])]);
}
