//! The library's modules depend on each other one way: no circle between the top-level modules
//! of `src/` (the layers of `src/lib.rs`'s crate documentation), nor between the modules inside
//! `step`, `contact` and `gpu`.
//!
//! The test reads every file of the library's modules (those `src/lib.rs` declares, so not the
//! binary's `src/main.rs`), skips the lines that start with `//` (comments and rustdoc, whose
//! links do not make a dependency) and collects the paths after `crate::`, `super::` and `self::`,
//! in `use` lines, their `{..}` groups and inline paths alike. Each path that leaves a module for
//! a sibling module is an edge between the two; a circle of edges fails the test and is printed
//! with the file and line of each of its references. References from a module to its own
//! parent's items (a `mod.rs`'s types and functions) and from a parent to its children are not
//! edges: a parent module declares its children and holds what they share.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The modules whose children must not form a circle either (the crate root is always checked).
const SCOPES: [&[&str]; 3] = [&["step"], &["contact"], &["gpu"]];

/// A module's path from the crate root (`["contact", "narrow"]`).
type ModPath = Vec<String>;

/// One dependency between two sibling modules, with the first reference that makes it.
type Edges = BTreeMap<(String, String), String>;

fn src() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("src")
}

/// The `.rs` files under `dir`, recursively, sorted.
fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("reading {}: {e}", dir.display()))
        .map(|e| e.expect("directory entry").path())
        .collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// The module a file under `src/` holds: `src/a.rs` and `src/a/mod.rs` are `a`, `src/a/b.rs` is
/// `a::b`.
fn module_of(file: &Path) -> ModPath {
    let rel = file.strip_prefix(src()).expect("a file under src/");
    let mut parts: ModPath = rel
        .with_extension("")
        .components()
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .collect();
    if parts.last().is_some_and(|p| p == "mod") {
        parts.pop();
    }
    parts
}

/// The library's top-level modules (`mod x;` in `src/lib.rs`) and the names it re-exports from
/// them (`pub use error::{Error, Result};`: `Error` -> `error`).
fn crate_root() -> (Vec<String>, BTreeMap<String, String>) {
    let lib = std::fs::read_to_string(src().join("lib.rs")).expect("src/lib.rs");
    let mut modules = Vec::new();
    let mut reexports = BTreeMap::new();
    for line in lib.lines().map(str::trim) {
        let line = line
            .trim_start_matches("pub ")
            .trim_start_matches("pub(crate) ");
        if let Some(name) = line.strip_prefix("mod ").and_then(|l| l.strip_suffix(';')) {
            modules.push(name.trim().to_string());
        } else if let Some(rest) = line.strip_prefix("use ") {
            for path in paths(rest.as_bytes(), 0).0 {
                if let (Some(module), Some(name)) = (path.first(), path.last()) {
                    reexports.insert(name.clone(), module.clone());
                }
            }
        }
    }
    (modules, reexports)
}

fn ident_byte(b: u8) -> bool {
    b.is_ascii_alphanumeric() || b == b'_'
}

fn skip_space(s: &[u8], mut i: usize) -> usize {
    while i < s.len() && s[i].is_ascii_whitespace() {
        i += 1;
    }
    i
}

/// The paths of the use tree at `s[i..]` (`a::b`, `a::{b, c::d}`, `{a, b}`), each as its
/// segments, and the position after it.
fn paths(s: &[u8], i: usize) -> (Vec<ModPath>, usize) {
    let mut i = skip_space(s, i);
    if s.get(i) == Some(&b'{') {
        let mut out = Vec::new();
        i += 1;
        loop {
            i = skip_space(s, i);
            match s.get(i) {
                None => return (out, i),
                Some(b'}') => return (out, i + 1),
                Some(b',') => i += 1,
                Some(_) => {
                    let (inner, next) = paths(s, i);
                    out.extend(inner);
                    // Not a path (a stray token): step over it.
                    i = next.max(i + 1);
                }
            }
        }
    }
    let start = i;
    while i < s.len() && (ident_byte(s[i]) || s[i] == b'*') {
        i += 1;
    }
    let ident = String::from_utf8_lossy(&s[start..i]).into_owned();
    if ident.is_empty() {
        return (vec![Vec::new()], i);
    }
    let after = skip_space(s, i);
    if s[after..].starts_with(b"::") {
        let (rest, next) = paths(s, after + 2);
        let out = rest
            .into_iter()
            .map(|mut p| {
                p.insert(0, ident.clone());
                p
            })
            .collect();
        return (out, next);
    }
    (vec![vec![ident]], i)
}

