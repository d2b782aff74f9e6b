//! `billow emptyspace` driven as the real binary in a temp dir: JSON summary, determinism
//! across thread counts, atomic output, refusals (cloud, already pruned, bad parameters).

mod common;

use std::path::Path;
use std::time::Duration;

use billow::emptyspace::synthetic::volume_from_fn;
use billow_core::gpu_memory::volume_gpu_bytes;
use billow_format::VolumeAsset;
use common::*;

/// A sparse 48×32×40 volume: two blobs and a bar, with normals.
fn write_sparse(dir: &Path, name: &str) {
    let a = volume_from_fn([48, 32, 40], true, |x, y, z| {
        let blob = (x.abs_diff(8) <= 2 && y.abs_diff(6) <= 2 && z.abs_diff(9) <= 3)
            || (x.abs_diff(40) <= 3 && y.abs_diff(25) <= 2 && z.abs_diff(30) <= 2)
            || ((20..30).contains(&x) && y == 16 && z == 20);
        if blob {
            [(x * 5) as u8, (y * 7) as u8, (z * 3) as u8, 200]
        } else {
            [0; 4]
        }
    });
    std::fs::write(dir.join(name), a.to_bytes().unwrap()).unwrap();
}

fn emptyspace(dir: &Path, args: &[&str], threads: &str) -> Run {
    let mut all = vec!["emptyspace"];
    all.extend_from_slice(args);
    run_with(
        &all,
        dir,
        Duration::from_secs(120),
        8 << 20,
        &[("RAYON_NUM_THREADS", threads)],
    )
}

#[test]
fn prunes_with_a_json_summary_deterministically() {
    let dir = tempfile::tempdir().unwrap();
    write_sparse(dir.path(), "in.billow");
    let r = emptyspace(
        dir.path(),
        &["in.billow", "-o", "out1.billow", "--json"],
        "1",
    );
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    let v: serde_json::Value = serde_json::from_str(&r.stdout).expect("one JSON document");
    for key in [
        "bands",
        "tail_level",
        "cells",
        "atlas_dims",
        "texel_bytes_before",
        "texel_bytes_after",
        "saving",
        "voxels_kept",
        "seconds",
        "file_bytes_before",
        "file_bytes_after",
    ] {
        assert!(v.get(key).is_some(), "missing {key} in {}", r.stdout);
    }
    assert!(v["cells"].as_u64().unwrap() >= 2);
    assert!(v["saving"].as_f64().unwrap() > 0.5, "{}", r.stdout);
    assert!(v["file_bytes_after"].as_u64() < v["file_bytes_before"].as_u64());
    let out = VolumeAsset::read(&dir.path().join("out1.billow")).unwrap();
    let all_cells = out.cells.len() + out.bands.iter().map(|b| b.cells.len()).sum::<usize>();
    assert_eq!(all_cells as u64, v["cells"].as_u64().unwrap());
    assert_eq!(out.bands.len() + 1, v["bands"].as_array().unwrap().len());
    assert!(out.normals.is_some() && out.bands.iter().all(|b| b.normals.is_some()));
    let r2 = emptyspace(dir.path(), &["in.billow", "-o", "out2.billow"], "2");
    assert_eq!(r2.code, Some(0), "{}", r2.stderr);
    assert!(r2.stdout.is_empty());
    assert_eq!(
        sha256(&dir.path().join("out1.billow")),
        sha256(&dir.path().join("out2.billow"))
    );
}

#[test]
fn refuses_clouds_pruned_volumes_and_bad_parameters() {
    let dir = tempfile::tempdir().unwrap();
    let cloud = repo().join("fixtures/format/v1_cloud_tiny.billow");
    let r = emptyspace(
        dir.path(),
        &[cloud.to_str().unwrap(), "-o", "x.billow"],
        "2",
    );
    assert_eq!(r.code, Some(5), "{}", r.stderr);
    let line = r.error_line().unwrap();
    assert!(
        line.contains("v1_cloud_tiny.billow") && line.contains("Cloud"),
        "{line}"
    );
    assert!(!dir.path().join("x.billow").exists());

    write_sparse(dir.path(), "in.billow");
    let r = emptyspace(dir.path(), &["in.billow", "-o", "p.billow"], "2");
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    let r = emptyspace(dir.path(), &["p.billow", "-o", "pp.billow"], "2");
    assert_eq!(r.code, Some(4), "{}", r.stderr);
    assert!(
        r.error_line().unwrap().contains("already pruned"),
        "{}",
        r.stderr
    );
    assert!(!dir.path().join("pp.billow").exists());

    let r = emptyspace(
        dir.path(),
        &["in.billow", "-o", "q.billow", "--min-gain", "1"],
        "2",
    );
    assert_eq!(r.code, Some(8), "{}", r.stderr);
    assert!(!dir.path().join("q.billow").exists());
}

#[test]
fn output_is_atomic_and_inputs_are_untouched() {
    let dir = tempfile::tempdir().unwrap();
    write_sparse(dir.path(), "in.billow");
    let before = sha256(&dir.path().join("in.billow"));
    // A corrupt input leaves an existing output as it was.
    std::fs::write(dir.path().join("out.billow"), b"keep me").unwrap();
    let good = std::fs::read(dir.path().join("in.billow")).unwrap();
    std::fs::write(dir.path().join("bad.billow"), &good[..good.len() / 2]).unwrap();
    let r = emptyspace(dir.path(), &["bad.billow", "-o", "out.billow"], "2");
    assert_eq!(r.code, Some(4), "{}", r.stderr);
    assert!(r.error_line().unwrap().contains("bad.billow"));
    assert_eq!(
        std::fs::read(dir.path().join("out.billow")).unwrap(),
        b"keep me"
    );
    // An unwritable destination: exit 7, nothing left behind.
    let r = emptyspace(
        dir.path(),
        &["in.billow", "-o", "no/such/dir/out.billow"],
        "2",
    );
    assert_eq!(r.code, Some(7), "{}", r.stderr);
    assert_eq!(sha256(&dir.path().join("in.billow")), before);
    let names: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
    assert_eq!(names.len(), 3, "only in, bad and out: {names:?}");
}

