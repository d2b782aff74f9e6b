//! `billow voxelize` and the library's `voxelize::bake` (issue 39 item 1) write the same
//! file from the same options: `BakeOptions::at(res)` with the mesh's source is the CLI's
//! `--res res` without other flags, dense and `--prune`d, byte for byte.

mod common;

use billow::import::{import, ImportOptions, Imported};
use billow::provenance::source_info_all;
use billow::voxelize::{bake, BakeHooks, BakeOptions, Resolution};
use common::{repo, run};

#[test]
fn the_library_bake_writes_the_cli_s_file() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let mesh = repo().join("fixtures/oak/eztree_oak_medium.gltf");
    let m = mesh.to_str().unwrap();
    let Imported { scene, report } = import(&mesh, &ImportOptions { strict: false }).unwrap();
    let source = source_info_all(&mesh, &report.files).unwrap();
    for (prune, name) in [(false, "dense.billow"), (true, "pruned.billow")] {
        let mut args = vec!["voxelize", m, "-o", name, "--res", "48", "-q"];
        if prune {
            args.push("--prune");
        }
        let r = run(&args, d);
        assert_eq!(r.code, Some(0), "{}", r.stderr);
        let opts = BakeOptions {
            prune,
            source: Some(source.clone()),
            ..BakeOptions::at(Resolution::Longest(48))
        };
        let baked = bake(&scene, &opts, &BakeHooks::default()).unwrap();
        let lib = baked.asset.to_bytes_with(baked.blocks.as_ref()).unwrap();
        let cli = std::fs::read(d.join(name)).unwrap();
        assert!(
            lib == cli,
            "{name}: library {} bytes, CLI {} bytes",
            lib.len(),
            cli.len()
        );
    }
}
