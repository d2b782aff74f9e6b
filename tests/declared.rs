//! Every integration test in tests/ is declared in exactly one package: the library's
//! (Cargo.toml: tests of `src/` that never link the viewer) or the CLI's
//! (bin/billow/Cargo.toml: tests that drive the real binary). Both packages set
//! `autotests = false`, so a test file declared in neither would silently never run.

use std::collections::BTreeMap;
use std::path::Path;

/// `(name, path)` of every `[[test]]` in a manifest (the simple form billow's manifests
/// use: `name = "…"` then `path = "…"`).
fn declared(manifest: &Path) -> Vec<(String, String)> {
    let text = std::fs::read_to_string(manifest).unwrap();
    let value = |line: &str, key: &str| -> Option<String> {
        let rest = line
            .trim()
            .strip_prefix(key)?
            .trim_start()
            .strip_prefix('=')?;
        Some(rest.trim().trim_matches('"').to_string())
    };
    let mut out = Vec::new();
    let mut in_test = false;
    let mut name = None;
    for line in text.lines() {
        let t = line.trim();
        if t.starts_with('[') {
            in_test = t == "[[test]]";
            name = None;
            continue;
        }
        if !in_test {
            continue;
        }
        if let Some(n) = value(t, "name") {
            name = Some(n);
        } else if let Some(p) = value(t, "path") {
            let n = name
                .take()
                .unwrap_or_else(|| panic!("{manifest:?}: path {p} without a name"));
            out.push((n, p));
        }
    }
    out
}

#[test]
fn every_test_file_is_declared_in_exactly_one_package() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut owner: BTreeMap<String, Vec<&str>> = BTreeMap::new();
    for (manifest, prefix, package) in [
        (root.join("Cargo.toml"), "", "billow"),
        (root.join("bin/billow/Cargo.toml"), "../../", "billow-cli"),
    ] {
        let tests = declared(&manifest);
        assert!(tests.len() > 10, "{manifest:?}: {} tests", tests.len());
        for (name, path) in tests {
            let file = path
                .strip_prefix(prefix)
                .unwrap_or_else(|| panic!("{package}: {path} is not under {prefix}tests/"));
            assert_eq!(
                file,
                format!("tests/{name}.rs"),
                "{package}: test {name} at {path}"
            );
            owner.entry(file.to_string()).or_default().push(package);
        }
    }
    let mut files: Vec<String> = std::fs::read_dir(root.join("tests"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "rs"))
        .map(|p| format!("tests/{}", p.file_name().unwrap().to_string_lossy()))
        .collect();
    files.sort();
    assert!(files.len() > 40, "{files:?}");
    for f in &files {
        match owner.get(f).map(Vec::as_slice) {
            Some([_]) => {}
            Some(more) => panic!("{f} is declared in {more:?}: one package runs it"),
            None => panic!(
                "{f} is declared in no package, so it never runs: add a [[test]] to Cargo.toml \
                 (library tests) or bin/billow/Cargo.toml (tests that drive the binary)"
            ),
        }
    }
    for f in owner.keys() {
        assert!(files.contains(f), "{f} is declared but does not exist");
    }
}

/// The library's integration tests do not link the viewer: the library's manifest has no
/// dependency on billow-view (not even a dev-dependency), and none on clap, indicatif or
/// libc (the CLI package owns them; an example may use libc as a dev-dependency).
#[test]
fn the_library_does_not_depend_on_what_only_the_binary_uses() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(root.join("Cargo.toml")).unwrap();
    let deps = |dev: bool| -> Vec<String> {
        text.split("\n[")
            .filter(|s| {
                let head = s.lines().next().unwrap_or("");
                head.ends_with("dependencies]") && head.contains("dev-dependencies") == dev
            })
            .flat_map(|s| s.lines().skip(1))
            .filter_map(|l| l.split('=').next())
            .map(|k| k.trim().to_string())
            .collect()
    };
    let (normal, dev) = (deps(false), deps(true));
    assert!(normal.iter().any(|d| d == "billow-format"), "{normal:?}");
    for banned in ["billow-view", "clap", "indicatif", "libc"] {
        assert!(
            !normal.iter().any(|d| d == banned),
            "Cargo.toml: the library depends on {banned}"
        );
    }
    assert!(
        !dev.iter().any(|d| d == "billow-view"),
        "Cargo.toml: the library's tests link the viewer"
    );
}