#[test]
fn odd_sides_are_kept_whole_with_a_warning_naming_the_fix() {
    let dir = tempfile::tempdir().unwrap();
    let a = volume_from_fn([33, 16, 16], false, |x, _, _| {
        if x < 3 {
            [9, 9, 9, 99]
        } else {
            [0; 4]
        }
    });
    std::fs::write(dir.path().join("odd.billow"), a.to_bytes().unwrap()).unwrap();
    // Default flags (`--compress bc`): a volume kept whole is written as it came, so a raw
    // input stays raw and its texels compare byte for byte.
    let r = emptyspace(dir.path(), &["odd.billow", "-o", "o.billow", "--json"], "2");
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    assert!(
        r.stderr.contains("warning") && r.stderr.contains("--align 8"),
        "{}",
        r.stderr
    );
    let v: serde_json::Value = serde_json::from_str(&r.stdout).unwrap();
    assert_eq!(v["kept_whole"], true);
    assert_eq!(v["saving"].as_f64(), Some(0.0));
    let out = VolumeAsset::read(&dir.path().join("o.billow")).unwrap();
    assert_eq!(out.levels, a.levels);
    assert!(out.bands.is_empty());
}

/// Issue 23 item 5: `billow emptyspace` prunes what a default `billow voxelize` writes (the
/// default `--align` makes the oak's sides even; both default to `--compress bc`), with no
/// warning, losing nothing. A BC7 file already leaves its empty 4×4 blocks out, so what
/// the pruning saves is what the renderer holds and draws: the dense GPU textures and the
/// voxels rasterized. The file grows by the aprons, the LOD bands and the cells, within a
/// bound (docs/emptyspace.md).
#[test]
fn default_voxelize_output_of_the_oak_is_pruned() {
    let dir = tempfile::tempdir().unwrap();
    let oak = repo().join("fixtures/oak/eztree_oak_medium.gltf");
    let r = run_with(
        &["voxelize", oak.to_str().unwrap(), "-o", "oak.billow", "-q"],
        dir.path(),
        Duration::from_secs(300),
        8 << 20,
        &[("RAYON_NUM_THREADS", "2")],
    );
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    let r = emptyspace(
        dir.path(),
        &["oak.billow", "-o", "pruned.billow", "--json"],
        "2",
    );
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    assert!(!r.stderr.contains("warning"), "{}", r.stderr);
    let v: serde_json::Value = serde_json::from_str(&r.stdout).unwrap();
    assert_eq!(v["kept_whole"], false, "{v}");
    let saving = v["saving"].as_f64().unwrap();
    assert!(saving > 0.25, "texel saving {saving}");
    let n = |k: &str| v[k].as_u64().unwrap();
    let (gpu0, gpu1) = (n("gpu_bytes_before"), n("gpu_bytes_after"));
    assert!(gpu1 < gpu0 * 7 / 10, "GPU textures {gpu0} -> {gpu1} bytes");
    let (vox0, vox1) = (n("voxels_before"), n("voxels_kept"));
    assert!(vox1 < vox0 * 4 / 10, "voxels drawn {vox0} -> {vox1}");
    let (before, after) = (n("file_bytes_before"), n("file_bytes_after"));
    assert!(after < before * 16 / 10, "file {before} -> {after} bytes");
    let src = VolumeAsset::read(&dir.path().join("oak.billow")).unwrap();
    // The source is BC7: about a byte a texel on a device that samples blocks; decoded,
    // eight (Rgba16Float in extinction space), as the viewer uploads it.
    assert_eq!(gpu0, volume_gpu_bytes(&src, true).with_bc);
    let texels: u64 = (0..src.levels.len() as u32)
        .map(|l| {
            billow_format::mip_dims(src.level_dims(0), l)
                .iter()
                .map(|&d| u64::from(d))
                .product::<u64>()
        })
        .sum();
    // A byte a texel, but for the coarse levels' whole 4×4 blocks, twice: the colour and
    // the normal moments the default bake stores (`--normals auto`), both sampled as blocks.
    assert!(
        src.normals.is_some(),
        "the default bake stores normal moments"
    );
    let want = 2 * texels;
    assert!(
        gpu0 >= want && gpu0 < want + texels / 50,
        "{gpu0} vs {want}"
    );
    assert_eq!(n("gpu_bytes_before_no_bc"), (8 + 4) * texels);
    let d = src.level_dims(0);
    assert!(d.iter().all(|s| s.is_multiple_of(8)), "default grid {d:?}");
    let out = VolumeAsset::read(&dir.path().join("pruned.billow")).unwrap();
    assert!(!out.bands.is_empty());
    assert_eq!(gpu1, volume_gpu_bytes(&out, true).with_bc);
    assert_eq!(
        n("gpu_bytes_after_no_bc"),
        volume_gpu_bytes(&out, true).without_bc
    );
    let d = out.level_dims(0);
    assert!(
        d[0].is_multiple_of(4) && d[1].is_multiple_of(4),
        "whole 4×4 blocks: {d:?}"
    );
}
