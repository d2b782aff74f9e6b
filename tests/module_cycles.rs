//! Dependencies between source files point one way (issue 39, item 2): in every package
//! (the library, the CLI, formats, core, the viewer) no two files import each other,
//! directly or round a longer circle.
//!
//! A file depends on another when it names a path into it: `crate::a::b::…`,
//! `super::…`, `self::…` or, in a `use` of a module with children, `child::…` (groups
//! `{…}` expanded), resolved to the deepest module file the path reaches. Edges between a
//! module and its own ancestors are left out: a `mod.rs` re-exporting its children and a
//! child using the types its parent declares is how a Rust module is built. Paths inside
//! an inline `mod tests` are resolved from the file's own module (test code is left
//! out of the circles, mostly). What remains must be acyclic; `KNOWN` lists the circles that are still to be broken and may only
//! shrink (a circle listed but gone fails too, so the list stays true).

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Circles still to be broken, each as its files sorted and joined by ` ↔ `.
const KNOWN: &[&str] = &[];

/// One package: its name and source root (the folder of its `lib.rs` or `main.rs`).
const PACKAGES: &[(&str, &str)] = &[
    ("billow", "src"),
    ("billow-cli", "bin/billow"),
    ("billow-format", "formats/src"),
    ("billow-core", "core/src"),
    ("billow-view", "viewer/src"),
];

/// The module path of `file` under `root` (`a/b.rs` and `a/b/mod.rs` → `[a, b]`).
fn module_of(root: &Path, file: &Path) -> Vec<String> {
    let rel = file.strip_prefix(root).expect("under the root");
    let mut parts: Vec<String> = rel
        .iter()
        .map(|p| p.to_string_lossy().into_owned())
        .collect();
    let last = parts.pop().expect("a file name");
    let stem = last.trim_end_matches(".rs").to_string();
    if !(stem == "mod" || (parts.is_empty() && (stem == "lib" || stem == "main"))) {
        parts.push(stem);
    }
    parts
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let mut entries: Vec<_> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.expect("entry").path())
        .collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|e| e == "rs") {
            out.push(p);
        }
    }
}

/// The source without comments and string or char literals (so that paths in docs and
/// messages do not count).
fn code_only(src: &str) -> String {
    let b = src.as_bytes();
    let mut out = String::with_capacity(src.len());
    let mut i = 0;
    while i < b.len() {
        if b[i..].starts_with(b"//") {
            while i < b.len() && b[i] != b'\n' {
                i += 1;
            }
        } else if b[i..].starts_with(b"/*") {
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
        } else if b[i] == b'r' && (b[i..].starts_with(b"r\"") || b[i..].starts_with(b"r#")) {
            // Raw string: r#*"…"#*.
            let mut j = i + 1;
            let mut hashes = 0;
            while j < b.len() && b[j] == b'#' {
                hashes += 1;
                j += 1;
            }
            if j < b.len() && b[j] == b'"' {
                let close: Vec<u8> = std::iter::once(b'"')
                    .chain(std::iter::repeat_n(b'#', hashes))
                    .collect();
                j += 1;
                while j < b.len() && !b[j..].starts_with(&close) {
                    j += 1;
                }
                i = j + close.len();
                out.push_str("\"\"");
            } else {
                out.push('r');
                i += 1;
            }
        } else if b[i] == b'"' {
            i += 1;
            while i < b.len() && b[i] != b'"' {
                i += if b[i] == b'\\' { 2 } else { 1 };
            }
            i += 1;
            out.push_str("\"\"");
        } else if b[i] == b'\''
            && (b[i..].starts_with(b"'\\") || (i + 2 < b.len() && b[i + 2] == b'\''))
        {
            // A char literal (a lifetime has no closing quote).
            i += 1;
            while i < b.len() && b[i] != b'\'' {
                i += if b[i] == b'\\' { 2 } else { 1 };
            }
            i += 1;
        } else {
            let c = src[i..].chars().next().expect("char");
            out.push(c);
            i += c.len_utf8();
        }
    }
    out
}

/// Every path of a `use` tree (`a::{b, c::{d, e}}` → `a::b`, `a::c::d`, `a::c::e`).
fn expand_use(tree: &str) -> Vec<String> {
    let tree: String = tree.chars().filter(|c| !c.is_whitespace()).collect();
    fn go(prefix: &str, t: &str, out: &mut Vec<String>) {
        if let Some(open) = t.find('{') {
            let head = &t[..open];
            let inner = &t[open + 1..t.rfind('}').expect("closing brace")];
            let mut depth = 0;
            let mut start = 0;
            let mut parts = Vec::new();
            for (k, ch) in inner.char_indices() {
                match ch {
                    '{' => depth += 1,
                    '}' => depth -= 1,
                    ',' if depth == 0 => {
                        parts.push(&inner[start..k]);
                        start = k + 1;
                    }
                    _ => {}
                }
            }
            parts.push(&inner[start..]);
            for p in parts.into_iter().filter(|p| !p.is_empty()) {
                go(&format!("{prefix}{head}"), p, out);
            }
        } else {
            let t = t.split(" as ").next().unwrap_or(t);
            out.push(format!("{prefix}{t}"));
        }
    }
    let mut out = Vec::new();
    go("", &tree, &mut out);
    out
}

