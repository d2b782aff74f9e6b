//! `voxelize::bake`, all of `billow voxelize` as one library call: dense and pruned, with
//! and without BC7, on small procedural meshes. The asset validates, its header says what
//! was done, and a pruned bake is what `emptyspace::prune_sparse` makes of
//! `voxelize_sparse` called directly.

use std::cell::{Cell, RefCell};
use std::collections::BTreeMap;

use billow::compress::{encode_volume, Compression};
use billow::emptyspace::{prune_sparse, EmptySpaceOptions};
use billow::procgen::{torus, truss};
use billow::provenance::tool_version;
use billow::scene::{Scene, SceneBuilder};
use billow::voxelize::toksvig::{self, NormalsJudgement};
use billow::voxelize::{
    bake, bake_params, bake_params_for, voxelize, voxelize_sparse, BakeError, BakeHooks,
    BakeOptions, Baked, CombineFn, NormalsMode, Resolution, Stage, VoxelizeError, VoxelizeOptions,
};
use billow_format::{NormalKind, SourceInfo, VolumeAsset, VolumeBlocks};

fn small() -> VoxelizeOptions {
    VoxelizeOptions {
        resolution: Resolution::Longest(24),
        supersample: 2,
        ..VoxelizeOptions::default()
    }
}

fn scene() -> Scene {
    torus(1.0, 0.35, 24, 12)
}

fn options(normals: NormalsMode, prune: bool, compression: Compression) -> BakeOptions {
    BakeOptions {
        voxelize: small(),
        normals,
        prune,
        compression,
        ..BakeOptions::default()
    }
}

fn run(scene: &Scene, opts: &BakeOptions) -> Baked {
    bake(scene, opts, &BakeHooks::default()).expect("bake")
}

/// The file's bytes.
fn file(asset: &VolumeAsset, blocks: Option<&VolumeBlocks>) -> Vec<u8> {
    asset.to_bytes_with(blocks).expect("encode")
}

#[test]
fn dense_bake_is_voxelize_and_its_asset() {
    let scene = scene();
    let opts = options(NormalsMode::Off, false, Compression::None);
    let baked = run(&scene, &opts);
    baked.asset.validate().expect("valid asset");
    assert!(baked.blocks.is_none() && baked.pruned.is_none());
    let p = &baked.asset.header.params;
    assert_eq!(p["normals"], "false");
    assert_eq!(p["res"], "24");
    assert!(baked.asset.header.compress().is_none());
    assert!(baked.asset.header.pruned().is_none());
    assert_eq!(baked.asset.header.tool, tool_version());
    assert!(!baked.options.normals && !baked.normals.kept);

    // The same as voxelize + bake_params + into_asset by hand.
    let mut vo = small();
    vo.normals = false;
    vo.moments = false;
    let volume = voxelize(&scene, &vo, &|_, _| {}).unwrap();
    assert_eq!(baked.dims, volume.dims());
    assert_eq!(baked.mip_count, volume.mip_count());
    let params = bake_params(&volume, &vo, &BTreeMap::new());
    let expected = volume.into_asset(&tool_version(), None, params);
    assert_eq!(baked.asset, expected);
}

#[test]
fn header_says_what_was_done() {
    let scene = scene();
    // Auto on a closed surface: the moments, with the coherence judged.
    let baked = run(&scene, &options(NormalsMode::Auto, true, Compression::Bc));
    baked.asset.validate().expect("valid asset");
    let h = &baked.asset.header;
    assert_eq!(h.compress(), Some("bc7"));
    assert!(h.pruned().is_some(), "pruned: {:?}", h.params);
    assert_eq!(h.params["normals"], "moments");
    let k = baked.normals.coherence.expect("judged");
    assert_eq!(h.params["normal_coherence"], format!("{k:.3}"));
    assert_eq!(
        h.volume.and_then(|v| v.normal_kind()),
        Some(NormalKind::Moments)
    );
    assert!(baked.options.normals && baked.options.moments);
    assert!(baked.pruned.is_some() && baked.blocks.is_some());
    // The file reads back, blocks and all.
    let bytes = file(&baked.asset, baked.blocks.as_ref());
    let (back, blocks) = VolumeAsset::from_bytes_with_blocks(&bytes).expect("reads back");
    assert!(blocks.is_some());
    assert_eq!(back.header, baked.asset.header);

    // Mean normals, the caller's parameters, tool and source.
    let mut opts = options(NormalsMode::On, false, Compression::Bc);
    opts.tool = "my tool 1.0".into();
    opts.source = Some(SourceInfo {
        file_name: "torus.obj".into(),
        sha256: "0".repeat(64),
        bytes: 1234,
    });
    opts.params.insert("lod_group".into(), "ring".into());
    let baked = run(&scene, &opts);
    baked.asset.validate().expect("valid asset");
    let h = &baked.asset.header;
    assert_eq!(h.params["normals"], "true");
    assert_eq!(h.params["lod_group"], "ring");
    assert_eq!(h.tool, "my tool 1.0");
    assert_eq!(h.source, opts.source);
    assert_eq!(
        h.volume.and_then(|v| v.normal_kind()),
        Some(NormalKind::Mean)
    );
    assert!(h.pruned().is_none());
}