/// Every module path `crate::`, `super::` or `self::` reference of the module `module` (whose
/// text is `text`) names, resolved from the crate root, with its line number.
fn references(module: &ModPath, text: &str) -> Vec<(ModPath, usize)> {
    // Comment lines blanked, so that the positions keep their line numbers.
    let code: String = text
        .lines()
        .map(|l| {
            if l.trim_start().starts_with("//") {
                ""
            } else {
                l
            }
        })
        .collect::<Vec<_>>()
        .join("\n");
    let s = code.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < s.len() {
        let base = ["crate::", "super::", "self::"]
            .into_iter()
            .find(|b| s[i..].starts_with(b.as_bytes()));
        let Some(base) = base.filter(|_| i == 0 || !ident_byte(s[i - 1]) && s[i - 1] != b':')
        else {
            i += 1;
            continue;
        };
        let line = 1 + s[..i].iter().filter(|&&b| b == b'\n').count();
        let (found, next) = paths(s, i);
        for path in found {
            let mut abs: ModPath = match base {
                "crate::" => Vec::new(),
                _ => module.clone(),
            };
            let mut segments = path.into_iter().skip(1).peekable();
            if base == "super::" {
                abs.pop();
            }
            while segments.peek().is_some_and(|p| p == "super") {
                segments.next();
                abs.pop();
            }
            abs.extend(segments);
            out.push((abs, line));
        }
        i = next.max(i + base.len());
    }
    out
}

/// The dependencies between the children of `scope`: each reference from inside one child to
/// another child (a module of `modules`), with the first file and line that makes it.
fn edges(
    scope: &[String],
    modules: &BTreeSet<ModPath>,
    refs: &[(ModPath, ModPath, String)],
) -> Edges {
    let child = |p: &ModPath| -> Option<String> {
        let name = p.get(scope.len())?;
        let mut m = scope.to_vec();
        m.push(name.clone());
        (p.starts_with(scope) && modules.contains(&m)).then(|| name.clone())
    };
    let mut out = Edges::new();
    for (from, to, at) in refs {
        if let (Some(a), Some(b)) = (child(from), child(to)) {
            if a != b {
                out.entry((a, b)).or_insert_with(|| at.clone());
            }
        }
    }
    out
}

/// Every circle of `edges`, each once (from its smallest module), as its modules in order.
fn circles(edges: &Edges) -> Vec<Vec<String>> {
    let mut next: BTreeMap<&str, Vec<&str>> = BTreeMap::new();
    for (a, b) in edges.keys() {
        next.entry(a).or_default().push(b);
    }
    let mut found = BTreeSet::new();
    // A shortest path back from b to a closes the circle through the edge a -> b.
    for (a, b) in edges.keys() {
        let mut from: BTreeMap<&str, &str> = BTreeMap::new();
        let mut queue = std::collections::VecDeque::from([b.as_str()]);
        while let Some(n) = queue.pop_front() {
            if n == a {
                break;
            }
            for &m in next.get(n).into_iter().flatten() {
                if m != b && !from.contains_key(m) {
                    from.insert(m, n);
                    queue.push_back(m);
                }
            }
        }
        if a != b && !from.contains_key(a.as_str()) {
            continue;
        }
        let mut circle = vec![a.clone()];
        let mut n = a.as_str();
        while n != b {
            n = from[n];
            circle.push(n.to_string());
        }
        circle[1..].reverse();
        let start = (0..circle.len())
            .min_by_key(|&k| &circle[k])
            .expect("a circle has modules");
        circle.rotate_left(start);
        found.insert(circle);
    }
    found.into_iter().collect()
}