/// The paths a file names: its `use` trees and every `crate::`/`super::`/`self::` path.
fn paths_in(code: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut rest = code;
    while let Some(k) = rest.find("use ") {
        let before = rest[..k].chars().last();
        rest = &rest[k + 4..];
        if before.is_some_and(|c| c.is_alphanumeric() || c == '_') {
            continue;
        }
        if let Some(end) = rest.find(';') {
            out.extend(expand_use(&rest[..end]));
        }
    }
    let b = code.as_bytes();
    for start in ["crate::", "super::", "self::"] {
        let mut from = 0;
        while let Some(k) = code[from..].find(start) {
            let at = from + k;
            from = at + start.len();
            if at > 0
                && (b[at - 1].is_ascii_alphanumeric() || b[at - 1] == b'_' || b[at - 1] == b':')
            {
                continue;
            }
            let end = code[at..]
                .find(|c: char| !(c.is_alphanumeric() || c == '_' || c == ':'))
                .map_or(code.len(), |e| at + e);
            out.push(code[at..end].to_string());
        }
    }
    out
}

/// The file a path reaches from module `here`: the deepest module along it.
fn resolve(
    modules: &BTreeMap<Vec<String>, PathBuf>,
    here: &[String],
    path: &str,
) -> Option<PathBuf> {
    let segs: Vec<&str> = path.split("::").filter(|s| !s.is_empty()).collect();
    let (mut m, rest): (Vec<String>, &[&str]) = match segs.first()? {
        &"crate" => (Vec::new(), &segs[1..]),
        &"self" => (here.to_vec(), &segs[1..]),
        &"super" => {
            let mut m = here.to_vec();
            let mut k = 0;
            while segs.get(k) == Some(&"super") {
                m.pop();
                k += 1;
            }
            (m, &segs[k..])
        }
        // A child module named without `self::`.
        first => {
            let mut c = here.to_vec();
            c.push(first.to_string());
            if !modules.contains_key(&c) {
                return None;
            }
            (c, &segs[1..])
        }
    };
    for s in rest {
        let mut next = m.clone();
        next.push(s.to_string());
        if modules.contains_key(&next) {
            m = next;
        } else {
            break;
        }
    }
    modules.get(&m).cloned()
}

/// `a` is `b` or one of its ancestors, or the other way round.
fn related(a: &[String], b: &[String]) -> bool {
    a.starts_with(b) || b.starts_with(a)
}

/// The circles (strongly connected components of more than one file) of `edges`.
fn circles(edges: &BTreeMap<String, BTreeSet<String>>) -> Vec<Vec<String>> {
    // Tarjan's algorithm, iteration order fixed by the BTreeMap.
    struct T<'a> {
        edges: &'a BTreeMap<String, BTreeSet<String>>,
        index: BTreeMap<&'a str, usize>,
        low: BTreeMap<&'a str, usize>,
        stack: Vec<&'a str>,
        on: BTreeSet<&'a str>,
        out: Vec<Vec<String>>,
    }
    fn visit<'a>(t: &mut T<'a>, v: &'a str) {
        let i = t.index.len();
        t.index.insert(v, i);
        t.low.insert(v, i);
        t.stack.push(v);
        t.on.insert(v);
        if let Some(ws) = t.edges.get(v) {
            for w in ws {
                if !t.index.contains_key(w.as_str()) {
                    visit(t, w);
                    let lw = t.low[w.as_str()];
                    let lv = t.low[v];
                    t.low.insert(v, lv.min(lw));
                } else if t.on.contains(w.as_str()) {
                    let iw = t.index[w.as_str()];
                    let lv = t.low[v];
                    t.low.insert(v, lv.min(iw));
                }
            }
        }
        if t.low[v] == t.index[v] {
            let mut comp = Vec::new();
            while let Some(w) = t.stack.pop() {
                t.on.remove(w);
                comp.push(w.to_string());
                if w == v {
                    break;
                }
            }
            if comp.len() > 1 {
                comp.sort();
                t.out.push(comp);
            }
        }
    }
    let mut t = T {
        edges,
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        on: BTreeSet::new(),
        out: Vec::new(),
    };
    for v in edges.keys() {
        if !t.index.contains_key(v.as_str()) {
            visit(&mut t, v);
        }
    }
    t.out.sort();
    t.out
}

