//! Every command of the README's "Using it" block works as written (issue 37: the README's
//! first command failed on a fresh clone, and `cargo build --release` in the root built no
//! binary): each line runs in a fresh folder holding `fixtures/` (a link to the
//! repository's), with `target/release/billow` replaced by the binary under test and
//! `make` run on the repository with that binary and the batch's output in the folder.
//! `cargo build --release` itself is checked by what it must build: the workspace's
//! default members include the CLI package (Cargo.toml), and `make demo` by CI
//! (`.ci/run` runs it from a clean clone).

mod common;

use std::process::Command;

use common::{bin, repo};

/// The lines of the first ```sh block after "## Using it", without trailing comments.
fn using_it() -> Vec<String> {
    let readme = std::fs::read_to_string(repo().join("README.md")).unwrap();
    let section = readme
        .split("## Using it")
        .nth(1)
        .expect("README has a 'Using it' section");
    let block = section
        .split("```sh\n")
        .nth(1)
        .and_then(|b| b.split("```").next())
        .expect("a ```sh block in 'Using it'");
    block
        .lines()
        .map(|l| match l.find("  #") {
            Some(i) => l[..i].trim().to_string(),
            None => l.trim().to_string(),
        })
        .filter(|l| !l.is_empty())
        .collect()
}

#[test]
fn the_default_build_makes_the_binary() {
    let toml = std::fs::read_to_string(repo().join("Cargo.toml")).unwrap();
    let line = toml
        .lines()
        .find(|l| l.starts_with("default-members"))
        .expect("Cargo.toml: default-members");
    assert!(line.contains("\"bin/billow\""), "{line}");
}

#[test]
fn every_readme_command_runs() {
    let lines = using_it();
    assert!(lines.len() >= 5, "{lines:?}");
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    std::os::unix::fs::symlink(repo().join("fixtures"), d.join("fixtures")).unwrap();
    let billow = bin().display().to_string();
    for line in &lines {
        if line.starts_with("cargo build") {
            continue;
        }
        let status = if line.starts_with("make ") {
            Command::new("sh")
                .arg("-c")
                .arg(format!(
                    "{line} -C {} BILLOW={billow} OUT_DIR={}/out/assets",
                    repo().display(),
                    d.display()
                ))
                .current_dir(d)
                .env("RAYON_NUM_THREADS", "2")
                .output()
        } else {
            Command::new("sh")
                .arg("-c")
                .arg(line.replace("target/release/billow", &billow))
                .current_dir(d)
                .env("RAYON_NUM_THREADS", "2")
                .output()
        }
        .unwrap();
        assert!(
            status.status.success(),
            "README: `{line}`: {}{}",
            String::from_utf8_lossy(&status.stdout),
            String::from_utf8_lossy(&status.stderr)
        );
    }
    for f in [
        "out/oak.billow",
        "out/report.json",
        "out/assets/eztree_oak_medium.gltf.cloud.billow",
    ] {
        assert!(d.join(f).is_file(), "{f}");
    }
}