/// The circles of `edges` in words, one a line, with the reference behind each step.
fn describe(scope: &str, edges: &Edges, circles: &[Vec<String>]) -> String {
    let mut text = String::new();
    for c in circles {
        text += &format!("circle in {scope}: {} -> {}\n", c.join(" -> "), c[0]);
        for k in 0..c.len() {
            let (a, b) = (&c[k], &c[(k + 1) % c.len()]);
            text += &format!("    {a} -> {b}: {}\n", edges[&(a.clone(), b.clone())]);
        }
    }
    text
}

/// Every module of the library and every reference between modules (from, to, file:line).
fn library() -> (BTreeSet<ModPath>, Vec<(ModPath, ModPath, String)>) {
    let (top, reexports) = crate_root();
    let mut files = Vec::new();
    for m in &top {
        let file = src().join(format!("{m}.rs"));
        if file.exists() {
            files.push(file);
        }
        let dir = src().join(m);
        if dir.is_dir() {
            rust_files(&dir, &mut files);
        }
    }
    let modules: BTreeSet<ModPath> = files.iter().map(|f| module_of(f)).collect();
    let mut refs = Vec::new();
    for file in &files {
        let module = module_of(file);
        let text = std::fs::read_to_string(file).expect("a source file");
        let name = file
            .strip_prefix(src().parent().expect("the crate"))
            .expect("in the crate");
        for (mut to, line) in references(&module, &text) {
            // `crate::Error` is `crate::error::Error`.
            if let Some(first) = to.first().and_then(|f| reexports.get(f)) {
                to.insert(0, first.clone());
            }
            refs.push((module.clone(), to, format!("{}:{line}", name.display())));
        }
    }
    (modules, refs)
}

#[test]
fn the_modules_depend_on_each_other_without_a_circle() {
    let (modules, refs) = library();
    assert!(
        modules.contains(&vec!["step".to_string()]) && refs.len() > 100,
        "the library's modules were not found: {} modules, {} references",
        modules.len(),
        refs.len()
    );
    let mut report = String::new();
    let scopes = std::iter::once(Vec::new()).chain(
        SCOPES
            .iter()
            .map(|s| s.iter().map(|p| p.to_string()).collect()),
    );
    for scope in scopes {
        let edges = edges(&scope, &modules, &refs);
        let name = if scope.is_empty() {
            "the crate root".to_string()
        } else {
            scope.join("::")
        };
        if scope.is_empty() {
            assert!(
                edges.len() > 20,
                "too few dependencies between the top-level modules: {edges:?}"
            );
        }
        report += &describe(&name, &edges, &circles(&edges));
    }
    assert!(
        report.is_empty(),
        "modules depend on each other in a circle:\n{report}"
    );
}

#[test]
fn the_reader_finds_use_groups_inline_paths_and_supers_but_not_comments() {
    let module: ModPath = vec!["contact".into(), "narrow".into()];
    let text = "use crate::{model::Model, scene::{self, Scene}};\n\
                // crate::run::model is only mentioned\n\
                /// [`crate::plot`] neither\n\
                use super::solve::{a, b};\n\
                fn f() { let x = crate::step::element::is_triangle(&q); super::super::gpu::x(); }\n";
    let got: Vec<(String, usize)> = references(&module, text)
        .into_iter()
        .map(|(p, l)| (p.join("::"), l))
        .collect();
    let expected = [
        ("model::Model", 1),
        ("scene::self", 1),
        ("scene::Scene", 1),
        ("contact::solve::a", 4),
        ("contact::solve::b", 4),
        ("step::element::is_triangle", 5),
        ("gpu::x", 5),
    ];
    assert_eq!(
        got,
        expected.map(|(p, l)| (p.to_string(), l)),
        "the references of {text}"
    );
    // A circle is found and named from its smallest module.
    let edges: Edges = [("b", "c"), ("c", "a"), ("a", "b"), ("c", "d")]
        .into_iter()
        .map(|(a, b)| ((a.to_string(), b.to_string()), format!("{a}.rs")))
        .collect();
    assert_eq!(circles(&edges), vec![vec!["a", "b", "c"]]);
}