#[test]
fn decode_blocks_gives_what_a_reader_gets() {
    let scene = scene();
    let mut opts = options(NormalsMode::On, true, Compression::Bc);
    let own = run(&scene, &opts);
    opts.decode_blocks = true;
    let decoded = run(&scene, &opts);
    // The same file either way.
    let bytes = file(&own.asset, own.blocks.as_ref());
    assert_eq!(bytes, file(&decoded.asset, decoded.blocks.as_ref()));
    // With decode_blocks, the texels in memory are the file's.
    let back = VolumeAsset::from_bytes(&bytes).expect("reads back");
    assert_eq!(back.levels, decoded.asset.levels);
    assert_eq!(back.normals, decoded.asset.normals);
}

#[test]
fn pruned_bake_is_prune_sparse_of_voxelize_sparse() {
    let scene = truss(2.0, 1.0, 4, 0.05);
    for (mode, normals) in [(NormalsMode::Off, false), (NormalsMode::On, true)] {
        for compression in [Compression::None, Compression::Bc] {
            let mut opts = options(mode, true, compression);
            opts.voxelize.resolution = Resolution::Longest(32);
            let baked = run(&scene, &opts);
            baked.asset.validate().expect("valid asset");
            let (asset, blocks) = pruned_by_hand(&scene, normals, compression, 32);
            assert_eq!(
                file(&baked.asset, baked.blocks.as_ref()),
                file(&asset, blocks.as_ref()),
                "{mode:?}, {compression:?}"
            );
            let stats = baked.pruned.as_ref().expect("prune stats");
            assert_eq!(stats.source_dims, baked.dims);
        }
    }
}

/// `voxelize_sparse` then `prune_sparse` by hand (and BC7), as `bake` with `prune` should
/// do it.
fn pruned_by_hand(
    scene: &Scene,
    normals: bool,
    compression: Compression,
    res: u32,
) -> (VolumeAsset, Option<VolumeBlocks>) {
    let mut vo = small();
    vo.resolution = Resolution::Longest(res);
    vo.normals = normals;
    vo.moments = false;
    if !normals {
        // `--normals off` judges on a coarse bake whether the mesh is a closed surface
        // (foliage thins its opaque texels too), as `bake` does; `on` judges its own.
        if let Ok(NormalsJudgement::Coarse(k)) = toksvig::judge_normals(scene, &vo) {
            vo.surface = Some(toksvig::keeps(k));
        }
    }
    let sv = voxelize_sparse(scene, &vo, &|_, _| {}).unwrap();
    let params = bake_params_for(&sv.grid, &vo, &BTreeMap::new());
    let shell = sv.asset_shell(&tool_version(), None, params);
    let es = EmptySpaceOptions {
        bc_blocks: compression == Compression::Bc,
        memory_limit: vo.memory_limit,
        ..EmptySpaceOptions::default()
    };
    let mut asset = prune_sparse(&shell, sv.levels, &es).unwrap().asset;
    let blocks = (compression == Compression::Bc).then(|| {
        asset.header.set_compress("bc7");
        encode_volume(&mut asset)
    });
    (asset, blocks)
}

#[test]
fn expression_combines_are_pruned_dense() {
    // voxelize_sparse refuses expressions: bake falls back on the dense volume's prune.
    let scene = scene();
    let mut opts = options(NormalsMode::Off, true, Compression::None);
    opts.voxelize.combine = "expr:max(px, nx)".parse::<CombineFn>().unwrap();
    let baked = run(&scene, &opts);
    baked.asset.validate().expect("valid asset");
    assert!(baked.asset.header.pruned().is_some());
    assert!(baked.pruned.is_some());
}

#[test]
fn hooks_see_progress_notes_and_the_point_before_the_prune() {
    let scene = scene();
    for prune in [false, true] {
        let stages = RefCell::new(Vec::new());
        let between = Cell::new(0);
        let notes = RefCell::new(Vec::<String>::new());
        let progress = |s: Stage, f: f32| {
            assert!((0.0..=1.0).contains(&f));
            stages.borrow_mut().push(s);
        };
        let note = |m: &str| notes.borrow_mut().push(m.to_string());
        let count = || between.set(between.get() + 1);
        let hooks = BakeHooks {
            progress: &progress,
            note: &note,
            between: Some(&count),
        };
        bake(
            &scene,
            &options(NormalsMode::Off, prune, Compression::None),
            &hooks,
        )
        .unwrap();
        assert!(stages.borrow().contains(&Stage::Rasterize));
        assert_eq!(between.get(), usize::from(prune), "prune {prune}");
    }
}

#[test]
fn errors_are_the_bakes_and_name_no_file() {
    let empty = SceneBuilder::new().finish();
    let e = bake(
        &empty,
        &options(NormalsMode::Off, false, Compression::None),
        &BakeHooks::default(),
    )
    .expect_err("refused");
    assert!(matches!(e, BakeError::Voxelize(VoxelizeError::EmptyScene)));
    assert_eq!(e.to_string(), VoxelizeError::EmptyScene.to_string());
}
