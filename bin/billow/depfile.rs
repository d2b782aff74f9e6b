//! `--depfile FILE`: the files a bake read, as a Makefile rule without a recipe
//! (docs/cli.md):
//!
//! ```make
//! out.billow out.ktx2: \
//!  mesh.gltf \
//!  mesh.bin \
//!  bark.png
//! ```
//!
//! The targets are the command's output files; the prerequisites every file it read, the
//! input first, then the files read beside it in the order they were read. The first line
//! is always `TARGETS: \` and each prerequisite has its own line. Like `gcc -MP`, an empty
//! rule follows for each file read beside the input (`bark.png:`), so that make rebakes,
//! rather than stops, when one of them is deleted. Spaces, `#` and `%` are
//! escaped with a backslash and `$` is written `$$`, as GNU make reads them; a path make
//! cannot express (a newline, a colon, a backslash) is refused with exit 8 before the bake.
//!
//! Files the bake looked for and did not find (a missing texture or .mtl) cannot be
//! prerequisites: make would stop on them, or rebake on every run. They go into a GNU make
//! conditional instead, so that the outputs are up to date while the file stays missing
//! and out of date as soon as it exists, whatever its modification time (a texture
//! restored from a backup keeps its old one):
//!
//! ```make
//! ifneq ($(wildcard tex/leaf.png),)
//! out.billow out.ktx2: .billow-restored
//! endif
//! .billow-restored:
//! ```
//!
//! `.billow-restored` has no file and no recipe, so make treats it as always new.

use std::path::{Path, PathBuf};

use billow::import::ImportReport;

use crate::exit::{CliError, Code};
use crate::staged::{out_err, Staged};

/// One path, escaped for a Makefile rule.
fn escape(flag: &str, p: &Path) -> Result<String, CliError> {
    let Some(s) = p.to_str() else {
        return Err(CliError::new(
            Code::BadParameter,
            format!(
                "{flag}: {} is not valid UTF-8, which a depfile cannot hold",
                p.display()
            ),
        ));
    };
    let mut out = String::with_capacity(s.len() + 8);
    for c in s.chars() {
        match c {
            ' ' | '\t' | '#' | '%' => {
                out.push('\\');
                out.push(c);
            }
            '$' => out.push_str("$$"),
            '\n' | '\r' | ':' | '\\' => {
                return Err(CliError::new(
                    Code::BadParameter,
                    format!(
                        "{flag}: the path {s:?} has a character a Makefile rule cannot hold \
                         ({c:?}); rename it or bake without --depfile"
                    ),
                ))
            }
            c => out.push(c),
        }
    }
    Ok(out)
}

/// Checks, before the bake, that every output and the input can be written into a depfile.
pub fn check(depfile: Option<&Path>, paths: &[&Path]) -> Result<(), CliError> {
    if depfile.is_some() {
        for p in paths {
            escape("--depfile", p)?;
        }
    }
    Ok(())
}

/// [`check`] for the files an import read beside the mesh.
pub fn check_read(depfile: Option<&Path>, read: &[PathBuf]) -> Result<(), CliError> {
    check(
        depfile,
        &read.iter().map(PathBuf::as_path).collect::<Vec<_>>(),
    )
}

/// Commits `stage`'s outputs, with `depfile` its rule ([`render`]) among them: the targets
/// are `output`, `also` and `written`, the prerequisites `input` and what `report` says the
/// import read.
pub fn commit(
    mut stage: Staged,
    depfile: Option<&Path>,
    (output, also, written): (&Path, Option<&Path>, &[PathBuf]),
    input: &Path,
    report: &ImportReport,
) -> Result<(), CliError> {
    if let Some(d) = depfile {
        let mut targets = vec![output];
        targets.extend(also);
        targets.extend(written.iter().map(PathBuf::as_path));
        let text = render(&targets, input, &report.files, &report.missing)?;
        stage.stage(d, text.as_bytes()).map_err(|e| out_err(d, e))?;
    }
    stage.commit_or_fail()
}

/// The depfile's text: `targets` depend on `input` and then `read`, and are out of date as
/// soon as one of `missing` exists.
pub fn render(
    targets: &[&Path],
    input: &Path,
    read: &[PathBuf],
    missing: &[PathBuf],
) -> Result<String, CliError> {
    let mut out = String::new();
    let mut target_list = String::new();
    for (i, t) in targets.iter().enumerate() {
        if i > 0 {
            target_list.push(' ');
        }
        target_list.push_str(&escape("--depfile", t)?);
    }
    out.push_str(&target_list);
    out.push(':');
    let mut prereqs = vec![input];
    prereqs.extend(read.iter().map(PathBuf::as_path));
    for p in prereqs {
        out.push_str(" \\\n ");
        out.push_str(&escape("--depfile", p)?);
    }
    out.push('\n');
    for p in read {
        out.push('\n');
        out.push_str(&escape("--depfile", p)?);
        out.push_str(":\n");
    }
    if !missing.is_empty() {
        out.push_str(
            "\n# Looked for when baked, not found: once one exists, the targets are out of date.\n",
        );
        out.push_str("ifneq ($(wildcard");
        for p in missing {
            out.push(' ');
            out.push_str(&glob_escape(&escape("--depfile", p)?));
        }
        out.push_str("),)\n");
        out.push_str(&target_list);
        out.push_str(": .billow-restored\nendif\n.billow-restored:\n");
    }
    Ok(out)
}

/// A path already escaped for make, with the characters `$(wildcard)`'s glob would take
/// as patterns (`*`, `?`, `[`, `]`) escaped too.
fn glob_escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        if matches!(c, '*' | '?' | '[' | ']') {
            out.push('\\');
        }
        out.push(c);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn escapes_what_make_needs() {
        let t = render(
            &[Path::new("out dir/a.billow"), Path::new("b.ktx2")],
            Path::new("my mesh.gltf"),
            &[PathBuf::from("tex/50%#$.png")],
            &[],
        )
        .unwrap();
        assert_eq!(
            t,
            "out\\ dir/a.billow b.ktx2: \\\n my\\ mesh.gltf \\\n tex/50\\%\\#$$.png\n\n\
             tex/50\\%\\#$$.png:\n"
        );
        assert!(render(&[Path::new("a:b")], Path::new("m.obj"), &[], &[]).is_err());
        assert!(check(Some(Path::new("d")), &[Path::new("x\ny")]).is_err());
        assert!(check(None, &[Path::new("x\ny")]).is_ok());
    }

    #[test]
    fn missing_files_make_a_conditional_rule() {
        let t = render(
            &[Path::new("a.billow")],
            Path::new("m.obj"),
            &[PathBuf::from("m.mtl")],
            &[PathBuf::from("tex/leaf*1.png"), PathBuf::from("b c.png")],
        )
        .unwrap();
        assert!(
            t.starts_with("a.billow: \\\n m.obj \\\n m.mtl\n\nm.mtl:\n"),
            "{t}"
        );
        assert!(
            t.contains(
                "ifneq ($(wildcard tex/leaf\\*1.png b\\ c.png),)\na.billow: .billow-restored\nendif\n\
                 .billow-restored:\n"
            ),
            "{t}"
        );
    }
}
