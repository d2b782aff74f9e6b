//! Every file of the shared corpora goes through `import`: Ok, or an error naming the
//! file — never a panic, never a hang.

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::time::Instant;

mod common;

use billow::import::{import, ImportOptions};

fn assets() -> Option<PathBuf> {
    common::shared_assets("import_corpus")
}

fn collect(dir: &Path, exts: &[&str], out: &mut Vec<PathBuf>) {
    let Ok(rd) = std::fs::read_dir(dir) else {
        return;
    };
    let mut entries: Vec<_> = rd.flatten().map(|e| e.path()).collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            collect(&p, exts, out);
        } else if let Some(e) = p.extension().and_then(|e| e.to_str()) {
            if exts.iter().any(|x| x.eq_ignore_ascii_case(e)) {
                out.push(p);
            }
        }
    }
}

#[test]
fn corpus_never_panics() {
    let Some(root) = assets() else { return };
    let mut files = Vec::new();
    collect(
        &root.join("gltf_validator_testsuite/test"),
        &["gltf", "glb"],
        &mut files,
    );
    let n_validator = files.len();
    collect(
        &root.join("bad_inputs"),
        &["gltf", "glb", "obj"],
        &mut files,
    );
    collect(&root.join("tobj_obj_testfiles/obj"), &["obj"], &mut files);
    assert!(
        n_validator > 300,
        "validator suite incomplete: {n_validator}"
    );

    // Silence the default hook so that a panic shows up once, in our list.
    let hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let start = Instant::now();
    let mut offenders = Vec::new();
    let (mut ok, mut err) = (0, 0);
    let (mut v_ok, mut v_err) = (0, 0);
    for (k, f) in files.iter().enumerate() {
        let t0 = Instant::now();
        let r = catch_unwind(AssertUnwindSafe(|| import(f, &ImportOptions::default())));
        let name = f.file_name().unwrap().to_string_lossy().into_owned();
        match r {
            Err(p) => {
                let msg = p
                    .downcast_ref::<String>()
                    .cloned()
                    .or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string()))
                    .unwrap_or_default();
                offenders.push(format!("{}: PANIC {msg}", f.display()));
            }
            Ok(Ok(_)) => {
                ok += 1;
                if k < n_validator {
                    v_ok += 1;
                }
            }
            Ok(Err(e)) => {
                err += 1;
                if k < n_validator {
                    v_err += 1;
                }
                let s = e.to_string();
                if !s.contains(&name) || s.contains('\n') {
                    offenders.push(format!(
                        "{}: error does not name the file on one line: {s}",
                        f.display()
                    ));
                }
            }
        }
        let dt = t0.elapsed();
        if dt.as_secs_f32() > 5.0 {
            offenders.push(format!("{}: took {dt:?}", f.display()));
        }
    }
    std::panic::set_hook(hook);
    println!(
        "{} files in {:?}: {ok} ok, {err} errors (validator suite: {v_ok} ok, {v_err} errors)",
        files.len(),
        start.elapsed()
    );
    assert!(
        offenders.is_empty(),
        "{} offenders:\n{}",
        offenders.len(),
        offenders.join("\n")
    );
}