/// The file graph of the package whose sources are under `root` (paths relative to the
/// repository).
fn file_graph(repo: &Path, root: &str) -> BTreeMap<String, BTreeSet<String>> {
    file_graph_with_paths(repo, root)
        .into_iter()
        .map(|(f, to)| (f, to.into_keys().collect()))
        .collect()
}

/// [`file_graph`] with, per edge, the paths that make it.
fn file_graph_with_paths(
    repo: &Path,
    root: &str,
) -> BTreeMap<String, BTreeMap<String, BTreeSet<String>>> {
    let dir = repo.join(root);
    let mut files = Vec::new();
    rust_files(&dir, &mut files);
    let modules: BTreeMap<Vec<String>, PathBuf> = files
        .iter()
        .map(|f| (module_of(&dir, f), f.clone()))
        .collect();
    let name = |p: &Path| p.strip_prefix(repo).expect("in repo").display().to_string();
    let mut edges = BTreeMap::new();
    for f in &files {
        let here = module_of(&dir, f);
        let code = code_only(&std::fs::read_to_string(f).expect("read"));
        let mut to: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
        for p in paths_in(&code) {
            if let Some(t) = resolve(&modules, &here, &p) {
                let tm = module_of(&dir, &t);
                if !related(&here, &tm) {
                    to.entry(name(&t)).or_default().insert(p);
                }
            }
        }
        edges.insert(name(f), to);
    }
    edges
}

/// All circles of every package, each as `a ↔ b ↔ …` (files sorted), with the paths that
/// close it (`a → b: paths`, within the circle).
fn all_circles(repo: &Path) -> BTreeMap<String, Vec<String>> {
    let mut out = BTreeMap::new();
    for (_, root) in PACKAGES {
        let g = file_graph_with_paths(repo, root);
        let plain = g
            .iter()
            .map(|(f, to)| (f.clone(), to.keys().cloned().collect()))
            .collect();
        for c in circles(&plain) {
            let why = c
                .iter()
                .flat_map(|a| {
                    g[a].iter()
                        .filter(|(b, _)| c.contains(b))
                        .map(move |(b, p)| format!("{a} → {b}: {p:?}"))
                })
                .collect();
            out.insert(c.join(" ↔ "), why);
        }
    }
    out
}

#[test]
fn no_two_files_import_each_other() {
    let repo = Path::new(env!("CARGO_MANIFEST_DIR"));
    let circles = all_circles(repo);
    let found: BTreeSet<String> = circles.keys().cloned().collect();
    let known: BTreeSet<String> = KNOWN.iter().map(|s| s.to_string()).collect();
    let new: Vec<_> = found.difference(&known).map(|c| (c, &circles[c])).collect();
    let gone: Vec<_> = known.difference(&found).collect();
    assert!(
        new.is_empty() && gone.is_empty(),
        "files that import each other (a new circle: break it; a listed one gone: take it \
         off KNOWN):\n  new: {new:#?}\n  gone: {gone:#?}"
    );
}

/// The check sees a circle: two files of a scratch package that name each other, one
/// through `super::`, one through a `use crate::` group.
#[test]
fn a_planted_circle_is_found() {
    let dir = tempfile::tempdir().expect("tempdir");
    let src = dir.path().join("src");
    std::fs::create_dir_all(src.join("m")).expect("mkdir");
    std::fs::write(src.join("lib.rs"), "pub mod m;\npub mod z;\n").expect("write");
    std::fs::write(src.join("m/mod.rs"), "pub mod a;\npub mod b;\n").expect("write");
    std::fs::write(
        src.join("m/a.rs"),
        "// super::b in a comment does not count\npub fn f() { super::b::g() }\n",
    )
    .expect("write");
    std::fs::write(
        src.join("m/b.rs"),
        "use crate::{m::a::{self}, z};\npub fn g() {}\npub fn h() { a::f(); z::k() }\n",
    )
    .expect("write");
    std::fs::write(
        src.join("z.rs"),
        "pub fn k() { let _ = \"crate::m::a\"; }\n",
    )
    .expect("write");
    let g = file_graph(dir.path(), "src");
    assert_eq!(
        circles(&g),
        vec![vec!["src/m/a.rs".to_string(), "src/m/b.rs".to_string()]],
        "{g:#?}"
    );
    assert!(
        g["src/z.rs"].is_empty(),
        "a path in a string literal counted: {g:#?}"
    );
}
